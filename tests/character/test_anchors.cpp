// Where the cape hangs without link names: the shipped humanoid's shoulders from its joint mapping, a robot
// whose shoulder joints hang from the torso through a chain of revolute joints, the user's links, and the
// exact bounds of every shape type; and the up axis turns a character into a Z-up world without changing it.
#include "cape/character/Anchors.h"

#include "CharacterTestWorld.h"

#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>

#include <random>

using namespace cape::character;
using capetest::World;

namespace {

// A torso box (back 0.11 m behind the shoulders) with each arm hanging from it through shoulder pitch, roll
// and yaw joints in a chain of shape-less links: the arm hangs from the torso, not from a shoulder link.
const char* kRobot = R"(<robot name="r">
  <link name="torso"><collision><origin xyz="0 0 0.3"/><geometry><box size="0.22 0.4 0.6"/></geometry></collision></link>
  <joint name="l_shoulder_pitch" type="revolute"><parent link="torso"/><child link="l_s1"/><origin xyz="0 0.25 0.55"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="l_s1"/>
  <joint name="l_shoulder_roll" type="revolute"><parent link="l_s1"/><child link="l_s2"/>
    <axis xyz="1 0 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="l_s2"/>
  <joint name="l_shoulder_yaw" type="revolute"><parent link="l_s2"/><child link="l_arm"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="l_arm"><collision><origin xyz="0 0 -0.15"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
  <joint name="r_shoulder_pitch" type="revolute"><parent link="torso"/><child link="r_s1"/><origin xyz="0 -0.25 0.55"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="r_s1"/>
  <joint name="r_shoulder_roll" type="revolute"><parent link="r_s1"/><child link="r_s2"/>
    <axis xyz="1 0 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="r_s2"/>
  <joint name="r_shoulder_yaw" type="revolute"><parent link="r_s2"/><child link="r_arm"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="r_arm"><collision><origin xyz="0 0 -0.15"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
</robot>)";

std::unique_ptr<Character> make(const UrdfModelPtr& model, World& w, UpAxis up = UpAxis::Y) {
  CharacterSettings s;
  s.up = up;
  CharacterResult made = Character::create(model, w.world, Gait::forScene(cape::SceneKind::Walk), s);
  EXPECT_TRUE(made.ok()) << made.status.message();
  return std::move(made.character);
}

}  // namespace

TEST(Anchors, ShippedHumanoidHangsItsCapeFromItsShoulderLinks) {
  World w;
  const UrdfLoadResult m = UrdfModel::humanoid();
  ASSERT_TRUE(m.ok());
  auto c = make(m.model, w);
  const ShoulderAnchors a = findShoulderAnchors(*c);
  ASSERT_TRUE(a.status.ok()) << a.status.message();
  EXPECT_EQ(m.model->links()[static_cast<std::size_t>(a.leftLink)].name, "left_shoulder");
  EXPECT_EQ(m.model->links()[static_cast<std::size_t>(a.rightLink)].name, "right_shoulder");
  EXPECT_EQ(m.model->links()[static_cast<std::size_t>(a.upperTorsoLink)].name, "torso");
  EXPECT_NEAR(a.left.x(), -0.22, 1e-9);
  EXPECT_NEAR(a.right.x(), 0.22, 1e-9);
  EXPECT_NEAR(a.left.y(), 1.52, 1e-9);
  EXPECT_NEAR(a.back, 0.12, 1e-12);  // the torso box's back; the shoulder spheres (r 0.08) are inside it
  EXPECT_NE(a.description.find("left_shoulder_pitch"), std::string::npos) << a.description;
}

TEST(Anchors, ArmsHangingThroughAChainOfJointsHangFromTheTorso) {
  World w;
  const UrdfLoadResult m = UrdfModel::fromString(kRobot);
  ASSERT_TRUE(m.ok()) << m.status.message();
  for (UpAxis up : {UpAxis::Y, UpAxis::Z}) {
    auto c = make(m.model, w, up);
    const ShoulderAnchors a = findShoulderAnchors(*c);
    ASSERT_TRUE(a.status.ok()) << a.status.message();
    EXPECT_EQ(m.model->links()[static_cast<std::size_t>(a.leftLink)].name, "torso");
    EXPECT_EQ(m.model->links()[static_cast<std::size_t>(a.rightLink)].name, "torso");
    // In the scene frame whatever the world's up: shoulders 0.5 m apart, left at -x, the back 11 cm behind.
    EXPECT_NEAR(a.right.x() - a.left.x(), 0.5, 1e-9);
    EXPECT_LT(a.left.x(), a.right.x());
    EXPECT_NEAR(a.left.y() - c->rootHeight(), 0.55, 1e-9);
    EXPECT_NEAR(a.back, 0.11, 1e-9);
  }
}

