// Loading: the shipped humanoid, and every documented error for broken input.
#include "cape/character/Urdf.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

using namespace cape::character;

namespace {

const LinkDesc& linkNamed(const UrdfModel& m, const std::string& name) {
  const int l = m.findLink(name);
  EXPECT_GE(l, 0) << name;
  return m.links()[static_cast<std::size_t>(std::max(l, 0))];
}

const JointDesc& jointNamed(const UrdfModel& m, const std::string& name) {
  const int j = m.findJoint(name);
  EXPECT_GE(j, 0) << name;
  return m.joints()[static_cast<std::size_t>(std::max(j, 0))];
}

// A chain root -> a -> b with one revolute joint and one fixed joint.
std::string twoJointUrdf(const std::string& parentOfA = "root") {
  return R"(<robot name="small">
  <link name="root"/>
  <link name="a"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
  <link name="b"/>
  <joint name="ja" type="revolute"><parent link=")" +
         parentOfA + R"("/><child link="a"/>
    <axis xyz="0 0 2"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="jb" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0 1"/></joint>
</robot>)";
}

}  // namespace

TEST(Urdf, ShippedHumanoidHasTheExpectedLinksJointsAndShapes) {
  const UrdfLoadResult r = UrdfModel::humanoid();
  ASSERT_TRUE(r.ok()) << r.status.message();
  const UrdfModel& m = *r.model;
  EXPECT_EQ(m.name(), "cape_humanoid");
  EXPECT_EQ(m.links().size(), 16u);
  EXPECT_EQ(m.joints().size(), 15u);
  EXPECT_EQ(m.links()[0].name, "base_link");
  EXPECT_TRUE(m.warnings().empty());
  for (const char* name : {"pelvis", "torso", "head", "left_shoulder", "right_shoulder", "left_upper_arm",
                           "right_upper_arm", "left_forearm", "right_forearm", "left_thigh", "right_thigh",
                           "left_shin", "right_shin", "left_foot", "right_foot"}) {
    EXPECT_GE(m.findLink(name), 0) << name;
  }
  // Parents come before children.
  for (std::size_t l = 1; l < m.links().size(); ++l) EXPECT_LT(m.links()[l].parentLink, static_cast<int>(l));

  // The cape's anchors are found by name, and only they.
  EXPECT_EQ(m.linksContaining("SHOULDER"), (std::vector<std::string>{"left_shoulder", "right_shoulder"}));

  // Shapes, with URDF sizes (box size is full, cylinder length is full: we store halves).
  const LinkDesc& torso = linkNamed(m, "torso");
  ASSERT_EQ(torso.shapes.size(), 1u);
  EXPECT_EQ(torso.shapes[0].type, ShapeType::Box);
  EXPECT_TRUE(torso.shapes[0].halfExtents.isApprox(Eigen::Vector3d(0.12, 0.20, 0.30)));
  const LinkDesc& shoulder = linkNamed(m, "left_shoulder");
  ASSERT_EQ(shoulder.shapes.size(), 1u);
  EXPECT_EQ(shoulder.shapes[0].type, ShapeType::Sphere);
  EXPECT_DOUBLE_EQ(shoulder.shapes[0].radius, 0.08);
  const LinkDesc& thigh = linkNamed(m, "right_thigh");
  ASSERT_EQ(thigh.shapes.size(), 1u);
  EXPECT_EQ(thigh.shapes[0].type, ShapeType::Cylinder);
  EXPECT_DOUBLE_EQ(thigh.shapes[0].radius, 0.07);
  EXPECT_DOUBLE_EQ(thigh.shapes[0].halfLength, 0.20);
  const LinkDesc& head = linkNamed(m, "head");
  ASSERT_EQ(head.shapes.size(), 2u);  // several elements on one link
  EXPECT_EQ(head.shapes[0].name, "skull");
  EXPECT_EQ(head.shapes[1].name, "head#1");
  EXPECT_TRUE(linkNamed(m, "base_link").shapes.empty());

  // Joints: types, axes, limits.
  EXPECT_EQ(jointNamed(m, "pelvis_joint").type, JointType::Fixed);
  const JointDesc& knee = jointNamed(m, "left_knee");
  EXPECT_EQ(knee.type, JointType::Revolute);
  EXPECT_TRUE(knee.hasLimits);
  EXPECT_DOUBLE_EQ(knee.lower, 0.0);
  EXPECT_DOUBLE_EQ(knee.upper, 2.3);
  EXPECT_TRUE(knee.axis.isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE(jointNamed(m, "left_hip_pitch").origin.translation().isApprox(Eigen::Vector3d(0, 0.10, 0)));
  int movable = 0;
  for (const JointDesc& j : m.joints()) movable += j.isMovable() ? 1 : 0;
  EXPECT_EQ(movable, 12);  // waist, neck, 2 x (hip, knee, ankle, shoulder, elbow)
}

TEST(Urdf, ShippedFileAndEmbeddedTextAgree) {
  const UrdfLoadResult file = UrdfModel::fromFile(std::string(CAPE_CHARACTER_MODELS_DIR) + "/humanoid.urdf");
  ASSERT_TRUE(file.ok()) << file.status.message();
  EXPECT_EQ(file.model->links().size(), UrdfModel::humanoid().model->links().size());
}

TEST(Urdf, JointTypesAndAxesAreRead) {
  const std::string xml = R"(<robot name="kinds">
    <link name="r"/><link name="a"/><link name="b"/><link name="c"/><link name="d"/>
    <joint name="cont" type="continuous"><parent link="r"/><child link="a"/><axis xyz="0 2 0"/></joint>
    <joint name="pris" type="prismatic"><parent link="a"/><child link="b"/><axis xyz="1 0 0"/>
      <limit lower="-0.5" upper="0.25" effort="1" velocity="2"/></joint>
    <joint name="float" type="floating"><parent link="b"/><child link="c"/></joint>
    <joint name="fix" type="fixed"><parent link="c"/><child link="d"/><origin xyz="1 2 3" rpy="0 0 1.5707963267948966"/></joint>
  </robot>)";
  const UrdfLoadResult r = UrdfModel::fromString(xml);
  ASSERT_TRUE(r.ok()) << r.status.message();
  const UrdfModel& m = *r.model;
  EXPECT_EQ(jointNamed(m, "cont").type, JointType::Continuous);
  EXPECT_FALSE(jointNamed(m, "cont").hasLimits);
  EXPECT_TRUE(jointNamed(m, "cont").axis.isApprox(Eigen::Vector3d::UnitY()));  // normalised
  EXPECT_EQ(jointNamed(m, "pris").type, JointType::Prismatic);
  EXPECT_DOUBLE_EQ(jointNamed(m, "pris").lower, -0.5);
  EXPECT_DOUBLE_EQ(jointNamed(m, "pris").upper, 0.25);
  EXPECT_DOUBLE_EQ(jointNamed(m, "pris").maxVelocity, 2.0);
  EXPECT_EQ(jointNamed(m, "float").type, JointType::Floating);
  const JointDesc& fix = jointNamed(m, "fix");
  EXPECT_EQ(fix.type, JointType::Fixed);
  EXPECT_TRUE(fix.origin.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE((fix.origin.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
}

TEST(Urdf, MalformedXmlIsReportedWithItsLine) {
  const UrdfLoadResult r = UrdfModel::fromString("<robot name=\"r\">\n  <link name=\"a\"/>\n</robo>");
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.model, nullptr);
  EXPECT_EQ(r.status.code(), ErrorCode::MalformedXml);
  EXPECT_NE(r.status.message().find("line 3"), std::string::npos) << r.status.message();
  EXPECT_NE(r.status.message().find("</robo>"), std::string::npos) << r.status.message();

  for (const char* bad : {"", "   ", "<robot name='r'><link name='a'></robot>", "<robot name=r/>",
                          "<robot name='r'/><robot name='s'/>", "<robot name='r'", "text <robot/>",
                          "<robot name='r'><!-- unterminated </robot>"}) {
    const UrdfLoadResult b = UrdfModel::fromString(bad);
    EXPECT_EQ(b.status.code(), ErrorCode::MalformedXml) << "'" << bad << "': " << b.status.message();
  }
}

TEST(Urdf, WellFormedXmlThatIsNoRobotIsAnInvalidModel) {
  const UrdfLoadResult r = UrdfModel::fromString("<?xml version='1.0'?><!-- c --><notarobot/>");
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
  const UrdfLoadResult noLimits = UrdfModel::fromString(R"(<robot name="r"><link name="a"/><link name="b"/>
    <joint name="j" type="revolute"><parent link="a"/><child link="b"/></joint></robot>)");
  EXPECT_EQ(noLimits.status.code(), ErrorCode::InvalidModel);
  EXPECT_NE(noLimits.status.message().find("limits"), std::string::npos) << noLimits.status.message();
}

TEST(Urdf, MissingParentLinkIsNamed) {
  ASSERT_TRUE(UrdfModel::fromString(twoJointUrdf()).ok());
  const UrdfLoadResult r = UrdfModel::fromString(twoJointUrdf("nowhere"));
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.status.code(), ErrorCode::MissingLink);
  EXPECT_NE(r.status.message().find("nowhere"), std::string::npos) << r.status.message();
}

TEST(Urdf, CyclesAreRejected) {
  // A pure cycle has no root; a cycle beside a proper tree is unreachable from the root. urdfdom accepts the
  // second, we do not.
  const std::string cycle = R"(<link name="a"/><link name="b"/>
    <joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
    <joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>)";
  const UrdfLoadResult pure = UrdfModel::fromString("<robot name='c'>" + cycle + "</robot>");
  EXPECT_EQ(pure.status.code(), ErrorCode::NotATree) << pure.status.message();
  const UrdfLoadResult beside =
      UrdfModel::fromString("<robot name='c'><link name='root'/>" + cycle + "</robot>");
  EXPECT_EQ(beside.status.code(), ErrorCode::NotATree) << beside.status.message();
  const std::string& msg = beside.status.message();
  EXPECT_TRUE(msg.find("a -> b -> a") != std::string::npos || msg.find("b -> a -> b") != std::string::npos)
      << msg;
}

