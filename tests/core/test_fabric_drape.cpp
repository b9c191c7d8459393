// Cusick's drape test (cape/scenes/Textile.h: BS 5058, ISO 9073-9) on the fabric presets, and the pieces it
// measures with: the specimen mesh, the shadow's area, the fold count.
#include "cape/scenes/Textile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

namespace cape {
namespace {

constexpr float kPi = 3.14159265358979f;

TEST(DrapeSpecimen, IsAnEquilateralMeshOfTheSpecimensCircleFacingUp) {
  DrapeSpec spec;
  spec.spacing = 0.01f;
  const FabricMaterial& wool = *findFabric("wool");
  const MeshDesc mesh = drapeSpecimen(wool, spec);
  ASSERT_GT(mesh.positions.size(), 700u);
  for (const Vec3& p : mesh.positions) {
    EXPECT_LE(std::hypot(p.x(), p.z()), 0.15f + 1e-6f);
    EXPECT_EQ(p.y(), 0.0f);
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    const Vec3& a = mesh.positions[mesh.triangles[t]];
    const Vec3& b = mesh.positions[mesh.triangles[t + 1]];
    const Vec3& c = mesh.positions[mesh.triangles[t + 2]];
    for (float edge : {(b - a).norm(), (c - b).norm(), (a - c).norm()}) EXPECT_NEAR(edge, 0.01f, 1e-5f);
    EXPECT_GT((b - a).cross(c - a).y(), 0.0f) << "triangle " << t / 3 << " faces down";
  }
  // The lattice inside the circle covers most of it (its rim is jagged by up to a spacing); the mass is the
  // material's over the mesh's own area.
  float area = 0.0f;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    const Vec3& a = mesh.positions[mesh.triangles[t]];
    area +=
        0.5f *
        (mesh.positions[mesh.triangles[t + 1]] - a).cross(mesh.positions[mesh.triangles[t + 2]] - a).norm();
  }
  EXPECT_GT(area, 0.92f * kPi * 0.15f * 0.15f);
  EXPECT_NEAR(mesh.totalMass, wool.arealDensity * area, 0.01f * mesh.totalMass);
  // Every interior vertex of the lattice bends along its three lines.
  MeshDesc copy = mesh;
  FabricResult fabric = Fabric::fromMesh(copy);
  ASSERT_TRUE(fabric.status.ok()) << fabric.status.message();
  std::map<std::uint32_t, int> perVertex;
  for (std::uint32_t j : fabric.fabric->hinges().middle) ++perVertex[j];
  int three = 0;
  for (const auto& [vertex, count] : perVertex) {
    EXPECT_LE(count, 3);
    three += count == 3;
  }
  EXPECT_GT(three, static_cast<int>(0.8 * static_cast<double>(mesh.positions.size())));
}

TEST(DrapeSpecimen, BadSpecsGiveNoMeshAndAClearError) {
  const FabricMaterial& silk = *findFabric("silk");
  for (float spacing : {0.0f, -0.01f, std::nanf(""), 1e-6f}) {
    DrapeSpec spec;
    spec.spacing = spacing;
    EXPECT_TRUE(drapeSpecimen(silk, spec).positions.empty()) << spacing;
    const DrapeResult r = runDrape(silk, spec);
    EXPECT_FALSE(r.status.ok()) << spacing;
  }
  DrapeSpec disc;
  disc.discDiameter = 0.4f;  // larger than the specimen
  EXPECT_NE(runDrape(silk, disc).status.message().find("disc"), std::string::npos);
  FabricMaterial bad = silk;
  bad.arealDensity = -1.0f;
  EXPECT_FALSE(runDrape(bad).status.ok());
  CantileverSpec strip;
  strip.segments = 0;
  EXPECT_FALSE(runCantilever(silk, strip).status.ok());
  EXPECT_FALSE(runCantilever(bad).status.ok());
}

TEST(DrapeMeasures, TheShadowOfASquareAndOfAFoldedSheet) {
  // A 0.1 m square of two triangles in the x-z plane, then the same folded over itself along x = 0.05: the
  // shadow counts the overlap once.
  Points flat(4, 3);
  flat << 0, 0, 0, 0.1f, 0, 0, 0.1f, 0, 0.1f, 0, 0, 0.1f;
  const std::vector<std::uint32_t> tri = {0, 1, 2, 0, 2, 3};
  EXPECT_NEAR(shadowArea(flat, tri, 5e-4f), 0.01f, 2e-4f);
  Points tilted = flat;
  tilted(1, 1) = tilted(2, 1) = 0.1f;  // lifted at one side: its shadow is the same
  EXPECT_NEAR(shadowArea(tilted, tri, 5e-4f), 0.01f, 2e-4f);
  Points stacked(6, 3);
  stacked << 0, 0, 0, 0.1f, 0, 0, 0.1f, 0, 0.1f, 0, 0, 0.1f, 0.05f, 0.01f, 0, 0.05f, 0.01f, 0.1f;
  const std::vector<std::uint32_t> two = {0, 1, 2, 0, 2, 3, 4, 1, 2, 4, 2, 5};
  EXPECT_NEAR(shadowArea(stacked, two, 5e-4f), 0.01f, 2e-4f);
  EXPECT_EQ(shadowArea(Points(), tri), 0.0f);
}

TEST(DrapeMeasures, FoldsAreTheLobesOfTheOutline) {
  for (int k : {3, 4, 5, 6, 7, 8, 9, 12}) {
    Points ring(720, 3);
    for (int i = 0; i < 720; ++i) {
      const float phi = 2.0f * kPi * static_cast<float>(i) / 720.0f + 0.3f;
      const float r = 0.13f + 0.01f * std::cos(static_cast<float>(k) * phi);
      ring.row(i) << r * std::cos(phi), -0.03f, r * std::sin(phi);
    }
    EXPECT_EQ(countFolds(ring), k) << k;
  }
  Points round(360, 3);
  for (int i = 0; i < 360; ++i) {
    const float phi = 2.0f * kPi * static_cast<float>(i) / 360.0f;
    round.row(i) << 0.15f * std::cos(phi), 0.0f, 0.15f * std::sin(phi);
  }
  EXPECT_EQ(countFolds(round), 0);
}

// The test itself, for every preset at two resolutions (1 cm and 7.5 mm). Leather is the one preset whose
// drape was published (47-70 %, Memon et al. 2021); the cloths' are reported, and Cusick (1968) found the
// coefficient to rise with the bending length, so the order is checked against it: silk (c 1.44 cm) below
// the three cloths (1.71-1.77 cm, within 0.06 of each other), leather (1.96 cm) above them.
TEST(FabricDrape, EveryPresetDrapesInFoldsInTheOrderOfItsBendingLength) {
  std::map<std::string, float> coefficient[2];
  for (int k = 0; k < 2; ++k) {
    DrapeSpec spec;
    spec.spacing = k == 0 ? 0.01f : 0.0075f;
    for (const FabricMaterial& m : fabricPresets()) {
      const DrapeResult r = runDrape(m, spec);
      ASSERT_TRUE(r.status.ok()) << r.status.message();
      std::printf("drape %-8s c %.2f cm  h %.1f mm  DC %.3f  folds %d  S %.1f cm2  Sf %.1f cm2  v %.4f m/s\n",
                  m.name.c_str(), 100 * m.bendingLength(), 1000 * spec.spacing, r.coefficient, r.folds,
                  1e4 * r.shadowArea, 1e4 * r.specimenArea, r.maxSpeed);
      ::testing::Test::RecordProperty("drape_" + m.name + "_" + std::to_string(k),
                                      std::to_string(r.coefficient));
      EXPECT_LT(r.maxSpeed, 0.01f) << m.name << ": not settled";
      EXPECT_GT(r.coefficient, 0.2f) << m.name;
      EXPECT_LT(r.coefficient, 0.8f) << m.name;
      EXPECT_GE(r.folds, 4) << m.name;
      EXPECT_LE(r.folds, 10) << m.name;
      EXPECT_GT(r.positions.col(1).minCoeff(), -0.07f) << m.name << " hangs below its free length";
      coefficient[k][m.name] = r.coefficient;
    }
    const auto& dc = coefficient[k];
    const float clothsLow = std::min({dc.at("cotton"), dc.at("wool"), dc.at("denim")});
    const float clothsHigh = std::max({dc.at("cotton"), dc.at("wool"), dc.at("denim")});
    EXPECT_LT(dc.at("silk"), clothsLow);
    EXPECT_LT(clothsHigh - clothsLow, 0.06f);
    EXPECT_GT(dc.at("leather"), clothsHigh);
    EXPECT_GE(dc.at("leather"), 0.47f - 0.05f);
    EXPECT_LE(dc.at("leather"), 0.70f + 0.05f);
  }
  for (const FabricMaterial& m : fabricPresets())
    EXPECT_LT(std::abs(coefficient[0][m.name] - coefficient[1][m.name]), 0.05f)
        << m.name << " at two resolutions";
}

}  // namespace
}  // namespace cape
