// Sleeping (CapeSettings::sleepSpeed): a cape at rest among still colliders stops simulating, changes nothing
// while asleep, and wakes the very step anything it feels changes.
#include "HangingCape.h"

#include "cape/core/Cape.h"
#include "cape/core/ColliderRecord.h"
#include "cape/scenes/Scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <vector>

namespace cape {
namespace {

using test::at;
using test::Hanging;

float largestDifference(const Points& a, const Points& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

bool sameBits(const Points& a, const Points& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(float) * a.size()) == 0;
}

CapeSettings neverSleeps() {
  CapeSettings s;
  s.sleepSpeed = 0.0f;
  return s;
}

TEST(Sleep, AHangingCapeFallsAsleepWhereItWouldHaveHung) {
  Hanging asleep{CapeSettings()}, awake{neverSleeps()};
  asleep.frames(600);
  awake.frames(600);
  EXPECT_TRUE(asleep.cape.isAsleep());
  EXPECT_GT(asleep.cape.sleptSteps(), 0u);
  EXPECT_FALSE(awake.cape.isAsleep());
  EXPECT_EQ(awake.cape.sleptSteps(), 0u);
  // What it skipped is the last drift of a cape at rest: far below a millimetre.
  EXPECT_LT(largestDifference(asleep.cape.state().positions, awake.cape.state().positions), 1e-3f);
  EXPECT_TRUE(asleep.cape.state().velocities.isZero());
  EXPECT_DOUBLE_EQ(asleep.cape.state().time, awake.cape.state().time);
}

TEST(Sleep, ASleepingStepChangesNothingButTheClock) {
  Hanging h{CapeSettings()};
  h.frames(600);
  ASSERT_TRUE(h.cape.isAsleep());
  const CapeState before = h.cape.state();
  const std::uint64_t slept = h.cape.sleptSteps();
  h.frames(100);
  EXPECT_TRUE(h.cape.isAsleep());
  EXPECT_EQ(h.cape.sleptSteps(), slept + 100);
  EXPECT_TRUE(sameBits(before.positions, h.cape.state().positions));
  EXPECT_TRUE(sameBits(before.velocities, h.cape.state().velocities));
  EXPECT_NEAR(h.cape.state().time, before.time + 100.0 * static_cast<double>(1.0f / 60.0f), 1e-9);
}

TEST(Sleep, AMovingPinWakesItTheSameStepAndItMovesAsAnAwakeCapeDoes) {
  Hanging asleep{CapeSettings()}, awake{neverSleeps()};
  asleep.frames(600);
  awake.frames(600);
  ASSERT_TRUE(asleep.cape.isAsleep());
  const Points rest = asleep.cape.state().positions;
  asleep.movePins(Vec3(0.02f, 0.0f, 0.0f));
  awake.movePins(Vec3(0.02f, 0.0f, 0.0f));
  asleep.frames(1);
  awake.frames(1);
  EXPECT_FALSE(asleep.cape.isAsleep());
  EXPECT_GT(largestDifference(asleep.cape.state().positions, rest), 0.01f);
  for (int f = 0; f < 60; ++f) {
    asleep.frames(1);
    awake.frames(1);
    ASSERT_LT(largestDifference(asleep.cape.state().positions, awake.cape.state().positions), 2e-3f) << f;
  }
}

TEST(Sleep, ColliderChangesWakeIt) {
  enum Change { Moves, Comes, Goes, Grows };
  for (const Change change : {Moves, Comes, Goes, Grows}) {
    Hanging h{CapeSettings()};
    h.frames(600);
    ASSERT_TRUE(h.cape.isAsleep());
    switch (change) {
      case Moves:
        h.colliders[0].moveTo(at(h.colliders[0].current.position + Vec3(0.0f, 0.0f, 0.05f)));
        break;
      case Comes:
        h.colliders.push_back(Collider::sphere(0.1f, at(Vec3(0.0f, 1.0f, 0.2f))));
        break;
      case Goes:
        h.colliders.pop_back();
        break;
      case Grows:
        h.colliders[0].halfExtents.z() += 0.05f;
        break;
    }
    h.frames(1);
    EXPECT_FALSE(h.cape.isAsleep()) << change;
    EXPECT_EQ(h.cape.sleptSteps() > 0, true);
  }
}

TEST(Sleep, ChangesToTheCapeWakeIt) {
  for (int change = 0; change < 6; ++change) {
    Hanging h{CapeSettings()};
    h.frames(600);
    ASSERT_TRUE(h.cape.isAsleep());
    switch (change) {
      case 0:
        ASSERT_TRUE(h.cape.setGravity(Vec3(0.0f, -9.8f, 1.0f)).ok());
        break;
      case 1: {
        CapeSettings s = h.cape.settings();
        s.wind.model = WindSettings::Model::Aerodynamic;
        s.wind.speed = 3.0f;
        ASSERT_TRUE(h.cape.setSettings(s).ok());
        break;
      }
      case 2:
        h.cape.teleport(at(Vec3(1.0f, 0.0f, 0.0f)));
        break;
      case 3:
        h.cape.unpin(h.rig.pinnedParticles[0]);
        break;
      case 4:
        h.cape.mutableState().velocities(100, 2) = 1.0f;
        break;
      case 5:
        h.cape.carry(Eigen::Matrix3f::Identity(), Vec3::Zero(), Vec3(0.0f, 0.1f, 0.0f));
        break;
    }
    EXPECT_FALSE(h.cape.isAsleep()) << change;
  }
  // Carrying by nothing (what the Bullet adapter's inertia does when the body stands still) is no change.
  Hanging h{CapeSettings()};
  h.frames(600);
  h.cape.carry(Eigen::Matrix3f::Identity(), Vec3(1.0f, 2.0f, 3.0f), Vec3::Zero());
  h.cape.setGravity(h.cape.settings().gravity);
  EXPECT_TRUE(h.cape.isAsleep());
}

TEST(Sleep, NeverInTheWindOrWhenSwitchedOff) {
  CapeSettings windy;
  windy.wind.model = WindSettings::Model::Aerodynamic;
  windy.wind.speed = 0.0f;  // still air, but a wind model: the cape does not sleep in it
  Hanging w{windy}, off{neverSleeps()};
  w.frames(600);
  off.frames(600);
  EXPECT_FALSE(w.cape.isAsleep());
  EXPECT_FALSE(off.cape.isAsleep());
}

TEST(Sleep, ASwingingCapeStaysAwake) {
  // A cape never slower than the limit for the delay never sleeps: the pins move a little every frame.
  Hanging h{CapeSettings()};
  for (int f = 0; f < 600; ++f) {
    h.movePins(Vec3(f % 120 < 60 ? 0.002f : -0.002f, 0.0f, 0.0f));
    h.frames(1);
    ASSERT_FALSE(h.cape.isAsleep()) << f;
  }
  EXPECT_EQ(h.cape.sleptSteps(), 0u);
}

// A large cape hanging from its corners rests above the strain limit on the settings' substeps and well
// below half of it on twice as many: the refinement's halving bounced back and forth for as long as it hung,
// each switch shaking it, and it never fell asleep (48 x 48: particles at 0.2 to 0.5 m/s after 30 s). A
// halving that bounces now makes the next one wait, twice as long each time: the switches die out and the
// cape settles, on the finer substeps, and sleeps.
TEST(Sleep, ALargeCapeAtRestSettlesItsRefinementAndFallsAsleep) {
  SimpleScene scene(SceneKind::Hang, 48, PinLayout::Corners,
                    settingsForScene(SceneKind::Hang, CapeSettings()));
  ASSERT_TRUE(scene.status().ok());
  int switches = 0, lateSwitches = 0, refinement = scene.cape().substepRefinement();
  for (int f = 0; f < 900 && !scene.cape().isAsleep(); ++f) {
    scene.advanceFrame();
    if (scene.cape().substepRefinement() != refinement) {
      ++switches;
      if (f >= 300) ++lateSwitches;
      refinement = scene.cape().substepRefinement();
    }
  }
  EXPECT_TRUE(scene.cape().isAsleep()) << switches << " switches of the refinement";
  EXPECT_LE(lateSwitches, 4) << "switches after 5 s";
  EXPECT_TRUE(scene.cape().state().positions.allFinite());
}

TEST(Sleep, SettingsAreChecked) {
  CapeSettings s;
  s.sleepSpeed = -1.0f;
  EXPECT_FALSE(s.validate().ok());
  s = CapeSettings();
  s.sleepDelay = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(s.validate().ok());
  s.sleepDelay = 0.0f;
  EXPECT_TRUE(s.validate().ok());
}

// stepAsleep, for a caller that vouches for its colliders: the same clock, state and count as step() with
// the colliders of the last step, and a refusal whenever step() would simulate.
TEST(Sleep, StepAsleepIsTheSleepingStepWithoutTheComparison) {
  Hanging vouched{CapeSettings()}, compared{CapeSettings()};
  vouched.frames(600);
  compared.frames(600);
  ASSERT_TRUE(vouched.cape.isAsleep());
  for (int k = 0; k < 50; ++k) {
    EXPECT_TRUE(vouched.cape.stepAsleep(1.0f / 240.0f));
    compared.cape.step(1.0f / 240.0f, compared.colliders);
  }
  EXPECT_EQ(vouched.cape.sleptSteps(), compared.cape.sleptSteps());
  EXPECT_EQ(vouched.cape.state().time, compared.cape.state().time);
  EXPECT_TRUE(sameBits(vouched.cape.state().positions, compared.cape.state().positions));
  EXPECT_TRUE(sameBits(vouched.cape.state().velocities, compared.cape.state().velocities));
  // Not a step's dt: refused, nothing counted.
  const std::uint64_t slept = vouched.cape.sleptSteps();
  for (float dt : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN()})
    EXPECT_FALSE(vouched.cape.stepAsleep(dt));
  EXPECT_EQ(vouched.cape.sleptSteps(), slept);
  // A pin moved: refused (it wakes the cape; step() simulates it).
  vouched.movePins(Vec3(0.0f, 0.01f, 0.0f));
  EXPECT_FALSE(vouched.cape.stepAsleep(1.0f / 240.0f));
  EXPECT_EQ(vouched.cape.sleptSteps(), slept);
  // Awake: refused.
  Hanging awake{neverSleeps()};
  awake.frames(60);
  EXPECT_FALSE(awake.cape.stepAsleep(1.0f / 240.0f));
  // On its coarse level: refused (the coarse level sleeps in step()).
  Hanging coarse{CapeSettings()};
  ASSERT_TRUE(coarse.cape.setCoarseLevel(true).ok());
  coarse.frames(900);
  EXPECT_FALSE(coarse.cape.stepAsleep(1.0f / 240.0f));
}

// The record a sleeping cape and the demos' metrics compare colliders with: every field the cape or the
// metrics read, bit for bit; a triangle soup by its corners (refilled in place), a hull by its address.
TEST(ColliderRecord, SeesEveryBitThatMattersAndNothingElse) {
  auto soup = std::make_shared<TriangleSoup>();
  soup->corners = {Vec3(0.0f, 0.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 1.0f)};
  std::vector<Collider> colliders{Collider::sphere(0.1f), Collider::capsule(0.05f, 0.2f, 1),
                                  Collider::triangleMesh(soup), Collider::plane(Vec3::UnitY(), 0.0f)};
  ColliderRecord record;
  record.remember(colliders);
  EXPECT_TRUE(record.same(colliders));
  const std::vector<Collider> copy = colliders;
  EXPECT_TRUE(record.same(copy));
  colliders[0].name = "renamed";  // reports only
  EXPECT_TRUE(record.same(colliders));
  const auto changes = [&](const char* what, const std::function<void()>& change) {
    const std::vector<Collider> before = colliders;
    const std::vector<Vec3> corners = soup->corners;
    change();
    EXPECT_FALSE(record.same(colliders)) << what;
    colliders = before;
    soup->corners = corners;
    EXPECT_TRUE(record.same(colliders)) << what;
  };
  const auto ulp = [](float& f) { f = std::nextafter(f, 1e30f); };
  changes("a radius", [&] { ulp(colliders[0].radius); });
  changes("a half height", [&] { ulp(colliders[1].halfHeight); });
  changes("an axis", [&] { colliders[1].axis = 2; });
  changes("a thickness", [&] { ulp(colliders[0].thickness); });
  changes("a friction", [&] { colliders[3].friction = 0.5f; });
  changes("a current pose", [&] { ulp(colliders[1].current.position.z()); });
  changes("a previous pose", [&] { ulp(colliders[1].previous.rotation.w()); });
  changes("a plane's constant", [&] { ulp(colliders[3].constant); });
  changes("a corner of the soup, in place", [&] { ulp(soup->corners[2].x()); });
  changes("a triangle more", [&] { soup->corners.insert(soup->corners.end(), 3, Vec3::Ones()); });
  changes("another soup of the same corners",
          [&] { colliders[2].triangles = std::make_shared<TriangleSoup>(*soup); });
  changes("a collider less", [&] { colliders.pop_back(); });
  changes("the order", [&] { std::swap(colliders[0], colliders[1]); });
}

}  // namespace
}  // namespace cape
