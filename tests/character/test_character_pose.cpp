// A character's place and pose: standing on the ground (the lowest point of every shape type, a root at the
// pelvis, a dummy world link, no shapes at all, the root height given), the user's starting pose and its text
// form, and the shipped humanoid unchanged to the bit.
#include "cape/character/Character.h"
#include "cape/character/Grounding.h"

#include "CharacterTestWorld.h"

#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

using namespace cape::character;
using capetest::World;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A humanoid whose root link is its pelvis, 0.93 m above its soles: hips 5 cm below it, 0.8 m legs, feet
// 6 cm thick centred under the ankles (so the walk's bent stance knee at t = 0 moves the sole under 1 mm),
// arms hanging from shoulder pitch joints. `root` goes before the pelvis: a dummy world link, say.
std::string pelvisRooted(const std::string& root = "") {
  std::string legs;
  for (const char* side : {"left", "right"}) {
    const std::string s(side), y = s == "left" ? "0.1" : "-0.1", ay = s == "left" ? "0.2" : "-0.2";
    legs +=
        R"(
  <link name=")" +
        s +
        R"(_thigh"><collision><origin xyz="0 0 -0.2"/><geometry><cylinder radius="0.06" length="0.4"/></geometry></collision></link>
  <link name=")" +
        s +
        R"(_shin"><collision><origin xyz="0 0 -0.2"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision></link>
  <link name=")" +
        s +
        R"(_foot"><collision><origin xyz="0 0 -0.05"/><geometry><box size="0.2 0.1 0.06"/></geometry></collision></link>
  <link name=")" +
        s +
        R"(_upper_arm"><collision><origin xyz="0 0 -0.15"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
  <link name=")" +
        s + R"(_hand"><collision><geometry><sphere radius="0.045"/></geometry></collision></link>
  <joint name=")" +
        s + R"(_hip_pitch" type="revolute"><parent link="pelvis"/><child link=")" + s +
        R"(_thigh"/><origin xyz="0 )" + y + R"( -0.05"/>
    <axis xyz="0 -1 0"/><limit lower="-1" upper="1.6" effort="1" velocity="1"/></joint>
  <joint name=")" +
        s + R"(_knee" type="revolute"><parent link=")" + s + R"(_thigh"/><child link=")" + s +
        R"(_shin"/><origin xyz="0 0 -0.4"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="2.3" effort="1" velocity="1"/></joint>
  <joint name=")" +
        s + R"(_ankle" type="revolute"><parent link=")" + s + R"(_shin"/><child link=")" + s +
        R"(_foot"/><origin xyz="0 0 -0.4"/>
    <axis xyz="0 -1 0"/><limit lower="-0.7" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name=")" +
        s + R"(_shoulder_pitch" type="revolute"><parent link="torso"/><child link=")" + s +
        R"(_upper_arm"/><origin xyz="0 )" + ay + R"( 0.5"/>
    <axis xyz="0 -1 0"/><limit lower="-1" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name=")" +
        s + R"(_elbow" type="revolute"><parent link=")" + s + R"(_upper_arm"/><child link=")" + s +
        R"(_hand"/><origin xyz="0 0 -0.55"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="2.4" effort="1" velocity="1"/></joint>)";
  }
  return R"(<robot name="pelvis_rooted">)" + root + R"(
  <link name="pelvis"><collision><geometry><box size="0.2 0.3 0.14"/></geometry></collision></link>
  <link name="torso"><collision><origin xyz="0 0 0.3"/><geometry><box size="0.2 0.34 0.5"/></geometry></collision></link>
  <joint name="waist" type="revolute"><parent link="pelvis"/><child link="torso"/>
    <axis xyz="0 0 1"/><limit lower="-0.5" upper="0.5" effort="1" velocity="1"/></joint>)" +
         legs + "\n</robot>";
}

UrdfModelPtr load(const std::string& urdf) {
  const UrdfLoadResult r = UrdfModel::fromString(urdf);
  EXPECT_TRUE(r.ok()) << r.status.message();
  return r.model;
}

