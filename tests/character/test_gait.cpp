// The gait: the scenes' root path and leg angle, periodic joint trajectories inside the limits, arm swing
// against the legs, the shoulders (the cape's anchors) riding rigidly with the character frame, and arms
// held down at the sides of models built in a T-pose or an A-pose.
#include "cape/character/Character.h"
#include "cape/character/Gait.h"

#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <sstream>
#include <string>

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

// A humanoid rooted at its pelvis (legs of 0.8 m, feet below) whose arms are built `spread` rad out from
// hanging down (pi/2: a T-pose, pi/4: an A-pose), from shoulders at (0, +-0.2, 0.45) above the pelvis
// through a pitch and a roll joint (URDF y and x axes), an elbow flexing forward, and hands 0.58 m out.
std::string spreadArmsHumanoid(double spread) {
  std::ostringstream u;
  u << R"(<robot name="spread_arms">
  <link name="pelvis"><collision><geometry><box size="0.2 0.3 0.14"/></geometry></collision></link>
  <link name="torso"><collision><origin xyz="0 0 0.25"/><geometry><box size="0.2 0.34 0.5"/></geometry></collision></link>
  <joint name="waist" type="fixed"><parent link="pelvis"/><child link="torso"/></joint>)";
  for (int k = 0; k < 2; ++k) {
    const std::string side = k == 0 ? "left" : "right";
    const double sy = k == 0 ? 1.0 : -1.0, dy = sy * std::sin(spread), dz = -std::cos(spread);
    auto along = [&](double l) {
      std::ostringstream o;
      o << "0 " << l * dy << " " << l * dz;
      return o.str();
    };
    std::ostringstream rpy, elbowAxis;
    rpy << sy * spread << " 0 0";
    elbowAxis << "0 " << dz << " " << -dy;
    const std::string limit = R"(<limit lower="-3" upper="3" effort="1" velocity="1"/>)";
    u << R"(
  <link name=")"
      << side << R"(_shoulder"><collision><geometry><sphere radius="0.06"/></geometry></collision></link>
  <joint name="torso_to_)"
      << side << R"(_shoulder" type="fixed"><parent link="torso"/><child link=")" << side
      << R"(_shoulder"/><origin xyz="0 )" << 0.2 * sy << R"( 0.45"/></joint>
  <link name=")"
      << side << R"(_shoulder_pitch_link"/>
  <joint name=")"
      << side << R"(_shoulder_pitch" type="revolute"><parent link=")" << side
      << R"(_shoulder"/><child link=")" << side << R"(_shoulder_pitch_link"/><axis xyz="0 1 0"/>)" << limit
      << R"(</joint>
  <link name=")"
      << side << R"(_upper_arm"><collision><origin xyz=")" << along(0.15) << R"(" rpy=")" << rpy.str()
      << R"("/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
  <joint name=")"
      << side << R"(_shoulder_roll" type="revolute"><parent link=")" << side
      << R"(_shoulder_pitch_link"/><child link=")" << side << R"(_upper_arm"/><axis xyz="1 0 0"/>)" << limit
      << R"(</joint>
  <link name=")"
      << side << R"(_forearm"><collision><origin xyz=")" << along(0.13) << R"(" rpy=")" << rpy.str()
      << R"("/><geometry><cylinder radius="0.035" length="0.26"/></geometry></collision></link>
  <joint name=")"
      << side << R"(_elbow" type="revolute"><parent link=")" << side << R"(_upper_arm"/><child link=")"
      << side << R"(_forearm"/><origin xyz=")" << along(0.3) << R"("/><axis xyz=")" << elbowAxis.str()
      << R"("/><limit lower="0" upper="2.4" effort="1" velocity="1"/></joint>
  <link name=")"
      << side << R"(_hand"><collision><geometry><sphere radius="0.04"/></geometry></collision></link>
  <joint name=")"
      << side << R"(_wrist" type="fixed"><parent link=")" << side << R"(_forearm"/><child link=")" << side
      << R"(_hand"/><origin xyz=")" << along(0.28) << R"("/></joint>
  <link name=")"
      << side
      << R"(_thigh"><collision><origin xyz="0 0 -0.2"/><geometry><cylinder radius="0.06" length="0.4"/></geometry></collision></link>
  <link name=")"
      << side
      << R"(_shin"><collision><origin xyz="0 0 -0.2"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision></link>
  <link name=")"
      << side
      << R"(_foot"><collision><origin xyz="0.04 0 -0.05"/><geometry><box size="0.22 0.1 0.06"/></geometry></collision></link>
  <joint name=")"
      << side << R"(_hip" type="revolute"><parent link="pelvis"/><child link=")" << side
      << R"(_thigh"/><origin xyz="0 )" << 0.1 * sy << R"( -0.05"/><axis xyz="0 1 0"/>)" << limit
      << R"(</joint>
  <joint name=")"
      << side << R"(_knee" type="revolute"><parent link=")" << side << R"(_thigh"/><child link=")" << side
      << R"(_shin"/><origin xyz="0 0 -0.4"/><axis xyz="0 1 0"/><limit lower="0" upper="2.4" effort="1" velocity="1"/></joint>
  <joint name=")"
      << side << R"(_ankle" type="revolute"><parent link=")" << side << R"(_shin"/><child link=")" << side
      << R"(_foot"/><origin xyz="0 0 -0.4"/><axis xyz="0 1 0"/>)" << limit << R"(</joint>)";
  }
  u << "\n</robot>";
  return u.str();
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

