// Many capes on a thread pool (bitwise identical whatever the thread count). The btSoftBody and deformable
// twins, the comparison's, are tested in tests/compare/test_twins.cpp.
#include "BulletFixture.h"

#include "cape/bullet/CapeGroup.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <thread>
#include <utility>

using namespace capetest;
using cape::bullet::CapeAction;

namespace {

/// `count` capes pinned to as many kinematic bodies that walk and turn, over a sphere each, stepped by a
/// group of `threads` (its hand-offs spinning `spin` us before they sleep, or as the group has it when
/// negative); returns every cape's final positions.
std::vector<cape::Points> runGroup(int threads, bool parallelPrepare = false, double spin = -1.0,
                                   int count = 2) {
  World w;
  std::vector<std::unique_ptr<CapeAction>> capes;
  std::vector<btRigidBody*> bodies;
  cape::bullet::CapeGroup group(threads);
  group.setParallelPrepare(parallelPrepare);
  if (spin >= 0.0) {
    EXPECT_TRUE(group.setSpinMicroseconds(spin).ok());
  }
  for (int k = 0; k < count; ++k) {
    const btVector3 at(btScalar(2 * k), btScalar(1.5), 0);
    bodies.push_back(w.addKinematic(new btBoxShape(btVector3(0.2f, 0.3f, 0.1f)),
                                    btTransform(btQuaternion::getIdentity(), at)));
    w.addStatic(new btSphereShape(0.25f),
                btTransform(btQuaternion::getIdentity(), at + btVector3(0, -0.6f, 0.3f)));
    capes.push_back(std::make_unique<CapeAction>(
        cornerFabric(), cape::CapeSettings(),
        btTransform(btQuaternion::getIdentity(), at + btVector3(-0.3f, 0.06f, 0.15f))));
    capes.back()->attach(0, bodies.back(), btVector3(-0.3f, 0.06f, 0.15f));
    capes.back()->attach(19, bodies.back(), btVector3(0.3f, 0.06f, 0.15f));
    group.add(capes.back().get());
  }
  w.world->addAction(&group);
  for (int frame = 1; frame <= 40; ++frame) {
    const double t = frame / 60.0;
    for (int k = 0; k < count; ++k)
      World::moveKinematic(bodies[std::size_t(k)],
                           btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.8 * t * (k + 1))),
                                       btVector3(btScalar(2 * k), btScalar(1.5 + 0.03 * std::sin(12.0 * t)),
                                                 btScalar(-1.4 * t))));
    w.world->stepSimulation(kFrame, 8, kFixed);
  }
  w.world->removeAction(&group);
  std::vector<cape::Points> out;
  for (const auto& c : capes) out.push_back(c->positions());
  return out;
}

void expectSameBits(const std::vector<cape::Points>& a, const std::vector<cape::Points>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_TRUE(b[k].allFinite()) << "cape " << k;
    ASSERT_EQ(a[k].size(), b[k].size());
    EXPECT_EQ(0, std::memcmp(a[k].data(), b[k].data(), sizeof(float) * std::size_t(a[k].size())))
        << "cape " << k;
  }
}

}  // namespace

TEST(CapeGroup, OneAndTwoThreadsGiveIdenticalBits) {
  const std::vector<cape::Points> one = runGroup(1), two = runGroup(2);
  ASSERT_EQ(one.size(), 2u);
  for (std::size_t k = 0; k < one.size(); ++k) {
    ASSERT_TRUE(one[k].allFinite());
    ASSERT_EQ(one[k].size(), two[k].size());
    EXPECT_EQ(0, std::memcmp(one[k].data(), two[k].data(), sizeof(float) * std::size_t(one[k].size())))
        << "cape " << k;
  }
  // Each body turns at its own rate, so the two capes differ: the comparison is not of two copies.
  EXPECT_GT((one[0].rowwise() - one[0].row(0)).norm(), 0.0f);
  EXPECT_GT((one[0] - one[1]).cwiseAbs().maxCoeff(), 0.0f);
}

