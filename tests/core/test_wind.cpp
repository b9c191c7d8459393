// Wind: the aerodynamic kernel against its formula, terminal speed and the deflection angle against force
// balances, the gust field's determinism, and the seed's sine-wave mode.
#include "CapeTestFixture.h"

#include "cape/core/Wind.h"
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <cmath>

namespace cape {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kRho = 1.2f;

/// The canonical cape's grid as a mesh fabric: masses by area, so mass per area is uniform to the edges (a
/// grid spreads mass evenly over particles, giving edge particles twice their area's share).
FabricPtr uniformSheet(int n, float width, float height, float mass,
                       std::vector<std::uint32_t> anchors = {}) {
  FabricPtr grid = test::makeGrid(n, n, width, height, mass, false);
  MeshDesc d;
  for (Eigen::Index i = 0; i < grid->restPositions().rows(); ++i)
    d.positions.push_back(test::row(grid->restPositions(), i));
  d.triangles = grid->triangles();
  d.totalMass = mass;
  d.bendSprings = true;
  d.tetherAnchors = std::move(anchors);
  FabricResult r = Fabric::fromMesh(d);
  EXPECT_TRUE(r) << r.status.message();
  return r.fabric;
}

WindSettings aero(float speed, const Vec3& direction, float cl = 0.0f) {
  WindSettings w;
  w.model = WindSettings::Model::Aerodynamic;
  w.speed = speed;
  w.direction = direction;
  w.gustAmplitude = 0.0f;
  w.airDensity = kRho;
  w.dragCoefficient = 1.0f;
  w.liftCoefficient = cl;
  return w;
}

TEST(Wind, AerodynamicKernel) {
  const float q = 0.5f * kRho, area = 0.3f, u = 4.0f;
  // Broadside: pure drag along the flow, q Cd A U^2, whichever way the normal points.
  for (float side : {1.0f, -1.0f}) {
    const Vec3 f = aerodynamicForce(Vec3(0, 0, u), side * area * Vec3::UnitZ(), kRho, 1.2f, 0.3f);
    EXPECT_LT((f - Vec3(0, 0, q * 1.2f * area * u * u)).norm(), 1e-5f) << f.transpose();
  }
  // Edge-on: nothing.
  EXPECT_LT(aerodynamicForce(Vec3(u, 0, 0), area * Vec3::UnitZ(), kRho, 1.0f, 0.5f).norm(), 1e-7f);
  // At 30 degrees of attack: drag q Cd A U^2 sin a along n, lift q Cl A U^2 cos a sin a across the flow.
  const float a = kPi / 6.0f;
  const Vec3 flow = u * Vec3(std::cos(a), 0.0f, std::sin(a));  // 30 degrees above the plate z = 0
  const Vec3 liftOnly = aerodynamicForce(flow, area * Vec3::UnitZ(), kRho, 0.0f, 1.0f);
  EXPECT_NEAR(liftOnly.dot(flow), 0.0f, 1e-5f);
  EXPECT_NEAR(liftOnly.norm(), q * area * u * u * std::cos(a) * std::sin(a), 1e-5f);
  const Vec3 dragOnly = aerodynamicForce(flow, area * Vec3::UnitZ(), kRho, 1.0f, 0.0f);
  EXPECT_LT((dragOnly - Vec3(0, 0, q * area * u * u * std::sin(a))).norm(), 1e-5f);
  // Still air, or a degenerate triangle: nothing, and no NaN.
  EXPECT_EQ(aerodynamicForce(Vec3::Zero(), Vec3::UnitZ(), kRho, 1, 1), Vec3::Zero());
  EXPECT_EQ(aerodynamicForce(Vec3::UnitX(), Vec3::Zero(), kRho, 1, 1), Vec3::Zero());
}

// A horizontal cape falling through still air reaches v_t = sqrt(m g / (q Cd A)).
TEST(Wind, HorizontalCapeReachesTheTerminalSpeedDragPredicts) {
  const float mass = 0.4f, width = 0.6f, height = 1.0f, g = 9.8f;
  FabricPtr f = uniformSheet(12, width, height, mass);
  CapeSettings s;
  s.damping = 0.0f;  // only the air slows it
  s.useTethers = false;
  s.wind = aero(0.0f, Vec3::UnitX());
  Cape cape(f, s, Pose{Vec3::Zero(), Quat(Eigen::AngleAxisf(-kPi / 2.0f, Vec3::UnitX()))});
  ASSERT_TRUE(cape.ok()) << cape.status().message();
  for (int i = 0; i < 4 * 60; ++i) cape.step(1.0f / 60.0f, {});  // 12 time constants v_t / g
  const float predicted = std::sqrt(mass * g / (0.5f * kRho * 1.0f * width * height));
  const float measured = -cape.state().velocities.col(1).mean();
  EXPECT_NEAR(measured, predicted, 0.05f * predicted) << "predicted " << predicted << " m/s";
  // It fell flat: no sideways drift to speak of.
  EXPECT_LT(cape.state().velocities.col(0).cwiseAbs().maxCoeff() +
                cape.state().velocities.col(2).cwiseAbs().maxCoeff(),
            0.05f * predicted);
}

// A cape pinned along its top edge in a steady horizontal wind U: a straight sheet at angle theta from the
// vertical is in equilibrium when the normal pressure q Cd U^2 cos(theta) balances the normal part of its
// weight per area, sigma g sin(theta): tan(theta) = q Cd U^2 / (sigma g).
TEST(Wind, SteadyWindDeflectsAHangingCapeByTheForceBalanceAngle) {
  const int n = 16;
  const float mass = 0.4f, width = 0.6f, height = 1.0f, g = 9.8f, u = 3.0f;
  std::vector<std::uint32_t> top;
  for (int c = 0; c < n; ++c) top.push_back(static_cast<std::uint32_t>(c));
  FabricPtr f = uniformSheet(n, width, height, mass, top);
  CapeSettings s;
  s.wind = aero(u, Vec3::UnitZ());  // across the cape, which hangs in the plane z = 0
  Cape cape(f, s);
  ASSERT_TRUE(cape.ok());
  for (std::uint32_t p : top) cape.pin(p, test::row(cape.state().positions, p));
  for (int i = 0; i < 6 * 60; ++i) cape.step(1.0f / 60.0f, {});
  const float sigma = mass / (width * height);
  const float predicted = std::atan(0.5f * kRho * u * u / (sigma * g));
  // The middle column, from the pinned top to the hem.
  const Points& x = cape.state().positions;
  const Eigen::Index topMid = n / 2, hemMid = (n - 1) * n + n / 2;
  const Vec3 d = test::row(x, hemMid) - test::row(x, topMid);
  const float measured = std::atan2(d.z(), -d.y());
  EXPECT_NEAR(measured, predicted, 0.10f * predicted)
      << "predicted " << predicted * 180 / kPi << " deg, measured " << measured * 180 / kPi;
  // Straight, as the balance says: the middle particle lies on the line from top to hem.
  const Vec3 mid = test::row(x, (n / 2) * n + n / 2) - test::row(x, topMid);
  EXPECT_LT(mid.cross(d.normalized()).norm(), 0.02f);
  // Lift, with the flow meeting the sheet from below, raises it further.
  s.wind = aero(u, Vec3::UnitZ(), 0.5f);
  Cape lifted(f, s);
  for (std::uint32_t p : top) lifted.pin(p, test::row(lifted.state().positions, p));
  for (int i = 0; i < 6 * 60; ++i) lifted.step(1.0f / 60.0f, {});
  const Vec3 dl = test::row(lifted.state().positions, hemMid) - test::row(lifted.state().positions, topMid);
  EXPECT_GT(std::atan2(dl.z(), -dl.y()), measured + 0.02f);
}

TEST(Wind, GustsAreDeterministicPerSeedAndBounded) {
  WindSettings w = aero(8.0f, Vec3::UnitX());
  w.gustAmplitude = 0.5f;
  w.gustFrequency = 0.5f;
  w.turbulenceScale = 2.0f;
  WindSettings other = w;
  other.seed = 2;
  double mean = 0.0;
  float lo = 1e9f, hi = -1e9f;
  bool differs = false, variesInSpace = false;
  const int samples = 2000;
  for (int k = 0; k < samples; ++k) {
    const double t = 0.05 * k;
    const Vec3 p(0.3f * static_cast<float>(k % 7), 1.0f, -0.2f * static_cast<float>(k % 5));
    const Vec3 a = windVelocity(w, p, t);
    const Vec3 b = windVelocity(w, p, t);
    ASSERT_EQ(a, b);
    ASSERT_TRUE(a.allFinite());
    differs |= windVelocity(other, p, t) != a;
    variesInSpace |= (windVelocity(w, p + Vec3(0.5f, 0, 0), t) - a).norm() > 0.1f;
    mean += a.x() / samples;
    lo = std::min(lo, a.x());
    hi = std::max(hi, a.x());
  }
  EXPECT_TRUE(differs) << "another seed gives other gusts";
  EXPECT_TRUE(variesInSpace) << "turbulence varies over space";
  EXPECT_NEAR(mean, 8.0, 0.8);  // the mean wind
  EXPECT_GE(lo, 8.0f * 0.5f - 1e-3f);
  EXPECT_LE(hi, 8.0f * 1.5f + 1e-3f);
  EXPECT_GT(hi - lo, 8.0f * 0.5f) << "gusts of +-50 % actually happen";
  // The batch and the single-point forms agree bit for bit.
  Points pts(3, 3), out(3, 3);
  pts << 0, 1, 0, 0.5f, 1.2f, -3, 10, 0, 2;
  windVelocities(w, pts, 7.25, out);
  for (Eigen::Index i = 0; i < 3; ++i) EXPECT_EQ(test::row(out, i), windVelocity(w, test::row(pts, i), 7.25));
}

TEST(Wind, SeedSineWaveWindPushesEachParticlesAreaShare) {
  // Steady (no sine) for a closed form: the cape at rest gains momentum q Cd A U^2 dt along the wind.
  FabricPtr f = test::makeGrid(10, 10, 0.6f, 1.0f, 0.4f, true);
  CapeSettings s = test::quietSettings();
  s.wind.model = WindSettings::Model::SineWave;
  s.wind.speed = 5.0f;
  s.wind.direction = Vec3(0, 0, 2);
  s.wind.gustAmplitude = 0.0f;
  Cape cape(f, s);
  const float dt = 1e-3f;
  cape.step(dt, {});
  const Eigen::VectorXf& m = f->masses();
  Vec3 momentum = Vec3::Zero();
  for (Eigen::Index i = 0; i < m.size(); ++i) momentum += m[i] * test::row(cape.state().velocities, i);
  const float expected = 0.5f * 1.2f * 1.0f * 0.6f * 1.0f * 25.0f * dt;
  EXPECT_NEAR(momentum.z(), expected, 1e-3f * expected);
  EXPECT_NEAR(momentum.x(), 0.0f, 1e-6f);
  // The sine: at a quarter period the wind is (1 + a) U, at three quarters (1 - a) U.
  s.wind.gustAmplitude = 0.5f;
  s.wind.gustFrequency = 1.0f;
  EXPECT_NEAR(windVelocity(s.wind, Vec3::Zero(), 0.25).z(), 7.5f, 1e-5f);
  EXPECT_NEAR(windVelocity(s.wind, Vec3(4, 5, 6), 0.75).z(), 2.5f, 1e-5f);
}

TEST(Wind, WindSceneBlowsTheCapeDownwindWithoutPenetration) {
  SimpleScene scene(SceneKind::Wind, 20, PinLayout::Corners, CapeSettings());
  ASSERT_TRUE(scene.status().ok());
  EXPECT_EQ(scene.cape().settings().wind.model, WindSettings::Model::Aerodynamic);
  MetricsRecorder rec;
  for (int i = 0; i < 3 * 60; ++i) {
    scene.advanceFrame();
    rec.add(measureFrame(scene.cape(), scene.body().bodyColliders(), scene.body().torsoCentre(), nullptr));
  }
  const RunSummary sum = rec.summary();
  EXPECT_FALSE(sum.blowUp);
  EXPECT_EQ(sum.framesPenetrationOver1mm, 0);
  EXPECT_GT(scene.cape().state().positions.col(0).mean(), 0.1f) << "blown towards +X";
}

}  // namespace
}  // namespace cape
