// Forward kinematics against poses computed by hand, the Z-up to Y-up mapping, scale and joint errors.
#include "cape/character/Skeleton.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace cape::character;

namespace {

constexpr double kPi = 3.14159265358979323846;

// base --(j1: revolute about z, at x = 1)--> arm --(j2: prismatic along x, at z = 0.5)--> tip
const char* kTwoLink = R"(<robot name="two">
  <link name="base"/>
  <link name="arm"><collision><origin xyz="0.5 0 0"/><geometry><box size="1 0.2 0.1"/></geometry></collision></link>
  <link name="tip"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="1 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j2" type="prismatic"><parent link="arm"/><child link="tip"/><origin xyz="0 0 0.5"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.4" effort="1" velocity="1"/></joint>
</robot>)";

Skeleton load(const std::string& xml) {
  const UrdfLoadResult r = UrdfModel::fromString(xml);
  EXPECT_TRUE(r.ok()) << r.status.message();
  return Skeleton(r.model);
}

Eigen::Vector3d position(const Skeleton& s, const std::string& link) {
  Eigen::Isometry3d pose;
  EXPECT_TRUE(s.linkPose(link, pose).ok()) << link;
  return pose.translation();
}

}  // namespace

TEST(Skeleton, UrdfAxesMapIntoTheYUpWorld) {
  const Eigen::Matrix3d m = Skeleton::urdfToWorld();
  EXPECT_TRUE((m * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitZ()));  // forward -> -Z
  EXPECT_TRUE((m * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitX()));  // left -> -X
  EXPECT_TRUE((m * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitY()));   // up -> +Y
  EXPECT_NEAR(m.determinant(), 1.0, 1e-15);
}