TEST(Gait, TPoseAndAPoseArmsWalkHangingDown) {
  // The issue's test: while walking (and sprinting) through gait cycles, both hands stay below the
  // shoulders every frame, and a little out from the body (clear of the torso and the thighs).
  for (double spread : {kPi / 2, kPi / 4}) {
    const UrdfLoadResult r = UrdfModel::fromString(spreadArmsHumanoid(spread));
    ASSERT_TRUE(r.ok()) << r.status.message();
    for (cape::SceneKind scene : {cape::SceneKind::Walk, cape::SceneKind::SprintTurn}) {
      btDefaultCollisionConfiguration config;
      btCollisionDispatcher dispatcher(&config);
      btDbvtBroadphase broadphase;
      btSequentialImpulseConstraintSolver solver;
      btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
      const Gait gait = Gait::forScene(scene);
      const CharacterResult made = Character::create(r.model, world, gait);
      ASSERT_TRUE(made.ok()) << made.status.message();
      Character& c = *made.character;
      const JointMapping& m = c.mapping();
      EXPECT_EQ(m[GaitRole::LeftShoulderRoll].joint, r.model->findJoint("left_shoulder_roll"));
      EXPECT_EQ(m[GaitRole::RightShoulderRoll].joint, r.model->findJoint("right_shoulder_roll"));
      EXPECT_EQ(m[GaitRole::LeftShoulder].joint, r.model->findJoint("left_shoulder_pitch"));
      EXPECT_NEAR(c.rootHeight(), 0.93, 1e-6);
      const std::string what = std::string(cape::toString(scene)) + " spread " + std::to_string(spread);
      double lowestDrop = 1.0, leastOut = 1.0, widestSwing = 0.0;
      for (int k = 0; k <= 2 * 240; ++k) {  // two walk cycles, five sprint cycles, at 1/240 s
        const double t = k / 240.0;
        c.advanceTo(t);
        for (const char* side : {"left", "right"}) {
          const Eigen::Vector3d shoulder =
              inCharacterFrame(c.skeleton(), r.model->findLink(std::string(side) + "_shoulder"))
                  .translation();
          const Eigen::Vector3d hand =
              inCharacterFrame(c.skeleton(), r.model->findLink(std::string(side) + "_hand")).translation();
          ASSERT_LT(hand.y(), shoulder.y()) << what << " " << side << " t " << t;
          lowestDrop = std::min(lowestDrop, shoulder.y() - hand.y());
          // Out: the character frame's x is the right side (the character faces -Z).
          const double out = (std::string(side) == "left" ? -1.0 : 1.0) * hand.x();
          leastOut = std::min(leastOut, out);
          widestSwing = std::max(widestSwing, std::abs(hand.z() - shoulder.z()));
        }
      }
      // Well below: the arms hang and swing (sprinting, the bent elbows lift the hands to 0.1 m below).
      EXPECT_GT(lowestDrop, scene == cape::SceneKind::Walk ? 0.35 : 0.05) << what;
      EXPECT_GT(leastOut, 0.22) << what;    // the torso's half width is 0.17, the thigh's outside 0.16
      EXPECT_GT(widestSwing, 0.1) << what;  // and they swing forward and back
    }
  }
}