bool hasWarningWith(const std::vector<std::string>& warnings, const std::string& text) {
  return std::any_of(warnings.begin(), warnings.end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

std::string joined(const std::vector<std::string>& warnings) {
  std::string out;
  for (const std::string& w : warnings) out += w + "\n";
  return out;
}

double lowest(const Skeleton& s) {
  const std::optional<double> y = lowestCollisionPoint(s);
  EXPECT_TRUE(y.has_value());
  return y.value_or(std::numeric_limits<double>::quiet_NaN());
}

Eigen::Isometry3d pose(const Eigen::Vector3d& at, const Eigen::Vector3d& axis, double angle) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = at;
  p.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  return p;
}

// FNV-1a over bytes.
void mix(std::uint64_t& h, const void* p, std::size_t n) {
  const unsigned char* c = static_cast<const unsigned char*>(p);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= c[i];
    h *= 1099511628211ull;
  }
}

// Every link pose, joint position, body transform and body velocity of the shipped humanoid over 4 s of a
// scene at 60 Hz, hashed.
std::uint64_t shippedHumanoidHash(cape::SceneKind scene) {
  World w;
  std::uint64_t h = 1469598103934665603ull;
  CharacterResult made = Character::create(UrdfModel::humanoid().model, w.world, Gait::forScene(scene));
  EXPECT_TRUE(made.ok()) << made.status.message();
  Character& c = *made.character;
  for (int f = 0; f <= 240; ++f) {
    if (f > 0) c.advanceTo(f / 60.0);
    for (int l = 0; l < c.skeleton().linkCount(); ++l)
      mix(h, c.skeleton().linkPose(l).matrix().data(), 16 * sizeof(double));
    for (double q : c.skeleton().jointPositions()) mix(h, &q, sizeof q);
    for (btRigidBody* b : c.bodies().bodies()) {
      const btTransform& t = b->getWorldTransform();
      for (int i = 0; i < 3; ++i) {
        const btScalar o = t.getOrigin()[i], v = b->getLinearVelocity()[i], a = b->getAngularVelocity()[i];
        mix(h, &o, sizeof o);
        mix(h, &v, sizeof v);
        mix(h, &a, sizeof a);
        for (int j = 0; j < 3; ++j) {
          const btScalar m = t.getBasis()[i][j];
          mix(h, &m, sizeof m);
        }
      }
    }
  }
  return h;
}

}  // namespace

// --- The lowest point of each shape type ----------------------------------------------------------------

TEST(LowestPoint, SphereAndBox) {
  ShapeDesc sphere;
  sphere.type = ShapeType::Sphere;
  sphere.radius = 0.3;
  EXPECT_DOUBLE_EQ(lowestPointY(sphere, pose({1, 2, 3}, {1, 1, 0}, 0.7)), 1.7);

  ShapeDesc box;
  box.type = ShapeType::Box;
  box.halfExtents = Eigen::Vector3d(0.1, 0.2, 0.3);
  const Eigen::Isometry3d p = pose({0, 1, 0}, {1, 2, 3}, 0.9);
  double corners = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d c((k & 1 ? 1 : -1) * 0.1, (k & 2 ? 1 : -1) * 0.2, (k & 4 ? 1 : -1) * 0.3);
    corners = std::min(corners, (p * c).y());
  }
  EXPECT_NEAR(lowestPointY(box, p), corners, 1e-12);
  EXPECT_NEAR(lowestPointY(box, pose({0, 1, 0}, {0, 1, 0}, 0.4)), 0.8, 1e-12);  // yawed: still flat
}