TEST(CapeGroup, APreparePutOnThePoolGivesTheSameBits) {
  const std::vector<cape::Points> serial = runGroup(2), parallel = runGroup(2, true), one = runGroup(1, true);
  ASSERT_EQ(serial.size(), parallel.size());
  for (std::size_t k = 0; k < serial.size(); ++k) {
    ASSERT_TRUE(parallel[k].allFinite());
    EXPECT_EQ(
        0, std::memcmp(serial[k].data(), parallel[k].data(), sizeof(float) * std::size_t(serial[k].size())))
        << "cape " << k;
    EXPECT_EQ(0, std::memcmp(serial[k].data(), one[k].data(), sizeof(float) * std::size_t(serial[k].size())))
        << "cape " << k;
  }
}

TEST(CapeGroup, SpinningOrSleepingHandOffsGiveTheSameBits) {
  // The workers wait for each step by sleeping at once, by spinning first (up to 200 us), and by spinning
  // up to a second; with the prepare on the calling thread and on the pool; three threads for five capes
  // (workers with two capes and with one).
  const std::vector<cape::Points> one = runGroup(1, false, -1.0, 5);
  for (const bool parallel : {false, true})
    for (const double spin : {0.0, 200.0, 1e6}) {
      SCOPED_TRACE("parallel prepare " + std::to_string(parallel) + ", spin " + std::to_string(spin));
      expectSameBits(one, runGroup(3, parallel, spin, 5));
    }
}

TEST(CapeGroup, MoreThreadsThanCoresFinishWithTheSameBits) {
  // Eight workers or more on what may be two cores, each spinning before it sleeps: the steps hand off all
  // the same (a worker that spins while the one it waits for has no core only loses its spin).
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const int threads = static_cast<int>(std::max(8u, 4 * cores));
  expectSameBits(runGroup(1, false, -1.0, 9), runGroup(threads, true, 200.0, 9));
}

namespace {

/// Capes pinned to bodies that walk, stepped by a group of `threads` spinning up to `spin` us, whose
/// members change between frames: the second cape leaves at frame 10 and comes back at frame 20 with a new
/// one, the first leaves at frame 30. A worker still taking capes of a step when the next one starts (it
/// spins through the gap) must take only that step's. Returns every cape's final positions.
std::vector<cape::Points> runChangingGroup(int threads, double spin) {
  World w;
  std::vector<std::unique_ptr<CapeAction>> capes;
  std::vector<btRigidBody*> bodies;
  cape::bullet::CapeGroup group(threads);
  EXPECT_TRUE(group.setSpinMicroseconds(spin).ok());
  for (int k = 0; k < 4; ++k) {
    const btVector3 at(btScalar(2 * k), btScalar(1.5), 0);
    bodies.push_back(w.addKinematic(new btBoxShape(btVector3(0.2f, 0.3f, 0.1f)),
                                    btTransform(btQuaternion::getIdentity(), at)));
    capes.push_back(std::make_unique<CapeAction>(
        cornerFabric(12), cape::CapeSettings(),
        btTransform(btQuaternion::getIdentity(), at + btVector3(-0.3f, 0.06f, 0.15f))));
    capes.back()->attach(0, bodies.back(), btVector3(-0.3f, 0.06f, 0.15f));
    capes.back()->attach(11, bodies.back(), btVector3(0.3f, 0.06f, 0.15f));
    if (k < 3) group.add(capes.back().get());
  }
  w.world->addAction(&group);
  for (int frame = 1; frame <= 40; ++frame) {
    if (frame == 10) group.remove(capes[1].get());
    if (frame == 20) {
      group.add(capes[3].get());
      group.add(capes[1].get());
    }
    if (frame == 30) group.remove(capes[0].get());
    const double t = frame / 60.0;
    for (int k = 0; k < 4; ++k)
      World::moveKinematic(bodies[std::size_t(k)],
                           btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.5 * t * (k + 1))),
                                       btVector3(btScalar(2 * k), btScalar(1.5), btScalar(-1.2 * t))));
    w.world->stepSimulation(kFrame, 8, kFixed);
  }
  w.world->removeAction(&group);
  std::vector<cape::Points> out;
  for (const auto& c : capes) out.push_back(c->positions());
  return out;
}

}  // namespace

