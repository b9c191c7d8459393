// Per-particle mass and stiffness scales (Cape::setMassScale, setStiffnessScale): the weight maps for mass
// and stiffness that issue 17 asks for beside the motion constraints' ones.
#include "cape/core/Cape.h"
#include "cape/core/WeightMap.h"

#include "CapeTestFixture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace cape {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A 12 x 12 canonical-size cape hanging from its two top corners under gravity.
struct Hang {
  FabricPtr fabric = test::makeGrid(12, 12, 0.6f, 1.0f, 0.4f, true, {0, 11});
  CapeSettings settings;
  Hang() {
    settings = test::quietSettings();
    settings.gravity = Vec3(0.0f, -9.8f, 0.0f);
    settings.damping = 2.0f;
    settings.substeps = 3;
    settings.useTethers = false;  // the springs alone hold the weight: their scale shows
    settings.structuralStiffness = 300.0f;
    settings.shearStiffness = 30.0f;
    settings.bendStiffness = 1.0f;
    settings.bendingRigidity = 1e-5f;
  }
  Cape make() const {
    Cape cape(fabric, settings, Pose());
    EXPECT_TRUE(cape.ok()) << cape.status().message();
    cape.pin(0, test::row(cape.state().positions, 0));
    cape.pin(11, test::row(cape.state().positions, 11));
    return cape;
  }
};

void run(Cape& cape, int frames) {
  for (int f = 0; f < frames; ++f) cape.step(1.0f / 60.0f, ColliderSpan());
}

// Mean stretch of the structural springs whose ends both lie in rows [r0, r1).
float meanStretch(const Cape& cape, int r0, int r1) {
  const SpringSet& set = cape.fabric().springs(SpringFamily::Structural);
  double sum = 0.0;
  int n = 0;
  for (std::size_t s = 0; s < set.size(); ++s) {
    const int a = static_cast<int>(set.first[s]) / 12, b = static_cast<int>(set.second[s]) / 12;
    if (a < r0 || a >= r1 || b < r0 || b >= r1) continue;
    const float len =
        (cape.state().positions.row(set.first[s]) - cape.state().positions.row(set.second[s])).norm();
    sum += len / set.restLength[s] - 1.0f;
    ++n;
  }
  return static_cast<float>(sum / n);
}

bool sameBits(const Points& a, const Points& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(float) * static_cast<std::size_t>(a.size())) == 0;
}

TEST(WeightScales, AScaleOfOneChangesNoBitAndEmptyRestoresTheFabric) {
  Hang h;
  Cape plain = h.make(), ones = h.make();
  ASSERT_TRUE(ones.setStiffnessScale(Eigen::VectorXf::Ones(144)).ok());
  ASSERT_TRUE(ones.setMassScale(Eigen::VectorXf::Ones(144)).ok());
  run(plain, 60);
  run(ones, 60);
  EXPECT_TRUE(sameBits(plain.state().positions, ones.state().positions));
  Cape cleared = h.make();
  ASSERT_TRUE(cleared.setMassScale(Eigen::VectorXf::Constant(144, 3.0f)).ok());
  ASSERT_TRUE(cleared.setMassScale(Eigen::VectorXf()).ok());
  ASSERT_TRUE(cleared.setStiffnessScale(Eigen::VectorXf::Constant(144, 0.1f)).ok());
  ASSERT_TRUE(cleared.setStiffnessScale(Eigen::VectorXf()).ok());
  run(cleared, 60);
  EXPECT_TRUE(sameBits(plain.state().positions, cleared.state().positions));
}

TEST(WeightScales, ASofterLowerHalfStretchesMoreThanTheSameCapeUnscaled) {
  Hang h;
  Cape plain = h.make(), soft = h.make();
  Eigen::VectorXf scale = Eigen::VectorXf::Ones(144);
  for (int i = 6 * 12; i < 144; ++i) scale[i] = 0.2f;  // rows 6..11
  ASSERT_TRUE(soft.setStiffnessScale(scale).ok());
  EXPECT_EQ(soft.stiffnessScale().size(), 144);
  run(plain, 180);
  run(soft, 180);
  const float plainLow = meanStretch(plain, 6, 12), softLow = meanStretch(soft, 6, 12);
  const float plainTop = meanStretch(plain, 0, 6), softTop = meanStretch(soft, 0, 6);
  EXPECT_GT(softLow, 2.0f * plainLow) << plainLow << " " << softLow;
  EXPECT_NEAR(softTop, plainTop, 0.5f * plainTop);  // the top half keeps its stiffness
}

