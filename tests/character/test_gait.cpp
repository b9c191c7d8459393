// The gait: the scenes' root path and leg angle, periodic joint trajectories inside the limits, arm swing
// against the legs, and the shoulders (the cape's anchors) riding rigidly with the character frame.
#include "cape/character/Gait.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace cape::character;

namespace {

constexpr double kPi = 3.14159265358979323846;

UrdfModelPtr humanoid() {
  return UrdfModel::humanoid().model;
}

// A link pose in the character frame (root and bob removed).
Eigen::Isometry3d inCharacterFrame(const Skeleton& s, int link) {
  return s.rootTransform().inverse() * s.linkPose(link);
}

}  // namespace

TEST(Gait, JointTrajectoriesArePeriodic) {
  const UrdfModelPtr model = humanoid();
  const JointMapping mapping = JointMapping::automatic(model);
  for (cape::SceneKind scene : {cape::SceneKind::Walk, cape::SceneKind::SprintTurn}) {
    const Gait gait = Gait::forScene(scene);
    const double period = gait.period();
    EXPECT_NEAR(period, scene == cape::SceneKind::Walk ? 1.0 : 0.4, 1e-9);
    Skeleton a(model), b(model);
    double worst = 0.0;
    for (double t = 0.0; t < 10.0; t += 0.0137) {
      gait.apply(t, mapping, a);
      gait.apply(t + period, mapping, b);
      for (int j = 0; j < a.jointCount(); ++j)
        worst = std::max(worst, std::abs(a.jointPosition(j) - b.jointPosition(j)));
      worst = std::max(worst, std::abs(gait.rootAt(t).bob - gait.rootAt(t + period).bob));
      for (int l = 0; l < a.linkCount(); ++l) {
        worst = std::max(
            worst, (inCharacterFrame(a, l).matrix() - inCharacterFrame(b, l).matrix()).cwiseAbs().maxCoeff());
      }
    }
    EXPECT_LT(worst, 1e-6) << cape::toString(scene);
  }
}

TEST(Gait, StaysInsideJointLimitsForTenSeconds) {
  const UrdfModelPtr model = humanoid();
  const JointMapping mapping = JointMapping::automatic(model);
  for (cape::SceneKind scene : {cape::SceneKind::Walk, cape::SceneKind::SprintTurn, cape::SceneKind::Hang}) {
    const Gait gait = Gait::forScene(scene);
    Skeleton s(model);
    int moved = 0;
    for (int k = 0; k <= 2400; ++k) {  // 10 s at 1/240 s
      gait.apply(k / 240.0, mapping, s);
      for (int j = 0; j < s.jointCount(); ++j) {
        const JointDesc& d = model->joints()[static_cast<std::size_t>(j)];
        if (!d.hasLimits) continue;
        ASSERT_GE(s.jointPosition(j), d.lower) << d.name;
        ASSERT_LE(s.jointPosition(j), d.upper) << d.name;
        moved += s.jointPosition(j) != s.restPosition(j) ? 1 : 0;
      }
    }
    if (scene == cape::SceneKind::Hang) {
      EXPECT_EQ(moved, 0);  // standing still: the rest pose
    } else {
      EXPECT_GT(moved, 0);
    }
  }
}

