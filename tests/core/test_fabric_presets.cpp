// Fabric presets: the published figures and their units, the mapping onto per-spring stiffness, bad input.
#include "cape/core/FabricPresets.h"
#include "cape/scenes/Textile.h"

#include "CapeTestFixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace cape {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

TEST(FabricPresets, EveryIssueFabricIsThereAndValid) {
  for (const char* name : {"silk", "cotton", "wool", "denim", "leather"}) {
    const FabricMaterial* m = findFabric(name);
    ASSERT_NE(m, nullptr) << name;
    EXPECT_EQ(m->name, name);
    EXPECT_TRUE(m->validate().ok()) << m->validate().message();
    EXPECT_FALSE(m->source.empty()) << name;
    EXPECT_TRUE(checkFabric(*m, 0.03f).ok()) << name;
  }
  EXPECT_EQ(fabricPresets().size(), 5u);
  EXPECT_EQ(fabricNames(), "silk, cotton, wool, denim, leather");
}

TEST(FabricPresets, UnknownNamesAreNotFound) {
  EXPECT_EQ(findFabric(""), nullptr);
  EXPECT_EQ(findFabric("Silk"), nullptr);
  EXPECT_EQ(findFabric("velvet"), nullptr);
  EXPECT_EQ(findFabric("silk "), nullptr);
}

// The KES-F figures of FabricPresets.cpp, converted by hand: W mg/cm^2 * 0.01 = kg/m^2; B gf·cm^2/cm *
// 9.80665e-5 = N·m; G gf/cm/deg * 0.980665 * 180 / pi = N/m per radian; 490.3325 N/m / (EMT / 100) = N/m.
TEST(FabricPresets, KawabataUnitsAreConvertedToSi) {
  const FabricMaterial& silk = *findFabric("silk");
  EXPECT_NEAR(silk.arealDensity, 0.050f, 1e-6f);
  EXPECT_NEAR(silk.bendingRigidity, 0.015 * 9.80665e-5, 1e-12);
  EXPECT_NEAR(silk.shearStiffness, 0.3 * 0.980665 * 57.29578, 1e-3);
  EXPECT_NEAR(silk.stretchStiffness, 490.3325 / 0.08, 0.05);
  const FabricMaterial& denim = *findFabric("denim");
  EXPECT_NEAR(denim.arealDensity, 0.4069f, 1e-4f);  // 12 oz/yd^2
  EXPECT_NEAR(denim.bendingRigidity, 0.227 * 9.80665e-5, 1e-11);
  // Bending length (B / (rho_A g))^(1/3): silk about 1.4 cm, the cloths 1.4-1.9 cm, leather the stiffest.
  EXPECT_NEAR(silk.bendingLength(), 0.01442f, 1e-4f);
  float cloths = 0.0f;
  for (const char* name : {"silk", "cotton", "wool", "denim"})
    cloths = std::max(cloths, findFabric(name)->bendingLength());
  EXPECT_GT(findFabric("leather")->bendingLength(), cloths);
}

TEST(FabricPresets, DampingIsStillAirDragAtOneMetrePerSecond) {
  // c = rho_air Cd v / (2 rho_A): the lighter the fabric, the more the air slows it.
  for (const FabricMaterial& m : fabricPresets())
    EXPECT_NEAR(m.damping, 1.2f * m.dragCoefficient * 1.0f / (2.0f * m.arealDensity), 1e-4f) << m.name;
  EXPECT_GT(findFabric("silk")->damping, findFabric("leather")->damping);
}

TEST(FabricPresets, MembraneStiffnessIsIndependentOfTheSpacing) {
  for (const FabricMaterial& m : fabricPresets()) {
    for (float h : {0.005f, 0.0316f, 0.1f}) {
      const CapeSettings s = applyFabric(m, h);
      EXPECT_FLOAT_EQ(s.structuralStiffness, m.stretchStiffness - m.shearStiffness) << m.name;
      EXPECT_FLOAT_EQ(s.shearStiffness, m.shearStiffness) << m.name;
      EXPECT_TRUE(s.validate().ok()) << s.validate().message();
    }
  }
}

