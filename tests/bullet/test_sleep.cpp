// Sleeping in a Bullet world: a cape on still bodies falls asleep, its action then reads nothing new from the
// world, and it wakes the step one of its bodies moves or another body comes near.
#include "BulletFixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

namespace {

using cape::bullet::CapeAction;
using namespace capetest;

void still(World& w, int frames) {
  for (int f = 0; f < frames; ++f) w.world->stepSimulation(kFrame, 8, kFixed);
}

bool sameBits(const cape::Points& a, const cape::Points& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(float) * a.size()) == 0;
}

TEST(BulletSleep, ACapeOnStillBodiesFallsAsleepAndStaysExactlyPut) {
  World w;
  SimpleWalk scene(w);
  still(w, 600);
  const CapeAction& a = *scene.action;
  ASSERT_TRUE(a.cape().isAsleep());
  const cape::Points x = a.cape().state().positions;
  const std::uint64_t slept = a.cape().sleptSteps();
  still(w, 60);
  EXPECT_TRUE(a.cape().isAsleep());
  EXPECT_EQ(a.cape().sleptSteps(), slept + 240) << "every internal step of the 60 frames";
  EXPECT_TRUE(sameBits(x, a.cape().state().positions));
}

TEST(BulletSleep, MovingTheBodiesWakesItTheSameStep) {
  World w;
  SimpleWalk scene(w);
  still(w, 600);
  ASSERT_TRUE(scene.action->cape().isAsleep());
  const cape::Points x = scene.action->cape().state().positions;
  scene.frame = 30;  // the walk half a second on: the character frame moves and turns a little
  scene.advance();
  EXPECT_FALSE(scene.action->cape().isAsleep());
  EXPECT_FALSE(sameBits(x, scene.action->cape().state().positions));
  EXPECT_LT(scene.action->maxPinError(), btScalar(1e-4));
}

TEST(BulletSleep, ABodyComingNearWakesIt) {
  World w;
  SimpleWalk scene(w);
  still(w, 600);
  ASSERT_TRUE(scene.action->cape().isAsleep());
  // A ball dropped onto the cape's lower part from 0.4 m above its bounds.
  auto* shape = new btSphereShape(btScalar(0.1));
  btVector3 inertia(0, 0, 0);
  shape->calculateLocalInertia(btScalar(1), inertia);
  w.shapes.emplace_back(shape);
  auto state = std::make_unique<btDefaultMotionState>(
      btTransform(btQuaternion::getIdentity(), btVector3(0, btScalar(1.9), btScalar(0.3))));
  auto ball =
      std::make_unique<btRigidBody>(btRigidBody::btRigidBodyConstructionInfo(1, state.get(), shape, inertia));
  w.world->addRigidBody(ball.get());
  w.states.push_back(std::move(state));
  w.bodies.push_back(std::move(ball));
  bool woke = false;
  for (int f = 0; f < 60 && !woke; ++f) {
    still(w, 1);
    woke = !scene.action->cape().isAsleep();
  }
  EXPECT_TRUE(woke);
}

// A body the cape found (not one it is pinned to) leaving the world while the cape sleeps: the broadphase's
// report changes, the action builds its colliders afresh without it, and the cape wakes and swings free of
// where it was.
TEST(BulletSleep, ABodyItRestsOnLeavingTheWorldWakesIt) {
  World w;
  SimpleWalk scene(w);
  still(w, 600);
  const CapeAction& a = *scene.action;
  ASSERT_TRUE(a.cape().isAsleep());
  btRigidBody* torso = scene.parts[0].first;
  const auto follows = [&] {
    return std::find(a.activeObjects().begin(), a.activeObjects().end(), torso) != a.activeObjects().end();
  };
  ASSERT_TRUE(follows());
  // Asleep, a frame changes nothing: the same objects, the same positions.
  const cape::Points x = a.cape().state().positions;
  still(w, 1);
  EXPECT_TRUE(a.cape().isAsleep());
  EXPECT_TRUE(follows());
  EXPECT_TRUE(sameBits(x, a.cape().state().positions));
  w.world->removeRigidBody(torso);
  still(w, 1);
  EXPECT_FALSE(follows());
  EXPECT_FALSE(a.cape().isAsleep());
  still(w, 30);
  EXPECT_FALSE(sameBits(x, a.cape().state().positions)) << "it fell where the torso was";
}

TEST(BulletSleep, AChangeOfItsCollidersWakesIt) {
  for (int change = 0; change < 2; ++change) {
    World w;
    SimpleWalk scene(w);
    still(w, 600);
    ASSERT_TRUE(scene.action->cape().isAsleep());
    if (change == 0) {
      scene.action->addCollider(w.addStatic(new btSphereShape(btScalar(0.05)),
                                            btTransform(btQuaternion::getIdentity(), btVector3(3, 3, 3))));
    } else {
      cape::bullet::CapeActionSettings s = scene.action->actionSettings();
      s.discoverColliders = false;  // the bodies it found are no longer its colliders
      scene.action->setActionSettings(s);
    }
    // Its colliders changed: it wakes, finds itself still at rest, and falls asleep again in a second.
    still(w, 1);
    EXPECT_FALSE(scene.action->cape().isAsleep()) << change;
    still(w, 120);
    EXPECT_TRUE(scene.action->cape().isAsleep()) << change;
  }
  {
    // A change of the action's settings that changes nothing the cape feels leaves it asleep.
    World w;
    SimpleWalk scene(w);
    still(w, 600);
    cape::bullet::CapeActionSettings s = scene.action->actionSettings();
    s.discoveryMargin = btScalar(0.3);
    scene.action->setActionSettings(s);
    still(w, 1);
    EXPECT_TRUE(scene.action->cape().isAsleep());
  }
}

}  // namespace