TEST(LowestPoint, CylinderIsTheLowestRimPoint) {
  ShapeDesc cyl;
  cyl.type = ShapeType::Cylinder;
  cyl.radius = 0.07;
  cyl.halfLength = 0.2;
  // Upright (URDF z turned to world y), lying (axis horizontal) and tilted.
  EXPECT_NEAR(lowestPointY(cyl, pose({0, 1, 0}, {1, 0, 0}, -kPi / 2)), 0.8, 1e-12);
  EXPECT_NEAR(lowestPointY(cyl, pose({0, 1, 0}, {1, 0, 0}, 0.0)), 0.93, 1e-12);
  for (double tilt : {0.3, 1.1, 2.5}) {
    const Eigen::Isometry3d p = pose({0.2, 1, -0.4}, {1, 0.3, 0.2}, tilt);
    double sampled = std::numeric_limits<double>::infinity();
    for (int end : {-1, 1}) {
      for (int k = 0; k < 20000; ++k) {
        const double a = 2 * kPi * k / 20000;
        sampled =
            std::min(sampled, (p * Eigen::Vector3d(0.07 * std::cos(a), 0.07 * std::sin(a), 0.2 * end)).y());
      }
    }
    const double exact = lowestPointY(cyl, p);
    EXPECT_LE(exact, sampled + 1e-12) << tilt;
    EXPECT_NEAR(exact, sampled, 1e-7) << tilt;
  }
}

TEST(LowestPoint, CapsuleAndRoundedHull) {
  ShapeDesc capsule;
  capsule.type = ShapeType::Capsule;
  capsule.radius = 0.05;
  capsule.halfLength = 0.15;
  const Eigen::Isometry3d p = pose({0, 1, 0}, {1, 0, 0}, 0.5);
  const double ends = std::min((p * Eigen::Vector3d(0, 0, 0.15)).y(), (p * Eigen::Vector3d(0, 0, -0.15)).y());
  EXPECT_NEAR(lowestPointY(capsule, p), ends - 0.05, 1e-12);
  EXPECT_NEAR(lowestPointY(capsule, pose({0, 1, 0}, {1, 0, 0}, -kPi / 2)), 1 - 0.15 - 0.05, 1e-12);

  ShapeDesc hull;
  hull.type = ShapeType::ConvexHull;
  hull.radius = 0.01;
  hull.hull = {{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}};
  const Eigen::Isometry3d q = pose({0, 2, 0}, {1, 1, 1}, 2.0);
  double vertices = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& v : hull.hull) vertices = std::min(vertices, (q * v).y());
  EXPECT_NEAR(lowestPointY(hull, q), vertices - 0.01, 1e-12);
  hull.hull.clear();  // no vertices, no surface
  EXPECT_TRUE(std::isinf(lowestPointY(hull, q)));
}

// --- Standing on the ground
// ---------------------------------------------------------------------------------

TEST(Grounding, ShippedHumanoidIsUnchangedToTheBit) {
  // Hashes of the shipped humanoid's link poses, joints and bodies, taken with the code before the character
  // stood itself on the ground, held arms down and took a pose: its root height is exactly 0.
  // The bodies' transforms are btScalar: one set of hashes per precision of Bullet (CAPE_BULLET_DOUBLE).
#ifdef BT_USE_DOUBLE_PRECISION
  EXPECT_EQ(shippedHumanoidHash(cape::SceneKind::Hang), 11272632647466176014ull);
  EXPECT_EQ(shippedHumanoidHash(cape::SceneKind::Walk), 2048027704543476663ull);
  EXPECT_EQ(shippedHumanoidHash(cape::SceneKind::SprintTurn), 16467489167288735896ull);
#else
  EXPECT_EQ(shippedHumanoidHash(cape::SceneKind::Hang), 0x7092d710dec9db78ull);
  EXPECT_EQ(shippedHumanoidHash(cape::SceneKind::Walk), 0x11f62289a3cdccdcull);
  EXPECT_EQ(shippedHumanoidHash(cape::SceneKind::SprintTurn), 0xc672ebcfd97dc1fdull);
#endif
  World w;
  const CharacterResult made =
      Character::create(UrdfModel::humanoid().model, w.world, Gait::forScene(cape::SceneKind::Walk));
  ASSERT_TRUE(made.ok());
  EXPECT_EQ(made.character->rootHeight(), 0.0);
  EXPECT_TRUE(made.character->warnings().empty()) << joined(made.character->warnings());
  // Its standing pose touches the ground; its lowest point is within rounding of y = 0.
  Skeleton standing(UrdfModel::humanoid().model);
  EXPECT_NEAR(lowest(standing), 0.0, 1e-12);
}