TEST(FabricPresets, BendingIsTheMaterialsRigidityAndTheBendSpringsAreOff) {
  for (const FabricMaterial& m : fabricPresets()) {
    for (float h : {0.0005f, 0.01f, 0.1f}) {
      const CapeSettings s = applyFabric(m, h);
      EXPECT_EQ(s.bendingRigidity, m.bendingRigidity) << m.name;
      EXPECT_EQ(s.bendStiffness, 0.0f) << m.name;
      EXPECT_TRUE(s.validate().ok()) << s.validate().message();
    }
  }
}

TEST(FabricPresets, ApplyFabricKeepsEverythingElseFromTheBase) {
  CapeSettings base;
  base.substeps = 7;
  base.selfCollision = true;
  base.gravity = Vec3(0.0f, -3.0f, 0.0f);
  base.wind.model = WindSettings::Model::Aerodynamic;
  base.wind.speed = 4.0f;
  const FabricMaterial& cotton = *findFabric("cotton");
  const CapeSettings s = applyFabric(cotton, 0.03f, base);
  EXPECT_EQ(s.substeps, 7);
  EXPECT_TRUE(s.selfCollision);
  EXPECT_EQ(s.gravity, base.gravity);
  EXPECT_EQ(s.wind.model, WindSettings::Model::Aerodynamic);
  EXPECT_EQ(s.wind.speed, 4.0f);
  EXPECT_EQ(s.damping, cotton.damping);
  EXPECT_EQ(s.wind.dragCoefficient, cotton.dragCoefficient);
  EXPECT_EQ(s.wind.liftCoefficient, cotton.liftCoefficient);
  EXPECT_EQ(s.bendingRigidity, cotton.bendingRigidity);
}

TEST(FabricPresets, FabricMassIsDensityTimesArea) {
  const FabricMaterial& denim = *findFabric("denim");
  EXPECT_NEAR(fabricMass(denim, 0.6f, 1.0f), 0.6f * denim.arealDensity, 1e-6f);
  EXPECT_EQ(fabricMass(denim, -1.0f, 1.0f), 0.0f);
  EXPECT_EQ(fabricMass(denim, 1.0f, kNaN), 0.0f);
  EXPECT_EQ(fabricMass(denim, kInf, 1.0f), 0.0f);
}

TEST(FabricPresets, BadInputIsRefusedWithAMessageAndLeavesTheBase) {
  const FabricMaterial& silk = *findFabric("silk");
  CapeSettings base;
  base.bendStiffness = 123.0f;
  for (float h : {0.0f, -0.01f, kNaN, kInf}) {
    const Status st = checkFabric(silk, h);
    EXPECT_FALSE(st.ok()) << h;
    EXPECT_NE(st.message().find("spacing"), std::string::npos) << st.message();
    EXPECT_EQ(applyFabric(silk, h, base).bendStiffness, 123.0f);
  }
  auto expectRefused = [&](FabricMaterial m, const char* field) {
    const Status st = m.validate();
    EXPECT_FALSE(st.ok()) << field;
    EXPECT_NE(st.message().find(field), std::string::npos) << st.message();
    EXPECT_FALSE(checkFabric(m, 0.03f).ok());
    EXPECT_EQ(applyFabric(m, 0.03f, base).bendStiffness, 123.0f) << field;
  };
  FabricMaterial m = silk;
  m.name.clear();
  expectRefused(m, "name");
  m = silk;
  m.arealDensity = 0.0f;
  expectRefused(m, "arealDensity");
  m = silk;
  m.stretchStiffness = kNaN;
  expectRefused(m, "stretchStiffness");
  m = silk;
  m.shearStiffness = -1.0f;
  expectRefused(m, "shearStiffness");
  m = silk;
  m.shearStiffness = m.stretchStiffness;
  expectRefused(m, "shearStiffness");
  m = silk;
  m.bendingRigidity = kInf;
  expectRefused(m, "bendingRigidity");
  m = silk;
  m.damping = -0.5f;
  expectRefused(m, "damping");
  m = silk;
  m.dragCoefficient = kNaN;
  expectRefused(m, "dragCoefficient");
  m = silk;
  m.liftCoefficient = kInf;
  expectRefused(m, "liftCoefficient");
}

