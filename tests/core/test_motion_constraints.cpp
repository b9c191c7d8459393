// Motion constraints to the animated pose (MotionConstraints, Cape::setMotionConstraints): no particle ever
// leaves its max distance, a backstop keeps the cape out of the space behind its animated surface that no
// collider covers, a drive of 1 holds the animated pose exactly, weight maps give each particle its own
// value, bad arrays are refused, and switched off nothing changes.
#include "CapeTestFixture.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace cape {
namespace {

using test::makeGrid;
using test::row;

constexpr int kSide = 12;
constexpr float kFrame = 1.0f / 60.0f;

/// A 12 x 12 cape pinned by its top corners; the corners shaken sideways (0.4 m at 3 Hz) and bobbed: a
/// violent motion that swings the free cape far from the rest shape.
struct ShakenCape {
  explicit ShakenCape(const CapeSettings& s = CapeSettings()) : cape(makeGrid(kSide, kSide), s) {
    left = row(cape.state().positions, 0);
    right = row(cape.state().positions, kSide - 1);
    a = cape.pin(0, left);
    b = cape.pin(kSide - 1, right);
  }
  void frame(int f) {
    const float t = static_cast<float>(f) * kFrame;
    const Vec3 shift(0.4f * std::sin(6.0f * 3.14159265f * t), 0.1f * std::sin(11.0f * t),
                     0.2f * std::cos(5.0f * t));
    cape.movePin(a, left + shift);
    cape.movePin(b, right + shift);
    cape.step(kFrame, {});
  }
  /// The farthest free particle from its animated position, m.
  float farthestFromAnimation() const {
    return (cape.state().positions - cape.animatedPositions()).rowwise().norm().maxCoeff();
  }
  Cape cape;
  Vec3 left, right;
  std::size_t a = 0, b = 0;
};

TEST(MotionConstraints, NoParticleEverLeavesItsMaxDistance) {
  // Without: the swing takes the cape far from the rest shape carried by the pins.
  float freeSwing = 0.0f;
  {
    ShakenCape shaken;
    MotionConstraints none;
    none.drive = Eigen::VectorXf::Zero(kSide * kSide);  // on, and doing nothing: animatedPositions() is kept
    ASSERT_TRUE(shaken.cape.setMotionConstraints(none).ok());
    for (int f = 1; f <= 120; ++f) {
      shaken.frame(f);
      freeSwing = std::max(freeSwing, shaken.farthestFromAnimation());
    }
  }
  EXPECT_GT(freeSwing, 0.2f);
  // With a weight map: 2 cm at the top row, 12 cm at the bottom.
  ShakenCape shaken;
  MotionConstraints c;
  c.maxDistance.resize(kSide * kSide);
  for (int i = 0; i < kSide * kSide; ++i)
    c.maxDistance[i] = 0.02f + 0.1f * static_cast<float>(i / kSide) / (kSide - 1);
  ASSERT_TRUE(shaken.cape.setMotionConstraints(c).ok());
  float worstExcess = -1.0f, farthest = 0.0f;
  for (int f = 1; f <= 120; ++f) {
    shaken.frame(f);
    const Points& x = shaken.cape.state().positions;
    const Points& animated = shaken.cape.animatedPositions();
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      const float d = (x.row(i) - animated.row(i)).norm();
      worstExcess = std::max(worstExcess, d - c.maxDistance[i]);
      farthest = std::max(farthest, d);
    }
    // The animation is the rest shape carried by the pins (a translation here): the pinned corners on it.
    EXPECT_LT((row(animated, 0) - row(x, 0)).norm(), 1e-5f);
    ASSERT_TRUE(x.allFinite());
  }
  std::printf(
      "shaken cape: %.0f mm from its animated pose at most without a max distance, %.0f mm with "
      "(2 to 12 cm allowed), %.2g m beyond it at worst\n",
      1e3 * freeSwing, 1e3 * farthest, worstExcess);
  EXPECT_LE(worstExcess, 1e-5f);
  EXPECT_GT(farthest, 0.1f) << "the bottom rows use their larger reach";
}

TEST(MotionConstraints, ADriveOfOneHoldsTheAnimatedPoseExactly) {
  ShakenCape shaken;
  MotionConstraints c;
  c.drive = Eigen::VectorXf::Ones(kSide * kSide);
  ASSERT_TRUE(shaken.cape.setMotionConstraints(c).ok());
  for (int f = 1; f <= 60; ++f) {
    shaken.frame(f);
    EXPECT_LT(shaken.farthestFromAnimation(), 1e-6f) << "frame " << f;
  }
  // A caller's animation (a skinning): the cape follows it.
  Points skin = shaken.cape.animatedPositions();
  skin.col(2).array() += 0.3f;
  skin.col(0).array() *= 1.1f;
  ASSERT_TRUE(shaken.cape.setAnimatedPositions(skin).ok());
  shaken.cape.step(kFrame, {});
  for (Eigen::Index i = 0; i < skin.rows(); ++i) {
    if (shaken.cape.state().inverseMasses[i] > 0.0f) {
      EXPECT_LT((shaken.cape.state().positions.row(i) - skin.row(i)).norm(), 1e-6f);
    }
  }
  // A drive of 0.5 closes half the gap per 1/60 s: the cape comes nearer, not all the way.
  c.drive.setConstant(0.5f);
  ASSERT_TRUE(shaken.cape.setMotionConstraints(c).ok());
  skin.col(2).array() -= 0.3f;
  ASSERT_TRUE(shaken.cape.setAnimatedPositions(skin).ok());
  shaken.cape.step(kFrame, {});
  const float gap = shaken.farthestFromAnimation();
  EXPECT_GT(gap, 0.05f);
  EXPECT_LT(gap, 0.25f);
}