TEST(Grounding, PelvisRootIsRaisedToStandAndSaidToBeAFloatingBase) {
  const UrdfModelPtr model = load(pelvisRooted());
  ASSERT_TRUE(model);
  World w;
  const CharacterResult hang = Character::create(model, w.world, Gait::forScene(cape::SceneKind::Hang));
  ASSERT_TRUE(hang.ok()) << hang.status.message();
  EXPECT_NEAR(hang.character->rootHeight(), 0.93, 1e-9);
  EXPECT_NEAR(lowest(hang.character->skeleton()), 0.0, 1e-9);
  const std::vector<std::string> warnings = hang.character->warnings();
  EXPECT_TRUE(
      hasWarningWith(warnings,
                     "root link 'pelvis' is 0.93 m above the lowest collision point (a floating base): "
                     "the character is raised 0.93 m to stand on the ground"))
      << joined(warnings);

  // Walking: the stance leg's slightly bent knee at t = 0 leaves the sole within 1 mm of the ground, and the
  // root follows the scenes' path raised by the root height.
  const CharacterResult walk = Character::create(model, w.world, Gait::forScene(cape::SceneKind::Walk));
  ASSERT_TRUE(walk.ok());
  EXPECT_NEAR(lowest(walk.character->skeleton()), 0.0, 1e-3);
  const cape::MotionDesc motion = cape::MotionDesc::forScene(cape::SceneKind::Walk);
  for (double t : {0.5, 1.25, 3.0}) {
    walk.character->advanceTo(t);
    const Eigen::Vector3d expected =
        cape::motionAt(motion, t).frame().position.cast<double>() + Eigen::Vector3d(0, 0.93, 0);
    EXPECT_LT((walk.character->skeleton().rootTransform().translation() - expected).norm(), 1e-9) << t;
  }
}

TEST(Grounding, DummyWorldLinkAndFloatingJointsAreSaid) {
  for (const char* type : {"floating", "fixed"}) {
    const std::string world = std::string(R"(<link name="world"/><joint name="world_to_pelvis" type=")") +
                              type + R"("><parent link="world"/><child link="pelvis"/></joint>)";
    const UrdfModelPtr model = load(pelvisRooted(world));
    ASSERT_TRUE(model);
    World w;
    const CharacterResult made = Character::create(model, w.world, Gait::forScene(cape::SceneKind::Hang));
    ASSERT_TRUE(made.ok()) << made.status.message();
    EXPECT_NEAR(made.character->rootHeight(), 0.93, 1e-9);
    EXPECT_NEAR(lowest(made.character->skeleton()), 0.0, 1e-9);
    const std::vector<std::string> warnings = made.character->warnings();
    EXPECT_TRUE(hasWarningWith(warnings,
                               "root link 'world' is a dummy world link, and its joint "
                               "'world_to_pelvis' to 'pelvis' is " +
                                   std::string(type)))
        << joined(warnings);
    EXPECT_TRUE(hasWarningWith(warnings, "root link 'world' is 0.93 m above")) << joined(warnings);
  }
}

TEST(Grounding, NoShapesKeepsTheRootAtZeroAndWarns) {
  const UrdfModelPtr model = load(R"(<robot name="bare"><link name="a"/><link name="b"/>
    <joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.5"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)");
  ASSERT_TRUE(model);
  World w;
  const CharacterResult made = Character::create(model, w.world, Gait::forScene(cape::SceneKind::Walk));
  ASSERT_TRUE(made.ok());
  EXPECT_EQ(made.character->rootHeight(), 0.0);
  EXPECT_EQ(made.character->skeleton().rootTransform().translation().y(), 0.0);
  EXPECT_TRUE(hasWarningWith(made.character->warnings(), "no link of 'bare' has a collision shape"));
}