TEST(Gait, ReproducesTheScenesRootPathAndLegAngle) {
  const UrdfModelPtr model = humanoid();
  const JointMapping mapping = JointMapping::automatic(model);
  const int leftHip = model->findJoint("left_hip_pitch"), rightHip = model->findJoint("right_hip_pitch");
  const int leftThigh = model->findLink("left_thigh");
  for (cape::SceneKind scene : {cape::SceneKind::Walk, cape::SceneKind::SprintTurn}) {
    const cape::MotionDesc motion = cape::MotionDesc::forScene(scene);
    const Gait gait = Gait::forScene(scene);
    Skeleton s(model);
    for (double t = 0.0; t <= 10.0; t += 0.05) {
      gait.apply(t, mapping, s);
      const cape::BodyPose body = cape::motionAt(motion, t);
      const cape::Pose frame = body.frame();
      // Root: the very frame the simple body uses.
      EXPECT_LT((s.rootTransform().translation() - frame.position.cast<double>()).norm(), 1e-9) << t;
      const Eigen::Matrix3d yaw = Eigen::AngleAxisd(body.yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
      EXPECT_LT((s.rootTransform().linear() - yaw).cwiseAbs().maxCoeff(), 1e-9) << t;
      // Hips: left +0.5236 sin(2 pi f t), right the negative (docs/SCENES.md), within the float of motionAt.
      EXPECT_NEAR(s.jointPosition(leftHip), body.legAngle, 1e-6) << t;
      EXPECT_NEAR(s.jointPosition(rightHip), -body.legAngle, 1e-6) << t;
      // The left thigh points where the simple body's left leg points: down, turned by legAngle about X
      // (towards -Z, forward), in the character frame.
      const Eigen::Vector3d down = inCharacterFrame(s, leftThigh).linear() * -Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d expected(0.0, -std::cos(body.legAngle), -std::sin(body.legAngle));
      EXPECT_LT((down - expected).norm(), 1e-6) << t;
    }
  }
}

TEST(Gait, ShouldersRideWithTheCharacterFrame) {
  // The cape's anchors must not swing with the arms: at (-+0.22, 1.52, 0) in the character frame, always.
  const UrdfModelPtr model = humanoid();
  const JointMapping mapping = JointMapping::automatic(model);
  const Gait gait = Gait::forScene(cape::SceneKind::SprintTurn);
  Skeleton s(model);
  const int left = model->findLink("left_shoulder"), right = model->findLink("right_shoulder");
  for (double t = 0.0; t <= 4.0; t += 0.1) {
    gait.apply(t, mapping, s);
    EXPECT_LT((inCharacterFrame(s, left).translation() - Eigen::Vector3d(-0.22, 1.52, 0)).norm(), 1e-9);
    EXPECT_LT((inCharacterFrame(s, right).translation() - Eigen::Vector3d(0.22, 1.52, 0)).norm(), 1e-9);
  }
}

TEST(Gait, ArmsSwingAgainstTheLegsAndKneesBendInSwing) {
  const Gait gait = Gait::forScene(cape::SceneKind::Walk);
  const auto a = gait.anglesAt(0.25);  // left leg fully forward
  auto at = [&](GaitRole r) { return a[static_cast<std::size_t>(r)]; };
  EXPECT_NEAR(at(GaitRole::LeftHip), 0.5236, 1e-6);
  EXPECT_LT(at(GaitRole::LeftShoulder), 0.0);   // left arm back
  EXPECT_GT(at(GaitRole::RightShoulder), 0.0);  // right arm forward
  EXPECT_GT(at(GaitRole::RightElbow), at(GaitRole::LeftElbow));
  const auto mid = gait.anglesAt(0.0);  // left leg passing under the body, swinging forward
  EXPECT_GT(mid[static_cast<std::size_t>(GaitRole::LeftKnee)],
            mid[static_cast<std::size_t>(GaitRole::RightKnee)] + 0.5);
  // Sprinting bends knees and elbows more than walking.
  const auto sprint = Gait::forScene(cape::SceneKind::SprintTurn).anglesAt(0.0);
  EXPECT_GT(sprint[static_cast<std::size_t>(GaitRole::LeftKnee)],
            mid[static_cast<std::size_t>(GaitRole::LeftKnee)]);
  EXPECT_GT(sprint[static_cast<std::size_t>(GaitRole::LeftElbow)],
            mid[static_cast<std::size_t>(GaitRole::LeftElbow)]);
}

TEST(Gait, ConstantTurnRateFollowsTheArc) {
  const GaitParams p = GaitParams::forSpeed(2.0, 1.5, 0.5);  // 2 m/s, turning left at 0.5 rad/s
  const Gait gait(p);
  const double h = 1e-4;
  for (double t = 0.3; t < 10.0; t += 0.7) {
    const RootPose r = gait.rootAt(t);
    EXPECT_NEAR(r.yaw, std::remainder(0.5 * t, 2 * kPi), 1e-12);
    // Velocity = speed along the heading (-sin yaw, 0, -cos yaw).
    const Eigen::Vector3d v = (gait.rootAt(t + h).position - gait.rootAt(t - h).position) / (2 * h);
    EXPECT_LT((v - 2.0 * Eigen::Vector3d(-std::sin(0.5 * t), 0, -std::cos(0.5 * t))).norm(), 1e-6) << t;
  }
  // No turn: exactly the core's straight line.
  const Gait straight(GaitParams::forSpeed(1.4, 1.0));
  const cape::BodyPose b = cape::motionAt(cape::MotionDesc::forScene(cape::SceneKind::Walk), 3.3);
  EXPECT_LT((straight.rootAt(3.3).position - b.position.cast<double>()).norm(), 1e-12);
}