TEST(Urdf, TwoParentsOrTwoRootsAreNotATree) {
  const UrdfLoadResult twoParents = UrdfModel::fromString(R"(<robot name="t">
    <link name="a"/><link name="b"/><link name="c"/>
    <joint name="ac" type="fixed"><parent link="a"/><child link="c"/></joint>
    <joint name="bc" type="fixed"><parent link="b"/><child link="c"/></joint></robot>)");
  EXPECT_EQ(twoParents.status.code(), ErrorCode::NotATree) << twoParents.status.message();
  EXPECT_NE(twoParents.status.message().find("'c'"), std::string::npos) << twoParents.status.message();
  const UrdfLoadResult twoRoots = UrdfModel::fromString(R"(<robot name="t">
    <link name="a"/><link name="b"/><link name="c"/>
    <joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint></robot>)");
  EXPECT_EQ(twoRoots.status.code(), ErrorCode::NotATree) << twoRoots.status.message();
}

TEST(Urdf, NonexistentFileIsFileNotFound) {
  const UrdfLoadResult r = UrdfModel::fromFile("/nonexistent/dir/robot.urdf");
  EXPECT_EQ(r.status.code(), ErrorCode::FileNotFound);
  EXPECT_NE(r.status.message().find("/nonexistent/dir/robot.urdf"), std::string::npos);
  EXPECT_EQ(UrdfModel::fromFile(CAPE_CHARACTER_MODELS_DIR).status.code(),
            ErrorCode::FileNotFound);  // a directory
}