TEST(Grounding, RootHeightGivenOverridesThePlacement) {
  World w;
  for (const UrdfModelPtr& model : {load(pelvisRooted()), UrdfModel::humanoid().model}) {
    ASSERT_TRUE(model);
    CharacterSettings settings;
    settings.rootHeight = 1.2;
    settings.offset = Eigen::Vector3d(2, 0, 0);
    const CharacterResult made =
        Character::create(model, w.world, Gait::forScene(cape::SceneKind::Walk), settings);
    ASSERT_TRUE(made.ok());
    EXPECT_EQ(made.character->rootHeight(), 1.2);
    // At t = 0 the bob is 0: the root origin is at the height given.
    EXPECT_LT((made.character->skeleton().rootTransform().translation() - Eigen::Vector3d(2, 1.2, 0)).norm(),
              1e-12);
  }
  const UrdfModelPtr model = load(pelvisRooted());
  CharacterSettings settings;
  settings.rootHeight = 1.0;
  const CharacterResult made =
      Character::create(model, w.world, Gait::forScene(cape::SceneKind::Hang), settings);
  ASSERT_TRUE(made.ok());
  EXPECT_TRUE(hasWarningWith(made.character->warnings(), "the root is placed at the given root height 1 m"))
      << joined(made.character->warnings());
  EXPECT_NEAR(lowest(made.character->skeleton()), 0.07, 1e-9);
  settings.rootHeight = std::numeric_limits<double>::infinity();
  EXPECT_EQ(Character::create(model, w.world, Gait::forScene(cape::SceneKind::Hang), settings).status.code(),
            ErrorCode::InvalidArgument);
}

// --- The user's pose
// ------------------------------------------------------------------------------------------

TEST(CharacterPose, BaseOfEveryFrame) {
  const UrdfModelPtr model = UrdfModel::humanoid().model;
  World w;
  CharacterSettings settings;
  settings.pose = {{"neck", 0.3}, {"left_elbow", 0.2}, {"waist", 9.0}};
  const Gait gait = Gait::forScene(cape::SceneKind::Walk);
  const CharacterResult made = Character::create(model, w.world, gait, settings);
  ASSERT_TRUE(made.ok()) << made.status.message();
  Character& c = *made.character;
  EXPECT_TRUE(hasWarningWith(c.warnings(),
                             "pose: joint 'waist' = 9 is outside its limits [-0.5, 0.5]: "
                             "clamped to 0.5"))
      << joined(c.warnings());
  const int neck = model->findJoint("neck"), waist = model->findJoint("waist");
  const int elbow = model->findJoint("left_elbow"), knee = model->findJoint("left_knee");
  for (int f = 0; f <= 120; ++f) {
    if (f > 0) c.advanceTo(f / 60.0);
    const auto angles = gait.anglesAt(f / 60.0);
    // Not driven: the pose's value, always.
    EXPECT_EQ(c.skeleton().jointPosition(neck), 0.3);
    EXPECT_EQ(c.skeleton().jointPosition(waist), 0.5);
    // Driven: the gait's angle added to the pose (or alone where the pose says nothing).
    EXPECT_EQ(c.skeleton().jointPosition(elbow),
              std::clamp(0.2 + angles[static_cast<std::size_t>(GaitRole::LeftElbow)], 0.0, 2.4));
    EXPECT_EQ(c.skeleton().jointPosition(knee),
              std::clamp(angles[static_cast<std::size_t>(GaitRole::LeftKnee)], 0.0, 2.3));
  }
}

TEST(CharacterPose, ACrouchStandsOnTheGround) {
  // Bent knees and hips lower the body: the placement uses the standing pose with the user's pose applied.
  const UrdfModelPtr model = UrdfModel::humanoid().model;
  World w;
  CharacterSettings settings;
  settings.pose = {{"left_hip_pitch", 0.5}, {"right_hip_pitch", 0.5}, {"left_knee", 1.0},
                   {"right_knee", 1.0},     {"left_ankle", 0.5},      {"right_ankle", 0.5}};
  const CharacterResult made =
      Character::create(model, w.world, Gait::forScene(cape::SceneKind::Hang), settings);
  ASSERT_TRUE(made.ok()) << made.status.message();
  EXPECT_LT(made.character->rootHeight(), -0.05);  // lowered
  EXPECT_NEAR(lowest(made.character->skeleton()), 0.0, 1e-9);
}

