// CapeActionSettings::teleportMode: a character teleported in one frame (5 m and a quarter turn) takes its
// swinging cape along as it is (Keep) or puts it back at rest in its reference pose (Reset); below the
// teleport thresholds both modes are the same bits. And the core's Cape::resetToReference on its own.
#include "BulletFixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace capetest;
using cape::bullet::CapeAction;
using cape::bullet::TeleportMode;

namespace {

const btVector3 kLeft(btScalar(-0.3), btScalar(0.06), btScalar(0.15)),
    kRight(btScalar(0.3), btScalar(0.06), btScalar(0.15));

struct Outcome {
  cape::Points shape;      ///< the cape's own positions (its frame) after the teleport frame
  cape::Points reference;  ///< its reference pose then (Cape::referencePose applied to the rest shape)
  double fastest = 0.0;    ///< m/s: the fastest particle then
  bool teleported = false;
  std::uint64_t restored = 0;  ///< particles the numerical guard restored
  cape::Points end;            ///< world positions one second later
};

/// Whether any internal step of a frame teleported (teleportedLastStep() says it of the last one).
struct TeleportProbe {
  const CapeAction* action = nullptr;
  bool teleported = false;
  static void tick(btDynamicsWorld* world, btScalar) {
    auto* self = static_cast<TeleportProbe*>(world->getWorldUserInfo());
    self->teleported = self->teleported || self->action->teleportedLastStep();
  }
};

double farthest(const cape::Points& a, const cape::Points& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

/// A cape pinned by its corners to a kinematic box that shakes from side to side for a second (the cape
/// swings) and then, unless `jump` is false, jumps 5 m and turns a quarter turn in one frame.
Outcome run(TeleportMode mode, bool jump) {
  World w;
  const btTransform start(btQuaternion::getIdentity(), btVector3(0, btScalar(1.5), 0));
  btRigidBody* body =
      w.addKinematic(new btBoxShape(btVector3(btScalar(0.2), btScalar(0.3), btScalar(0.1))), start);
  cape::bullet::CapeActionSettings settings;
  settings.teleportMode = mode;
  CapeAction action(
      cornerFabric(), cape::CapeSettings(),
      btTransform(btQuaternion::getIdentity(), btVector3(btScalar(-0.3), btScalar(1.56), btScalar(0.15))),
      settings);
  EXPECT_TRUE(action.attach(0, body, kLeft));
  EXPECT_TRUE(action.attach(19, body, kRight));
  w.world->addAction(&action);
  btTransform pose = start;
  for (int f = 1; f <= 60; ++f) {
    // 0.25 m of sideways shake at 2 Hz, and a step forward.
    pose.setOrigin(
        btVector3(btScalar(0.25 * std::sin(4.0 * SIMD_PI * f / 60.0)), btScalar(1.5), btScalar(-0.01 * f)));
    World::moveKinematic(body, pose);
    w.world->stepSimulation(kFrame, 8, kFixed);
  }
  Outcome o;
  if (jump) {
    pose = btTransform(btQuaternion(btVector3(0, 1, 0), SIMD_HALF_PI),
                       pose.getOrigin() + btVector3(btScalar(5), 0, btScalar(3)));
    World::moveKinematic(body, pose);
  }
  TeleportProbe probe{&action};
  w.world->setInternalTickCallback(&TeleportProbe::tick, &probe);
  w.world->stepSimulation(kFrame, 8, kFixed);
  w.world->setInternalTickCallback(nullptr);
  o.teleported = probe.teleported;
  o.shape = action.cape().state().positions;
  const cape::Points& rest = action.cape().fabric().restPositions();
  o.reference.resize(rest.rows(), 3);
  for (Eigen::Index i = 0; i < rest.rows(); ++i)
    o.reference.row(i) = action.cape().referencePose().apply(rest.row(i).transpose()).transpose();
  o.fastest = action.cape().state().velocities.rowwise().norm().maxCoeff();
  for (int f = 0; f < 60; ++f) w.world->stepSimulation(kFrame, 8, kFixed);
  o.end = action.positions();
  o.restored = action.cape().guard().total;
  w.world->removeAction(&action);
  return o;
}

}  // namespace

TEST(TeleportMode, ResetPutsTheCapeAtRestInItsReferencePoseKeepTakesItsSwingAlong) {
  const Outcome keep = run(TeleportMode::Keep, true), reset = run(TeleportMode::Reset, true);
  ASSERT_TRUE(keep.teleported);
  ASSERT_TRUE(reset.teleported);
  std::printf(
      "after the teleport frame: reset %.2f mm from its reference pose, fastest %.3f m/s; keep %.0f mm "
      "from it, fastest %.2f m/s\n",
      1e3 * farthest(reset.shape, reset.reference), reset.fastest,
      1e3 * farthest(keep.shape, reset.reference), keep.fastest);
  // Reset: one frame of falling from rest after it (g (1/60)^2 / 2 = 1.4 mm, less what the springs hold).
  EXPECT_LT(farthest(reset.shape, reset.reference), 5e-3);
  EXPECT_LT(reset.fastest, 0.25);
  // Keep: the swing comes along, turned with the body (the pins are where Reset's are: the same targets).
  EXPECT_GT(farthest(keep.shape, reset.reference), 0.05);
  EXPECT_GT(keep.fastest, 0.5);
  EXPECT_LT((keep.shape.row(0) - reset.shape.row(0)).norm(), 1e-5f);
  EXPECT_EQ(keep.restored, 0u);
  EXPECT_EQ(reset.restored, 0u);
  EXPECT_TRUE(allFinite(keep.end));
  EXPECT_TRUE(allFinite(reset.end));
}

TEST(TeleportMode, BelowTheThresholdsBothModesAreTheSameBits) {
  const Outcome keep = run(TeleportMode::Keep, false), reset = run(TeleportMode::Reset, false);
  EXPECT_FALSE(keep.teleported);
  EXPECT_EQ(keep.shape, reset.shape);
  EXPECT_EQ(keep.end, reset.end);
}

// The core on its own: a crumpled, moving cape with self-collision put back in its reference pose, at rest,
// the pins on their targets, the self-contacts dropped until the next step searches again.
TEST(TeleportMode, ResetToReferenceRestoresTheRestShapeFittedToThePins) {
  cape::CapeSettings s;
  s.selfCollision = true;
  cape::Cape cape(cornerFabric(), s);
  ASSERT_TRUE(cape.ok());
  const cape::Points& rest = cape.fabric().restPositions();
  const cape::Vec3 left = rest.row(0).transpose(), right = rest.row(19).transpose();
  const std::size_t a = cape.pin(0, left), b = cape.pin(19, right);
  for (int f = 0; f < 30; ++f) cape.step(1.0f / 60.0f, {});
  // The pins move together (a quarter turn about the middle and 1 m up): the fit must turn the rest shape.
  const cape::Vec3 centre = 0.5f * (left + right);
  const Eigen::AngleAxisf turn(float(SIMD_HALF_PI), cape::Vec3::UnitY());
  const cape::Vec3 up(0.0f, 1.0f, 0.0f);
  cape.movePin(a, turn * (left - centre) + centre + up);
  cape.movePin(b, turn * (right - centre) + centre + up);
  for (int f = 0; f < 10; ++f) cape.step(1.0f / 60.0f, {});
  ASSERT_GT(cape.state().velocities.rowwise().norm().maxCoeff(), 0.1f);
  cape.resetToReference();
  const cape::Pose& ref = cape.referencePose();
  double worst = 0.0;
  for (Eigen::Index i = 1; i < rest.rows(); ++i)
    if (i != 19)
      worst = std::max(
          worst,
          double((cape.state().positions.row(i).transpose() - ref.apply(rest.row(i).transpose())).norm()));
  EXPECT_LT(worst, 1e-6) << "every free particle on the fitted rest shape";
  EXPECT_LT((cape.state().positions.row(0).transpose() - (turn * (left - centre) + centre + up)).norm(),
            1e-5f);
  EXPECT_LT((cape.state().positions.row(19).transpose() - (turn * (right - centre) + centre + up)).norm(),
            1e-5f);
  EXPECT_TRUE(cape.state().velocities.isZero());
  EXPECT_EQ(cape.selfContactCount(), 0u);
  // The rest shape turned with the pins (its normal, z at rest, now along x), up to the fit's pull towards
  // the pose it had (Cape::fitReferenceToPins: two pins leave the turn about their line open); the pins'
  // targets off the fitted shape by under a millimetre.
  EXPECT_LT((ref.rotation * cape::Vec3::UnitZ() - turn * cape::Vec3::UnitZ()).norm(), 5e-3f);
  EXPECT_LT((ref.apply(left) - (turn * (left - centre) + centre + up)).norm(), 1e-3f);
  cape.step(1.0f / 60.0f, {});
  EXPECT_TRUE(cape.state().positions.allFinite());
  EXPECT_EQ(cape.guard().total, 0u);
}