// Peirce's cantilever (cape/scenes/Textile.h: ASTM D1388, BS 3356) for every preset at two resolutions, 8
// and 16 hinges along the standard overhang L = 2c, with the solver converged (200 substeps of 20 iterations
// per 1/60 s: the game's 3 x 1 leaves the strip drooping more; docs/SOLVER.md, "Fabric presets", has every
// figure). Issue 17 asks for Peirce's c within 10 % of (B / w)^(1/3) at both resolutions; the linear hinges
// give 0.3-1.3 %, held here to 3 %, and the two resolutions to 2 % of c of each other.
CantileverResult convergedCantilever(const FabricMaterial& m, int segments) {
  CantileverSpec spec;
  spec.segments = segments;
  const CantileverResult r = runCantilever(m, spec);
  EXPECT_TRUE(r.status.ok()) << r.status.message();
  return r;
}

void expectBendingLengthAtTwoResolutions(const char* name) {
  const FabricMaterial& m = *findFabric(name);
  const float c = m.bendingLength();
  float measured[2] = {0.0f, 0.0f};
  for (int k = 0; k < 2; ++k) {
    const int segments = k == 0 ? 8 : 16;
    const float h = 2.0f * c / static_cast<float>(segments);
    const CantileverResult r = convergedCantilever(m, segments);
    const float error = r.bendingLength / c - 1.0f;
    measured[k] = r.bendingLength;
    std::printf("cantilever %-8s c %.2f cm  %2d hinges  h %.2f mm  theta %.1f deg  c_sim %.2f cm  %+.1f %%\n",
                m.name.c_str(), 100 * c, segments, 1000 * h, r.theta * 57.29578f, 100 * r.bendingLength,
                100 * error);
    ::testing::Test::RecordProperty("bending_length_error_percent_" + std::to_string(segments),
                                    std::to_string(100 * error));
    EXPECT_LT(r.maxSpeed, 0.01f) << "the strip did not settle";
    EXPECT_LT(std::abs(error), 0.03f) << m.name << " at " << segments << " hinges";
  }
  EXPECT_LT(std::abs(measured[1] - measured[0]), 0.02f * c) << "8 and 16 hinges bend apart";
}

TEST(FabricCantilever, SilkBendsLikeSilkAtTwoResolutions) {
  expectBendingLengthAtTwoResolutions("silk");
}
TEST(FabricCantilever, CottonBendsLikeCottonAtTwoResolutions) {
  expectBendingLengthAtTwoResolutions("cotton");
}
TEST(FabricCantilever, WoolBendsLikeWoolAtTwoResolutions) {
  expectBendingLengthAtTwoResolutions("wool");
}
TEST(FabricCantilever, DenimBendsLikeDenimAtTwoResolutions) {
  expectBendingLengthAtTwoResolutions("denim");
}
TEST(FabricCantilever, LeatherBendsLikeLeatherAtTwoResolutions) {
  expectBendingLengthAtTwoResolutions("leather");
}

// The same test at the spacings of a cape (2 cm and 1 cm: an overhang of 2c is then 1-6 hinges) with the
// converged solver and with the game's (3 substeps of 1 iteration per 1/60 s), for docs/SOLVER.md. The game's
// solver leaves every strip droop more than the converged one: XPBD gives a soft spring in few iterations.
TEST(FabricCantileverReport, TheCapesSpacingsAndTheGamesSolver) {
  for (const FabricMaterial& m : fabricPresets()) {
    const float c = m.bendingLength();
    for (float h : {0.02f, 0.01f}) {
      float theta[2] = {0.0f, 0.0f};
      for (int solver : {0, 1}) {
        CantileverSpec spec;
        spec.segments = std::max(1, static_cast<int>(std::lround(2.0f * c / h)));
        spec.substeps = solver ? 200 : 3;
        spec.iterations = solver ? 20 : 1;
        spec.seconds = 1.5f;
        spec.overhang = h * static_cast<float>(spec.segments);
        const CantileverResult r = runCantilever(m, spec);
        ASSERT_TRUE(r.status.ok()) << r.status.message();
        theta[solver] = r.theta;
        std::printf(
            "cantilever %-8s h %.0f mm  L %.1f cm (%d)  %4d x %2d  theta %.1f deg  c_sim %.2f cm  %+.1f %%\n",
            m.name.c_str(), 1000 * h, 100 * spec.overhang, spec.segments, spec.substeps, spec.iterations,
            r.theta * 57.29578f, 100 * r.bendingLength, 100 * (r.bendingLength / c - 1));
      }
      if (std::lround(2.0f * c / h) >= 3) {
        EXPECT_GT(theta[0], theta[1]) << m.name << " at " << h << " m";
      }
    }
  }
}

}  // namespace
}  // namespace cape