TEST(Urdf, MeshCollisionIsSkippedWithAWarningNamingTheLink) {
  const std::string xml = R"(<robot name="m">
    <link name="body">
      <collision><geometry><mesh filename="package://robot/meshes/body.stl" scale="1 1 1"/></geometry></collision>
      <collision><origin xyz="0 0 0.5"/><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
    </link>
  </robot>)";
  const UrdfLoadResult r = UrdfModel::fromString(xml);
  ASSERT_TRUE(r.ok()) << r.status.message();
  ASSERT_EQ(r.model->warnings().size(), 1u);
  EXPECT_NE(r.model->warnings()[0].find("'body'"), std::string::npos) << r.model->warnings()[0];
  EXPECT_NE(r.model->warnings()[0].find("mesh"), std::string::npos) << r.model->warnings()[0];
  ASSERT_EQ(r.model->links()[0].shapes.size(), 1u);  // the box remains
  EXPECT_EQ(r.model->links()[0].shapes[0].type, ShapeType::Box);
}

TEST(Urdf, CapsulesAreReadAlongTheirZAsBulletsImporterReadsThem) {
  // Bullet's data/humanoid.urdf style: a capsule first, then a sphere; urdfdom alone drops both.
  const UrdfLoadResult r = UrdfModel::fromString(
      R"(<robot name="c"><link name="l">
           <collision name="arm"><origin xyz="0 0 0.3" rpy="0 1.5707963 0"/>
             <geometry><capsule radius="0.05" length="0.4"/></geometry></collision>
           <collision><geometry><sphere radius="0.1"/></geometry></collision>
         </link></robot>)");
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  const LinkDesc& l = r.model->links()[0];
  ASSERT_EQ(l.shapes.size(), 2u);
  EXPECT_EQ(l.shapes[0].type, ShapeType::Capsule);
  EXPECT_EQ(l.shapes[0].name, "arm");
  EXPECT_DOUBLE_EQ(l.shapes[0].radius, 0.05);
  EXPECT_DOUBLE_EQ(l.shapes[0].halfLength, 0.2);  // length is the distance between the sphere centres
  EXPECT_NEAR(l.shapes[0].origin.translation().z(), 0.3, 1e-12);
  EXPECT_NEAR((l.shapes[0].origin.linear() * Eigen::Vector3d::UnitZ()).x(), 1.0, 1e-6);  // pitched onto x
  EXPECT_EQ(l.shapes[1].type, ShapeType::Sphere);
  EXPECT_EQ(l.shapes[1].name, "l#1");
}