TEST(Anchors, NamedLinksAndTheirErrors) {
  World w;
  const UrdfLoadResult m = UrdfModel::fromString(kRobot);
  ASSERT_TRUE(m.ok());
  auto c = make(m.model, w);
  const ShoulderAnchors a = shoulderAnchorsOnLinks(*c, {"l_arm", "r_arm"});
  ASSERT_TRUE(a.status.ok()) << a.status.message();
  EXPECT_EQ(m.model->links()[static_cast<std::size_t>(a.leftLink)].name,
            "l_arm");                                                      // the left is -X (facing -Z)
  const ShoulderAnchors shapeless = shoulderAnchorsOnLinks(*c, {"l_s1"});  // pins to its nearest body: torso
  ASSERT_TRUE(shapeless.status.ok()) << shapeless.status.message();
  EXPECT_EQ(m.model->links()[static_cast<std::size_t>(shapeless.leftLink)].name, "torso");
  const ShoulderAnchors unknown = shoulderAnchorsOnLinks(*c, {"wing"});
  EXPECT_EQ(unknown.status.code(), ErrorCode::UnknownLink);
  EXPECT_NE(unknown.status.message().find("l_arm"), std::string::npos);  // lists the links
  EXPECT_EQ(shoulderAnchorsOnLinks(*c, {}).status.code(), ErrorCode::InvalidArgument);
}

TEST(Anchors, ShapeBoundsAreExactForEveryShapeType) {
  // Against dense sampling of each surface at random poses: the bounds contain every sample and are reached.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (ShapeType type :
       {ShapeType::Sphere, ShapeType::Box, ShapeType::Cylinder, ShapeType::Capsule, ShapeType::ConvexHull}) {
    ShapeDesc s;
    s.type = type;
    s.radius = type == ShapeType::ConvexHull ? 0.01 : 0.1;
    s.halfLength = 0.2;
    s.halfExtents = Eigen::Vector3d(0.1, 0.2, 0.3);
    s.hull = {{0.1, 0, 0}, {0, 0.2, 0}, {0, 0, 0.3}, {-0.1, -0.1, -0.1}};
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
      pose.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng));
      const Eigen::AlignedBox3d b = shapeBounds(s, pose);
      Eigen::AlignedBox3d sampled;
      for (int k = 0; k < 20000; ++k) {
        const Eigen::Vector3d d = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
        Eigen::Vector3d p = Eigen::Vector3d::Zero();  // the support point of the shape in direction d
        switch (type) {
          case ShapeType::Sphere:
            p = s.radius * d;
            break;
          case ShapeType::Box:
            p = s.halfExtents.cwiseProduct(d.cwiseSign());
            break;
          case ShapeType::Cylinder: {
            const Eigen::Vector2d r(d.x(), d.y());
            const Eigen::Vector2d rim =
                r.norm() > 0 ? Eigen::Vector2d(s.radius * r.normalized()) : Eigen::Vector2d::Zero();
            p = Eigen::Vector3d(rim.x(), rim.y(), (d.z() > 0 ? 1 : -1) * s.halfLength);
            break;
          }
          case ShapeType::Capsule:
            p = Eigen::Vector3d(0, 0, (d.z() > 0 ? 1 : -1) * s.halfLength) + s.radius * d;
            break;
          case ShapeType::ConvexHull: {
            p = s.hull[0];
            for (const Eigen::Vector3d& v : s.hull)
              if (v.dot(d) > p.dot(d)) p = v;
            p += s.radius * d;
            break;
          }
        }
        sampled.extend(pose * p);
      }
      EXPECT_TRUE((sampled.min() - b.min()).minCoeff() >= -1e-12 &&
                  (b.max() - sampled.max()).minCoeff() >= -1e-12)
          << toString(type);
      EXPECT_LT((sampled.min() - b.min()).maxCoeff(), 2e-3) << toString(type);
      EXPECT_LT((b.max() - sampled.max()).maxCoeff(), 2e-3) << toString(type);
    }
  }
}