TEST(CharacterPose, UnknownAndFixedJointsAreErrorsListingTheMovableOnes) {
  const UrdfModelPtr model = UrdfModel::humanoid().model;
  World w;
  const Gait gait = Gait::forScene(cape::SceneKind::Walk);
  CharacterSettings settings;
  settings.pose = {{"neck", 0.1}, {"no_such_joint", 0.2}};
  CharacterResult made = Character::create(model, w.world, gait, settings);
  EXPECT_FALSE(made.ok());
  EXPECT_EQ(made.status.code(), ErrorCode::UnknownJoint);
  const std::string& message = made.status.message();
  EXPECT_NE(message.find("no_such_joint"), std::string::npos) << message;
  for (const char* joint :
       {"waist", "neck", "left_shoulder_pitch", "right_elbow", "left_hip_pitch", "right_knee", "left_ankle"})
    EXPECT_NE(message.find(joint), std::string::npos) << joint << ": " << message;
  EXPECT_EQ(message.find("pelvis_joint"), std::string::npos) << message;  // fixed: not listed
  EXPECT_EQ(w.world.getNumCollisionObjects(), 0);                         // nothing was added

  settings.pose = {{"pelvis_joint", 0.1}};
  made = Character::create(model, w.world, gait, settings);
  EXPECT_EQ(made.status.code(), ErrorCode::NotMovable);
  EXPECT_NE(made.status.message().find("left_knee"), std::string::npos) << made.status.message();
  settings.pose = {{"neck", 0.1}, {"neck", 0.2}};
  EXPECT_EQ(Character::create(model, w.world, gait, settings).status.code(), ErrorCode::InvalidArgument);
  settings.pose = {{"neck", std::numeric_limits<double>::quiet_NaN()}};
  EXPECT_EQ(Character::create(model, w.world, gait, settings).status.code(), ErrorCode::InvalidArgument);
}

TEST(CharacterPose, ParsesTheDemosText) {
  JointPose pose;
  ASSERT_TRUE(parsePose("neck=0.3, left_elbow = -0.25,waist=+1e-1", pose).ok());
  ASSERT_EQ(pose.size(), 3u);
  EXPECT_EQ(pose[0], (std::pair<std::string, double>("neck", 0.3)));
  EXPECT_EQ(pose[1], (std::pair<std::string, double>("left_elbow", -0.25)));
  EXPECT_EQ(pose[2], (std::pair<std::string, double>("waist", 0.1)));
  EXPECT_TRUE(parsePose("  ", pose).ok());
  EXPECT_TRUE(pose.empty());

  struct Bad {
    const char* text;
    const char* says;
  };
  for (const Bad& bad :
       {Bad{"neck0.3", "entry 1 'neck0.3': no '='"}, Bad{"=0.3", "no joint name"}, Bad{"neck=", "no value"},
        Bad{"neck=abc", "'abc' is not a number"}, Bad{"neck=0.3rad", "'0.3rad' is not a number"},
        Bad{"neck=1.2.3", "is not a number"}, Bad{"neck=nan", "finite"}, Bad{"neck=-inf", "finite"},
        Bad{"neck=0.1,,waist=0.2", "entry 2 '': no '='"}, Bad{"neck=0.1,neck=0.2", "given twice"},
        Bad{"neck=0.1,", "entry 2"}}) {
    pose = {{"stale", 1.0}};
    const Status s = parsePose(bad.text, pose);
    EXPECT_EQ(s.code(), ErrorCode::InvalidArgument) << bad.text;
    EXPECT_NE(s.message().find(bad.says), std::string::npos) << bad.text << ": " << s.message();
    EXPECT_TRUE(pose.empty()) << bad.text;
  }
}
