// Strain limiting (CapeSettings::strainCeiling): the kernel alone (a spring stretched beyond the ceiling
// comes back to it, shared by inverse mass; every other spring keeps its bits), the settings' checks, and the
// canonical sprint-turn with and without it: a lower peak stretch, the same bits at every instruction set,
// and no bit changed while it is off, whatever its passes.
#include "SpringSolver.h"

#include "cape/core/Simd.h"
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace cape {
namespace {

// Three particles on the x axis joined by two springs of rest length 1, with positions and inverse masses
// as given.
struct Chain {
  std::vector<float> x, y, z, w;
  SpringSet springs;
  Chain(std::vector<float> xs, std::vector<float> ws) : x(std::move(xs)), w(std::move(ws)) {
    y.assign(x.size(), 0.0f);
    z.assign(x.size(), 0.0f);
    for (std::uint32_t i = 0; i + 1 < x.size(); ++i) {
      springs.first.push_back(i);
      springs.second.push_back(i + 1);
      springs.restLength.push_back(1.0f);
    }
    // One run read one spring at a time (a fabric's build cuts its sets into vector runs; the kernel's
    // vector path has its own test in test_spring_solver.cpp).
    springs.runs.push_back({0, static_cast<std::uint32_t>(springs.size()), SpringLayout::Scalar});
  }
  void limit(float ceiling) {
    detail::limitStretch(x.data(), y.data(), z.data(), w.data(), springs, 1.0f + ceiling);
  }
  float length(std::size_t s) const {
    const std::uint32_t i = springs.first[s], j = springs.second[s];
    return std::sqrt((x[j] - x[i]) * (x[j] - x[i]) + (y[j] - y[i]) * (y[j] - y[i]) +
                     (z[j] - z[i]) * (z[j] - z[i]));
  }
};

bool sameBits(float a, float b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

TEST(StrainCeiling, AStretchedSpringComesBackToTheCeilingSharedByInverseMass) {
  // Equal masses: both ends move, the middle stays.
  Chain equal({0.0f, 2.0f}, {1.0f, 1.0f});
  equal.limit(0.1f);
  EXPECT_NEAR(equal.length(0), 1.1f, 1e-6f);
  EXPECT_NEAR(0.5f * (equal.x[0] + equal.x[1]), 1.0f, 1e-6f);
  // Inverse masses 1 : 3: the lighter end moves three times as far (0.9 in all: 0.225 and 0.675).
  Chain uneven({0.0f, 2.0f}, {1.0f, 3.0f});
  uneven.limit(0.1f);
  EXPECT_NEAR(uneven.x[0], 0.225f, 1e-6f);
  EXPECT_NEAR(uneven.x[1], 1.325f, 1e-6f);
  // A pinned end does not move; the free one goes the whole way, along the spring (off the axis too).
  Chain pinned({0.0f, 3.0f}, {0.0f, 1.0f});
  pinned.y[1] = 4.0f;  // length 5, direction (0.6, 0.8)
  pinned.limit(0.2f);
  EXPECT_EQ(pinned.x[0], 0.0f);
  EXPECT_EQ(pinned.y[0], 0.0f);
  EXPECT_NEAR(pinned.x[1], 0.72f, 1e-6f);
  EXPECT_NEAR(pinned.y[1], 0.96f, 1e-6f);
}

TEST(StrainCeiling, SpringsAtOrUnderTheCeilingPinnedOrNotFiniteKeepTheirBits) {
  // Compressed, slack, just under the ceiling, both ends pinned, and a NaN end: nothing moves, and the NaN
  // goes nowhere.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<std::vector<float>> cases = {
      {0.0f, 0.5f, 1.0f}, {0.0f, 1.0f, 2.0f}, {0.0f, 1.099f, 2.19f}};
  for (const std::vector<float>& xs : cases) {
    Chain c(xs, {1.0f, 1.0f, 1.0f});
    c.limit(0.1f);
    for (std::size_t i = 0; i < xs.size(); ++i) EXPECT_TRUE(sameBits(c.x[i], xs[i])) << i;
  }
  Chain held({0.0f, 5.0f}, {0.0f, 0.0f});
  held.limit(0.1f);
  EXPECT_EQ(held.x[1], 5.0f);
  Chain broken({0.0f, nan, 7.0f}, {1.0f, 1.0f, 1.0f});
  broken.limit(0.1f);
  EXPECT_EQ(broken.x[0], 0.0f);
  EXPECT_TRUE(std::isnan(broken.x[1]));
  EXPECT_EQ(broken.x[2], 7.0f);
}

TEST(StrainCeiling, OnePassIsGaussSeidelInTheSetsOrderAndMorePassesConverge) {
  // Two springs, each stretched to 2: the first is brought to 1.1, which stretches the second further;
  // the second then comes to 1.1 and leaves the first beyond it again. More passes bring both to it.
  Chain once({0.0f, 2.0f, 4.0f}, {1.0f, 1.0f, 1.0f});
  once.limit(0.1f);
  EXPECT_GT(once.length(0), 1.1f + 1e-3f);
  EXPECT_NEAR(once.length(1), 1.1f, 1e-6f);
  Chain many({0.0f, 2.0f, 4.0f}, {1.0f, 1.0f, 1.0f});
  for (int pass = 0; pass < 40; ++pass) many.limit(0.1f);
  EXPECT_NEAR(many.length(0), 1.1f, 1e-4f);
  EXPECT_NEAR(many.length(1), 1.1f, 1e-4f);
}

TEST(StrainCeiling, SettingsRefuseWhatIsNotAStrainOrAPassCount) {
  CapeSettings s;
  EXPECT_EQ(s.strainCeiling, 0.0f) << "off by default";
  for (const float bad :
       {-0.01f, 10.5f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    s.strainCeiling = bad;
    const Status status = s.validate();
    EXPECT_FALSE(status.ok()) << bad;
    EXPECT_NE(status.message().find("strainCeiling"), std::string::npos) << status.message();
  }
  s.strainCeiling = 0.1f;
  EXPECT_TRUE(s.validate().ok());
  for (const int bad : {0, -1, 65}) {
    s.strainCeilingPasses = bad;
    EXPECT_FALSE(s.validate().ok()) << bad;
  }
  s.strainCeilingPasses = 64;
  EXPECT_TRUE(s.validate().ok());
}

struct SprintRun {
  float maxStrain = 0.0f;  ///< Over the frames, of each frame's max structural strain.
  std::uint64_t hash = 0;
};

// The canonical 20 x 20 sprint-turn (docs/SCENES.md) for 180 frames, its first turn in frames 90..120.
SprintRun sprintTurn(const CapeSettings& settings) {
  SimpleScene scene(SceneKind::SprintTurn, 20, PinLayout::Corners,
                    settingsForScene(SceneKind::SprintTurn, settings));
  EXPECT_TRUE(scene.status().ok());
  SprintRun r;
  for (int f = 0; f < 180; ++f) {
    scene.advanceFrame();
    r.maxStrain =
        std::max(r.maxStrain, structuralStrain(scene.cape().fabric(), scene.cape().state().positions).max);
  }
  r.hash = stateHash(scene.cape().state());
  return r;
}

TEST(StrainCeiling, TheSprintTurnStretchesLessAndOffChangesNoBit) {
  const SimdLevel before = simdLevel();
  CapeSettings off;
  const SprintRun plain = sprintTurn(off);
  // Off whatever the passes: the same bits.
  off.strainCeilingPasses = 7;
  EXPECT_EQ(sprintTurn(off).hash, plain.hash);
  CapeSettings on;
  on.strainCeiling = 0.1f;
  std::uint64_t first = 0;
  for (const SimdLevel level : {SimdLevel::Portable, SimdLevel::Avx2}) {
    if (!setSimdLevel(level).ok()) continue;
    const SprintRun limited = sprintTurn(on);
    // The same bits at every instruction set (the kernel is scalar at all, the springs' lanes are exact).
    if (first == 0) first = limited.hash;
    EXPECT_EQ(limited.hash, first) << simdLevelName(level);
    EXPECT_NE(limited.hash, plain.hash);
    // Measured: a peak of 30.2 % without the ceiling, 16.3 % with it (the collisions come after it in a
    // substep, and the peaks are where the body pushes the cape).
    EXPECT_GT(plain.maxStrain, 0.25f);
    EXPECT_LT(limited.maxStrain, 0.2f) << "without the ceiling " << plain.maxStrain;
  }
  ASSERT_TRUE(setSimdLevel(before).ok());
}

}  // namespace
}  // namespace cape