TEST(CapeGroup, MembersChangingBetweenStepsKeepTheBits) {
  const std::vector<cape::Points> one = runChangingGroup(1, 0.0);
  // Each cape moved while it was a member, and the ones that left stopped where they were.
  for (const cape::Points& x : one) ASSERT_TRUE(x.allFinite());
  EXPECT_GT((one[0] - one[2]).cwiseAbs().maxCoeff(), 0.0f);
  for (const double spin : {0.0, 200.0}) {
    SCOPED_TRACE("spin " + std::to_string(spin));
    expectSameBits(one, runChangingGroup(3, spin));
  }
}

TEST(CapeGroup, RefusesASpinThatIsNotATime) {
  cape::bullet::CapeGroup group(2);
  EXPECT_EQ(group.spinMicroseconds(), cape::bullet::CapeGroup::kDefaultSpinMicroseconds);
  for (const double bad : {-1.0, 2e6, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const cape::Status s = group.setSpinMicroseconds(bad);
    EXPECT_FALSE(s.ok()) << bad;
    EXPECT_NE(s.message().find("setSpinMicroseconds"), std::string::npos) << s.message();
    EXPECT_EQ(group.spinMicroseconds(), cape::bullet::CapeGroup::kDefaultSpinMicroseconds);
  }
  EXPECT_TRUE(group.setSpinMicroseconds(0.0).ok());
  EXPECT_EQ(group.spinMicroseconds(), 0.0);
  EXPECT_TRUE(group.setSpinMicroseconds(1e6).ok());
  EXPECT_EQ(group.spinMicroseconds(), 1e6);
}

TEST(CapeGroup, WarningsOfAParallelPrepareAreSaidOnceOnTheCallingThread) {
  // Two capes pinned to one body, which is removed from the world while they hang from it: each cape says so
  // once, through its handler, on the thread that steps the world.
  World w;
  btRigidBody* body = w.addKinematic(new btSphereShape(0.05f),
                                     btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
  std::vector<std::unique_ptr<CapeAction>> capes;
  std::vector<std::pair<std::thread::id, std::string>> said;
  cape::bullet::CapeGroup group(2);
  group.setParallelPrepare(true);
  for (int k = 0; k < 2; ++k) {
    capes.push_back(std::make_unique<CapeAction>(
        cornerFabric(), cape::CapeSettings(),
        btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f))));
    capes.back()->attachRow(0, body);
    capes.back()->setWarningHandler(
        [&said](const std::string& m) { said.emplace_back(std::this_thread::get_id(), m); });
    group.add(capes.back().get());
  }
  w.world->addAction(&group);
  w.world->stepSimulation(kFrame, 8, kFixed);
  w.world->removeRigidBody(body);  // the world fixture deletes it at the end
  for (int frame = 0; frame < 5; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  w.world->removeAction(&group);
  ASSERT_EQ(said.size(), 2u);
  for (const auto& [thread, message] : said) {
    EXPECT_EQ(thread, std::this_thread::get_id());
    EXPECT_NE(message.find("removed from the world"), std::string::npos) << message;
  }
  for (auto& c : capes) EXPECT_TRUE(c->attachments().empty());
}

TEST(CapeGroup, SameResultAsTheCapeAddedAlone) {
  auto run = [](bool grouped) {
    World w;
    btRigidBody* body = w.addKinematic(new btSphereShape(0.05f),
                                       btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
    CapeAction action(cornerFabric(), cape::CapeSettings(),
                      btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)));
    action.attachRow(0, body);
    cape::bullet::CapeGroup group(2);
    group.add(&action);
    btActionInterface* added = grouped ? static_cast<btActionInterface*>(&group) : &action;
    w.world->addAction(added);
    for (int frame = 1; frame <= 30; ++frame) {
      World::moveKinematic(body,
                           btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, -0.02f * frame)));
      w.world->stepSimulation(kFrame, 8, kFixed);
    }
    w.world->removeAction(added);
    return cape::Points(action.positions());
  };
  const cape::Points a = run(false), b = run(true);
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), sizeof(float) * std::size_t(a.size())));
}