TEST(Urdf, NumbersWithWhiteSpaceAroundThemAreReadAndSaidOnce) {
  // urdfdom refuses " 1.0 " as a number and then drops every shape of the link after its <inertial>; and
  // " -1 " in a joint limit would make it refuse the model.
  const UrdfLoadResult r = UrdfModel::fromString(
      R"(<robot name="s">
           <link name="a"><inertial><mass value=" 2.5 "/><inertia ixx=" 0.1" ixy="0" ixz="0" iyy="0.1 "
             iyz="0" izz="0.1"/></inertial>
             <collision><origin xyz=" 0 0	0.5 "/><geometry><box size="0.2  0.2 0.2 "/></geometry></collision>
           </link>
           <link name="b"><collision><geometry><cylinder radius=" 0.1" length="0.5 "/></geometry></collision></link>
           <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/>
             <limit lower=" -1 " upper="1" effort="1" velocity="1"/></joint>
         </robot>)");
  ASSERT_TRUE(r.ok()) << r.status.message();
  const LinkDesc& a = linkNamed(*r.model, "a");
  EXPECT_DOUBLE_EQ(a.mass, 2.5);
  ASSERT_EQ(a.shapes.size(), 1u);
  EXPECT_EQ(a.shapes[0].halfExtents, Eigen::Vector3d(0.1, 0.1, 0.1));
  EXPECT_DOUBLE_EQ(a.shapes[0].origin.translation().z(), 0.5);
  ASSERT_EQ(linkNamed(*r.model, "b").shapes.size(), 1u);
  EXPECT_DOUBLE_EQ(jointNamed(*r.model, "j").lower, -1.0);
  ASSERT_EQ(r.model->warnings().size(), 1u);  // one line for every such value, naming the first
  EXPECT_NE(r.model->warnings()[0].find("white space"), std::string::npos) << r.model->warnings()[0];
  EXPECT_NE(r.model->warnings()[0].find("joint 'j'"), std::string::npos) << r.model->warnings()[0];
}

TEST(Urdf, TextEndsAtItsFirstNulByteAsForBulletsImporter) {
  // PyBullet's humanoid.urdf ships with a NUL after </robot>.
  std::string xml = twoJointUrdf();
  xml += std::string("\n\0", 2);
  const UrdfLoadResult quiet = UrdfModel::fromString(xml);
  ASSERT_TRUE(quiet.ok()) << quiet.status.message();
  EXPECT_TRUE(quiet.warnings.empty());  // only NULs and white space after it: nothing worth saying
  xml += "garbage";
  const UrdfLoadResult said = UrdfModel::fromString(xml);
  ASSERT_TRUE(said.ok()) << said.status.message();
  ASSERT_EQ(said.warnings.size(), 1u);
  EXPECT_NE(said.warnings[0].find("NUL"), std::string::npos) << said.warnings[0];
}

