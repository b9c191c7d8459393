// A cape recovers from a jump of its character (issue 14's numerical guard: "a cape recovers within one frame
// from any finite or non-finite input pose"). The shipped humanoid stands in a Bullet world wearing a cape
// fitted to its shoulders as the demos fit it; after 1 s its root link is moved 0.5 m or 2 m sideways, or
// turned 90 degrees about the vertical, in one frame through Character::setMotion (its bodies move with the
// velocity of the change, as a game's would), and held there. Measured for 2 s after the jump: the per-frame
// max structural strain and the particles the numerical guard restored, for 20 x 20 and 32 x 32 capes,
// self-collision on and off.
#include "cape/bullet/CapeAction.h"
#include "cape/bullet/Convert.h"
#include "cape/character/Anchors.h"
#include "cape/character/Character.h"
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include "CapedHumanoid.h"
#include "CharacterTestWorld.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace {

using cape::bullet::CapeAction;
using cape::bullet::toBt;
using namespace cape::character;

constexpr double kPi = 3.14159265358979323846;
constexpr int kSettleFrames = 60;  // 1 s standing before the jump
constexpr int kAfterFrames = 120;  // 2 s measured after it

enum class Jump { Half, Two, Turn };

const char* name(Jump j) {
  switch (j) {
    case Jump::Half:
      return "0.5 m";
    case Jump::Two:
      return "2 m";
    case Jump::Turn:
      return "90 deg";
  }
  return "?";
}

/// What one run measured, per frame after the jump (frame 0: the frame in which the character moved).
struct Recovery {
  std::vector<float> strain;           ///< max structural strain at the end of each frame
  std::vector<std::uint64_t> guarded;  ///< particles the guard restored in each frame
  bool finite = true;                  ///< every position and velocity finite at the end of every frame
  float strainBefore = 0.0f;           ///< max structural strain at the end of the last frame before
  std::uint64_t guardedBefore = 0;     ///< particles restored before the jump (a healthy cape: none)

  /// The largest strain from frame `from` on.
  float worstFrom(std::size_t from) const {
    float worst = 0.0f;
    for (std::size_t f = from; f < strain.size(); ++f) worst = std::max(worst, strain[f]);
    return worst;
  }
  /// Particles restored from frame `from` on, and the last frame that restored any (-1: none).
  std::pair<std::uint64_t, int> guardedFrom(std::size_t from) const {
    std::uint64_t sum = 0;
    int last = -1;
    for (std::size_t f = from; f < guarded.size(); ++f) {
      sum += guarded[f];
      if (guarded[f] > 0) last = static_cast<int>(f);
    }
    return {sum, last};
  }
};

/// The shipped humanoid standing still (its standing pose held through setMotion) wearing an N x N cape
/// (CapedHumanoid), stepped stepSimulation(1/60, 8, 1/240) with the default CapeActionSettings (a jump beyond
/// 1 m or 1 rad teleports the cape with the character; the 0.5 m one is swept, at 30 m/s).
Recovery runJump(int n, bool selfCollision, Jump jump) {
  Recovery out;
  capetest::CapedHumanoid h(n, selfCollision, cape::SceneKind::Hang);
  if (!h.ok) return out;
  capetest::World& w = h.w;
  Character& c = *h.character;
  CapeAction& action = *h.action;
  action.setWarningHandler([](const std::string&) {});  // what the guard did is measured here

  // The root link held where it stands, then moved once and held there.
  const Eigen::Isometry3d standing = c.skeleton().linkPose(0);
  Eigen::Isometry3d moved = standing;
  switch (jump) {
    case Jump::Half:
      moved.pretranslate(Eigen::Vector3d(0.5, 0.0, 0.0));
      break;
    case Jump::Two:
      moved.pretranslate(Eigen::Vector3d(2.0, 0.0, 0.0));
      break;
    case Jump::Turn: {
      const Eigen::Vector3d at = standing.translation();
      moved = Eigen::Translation3d(at) * Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitY()) *
              Eigen::Translation3d(-at) * standing;
      break;
    }
  }
  std::uint64_t guardTotal = 0;
  for (int frame = 1; frame <= kSettleFrames + kAfterFrames; ++frame) {
    const bool after = frame > kSettleFrames;
    const cape::character::Status s = c.setMotion(frame / 60.0, after ? moved : standing);
    EXPECT_TRUE(s.ok()) << s.message();
    w.world.stepSimulation(btScalar(1.0 / 60.0), 8, btScalar(1.0 / 240.0));
    const cape::Cape& cape = action.cape();
    const float strain = cape::structuralStrain(cape.fabric(), cape.state().positions).max;
    const std::uint64_t restored = cape.guard().total - guardTotal;
    guardTotal = cape.guard().total;
    if (!after) {
      out.strainBefore = strain;
      out.guardedBefore += restored;
      continue;
    }
    out.finite = out.finite && cape.state().positions.allFinite() && cape.state().velocities.allFinite();
    out.strain.push_back(strain);
    out.guarded.push_back(restored);
  }
  return out;
}

