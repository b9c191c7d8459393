// The linear bending model (CapeSettings::bendingRigidity over Fabric::hinges()): which hinges a grid and a
// mesh get, the plate's energy 1/2 B kappa^2 at any resolution and, on an equilateral mesh, in any direction.
#include "cape/core/Cape.h"
#include "cape/core/FabricPresets.h"
#include "cape/scenes/Textile.h"

#include "CapeTestFixture.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

namespace cape {
namespace {

constexpr float kPi = 3.14159265358979f;

TEST(LinearBending, AGridHingesAlongEveryRowAndColumnStraightAtRest) {
  GridDesc g;
  g.columns = 7;
  g.rows = 5;
  g.width = 0.6f;
  g.height = 0.4f;
  g.massByArea = true;
  FabricResult f = Fabric::grid(g);
  ASSERT_TRUE(f.status.ok());
  const HingeSet& h = f.fabric->hinges();
  EXPECT_EQ(h.size(), static_cast<std::size_t>(5 * (7 - 2) + 7 * (5 - 2)));
  const float hx = 0.1f, hy = 0.1f;
  for (std::size_t k = 0; k < h.size(); ++k) {
    EXPECT_NEAR(h.restBend[k], 0.0f, 1e-6f);
    EXPECT_NEAR(h.firstWeight[k], 10.0f, 1e-4f);
    // The middle particle's area share over the arm squared: an interior particle hx hy, an edge one half.
    const std::uint32_t j = h.middle[k];
    const int r = static_cast<int>(j) / 7, c = static_cast<int>(j) % 7;
    const float share = hx * hy * ((r == 0 || r == 4) ? 0.5f : 1.0f) * ((c == 0 || c == 6) ? 0.5f : 1.0f);
    EXPECT_NEAR(h.areaOverLength2[k], share / (0.1f * 0.1f), 1e-4f) << r << "," << c;
  }
}

// Bends a flat fabric (in its x-y plane) onto a cylinder of radius R about an axis in the plane at `angle`
// from +y, keeping arc length, and returns the cape's energy: only the hinges store any (gravity off, the
// springs all but free).
double cylinderEnergy(const FabricPtr& fabric, float bendingRigidity, float radius, float angle) {
  CapeSettings s = test::quietSettings();
  s.structuralStiffness = 1e-12f;
  s.shearStiffness = 0.0f;
  s.bendStiffness = 0.0f;
  s.bendingRigidity = bendingRigidity;
  Cape cape(fabric, s, Pose());
  EXPECT_TRUE(cape.ok()) << cape.status().message();
  const Eigen::Vector3f across(std::cos(angle), -std::sin(angle), 0.0f);  // the direction that curves
  const Eigen::Vector3f along(std::sin(angle), std::cos(angle), 0.0f);
  Points& x = cape.mutableState().positions;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const Vec3 p = fabric->restPositions().row(i).transpose();
    const float u = p.dot(across), v = p.dot(along);
    const Vec3 q = radius * std::sin(u / radius) * across + v * along +
                   radius * (1.0f - std::cos(u / radius)) * Vec3::UnitZ();
    x.row(i) = q.transpose();
  }
  return cape.energy();
}

TEST(LinearBending, AGridStoresThePlatesEnergyAtEveryResolution) {
  // 1/2 B kappa^2 over the area the row hinges cover (all but the half cells of the two border columns).
  const float b = findFabric("wool")->bendingRigidity, radius = 0.25f, size = 0.4f;
  for (int n : {9, 21, 41}) {
    GridDesc g;
    g.columns = g.rows = n;
    g.width = g.height = size;
    g.massByArea = true;
    FabricResult f = Fabric::grid(g);
    ASSERT_TRUE(f.status.ok());
    const double covered = size * size * (n - 2.0) / (n - 1.0);
    const double expected = 0.5 * b * covered / (radius * radius);
    const double e = cylinderEnergy(f.fabric, b, radius, 0.0f);
    EXPECT_NEAR(e / expected, 1.0, 0.01) << n << " x " << n;
  }
}

TEST(LinearBending, AnEquilateralMeshBendsAlikeInEveryDirection) {
  DrapeSpec spec;
  spec.spacing = 0.01f;
  spec.specimenDiameter = 0.3f;
  MeshDesc mesh = drapeSpecimen(*findFabric("wool"), spec);
  // The specimen lies in x-z; the cylinder helper bends the fabric's x-y plane: turn the mesh.
  for (Vec3& p : mesh.positions) p = Vec3(p.x(), p.z(), 0.0f);
  FabricResult f = Fabric::fromMesh(mesh);
  ASSERT_TRUE(f.status.ok()) << f.status.message();
  const float b = 1e-5f, radius = 0.3f;
  double first = 0.0;
  for (float degrees : {0.0f, 15.0f, 30.0f, 45.0f, 60.0f, 90.0f}) {
    const double e = cylinderEnergy(f.fabric, b, radius, degrees * kPi / 180.0f);
    if (degrees == 0.0f) first = e;
    EXPECT_NEAR(e / first, 1.0, 0.03) << degrees << " degrees";
  }
  // And about the plate's: 1/2 B kappa^2 over the area (the rim's vertices, with fewer lines, differ).
  const double plate = 0.5 * b * mesh.totalMass / findFabric("wool")->arealDensity / (radius * radius);
  EXPECT_NEAR(first / plate, 1.0, 0.1);
}

TEST(LinearBending, AVertexWithTooManyNeighboursGetsNoHingeAndTheBuildStaysFast) {
  // A fan of 20,000 triangles around one vertex: pairing its neighbours would take 4e8 steps.
  MeshDesc fan;
  const int spokes = 20000;
  fan.positions.push_back(Vec3::Zero());
  for (int i = 0; i < spokes; ++i) {
    const float phi = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(spokes);
    fan.positions.emplace_back(std::cos(phi), std::sin(phi), 0.0f);
  }
  for (int i = 0; i < spokes; ++i)
    fan.triangles.insert(fan.triangles.end(), {0u, static_cast<std::uint32_t>(1 + i),
                                               static_cast<std::uint32_t>(1 + (i + 1) % spokes)});
  const auto t0 = std::chrono::steady_clock::now();
  FabricResult f = Fabric::fromMesh(fan);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(f.status.ok()) << f.status.message();
  for (std::uint32_t j : f.fabric->hinges().middle) EXPECT_NE(j, 0u);
  EXPECT_LT(seconds, 30.0);  // a generous bound against a quadratic pairing (seconds, not hours)
}

TEST(LinearBending, TheExplicitIntegratorBendsTooAndRefusesAnUnstableStep) {
  GridDesc g;
  g.columns = 3;
  g.rows = 12;
  g.width = 0.02f;
  g.height = 0.11f;
  g.totalMass = 0.0005f;
  FabricResult f = Fabric::grid(g);
  ASSERT_TRUE(f.status.ok());
  CapeSettings s = test::quietSettings();
  s.integrator = Integrator::ExplicitSpring;
  s.structuralStiffness = 5.0f;
  s.shearStiffness = 1.0f;
  s.bendStiffness = 0.0f;
  s.substeps = 200;
  s.damping = 5.0f;
  s.bendingRigidity = 1e-7f;
  s.gravity = Vec3(0.0f, 0.0f, -9.8f);
  Cape cape(f.fabric, s, Pose());
  ASSERT_TRUE(cape.ok()) << cape.status().message();
  for (std::uint32_t i = 0; i < 6; ++i) cape.pin(i, test::row(cape.state().positions, i));
  for (int frame = 0; frame < 120; ++frame) cape.step(1.0f / 60.0f, ColliderSpan());
  EXPECT_TRUE(cape.state().positions.allFinite());
  const float tipDrop = -cape.state().positions.col(2).minCoeff();
  // Stiffer bending droops the strip less.
  s.bendingRigidity = 1e-6f;
  Cape stiff(f.fabric, s, Pose());
  ASSERT_TRUE(stiff.ok()) << stiff.status().message();
  for (std::uint32_t i = 0; i < 6; ++i) stiff.pin(i, test::row(stiff.state().positions, i));
  for (int frame = 0; frame < 120; ++frame) stiff.step(1.0f / 60.0f, ColliderSpan());
  EXPECT_TRUE(stiff.state().positions.allFinite());
  EXPECT_LT(-stiff.state().positions.col(2).minCoeff(), tipDrop);
  // A rigidity the substep cannot carry is refused, naming the stability bound.
  s.bendingRigidity = 1.0f;
  Cape unstable(f.fabric, s, Pose());
  EXPECT_FALSE(unstable.ok());
  EXPECT_NE(unstable.status().message().find("unstable"), std::string::npos) << unstable.status().message();
}

TEST(LinearBending, BadRigidityIsRefused) {
  CapeSettings s;
  for (float b : {-1e-6f, std::nanf(""), std::numeric_limits<float>::infinity()}) {
    s.bendingRigidity = b;
    const Status st = s.validate();
    EXPECT_FALSE(st.ok()) << b;
    EXPECT_NE(st.message().find("bendingRigidity"), std::string::npos) << st.message();
  }
}

}  // namespace
}  // namespace cape
