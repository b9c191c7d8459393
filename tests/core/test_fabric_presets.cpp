// Fabric presets: the published figures and their units, the mapping onto per-spring stiffness, bad input.
#include "cape/core/FabricPresets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

TEST(FabricPresets, BendStiffnessScalesAsTheInverseFourthPowerOfTheSpacing) {
  const FabricMaterial& wool = *findFabric("wool");
  const float k1 = fabricBendStiffness(wool, 0.01f);
  const float k2 = fabricBendStiffness(wool, 0.02f);
  EXPECT_NEAR(k1 / k2, 16.0f, 1e-3f);
  // Equal moments at the curvature 1/c: the hinge angle there is h / c, the spring's moment k h^2 theta^3 / 8
  // and the strip's B theta.
  const float h = 0.01f, c = wool.bendingLength(), theta = h / c;
  EXPECT_NEAR(k1 * h * h * theta * theta * theta / 8.0f, wool.bendingRigidity * theta,
              1e-5f * wool.bendingRigidity * theta);
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
  EXPECT_EQ(s.bendStiffness, fabricBendStiffness(cotton, 0.03f));
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
  for (float h : {0.0f, -0.01f, kNaN, kInf, 1e-12f}) {
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

}  // namespace
}  // namespace cape