TEST(Urdf, MissingInertialIsFine) {
  const UrdfLoadResult r = UrdfModel::fromString(twoJointUrdf());
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(linkNamed(*r.model, "a").mass, 0.0);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(Urdf, EveryUnusableElementIsSkippedWithOneWarningNamingLinkElementAndReason) {
  const UrdfLoadResult r = UrdfModel::fromString(
      R"(<robot name="bad"><link name="l">
           <collision name="zero"><geometry><sphere radius="0"/></geometry></collision>
           <collision name="nan"><geometry><box size="1 nan 1"/></geometry></collision>
           <collision name="two"><geometry><box size="1 1"/></geometry></collision>
           <collision name="odd"><geometry><torus radius="1"/></geometry></collision>
           <collision name="empty"><geometry/></collision>
           <collision name="origin"><origin xyz="0 0"/><geometry><sphere radius="1"/></geometry></collision>
           <collision name="ok"><geometry><sphere radius="1"/></geometry></collision>
         </link></robot>)");
  ASSERT_TRUE(r.ok()) << r.status.message();
  ASSERT_EQ(r.model->links()[0].shapes.size(), 1u);
  EXPECT_EQ(r.model->links()[0].shapes[0].name, "ok");
  ASSERT_EQ(r.warnings.size(), 6u);
  for (const char* name : {"zero", "nan", "two", "odd", "empty", "origin"}) {
    const auto it = std::find_if(r.warnings.begin(), r.warnings.end(), [&](const std::string& w) {
      return w.find(std::string("'") + name + "'") != std::string::npos &&
             w.find("link 'l'") != std::string::npos && w.find("skipped") != std::string::npos;
    });
    EXPECT_NE(it, r.warnings.end()) << name;
  }
}

TEST(Urdf, WarningsComeBackWithAFailedLoad) {
  // The capsule's warning is said, then the missing link fails the load: the caller sees both.
  const UrdfLoadResult r = UrdfModel::fromString(
      R"(<robot name="f"><link name="a"><collision name="c"><geometry><capsule radius="-1" length="1"/>
         </geometry></collision></link>
         <joint name="j" type="fixed"><parent link="a"/><child link="ghost"/></joint></robot>)");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status.code(), ErrorCode::MissingLink) << r.status.message();
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("'c'"), std::string::npos) << r.warnings[0];
}

TEST(Urdf, DeepNestingIsRefusedAsMalformedNotACrash) {
  std::string xml = "<robot name=\"deep\">";
  for (int i = 0; i < 40000; ++i) xml += "<a>";
  for (int i = 0; i < 40000; ++i) xml += "</a>";
  xml += "</robot>";
  const UrdfLoadResult r = UrdfModel::fromString(xml);
  EXPECT_EQ(r.status.code(), ErrorCode::MalformedXml) << r.status.message();
  EXPECT_NE(r.status.message().find("nested deeper"), std::string::npos) << r.status.message();
}

