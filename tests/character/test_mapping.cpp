// Joint mapping: the shipped names, the common-name fallback on another humanoid, signs found from the model,
// unmapped roles reported, and the shoulder rolls that bring T-pose and A-pose arms down (by name and by
// geometry, a ball shoulder of three revolute joints in any order).
#include "cape/character/Gait.h"
#include "cape/character/JointMapping.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

using namespace cape::character;

namespace {

// A different humanoid: other names, hip yaw and pitch joints, a knee turning the other way, no ankles and no
// elbows, and a shoulder turning about the vertical axis.
const char* kOtherHumanoid = R"(<robot name="other">
  <link name="Pelvis"><collision><geometry><box size="0.2 0.3 0.1"/></geometry></collision></link>
  <link name="l_hip_link"/>
  <link name="l_thigh"><collision><origin xyz="0 0 -0.2"/><geometry><cylinder radius="0.06" length="0.4"/></geometry></collision></link>
  <link name="l_shin"><collision><origin xyz="0 0 -0.2"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision></link>
  <link name="r_thigh"><collision><origin xyz="0 0 -0.2"/><geometry><cylinder radius="0.06" length="0.4"/></geometry></collision></link>
  <link name="r_shin"><collision><origin xyz="0 0 -0.2"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision></link>
  <link name="l_arm"><collision><origin xyz="0 0 -0.15"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
  <link name="r_arm"><collision><origin xyz="0 0 -0.15"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
  <joint name="l_hip_yaw" type="revolute"><parent link="Pelvis"/><child link="l_hip_link"/><origin xyz="0 0.1 0"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="l_hip_pitch" type="revolute"><parent link="l_hip_link"/><child link="l_thigh"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="1" effort="1" velocity="1"/></joint>
  <joint name="LKnee" type="revolute"><parent link="l_thigh"/><child link="l_shin"/><origin xyz="0 0 -0.4"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="hip_r" type="continuous"><parent link="Pelvis"/><child link="r_thigh"/><origin xyz="0 -0.1 0"/>
    <axis xyz="0 1 0"/></joint>
  <joint name="RightKnee" type="revolute"><parent link="r_thigh"/><child link="r_shin"/><origin xyz="0 0 -0.4"/>
    <axis xyz="0 -1 0"/><limit lower="-2.5" upper="0" effort="1" velocity="1"/></joint>
  <joint name="LeftShoulder" type="revolute"><parent link="Pelvis"/><child link="l_arm"/><origin xyz="0 0.25 0.5"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="right_shoulder_twist" type="revolute"><parent link="Pelvis"/><child link="r_arm"/><origin xyz="0 -0.25 0.5"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>)";

