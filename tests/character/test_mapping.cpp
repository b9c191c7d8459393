// Joint mapping: the shipped names, the common-name fallback on another humanoid, signs found from the model,
// and unmapped roles reported.
#include "cape/character/Gait.h"
#include "cape/character/JointMapping.h"

#include <gtest/gtest.h>

#include <algorithm>

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

}  // namespace

TEST(JointMapping, ShippedHumanoidIsFullyMappedWithPositiveSigns) {
  const UrdfModelPtr model = UrdfModel::humanoid().model;
  const JointMapping m = JointMapping::automatic(model);
  EXPECT_TRUE(m.unmappedRoles().empty());
  EXPECT_TRUE(m.warnings().empty()) << m.warnings().front();
  const auto names = JointMapping::shippedHumanoidNames();
  for (int r = 0; r < kGaitRoleCount; ++r) {
    const JointMapping::Entry& e = m.entries()[static_cast<std::size_t>(r)];
    EXPECT_EQ(model->joints()[static_cast<std::size_t>(e.joint)].name, names[static_cast<std::size_t>(r)]);
    EXPECT_EQ(e.sign, 1.0) << toString(static_cast<GaitRole>(r));  // the URDF is written in the gait's sense
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
                                   GaitRole::LeftElbow, GaitRole::RightElbow}));
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
  EXPECT_EQ(m.unmappedRoles(), (std::vector<GaitRole>{GaitRole::LeftElbow, GaitRole::RightElbow}));
  EXPECT_TRUE(hasWarningWith(m, "no_such_joint"));
  EXPECT_TRUE(hasWarningWith(m, "pelvis_joint"));
}