TEST(Urdf, MeshElementsBecomeHullsAndMissingOrEmptyMeshesAreSkippedWithAWarning) {
  // A package folder the test writes: an ASCII STL cube of side 2 (mm scale in the URDF), an empty STL.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("cape_urdf_meshes-" + std::to_string(::getpid())) / "robot";
  std::filesystem::create_directories(dir / "meshes");
  {
    std::ofstream stl(dir / "meshes" / "cube.stl");
    stl << "solid c\n";
    const int f[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                          {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    for (const auto& t : f) {
      stl << "facet normal 0 0 0\nouter loop\n";
      for (int k : t)
        stl << "vertex " << (k & 1 ? 1000 : -1000) << " " << (k & 2 ? 1000 : -1000) << " "
            << (k & 4 ? 1000 : -1000) << "\n";
      stl << "endloop\nendfacet\n";
    }
    stl << "endsolid c\n";
    std::ofstream(dir / "meshes" / "empty.stl");
  }
  const std::string xml = R"(<robot name="m"><link name="body">
      <collision name="cube"><geometry><mesh filename="package://robot/meshes/cube.stl" scale="0.0001 0.0002 0.0003"/></geometry></collision>
      <collision name="empty"><geometry><mesh filename="package://robot/meshes/empty.stl"/></geometry></collision>
      <collision name="missing"><geometry><mesh filename="meshes/missing.stl"/></geometry></collision>
    </link></robot>)";
  UrdfLoadOptions options;
  options.packagePaths = {dir.parent_path().string()};
  options.baseDir = dir.string();
  const UrdfLoadResult r = UrdfModel::fromString(xml, options);
  ASSERT_TRUE(r.ok()) << r.status.message();
  const LinkDesc& body = r.model->links()[0];
  ASSERT_EQ(body.shapes.size(), 1u);
  const ShapeDesc& hull = body.shapes[0];
  EXPECT_EQ(hull.type, ShapeType::ConvexHull);
  EXPECT_EQ(hull.name, "cube");
  EXPECT_EQ(hull.hull.size(), 8u);
  EXPECT_EQ(hull.hullPlanes.size(), 6u);
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : hull.hull) box.extend(v);
  EXPECT_TRUE(box.max().isApprox(Eigen::Vector3d(0.1, 0.2, 0.3), 1e-9)) << box.max().transpose();
  EXPECT_NE(hull.meshFile.find("cube.stl"), std::string::npos);
  ASSERT_EQ(r.warnings.size(), 2u);
  EXPECT_NE(r.warnings[0].find("'empty'"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[1].find("'missing'"), std::string::npos) << r.warnings[1];
  for (const std::string& w : r.warnings) EXPECT_NE(w.find("link 'body'"), std::string::npos) << w;
  // Meshes off: every mesh element skipped, each with its warning, no file opened.
  options.loadMeshes = false;
  const UrdfLoadResult off = UrdfModel::fromString(xml, options);
  ASSERT_TRUE(off.ok());
  EXPECT_TRUE(off.model->links()[0].shapes.empty());
  EXPECT_EQ(off.warnings.size(), 3u);
  std::filesystem::remove_all(dir.parent_path());
}

TEST(Urdf, SphericalJointsAreReadAsHeldJointsWithAWarning) {
  const UrdfLoadResult r = UrdfModel::fromString(
      R"(<robot name="s"><link name="a"/><link name="b"/>
         <joint name="ball" type="spherical"><parent link="a"/><child link="b"/></joint></robot>)");
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_FALSE(jointNamed(*r.model, "ball").isMovable());
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("'ball'"), std::string::npos) << r.warnings[0];
}

TEST(Urdf, AModelStandingAlongYIsTurnedOntoZ) {
  // A stick figure standing along y (as Y-up tools write them): a 0.3 m wide body, 1.6 m tall.
  const std::string xml = R"(<robot name="yup"><link name="pelvis">
        <collision><origin xyz="0 0.5 0"/><geometry><box size="0.2 1.0 0.3"/></geometry></collision></link>
      <link name="head"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
      <joint name="neck" type="revolute"><parent link="pelvis"/><child link="head"/><origin xyz="0 1.5 0"/>
        <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)";
  // Auto: said, not turned (an upper body in a T-pose looks the same).
  const UrdfLoadResult said = UrdfModel::fromString(xml);
  ASSERT_TRUE(said.ok()) << said.status.message();
  ASSERT_EQ(said.warnings.size(), 1u);
  EXPECT_NE(said.warnings[0].find("--model-up y"), std::string::npos) << said.warnings[0];
  EXPECT_TRUE(
      jointNamed(*said.model, "neck").origin.translation().isApprox(Eigen::Vector3d(0, 1.5, 0), 1e-12));
  UrdfLoadOptions y;
  y.modelUp = UrdfLoadOptions::Up::Y;
  const UrdfLoadResult automatic = UrdfModel::fromString(xml, y);
  ASSERT_TRUE(automatic.ok()) << automatic.status.message();
  EXPECT_TRUE(automatic.warnings.empty());
  // The neck now rises along z, its axis (z, side to side in the file) is now -y in the root's frame, and
  // the body box stands along z.
  const JointDesc& neck = jointNamed(*automatic.model, "neck");
  EXPECT_TRUE(neck.origin.translation().isApprox(Eigen::Vector3d(0, 0, 1.5), 1e-12));
  EXPECT_TRUE((neck.origin.linear() * neck.axis).isApprox(Eigen::Vector3d(0, -1, 0), 1e-12));
  EXPECT_TRUE(
      automatic.model->links()[0].shapes[0].origin.translation().isApprox(Eigen::Vector3d(0, 0, 0.5), 1e-12));
  // Told z: the file's frame, and no warning.
  UrdfLoadOptions z;
  z.modelUp = UrdfLoadOptions::Up::Z;
  const UrdfLoadResult kept = UrdfModel::fromString(xml, z);
  ASSERT_TRUE(kept.ok());
  EXPECT_TRUE(kept.warnings.empty());
  EXPECT_TRUE(
      jointNamed(*kept.model, "neck").origin.translation().isApprox(Eigen::Vector3d(0, 1.5, 0), 1e-12));
  // The shipped humanoid stands along z: nothing is turned.
  EXPECT_TRUE(UrdfModel::humanoid().warnings.empty());
}