TEST(WeightScales, AHeavierHemWeighsOnTheSpringsAndCountsInTheEnergy) {
  Hang h;
  Cape plain = h.make(), heavy = h.make();
  Eigen::VectorXf scale = Eigen::VectorXf::Ones(144);
  for (int i = 11 * 12; i < 144; ++i) scale[i] = 10.0f;  // the bottom row ten times heavier
  ASSERT_TRUE(heavy.setMassScale(scale).ok());
  // Free particles weigh m s; the pins stay pinned; a released pin gets its scaled mass back.
  const float m = h.fabric->masses()[140];
  EXPECT_FLOAT_EQ(heavy.state().inverseMasses[140], 1.0f / (10.0f * m));
  EXPECT_EQ(heavy.state().inverseMasses[0], 0.0f);
  run(plain, 180);
  run(heavy, 180);
  EXPECT_GT(meanStretch(heavy, 0, 12), 1.5f * meanStretch(plain, 0, 12));
  // Kinetic energy of a uniform velocity counts the scaled masses.
  Cape moving = h.make();
  ASSERT_TRUE(moving.setMassScale(scale).ok());
  moving.mutableState().velocities.col(0).setConstant(1.0f);
  CapeSettings still = moving.settings();
  still.gravity = Vec3::Zero();
  ASSERT_TRUE(moving.setSettings(still).ok());
  const double totalMass = (h.fabric->masses().cast<double>().array() * scale.cast<double>().array()).sum();
  EXPECT_NEAR(moving.energy(), 0.5 * totalMass, 1e-3 * totalMass);
  Eigen::VectorXf pinScale = Eigen::VectorXf::Ones(144);
  pinScale[0] = 4.0f;
  ASSERT_TRUE(moving.setMassScale(pinScale).ok());
  EXPECT_EQ(moving.state().inverseMasses[0], 0.0f);
  moving.unpin(0);
  EXPECT_FLOAT_EQ(moving.state().inverseMasses[0], 1.0f / (4.0f * h.fabric->masses()[0]));
}

TEST(WeightScales, AScalePaintedFromAnImageOverTheUvs) {
  Hang h;
  Cape cape = h.make();
  GrayImage image;  // black at the top, white at the bottom
  image.width = 1;
  image.height = 2;
  image.pixels = {0.0f, 1.0f};
  const WeightMapResult map = weightMapFromImage(*h.fabric, image, 1.0f, 0.25f);
  ASSERT_TRUE(map) << map.status.message();
  ASSERT_TRUE(cape.setStiffnessScale(map.values).ok());
  EXPECT_FLOAT_EQ(cape.stiffnessScale()[0], 1.0f);
  EXPECT_FLOAT_EQ(cape.stiffnessScale()[143], 0.25f);
  run(cape, 30);
  EXPECT_TRUE(cape.state().positions.allFinite());
}

TEST(WeightScales, BadScalesAreRefusedAndTheOldOnesKept) {
  Hang h;
  Cape cape = h.make();
  Eigen::VectorXf good = Eigen::VectorXf::Constant(144, 2.0f);
  ASSERT_TRUE(cape.setStiffnessScale(good).ok());
  ASSERT_TRUE(cape.setMassScale(good).ok());
  for (float bad : {0.0f, -1.0f, kNaN, std::numeric_limits<float>::infinity(), 2e6f}) {
    Eigen::VectorXf v = good;
    v[17] = bad;
    const Status s = cape.setStiffnessScale(v);
    EXPECT_FALSE(s.ok()) << bad;
    EXPECT_NE(s.message().find("setStiffnessScale"), std::string::npos) << s.message();
    EXPECT_FALSE(cape.setMassScale(v).ok()) << bad;
  }
  EXPECT_FALSE(cape.setMassScale(Eigen::VectorXf::Ones(10)).ok());
  EXPECT_NE(cape.setStiffnessScale(Eigen::VectorXf::Ones(145)).message().find("145 values for 144"),
            std::string::npos);
  EXPECT_EQ(cape.stiffnessScale(), good);
  EXPECT_EQ(cape.massScale(), good);
}

TEST(WeightScales, TheExplicitIntegratorRefusesAScaleItCannotCarry) {
  Hang h;
  h.settings = CapeSettings::unitySeed();
  Cape cape(h.fabric, h.settings, Pose());
  ASSERT_TRUE(cape.ok()) << cape.status().message();
  const Status light = cape.setMassScale(Eigen::VectorXf::Constant(144, 1e-4f));
  EXPECT_FALSE(light.ok());
  EXPECT_NE(light.message().find("unstable"), std::string::npos) << light.message();
  EXPECT_FALSE(cape.setStiffnessScale(Eigen::VectorXf::Constant(144, 1e5f)).ok());
  EXPECT_TRUE(cape.setMassScale(Eigen::VectorXf::Constant(144, 2.0f)).ok());  // heavier is more stable
  EXPECT_EQ(cape.massScale().size(), 144);
}

}  // namespace
}  // namespace cape