/// Every jump, with self-collision off and on, of an n x n cape, and the bounds each must meet.
void checkRecovery(int n) {
  // For every case: nothing restored by the guard before the jump or after the jump's own frame (frame 0),
  // nothing not finite. A teleported cape (2 m, 90 degrees) is back under 20 % strain from frame 2 on. The
  // swept 0.5 m jump (30 m/s) leaves the cape folded and twisted between its pins with self-collision off
  // too (measured: 149 % and 217 % at most from frame 2 on, 44 % and 49 % two seconds later, 20 x 20 and
  // 32 x 32), so 20 % is out of reach there: with self-collision on it must stay under 500 % and under
  // twice the same jump without it (measured 156 % and 329 %; 68 % and 113 % two seconds later; the tangle
  // is chaotic, and the bound is loose on purpose). Before the fix in SelfCollision::solve this jump with
  // self-collision on reached 10,422 % (20 x 20) and 15,261 % (32 x 32), and the guard restored 3,600 and
  // 7,618 particles after frame 0, in every frame to the end.
  float sweptWithout = 0.0f;
  for (const bool self : {false, true})
    for (const Jump jump : {Jump::Half, Jump::Two, Jump::Turn}) {
      const Recovery r = runJump(n, self, jump);
      ASSERT_EQ(r.strain.size(), static_cast<std::size_t>(kAfterFrames));
      const std::string what = std::to_string(n) + "x" + std::to_string(n) +
                               (self ? " self-collision on" : " self-collision off") + ", jump " + name(jump);
      const float worst = r.worstFrom(2);
      const auto [guardedLate, lastGuarded] = r.guardedFrom(1);
      std::printf(
          "%-40s strain before %.2f %%, frames 0-2 %.1f %.1f %.1f %%, from frame 2 at most %.1f %%, "
          "last frame %.1f %%; restored in frame 0: %llu, after it: %llu\n",
          what.c_str(), 100.0 * r.strainBefore, 100.0 * r.strain[0], 100.0 * r.strain[1], 100.0 * r.strain[2],
          100.0 * worst, 100.0 * r.strain.back(), static_cast<unsigned long long>(r.guarded[0]),
          static_cast<unsigned long long>(guardedLate));
      EXPECT_EQ(r.guardedBefore, 0u) << what << ": a standing cape never trips the guard";
      EXPECT_TRUE(r.finite) << what;
      EXPECT_EQ(guardedLate, 0u) << what << ": restored after the jump's frame, last in frame "
                                 << lastGuarded;
      if (jump != Jump::Half) {
        EXPECT_LT(worst, 0.2f) << what;
      } else if (!self) {
        sweptWithout = worst;
      } else {
        EXPECT_LT(worst, 5.0f) << what;
        EXPECT_LT(worst, 2.0f * sweptWithout) << what << " (without self-collision: " << sweptWithout << ")";
      }
    }
}

TEST(JumpRecovery, A20x20CapeIsBackWithinAFrameAfterItsCharacterJumps) {
  checkRecovery(20);
}

// Labelled slow (tests/character/CMakeLists.txt): the tangle after the swept jump keeps hundreds of
// self-contacts per substep, which the sanitized Debug build runs some 20 times slower than the Release
// build; the sanitized run checks the same code paths on the 20 x 20 cape above.
TEST(JumpRecovery, A32x32CapeIsBackWithinAFrameAfterItsCharacterJumps) {
  checkRecovery(32);
}

}  // namespace