TEST(Urdf, AYUpHumanoidWithLegsIsTurnedByItself) {
  // Y-up, x forward, z to the right (as DeepMimic's humanoid): legs hang along -y from hip and knee joints
  // about z, the torso rises along +y.
  std::string xml = R"(<robot name="yup"><link name="pelvis"><collision><geometry><box size="0.2 0.15 0.3"/>
      </geometry></collision></link>
      <link name="torso"><collision><origin xyz="0 0.3 0"/><geometry><box size="0.2 0.5 0.35"/></geometry></collision></link>
      <joint name="waist" type="fixed"><parent link="pelvis"/><child link="torso"/><origin xyz="0 0.1 0"/></joint>)";
  for (const char* side : {"left", "right"}) {
    const std::string z = std::string(side) == "left" ? "-0.1" : "0.1";
    const std::string s(side);
    xml += "<link name='" + s +
           "_thigh'><collision><origin xyz='0 -0.2 0'/><geometry><box size='0.1 0.4 0.1'/>"
           "</geometry></collision></link><link name='" +
           s +
           "_shin'><collision><origin xyz='0 -0.2 0'/>"
           "<geometry><box size='0.1 0.4 0.1'/></geometry></collision></link>"
           "<joint name='" +
           s + "_hip' type='revolute'><parent link='pelvis'/><child link='" + s +
           "_thigh'/>"
           "<origin xyz='0 -0.05 " +
           z +
           "'/><axis xyz='0 0 1'/><limit lower='-2' upper='2' effort='1' velocity='1'/></joint>"
           "<joint name='" +
           s + "_knee' type='revolute'><parent link='" + s + "_thigh'/><child link='" + s +
           "_shin'/>"
           "<origin xyz='0 -0.42 0'/><axis xyz='0 0 1'/><limit lower='-2' upper='2' effort='1' "
           "velocity='1'/></joint>";
  }
  xml += "</robot>";
  const UrdfLoadResult r = UrdfModel::fromString(xml);
  ASSERT_TRUE(r.ok()) << r.status.message();
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings.back().find("turned onto z"), std::string::npos) << r.warnings.back();
  // The knee now hangs along -z below the hip, and its axis is side to side (y).
  const JointDesc& hip = jointNamed(*r.model, "left_hip");
  EXPECT_TRUE(hip.origin.translation().isApprox(Eigen::Vector3d(0, 0.1, -0.05), 1e-12))
      << hip.origin.translation();
  EXPECT_NEAR(std::fabs((hip.origin.linear() * hip.axis).y()), 1.0, 1e-12);
}

TEST(Urdf, XmlCheckAcceptsOrdinaryDocuments) {
  std::string msg;
  EXPECT_TRUE(
      checkXmlWellFormed("\xEF\xBB\xBF<?xml version=\"1.0\"?>\n<!DOCTYPE r [<!ENTITY e \"x\">]>\n<r a='1' b "
                         "= \"2\"><![CDATA[<x>]]>"
                         "<!-- <c> --><s/>t &amp; u</r>\n",
                         msg))
      << msg;
}