TEST(Skeleton, ForwardKinematicsMatchesHandComputedPoses) {
  Skeleton s = load(kTwoLink);
  ASSERT_TRUE(s.setJointPosition("j1", kPi / 2).ok());
  ASSERT_TRUE(s.setJointPosition("j2", 0.3).ok());
  // URDF frame: arm at (1, 0, 0) turned 90 degrees about z; tip = (1,0,0) + Rz(90) (0.3, 0, 0.5) = (1, 0.3,
  // 0.5). World: x -> -Z, y -> -X, z -> +Y gives (-0.3, 0.5, -1).
  EXPECT_TRUE(position(s, "base").isZero(1e-15));
  EXPECT_TRUE(position(s, "arm").isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
  EXPECT_TRUE(position(s, "tip").isApprox(Eigen::Vector3d(-0.3, 0.5, -1), 1e-12));
  // The arm's URDF x axis, turned to URDF +y, is world -X.
  Eigen::Isometry3d arm;
  ASSERT_TRUE(s.linkPose("arm", arm).ok());
  EXPECT_TRUE((arm.linear() * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitX(), 1e-12));

  // Root at (2, 0, 3) turned 90 degrees about +Y: (x, y, z) -> (z, y, -x), then translated.
  s.setRoot(Eigen::Vector3d(2, 0, 3), kPi / 2);
  EXPECT_TRUE(position(s, "tip").isApprox(Eigen::Vector3d(2 - 1, 0.5, 3 + 0.3), 1e-12));

  // Shapes in the world: the arm's box centre is 0.5 along the arm's x.
  s.setRoot(Eigen::Vector3d::Zero(), 0.0);
  const std::vector<WorldShape> shapes = s.worldShapes();
  ASSERT_EQ(shapes.size(), 2u);
  EXPECT_EQ(*shapes[0].linkName, "arm");
  EXPECT_EQ(shapes[0].shape->type, ShapeType::Box);
  EXPECT_TRUE(shapes[0].pose.translation().isApprox(Eigen::Vector3d(-0.5, 0, -1), 1e-12));
}

TEST(Skeleton, UniformScaleScalesLengthsNotAngles) {
  Skeleton s = load(kTwoLink);
  ASSERT_TRUE(s.setScale(2.0).ok());
  ASSERT_TRUE(s.setJointPosition("j1", kPi / 2).ok());
  ASSERT_TRUE(s.setJointPosition("j2", 0.3).ok());
  EXPECT_TRUE(position(s, "tip").isApprox(Eigen::Vector3d(-0.6, 1.0, -2), 1e-12));
  EXPECT_DOUBLE_EQ(s.shapes(2)[0].radius, 0.10);
  EXPECT_TRUE(s.shapes(1)[0].halfExtents.isApprox(Eigen::Vector3d(1.0, 0.2, 0.1)));
  EXPECT_EQ(s.setScale(0.0).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(s.setScale(NAN).code(), ErrorCode::InvalidArgument);
  EXPECT_DOUBLE_EQ(s.scale(), 2.0);
}

TEST(Skeleton, JointErrorsAreValuesNotCrashes) {
  Skeleton s = load(kTwoLink);
  EXPECT_EQ(s.setJointPosition("no_such_joint", 0.1).code(), ErrorCode::UnknownJoint);
  EXPECT_EQ(s.setJointPosition(99, 0.1).code(), ErrorCode::UnknownJoint);
  EXPECT_EQ(s.setJointPosition("j1", INFINITY).code(), ErrorCode::InvalidArgument);
  double q = -1.0;
  EXPECT_EQ(s.jointPosition("nope", q).code(), ErrorCode::UnknownJoint);
  Eigen::Isometry3d pose;
  EXPECT_EQ(s.linkPose("nope", pose).code(), ErrorCode::UnknownLink);

  // Outside the limits: clamped, applied, and reported.
  const Status st = s.setJointPosition("j2", 1.0);
  EXPECT_EQ(st.code(), ErrorCode::OutsideLimits);
  EXPECT_NE(st.message().find("clamped"), std::string::npos);
  ASSERT_TRUE(s.jointPosition("j2", q).ok());
  EXPECT_DOUBLE_EQ(q, 0.4);

  const Skeleton h(UrdfModel::humanoid().model);
  Skeleton hs = h;
  EXPECT_EQ(hs.setJointPosition("pelvis_joint", 0.1).code(), ErrorCode::NotMovable);
}

TEST(Skeleton, HumanoidStandsInTheWorldAsTheScenesSay) {
  Skeleton s(UrdfModel::humanoid().model);
  // Shoulders at (+-0.22, 1.52, 0); left is -X (the character faces -Z).
  EXPECT_TRUE(position(s, "left_shoulder").isApprox(Eigen::Vector3d(-0.22, 1.52, 0), 1e-12));
  EXPECT_TRUE(position(s, "right_shoulder").isApprox(Eigen::Vector3d(0.22, 1.52, 0), 1e-12));
  EXPECT_TRUE(position(s, "left_thigh").isApprox(Eigen::Vector3d(-0.10, 0.95, 0), 1e-12));

  // The head is the highest point, at about 1.75 m; the feet touch the ground.
  double top = -1e9, bottom = 1e9;
  Eigen::Vector3d headCentre = Eigen::Vector3d::Zero();
  for (const WorldShape& w : s.worldShapes()) {
    const ShapeDesc& sh = *w.shape;
    const Eigen::Vector3d c = w.pose.translation();
    if (sh.type == ShapeType::Sphere) {
      top = std::max(top, c.y() + sh.radius);
      bottom = std::min(bottom, c.y() - sh.radius);
      if (sh.name == "skull") headCentre = c;
    } else if (sh.type == ShapeType::Box) {
      const Eigen::Vector3d ext = (w.pose.linear() * sh.halfExtents).cwiseAbs();
      top = std::max(top, c.y() + ext.y());
      bottom = std::min(bottom, c.y() - ext.y());
      if (*w.linkName == "torso") {
        EXPECT_TRUE(c.isApprox(Eigen::Vector3d(0, 1.25, 0), 1e-12));
        EXPECT_TRUE(ext.isApprox(Eigen::Vector3d(0.20, 0.30, 0.12), 1e-12));  // docs/SCENES.md's torso
      }
    }
  }
  EXPECT_NEAR(top, 1.75, 1e-9);
  EXPECT_NEAR(bottom, 0.0, 1e-9);
  EXPECT_NEAR(headCentre.y(), 1.64, 1e-9);
  EXPECT_NEAR(headCentre.x(), 0.0, 1e-12);

  // Facing -Z: the toes are ahead of the ankles, towards -Z.
  Eigen::Isometry3d foot;
  ASSERT_TRUE(s.linkPose("left_foot", foot).ok());
  const Eigen::Vector3d toes = foot * Eigen::Vector3d(0.17, 0, -0.10);  // front of the foot box, URDF frame
  EXPECT_LT(toes.z() - foot.translation().z(), -0.1);

  // Turned to yaw 90 degrees it faces -X (forward = (-sin yaw, 0, -cos yaw), as the core's motionAt).
  s.setRoot(Eigen::Vector3d(1, 0, 2), kPi / 2);
  ASSERT_TRUE(s.linkPose("left_foot", foot).ok());
  const Eigen::Vector3d forward = foot.linear() * Eigen::Vector3d::UnitX();
  EXPECT_TRUE(forward.isApprox(Eigen::Vector3d(-1, 0, 0), 1e-12));
}

TEST(Skeleton, PositiveHipAngleSwingsTheLegForward) {
  // The gait and docs/SCENES.md agree on the sign: left leg angle +0.5236 puts the foot ahead (towards -Z).
  Skeleton s(UrdfModel::humanoid().model);
  ASSERT_TRUE(s.setJointPosition("left_hip_pitch", 0.5236).ok());
  const Eigen::Vector3d knee = position(s, "left_shin");
  EXPECT_NEAR(knee.z(), -0.40 * std::sin(0.5236), 1e-9);
  EXPECT_NEAR(knee.y(), 0.95 - 0.40 * std::cos(0.5236), 1e-9);
}

TEST(Skeleton, FloatingJointsHoldTheirOrigin) {
  // A "world" link with a floating joint to the body, as many robot descriptions have: it loads, the floating
  // joint has no single position, and the body sits at the joint origin (the root transform places it).
  Skeleton s = load(R"(<robot name="f">
    <link name="world"/>
    <link name="body"><collision><geometry><sphere radius="0.2"/></geometry></collision></link>
    <joint name="free" type="floating"><parent link="world"/><child link="body"/><origin xyz="0 0 1"/></joint>
  </robot>)");
  EXPECT_EQ(s.setJointPosition("free", 0.3).code(), ErrorCode::NotMovable);
  s.setRoot(Eigen::Vector3d(1, 0, 0), 0.0);
  EXPECT_TRUE(position(s, "body").isApprox(Eigen::Vector3d(1, 1, 0), 1e-12));
}