bool hasWarningWith(const JointMapping& m, const std::string& text) {
  return std::any_of(m.warnings().begin(), m.warnings().end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

std::string joined(const std::vector<std::string>& warnings) {
  std::string out;
  for (const std::string& w : warnings) out += w + "\n";
  return out;
}

// One revolute joint of a shoulder: its name and its axis in the URDF.
struct ShoulderJoint {
  std::string name;
  char axis;  // 'x' (forward), 'y' (left) or 'z' (up)
  double lower = -3.0, upper = 3.0;
};

// A torso (the root) and two arms from shoulders at (0, +-0.2, 0.5), built `spread` rad out from hanging
// down (pi/2: a T-pose, pi/4: an A-pose), each through its shoulder's revolute joints (root outwards, all at
// the shoulder point), an upper arm, an elbow flexing forward (for the hanging arm), a forearm and a hand.
std::string armsModel(double spread, const std::vector<ShoulderJoint>& left,
                      const std::vector<ShoulderJoint>& right) {
  std::ostringstream u;
  u << "<robot name=\"arms\">\n"
    << R"(<link name="torso"><collision><origin xyz="0 0 0.25"/><geometry><box size="0.2 0.3 0.5"/></geometry></collision></link>)"
    << "\n";
  for (int k = 0; k < 2; ++k) {
    const bool isLeft = k == 0;
    const std::string side = isLeft ? "left" : "right";
    const std::vector<ShoulderJoint>& joints = isLeft ? left : right;
    const double sy = isLeft ? 1.0 : -1.0;
    // The arm's direction d = (0, sy sin(spread), -cos(spread)); a cylinder along it turns by sy spread about
    // x.
    const double dy = sy * std::sin(spread), dz = -std::cos(spread);
    auto along = [&](double l) {
      std::ostringstream o;
      o << "0 " << l * dy << " " << l * dz;
      return o.str();
    };
    const std::string rpy = std::to_string(sy * spread) + " 0 0";
    u << "<link name=\"" << side << "_shoulder\"><collision><geometry><sphere radius=\"0.06\"/></geometry>"
      << "</collision></link>\n"
      << "<joint name=\"torso_to_" << side
      << "_shoulder\" type=\"fixed\"><parent link=\"torso\"/><child link=\"" << side
      << "_shoulder\"/><origin xyz=\"0 " << 0.2 * sy << " 0.5\"/></joint>\n";
    std::string parent = side + "_shoulder";
    for (std::size_t j = 0; j < joints.size(); ++j) {
      const std::string child =
          j + 1 == joints.size() ? side + "_upper_arm" : side + "_ball_" + std::to_string(j);
      if (j + 1 < joints.size()) u << "<link name=\"" << child << "\"/>\n";
      const char* axis = joints[j].axis == 'x' ? "1 0 0" : joints[j].axis == 'y' ? "0 1 0" : "0 0 1";
      u << "<joint name=\"" << joints[j].name << "\" type=\"revolute\"><parent link=\"" << parent
        << "\"/><child link=\"" << child << "\"/><axis xyz=\"" << axis << "\"/><limit lower=\""
        << joints[j].lower << "\" upper=\"" << joints[j].upper
        << "\" effort=\"1\" velocity=\"1\"/></joint>\n";
      parent = child;
    }
    // Elbow axis d x (forward): a positive turn moves the forearm forward, whatever the spread.
    std::ostringstream elbowAxis;
    elbowAxis << "0 " << dz << " " << -dy;
    u << "<link name=\"" << side << "_upper_arm\"><collision><origin xyz=\"" << along(0.15) << "\" rpy=\""
      << rpy << "\"/><geometry><cylinder radius=\"0.04\" length=\"0.3\"/></geometry></collision></link>\n"
      << "<link name=\"" << side << "_forearm\"><collision><origin xyz=\"" << along(0.13) << "\" rpy=\""
      << rpy << "\"/><geometry><cylinder radius=\"0.035\" length=\"0.26\"/></geometry></collision></link>\n"
      << "<link name=\"" << side << "_hand\"><collision><geometry><sphere radius=\"0.04\"/></geometry>"
      << "</collision></link>\n"
      << "<joint name=\"" << side << "_elbow\" type=\"revolute\"><parent link=\"" << side
      << "_upper_arm\"/><child link=\"" << side << "_forearm\"/><origin xyz=\"" << along(0.3)
      << "\"/><axis xyz=\"" << elbowAxis.str()
      << "\"/><limit lower=\"0\" upper=\"2.4\" effort=\"1\" velocity=\"1\"/></joint>\n"
      << "<joint name=\"" << side << "_wrist\" type=\"fixed\"><parent link=\"" << side
      << "_forearm\"/><child link=\"" << side << "_hand\"/><origin xyz=\"" << along(0.28) << "\"/></joint>\n";
  }
  u << "</robot>";
  return u.str();
}

UrdfModelPtr load(const std::string& urdf) {
  const UrdfLoadResult r = UrdfModel::fromString(urdf);
  EXPECT_TRUE(r.ok()) << r.status.message() << "\n" << urdf;
  return r.model;
}

std::string jointName(const UrdfModel& model, const JointMapping& m, GaitRole role) {
  const int j = m[role].joint;
  return j < 0 ? std::string("-") : model.joints()[static_cast<std::size_t>(j)].name;
}

// A link's origin in the URDF root frame (x forward, y left, z up) of a skeleton at the world origin.
Eigen::Vector3d inUrdf(const Skeleton& s, const std::string& link) {
  Eigen::Isometry3d pose;
  EXPECT_TRUE(s.linkPose(link, pose).ok()) << link;
  return Skeleton::urdfToWorld().transpose() * pose.translation();
}

// The standing pose with one role's anatomical angle changed.
void poseWith(const JointMapping& m, Skeleton& s, GaitRole role = GaitRole::LeftHip, double angle = 0.0) {
  std::array<double, kGaitRoleCount> angles = Gait::forScene(cape::SceneKind::Hang).standingAngles();
  angles[static_cast<std::size_t>(role)] += angle;
  s.resetJointPositions();
  Gait::setJoints(angles, m, s);
}

// Both arms hang down a little away from the body in the standing pose, swing forward with a positive
// shoulder angle, bend forward at the elbow, and lift sideways with a positive roll angle.
void expectArmsWork(const UrdfModelPtr& model, const JointMapping& m, const std::string& what) {
  Skeleton s(model);
  for (int side = 0; side < 2; ++side) {
    const std::string name = side == 0 ? "left" : "right";
    const double out = side == 0 ? 1.0 : -1.0;  // URDF y away from the body
    const auto role = [&](GaitRole left) { return static_cast<GaitRole>(static_cast<int>(left) + side); };
    poseWith(m, s);
    const Eigen::Vector3d shoulder = inUrdf(s, name + "_shoulder"), hand = inUrdf(s, name + "_hand");
    const Eigen::Vector3d arm = hand - shoulder;
    EXPECT_LT(arm.z(), -0.55) << what << " " << name;       // hanging down (the arm is 0.58 m)
    EXPECT_GT(out * arm.y(), 0.03) << what << " " << name;  // a little away from the body
    EXPECT_LT(out * arm.y(), 0.58 * std::sin(0.16)) << what << " " << name;  // only a little (0.12 rad)
    EXPECT_LT(std::abs(arm.x()), 0.01) << what << " " << name;
    poseWith(m, s, role(GaitRole::LeftShoulder), 0.4);
    EXPECT_GT(inUrdf(s, name + "_hand").x() - hand.x(), 0.15) << what << " " << name << ": shoulder forward";
    poseWith(m, s, role(GaitRole::LeftElbow), 0.6);
    EXPECT_GT(inUrdf(s, name + "_hand").x() - hand.x(), 0.1) << what << " " << name << ": elbow forward";
    poseWith(m, s, role(GaitRole::LeftShoulderRoll), 0.5);
    EXPECT_GT(out * (inUrdf(s, name + "_hand").y() - hand.y()), 0.1) << what << " " << name << ": roll out";
  }
}

}  // namespace

TEST(JointMapping, ShoulderRollsByNameAndGeometryBringTPoseArmsDown) {
  struct Names {
    const char* leftPitch;
    const char* leftRoll;
    const char* rightPitch;
    const char* rightRoll;
    bool rollFirst;
  };
  const Names cases[] = {
      {"left_shoulder_pitch", "left_shoulder_roll", "right_shoulder_pitch", "right_shoulder_roll", false},
      {"l_shoulder_pitch_joint", "l_shoulder_roll_joint", "r_shoulder_pitch_joint", "r_shoulder_roll_joint",
       true},
      {"LShoulderPitch", "LShoulderRoll", "RShoulderPitch", "RShoulderRoll", false},
      {"l_arm_shy", "l_arm_shx", "r_arm_shy", "r_arm_shx", true},
      {"leftShoulderPitch", "leftShoulderRoll", "rightShoulderPitch", "rightShoulderRoll", false},
      {"left_shoulder_1", "left_shoulder_2", "right_shoulder_1", "right_shoulder_2", false},  // geometry only
  };
  for (const Names& n : cases) {
    // Pitch then roll; or roll then a joint about URDF z, which the roll turns into the side-to-side axis (a
    // joint about y after the roll would lie along the T-pose arm: a twist).
    auto arm = [&](const char* pitch, const char* roll) {
      return n.rollFirst ? std::vector<ShoulderJoint>{{roll, 'x'}, {pitch, 'z'}}
                         : std::vector<ShoulderJoint>{{pitch, 'y'}, {roll, 'x'}};
    };
    const UrdfModelPtr model =
        load(armsModel(std::acos(-1.0) / 2, arm(n.leftPitch, n.leftRoll), arm(n.rightPitch, n.rightRoll)));
    ASSERT_TRUE(model);
    const JointMapping m = JointMapping::automatic(model);
    EXPECT_EQ(jointName(*model, m, GaitRole::LeftShoulderRoll), n.leftRoll);
    EXPECT_EQ(jointName(*model, m, GaitRole::RightShoulderRoll), n.rightRoll);
    EXPECT_EQ(jointName(*model, m, GaitRole::LeftShoulder), n.leftPitch);
    EXPECT_EQ(jointName(*model, m, GaitRole::RightShoulder), n.rightPitch);
    EXPECT_EQ(jointName(*model, m, GaitRole::LeftElbow), "left_elbow");
    EXPECT_FALSE(hasWarningWith(m, "cannot tell")) << n.leftRoll << "\n" << joined(m.warnings());
    EXPECT_FALSE(hasWarningWith(m, "arm")) << n.leftRoll << "\n" << joined(m.warnings());
    // Straight down from a T-pose is a quarter turn.
    EXPECT_NEAR(std::abs(m[GaitRole::LeftShoulderRoll].neutral), std::acos(-1.0) / 2, 1e-9) << n.leftRoll;
    expectArmsWork(model, m, n.leftRoll);
  }
}

TEST(JointMapping, BallShoulderOfThreeRevoluteJointsInAnyOrder) {
  // Numbered joints (no name says which is which): the roll is found by its forward axis, and the shoulder
  // is whichever joint swings the hanging arm forward once the roll has brought it down.
  const char* orders[] = {"yxz", "xzy", "zyx", "xyz", "zxy", "yzx"};
  for (double spread : {std::acos(-1.0) / 2, std::acos(-1.0) / 4}) {
    for (const char* order : orders) {
      auto arm = [&](const std::string& side) {
        std::vector<ShoulderJoint> j;
        for (int k = 0; k < 3; ++k) j.push_back({side + "_shoulder_" + std::to_string(k + 1), order[k]});
        return j;
      };
      const UrdfModelPtr model = load(armsModel(spread, arm("left"), arm("right")));
      ASSERT_TRUE(model);
      const JointMapping m = JointMapping::byCommonNames(model);
      const std::string what = std::string(order) + " spread " + std::to_string(spread);
      const int roll = static_cast<int>(std::string(order).find('x'));
      EXPECT_EQ(jointName(*model, m, GaitRole::LeftShoulderRoll), "left_shoulder_" + std::to_string(roll + 1))
          << what;
      EXPECT_FALSE(hasWarningWith(m, "elbow")) << what << "\n" << joined(m.warnings());
      if (spread > 1.5 && std::string(order) == "zxy") {
        // Gimbal lock: once the roll has brought the T-pose arm down, the joints about z (before it) and y
        // (after it, turned with the arm) both lie along the arm. No single joint swings it forward: the
        // shoulder is left unmapped, said, and the arms still hang down.
        EXPECT_EQ(m[GaitRole::LeftShoulder].joint, -1) << what;
        EXPECT_TRUE(hasWarningWith(m, "left shoulder: no candidate turns about the side-to-side axis"))
            << joined(m.warnings());
        Skeleton s(model);
        poseWith(m, s);
        EXPECT_LT(inUrdf(s, "left_hand").z() - inUrdf(s, "left_shoulder").z(), -0.55) << what;
        continue;
      }
      EXPECT_FALSE(hasWarningWith(m, "shoulder")) << what << "\n" << joined(m.warnings());
      expectArmsWork(model, m, what);
    }
  }
}

TEST(JointMapping, ArmsThatCannotComeDownAreSaid) {
  const double tPose = std::acos(-1.0) / 2;
  // No roll joint at all.
  UrdfModelPtr model =
      load(armsModel(tPose, {{"left_shoulder_pitch", 'y'}}, {{"right_shoulder_pitch", 'y'}}));
  ASSERT_TRUE(model);
  JointMapping m = JointMapping::automatic(model);
  EXPECT_TRUE(hasWarningWith(m, "left arm: 1.6 rad from hanging straight down")) << joined(m.warnings());
  EXPECT_TRUE(hasWarningWith(m, "right arm")) << joined(m.warnings());
  // A roll joint whose limits stop it half way.
  model = load(armsModel(tPose, {{"left_shoulder_pitch", 'y'}, {"left_shoulder_roll", 'x', -0.7, 0.7}},
                         {{"right_shoulder_pitch", 'y'}, {"right_shoulder_roll", 'x'}}));
  ASSERT_TRUE(model);
  m = JointMapping::automatic(model);
  EXPECT_TRUE(
      hasWarningWith(m, "left shoulder roll: the limits of joint 'left_shoulder_roll' keep the arm 0.87"))
      << joined(m.warnings());
  EXPECT_FALSE(hasWarningWith(m, "right shoulder roll")) << joined(m.warnings());
}

TEST(JointMapping, ShippedHumanoidIsFullyMappedWithPositiveSigns) {
  const UrdfModelPtr model = UrdfModel::humanoid().model;
  const JointMapping m = JointMapping::automatic(model);
  EXPECT_EQ(m.unmappedRoles(),
            (std::vector<GaitRole>{GaitRole::LeftShoulderRoll, GaitRole::RightShoulderRoll}));
  EXPECT_TRUE(m.warnings().empty()) << m.warnings().front();
  const auto names = JointMapping::shippedHumanoidNames();
  for (int r = 0; r < kGaitRoleCount; ++r) {
    const JointMapping::Entry& e = m.entries()[static_cast<std::size_t>(r)];
    if (JointMapping::isShoulderRoll(static_cast<GaitRole>(r))) {
      // Its arms hang down already, from pitch joints alone: no shoulder rolls, and nothing said.
      EXPECT_EQ(e.joint, -1);
      EXPECT_TRUE(names[static_cast<std::size_t>(r)].empty());
      continue;
    }
    EXPECT_EQ(model->joints()[static_cast<std::size_t>(e.joint)].name, names[static_cast<std::size_t>(r)]);
    EXPECT_EQ(e.sign, 1.0) << toString(static_cast<GaitRole>(r));  // the URDF is written in the gait's sense
    EXPECT_EQ(e.neutral, 0.0);
  }
  // The common-name fallback finds the same joints and signs on the shipped model.
  const JointMapping fallback = JointMapping::byCommonNames(model);
  for (int r = 0; r < kGaitRoleCount; ++r) {
    EXPECT_EQ(fallback.entries()[static_cast<std::size_t>(r)].joint,
              m.entries()[static_cast<std::size_t>(r)].joint);
    EXPECT_EQ(fallback.entries()[static_cast<std::size_t>(r)].sign,
              m.entries()[static_cast<std::size_t>(r)].sign);
  }
}

TEST(JointMapping, CommonNamesOnAnotherHumanoid) {
  const UrdfLoadResult r = UrdfModel::fromString(kOtherHumanoid);
  ASSERT_TRUE(r.ok()) << r.status.message();
  const JointMapping m = JointMapping::automatic(r.model);
  auto joint = [&](GaitRole role) {
    const int j = m[role].joint;
    return j < 0 ? std::string("-") : r.model->joints()[static_cast<std::size_t>(j)].name;
  };
  EXPECT_EQ(joint(GaitRole::LeftHip), "l_hip_pitch");  // the pitch joint, not the yaw
  EXPECT_EQ(joint(GaitRole::RightHip), "hip_r");
  EXPECT_EQ(joint(GaitRole::LeftKnee), "LKnee");
  EXPECT_EQ(joint(GaitRole::RightKnee), "RightKnee");
  EXPECT_EQ(joint(GaitRole::LeftShoulder), "LeftShoulder");
  // Signs: about +y a positive angle swings a hanging limb backwards.
  EXPECT_EQ(m[GaitRole::LeftHip].sign, -1.0);
  EXPECT_EQ(m[GaitRole::RightHip].sign, -1.0);
  EXPECT_EQ(m[GaitRole::LeftKnee].sign, 1.0);
  EXPECT_EQ(m[GaitRole::RightKnee].sign, -1.0);
  EXPECT_EQ(m[GaitRole::LeftShoulder].sign, -1.0);

  // Unmapped: no ankles, no elbows, and a right shoulder that only twists.
  std::vector<GaitRole> unmapped = m.unmappedRoles();
  EXPECT_EQ(unmapped,
            (std::vector<GaitRole>{GaitRole::LeftAnkle, GaitRole::RightAnkle, GaitRole::RightShoulder,
                                   GaitRole::LeftElbow, GaitRole::RightElbow, GaitRole::LeftShoulderRoll,
                                   GaitRole::RightShoulderRoll}));
  EXPECT_TRUE(hasWarningWith(m, "left ankle"));
  EXPECT_TRUE(hasWarningWith(m, "right_shoulder_twist"));

  // Walking it: legs swing the right way (the left thigh forward, towards -Z in the world, at t = 1/4
  // period), and the knees bend the right way inside their limits.
  const Gait gait = Gait::forScene(cape::SceneKind::Walk);
  Skeleton s(r.model);
  gait.apply(0.25, m, s);
  Eigen::Isometry3d shin;
  ASSERT_TRUE(s.linkPose("l_shin", shin).ok());
  EXPECT_LT(shin.translation().z(), -0.15);
  double knee = 0.0;
  ASSERT_TRUE(s.jointPosition("RightKnee", knee).ok());
  EXPECT_LE(knee, 0.0);
  const int twist = r.model->findJoint("right_shoulder_twist");
  EXPECT_EQ(s.jointPosition(twist), s.restPosition(twist));  // unmapped: at rest
}

TEST(JointMapping, ExplicitNamesReportUnknownOnes) {
  const UrdfModelPtr model = UrdfModel::humanoid().model;
  auto names = JointMapping::shippedHumanoidNames();
  names[static_cast<std::size_t>(GaitRole::LeftElbow)] = "no_such_joint";
  names[static_cast<std::size_t>(GaitRole::RightElbow)] = "pelvis_joint";  // fixed
  const JointMapping m = JointMapping::fromNames(model, names);
  EXPECT_EQ(m.unmappedRoles(),
            (std::vector<GaitRole>{GaitRole::LeftElbow, GaitRole::RightElbow, GaitRole::LeftShoulderRoll,
                                   GaitRole::RightShoulderRoll}));
  EXPECT_TRUE(hasWarningWith(m, "no_such_joint"));
  EXPECT_TRUE(hasWarningWith(m, "pelvis_joint"));
}