TEST(MotionConstraints, ABackstopKeepsTheCapeOutOfATorsoTheCollidersMiss) {
  // A torso behind the hanging cape that no collider stands for: a box from 1 to 20 cm behind the animated
  // surface, 5 cm inside the cape's edges. An acceleration towards the back of the animated surface
  // (against its normal) blows the cape into it unless the backstop (a 1 m sphere touching the animated
  // surface from 5 mm behind at every particle) holds it.
  struct Found {
    float deepest = 0.0f;  // the deepest any particle goes into its backstop sphere, m
    int inTorso = 0;       // particle-frames inside the torso box
  };
  const auto run = [](bool backstop) {
    Found found;
    CapeSettings s;
    Cape cape(makeGrid(kSide, kSide), s);  // 0.6 x 1 m in the x-y plane, x in [0, 0.6], y in [-1, 0]
    cape.pin(0, row(cape.state().positions, 0));
    cape.pin(kSide - 1, row(cape.state().positions, kSide - 1));
    MotionConstraints c;
    c.backstopRadius = Eigen::VectorXf::Constant(kSide * kSide, backstop ? 1.0f : 0.0f);
    c.backstopDistance = Eigen::VectorXf::Constant(kSide * kSide, 0.005f);
    EXPECT_TRUE(cape.setMotionConstraints(c).ok());
    cape.step(kFrame, {});
    const Vec3 n = row(cape.animatedNormals(), kSide * kSide / 2);
    EXPECT_NEAR(std::abs(n.z()), 1.0f, 1e-3f);
    EXPECT_TRUE(cape.setGravity(Vec3(0.0f, -9.8f, 0.0f) - 6.0f * n).ok());
    for (int f = 0; f < 120; ++f) {
      cape.step(kFrame, {});
      const Points& x = cape.state().positions;
      for (Eigen::Index i = 0; i < x.rows(); ++i) {
        const Vec3 p = row(x, i);
        const Vec3 centre =
            row(cape.animatedPositions(), i) - (0.005f + 1.0f) * row(cape.animatedNormals(), i);
        found.deepest = std::max(found.deepest, 1.0f - (p - centre).norm());
        const float behind = -p.dot(n);  // the animated surface is the plane z = 0
        if (behind > 0.01f && behind < 0.2f && p.x() > 0.05f && p.x() < 0.55f && p.y() > -0.95f &&
            p.y() < -0.05f)
          ++found.inTorso;
      }
    }
    EXPECT_TRUE(cape.state().positions.allFinite());
    return found;
  };
  const Found without = run(false), with = run(true);
  std::printf(
      "pushed behind its animated pose: without backstops %.0f mm into their spheres and %d "
      "particle-frames in the torso, with them %.2g m and %d\n",
      1e3 * without.deepest, without.inTorso, with.deepest, with.inTorso);
  EXPECT_GT(without.deepest, 0.1f) << "the push takes the cape behind its animated pose";
  EXPECT_GT(without.inTorso, 100);
  EXPECT_LT(with.deepest, 1e-5f);
  EXPECT_EQ(with.inTorso, 0);
}

TEST(MotionConstraints, BadArraysAreRefusedAndKeepTheOldOnes) {
  Cape cape(makeGrid(4, 4), CapeSettings());
  MotionConstraints good;
  good.maxDistance = Eigen::VectorXf::Constant(16, 0.1f);
  ASSERT_TRUE(cape.setMotionConstraints(good).ok());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<MotionConstraints> bad(7);
  bad[0].maxDistance = Eigen::VectorXf::Constant(15, 0.1f);
  bad[1].maxDistance = Eigen::VectorXf::Constant(16, -0.1f);
  bad[2].maxDistance = Eigen::VectorXf::Constant(16, nan);
  bad[3].drive = Eigen::VectorXf::Constant(16, 1.5f);
  bad[4].backstopRadius = Eigen::VectorXf::Constant(16, std::numeric_limits<float>::infinity());
  bad[5].backstopDistance = Eigen::VectorXf::Constant(16, 0.1f);  // without a radius
  bad[6].backstopRadius = Eigen::VectorXf::Constant(16, 0.1f);
  bad[6].backstopDistance = Eigen::VectorXf::Constant(16, -0.1f);
  for (const MotionConstraints& c : bad) {
    const Status st = cape.setMotionConstraints(c);
    EXPECT_FALSE(st.ok());
    EXPECT_NE(st.message().find("MotionConstraints"), std::string::npos) << st.message();
  }
  EXPECT_EQ(cape.motionConstraints().maxDistance, good.maxDistance);
  // An infinite max distance is no limit for that particle.
  good.maxDistance[3] = std::numeric_limits<float>::infinity();
  EXPECT_TRUE(cape.setMotionConstraints(good).ok());
  EXPECT_FALSE(cape.setAnimatedPositions(Points::Zero(3, 3)).ok());
  Points notFinite = cape.state().positions;
  notFinite(2, 1) = nan;
  EXPECT_FALSE(cape.setAnimatedPositions(notFinite).ok());
  EXPECT_TRUE(cape.setAnimatedPositions(Points()).ok());  // back to the fit
}

TEST(MotionConstraints, EmptyConstraintsChangeNoBit) {
  ShakenCape plain, emptied;
  ASSERT_TRUE(emptied.cape.setMotionConstraints(MotionConstraints()).ok());
  for (int f = 1; f <= 60; ++f) {
    plain.frame(f);
    emptied.frame(f);
  }
  EXPECT_EQ(plain.cape.state().positions, emptied.cape.state().positions);
  EXPECT_EQ(plain.cape.state().velocities, emptied.cape.state().velocities);
}

}  // namespace
}  // namespace cape
