// The URDF loader against hostile input: every limit of UrdfLimits hit by a generated model (and the error
// naming it), graph checks that stay linear on a 30,000-link chain and cycle, joints with a second or an
// empty parent or child element (urdfdom would build, and leak, a self-loop), cycles named, and deep nesting.
#include "cape/character/Urdf.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

using namespace cape::character;
namespace fs = std::filesystem;

namespace {

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A chain l0 <- l1 <- ... <- l(n-1) of fixed joints, 1 cm apart along z.
std::string chainUrdf(int links) {
  std::string xml = "<robot name=\"chain\">\n<link name=\"l0\"/>\n";
  for (int i = 1; i < links; ++i) {
    const std::string n = std::to_string(i), p = std::to_string(i - 1);
    xml += "<link name=\"l" + n + "\"/><joint name=\"j" + n + "\" type=\"fixed\"><parent link=\"l" + p +
           "\"/><child link=\"l" + n + "\"/><origin xyz=\"0 0 0.01\"/></joint>\n";
  }
  return xml + "</robot>\n";
}

// `count` spheres on each of two links.
std::string spheresUrdf(int count) {
  std::string spheres;
  for (int i = 0; i < count; ++i)
    spheres += "<collision><geometry><sphere radius=\"0.1\"/></geometry></collision>";
  return "<robot name=\"s\"><link name=\"a\">" + spheres + "</link><link name=\"b\">" + spheres +
         "</link><joint name=\"ab\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>";
}

UrdfLoadOptions withLimits(const UrdfLimits& limits) {
  UrdfLoadOptions options;
  options.limits = limits;
  return options;
}

// A fresh folder per process and test, removed afterwards.
class UrdfLimitsFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("cape_urdf_limits_" + std::to_string(::getpid())) / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_.parent_path(), ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  fs::path dir_;
};

// An ASCII STL of a closed box of `boxes` x 1 x 1 unit cubes along x: 12 triangles per cube.
std::string boxesStl(int boxes) {
  std::string stl = "solid boxes\n";
  const auto corner = [](int x0, int c) {
    return std::to_string(x0 + (c & 1)) + " " + std::to_string((c >> 1) & 1) + " " + std::to_string(c >> 2);
  };
  // The six faces of a unit cube as corner indices (bit 0 x, bit 1 y, bit 2 z), two triangles each.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int b = 0; b < boxes; ++b) {
    for (const auto& f : faces) {
      for (const auto& t : {std::array<int, 3>{f[0], f[1], f[2]}, std::array<int, 3>{f[0], f[2], f[3]}}) {
        stl += "facet normal 0 0 0\nouter loop\n";
        for (int c : t) stl += "vertex " + corner(b, c) + "\n";
        stl += "endloop\nendfacet\n";
      }
    }
  }
  return stl + "endsolid boxes\n";
}

}  // namespace

TEST(UrdfLimits, DefaultsAreDocumentedValuesAndTheShippedHumanoidLoadsWithinThem) {
  const UrdfLimits limits;
  EXPECT_EQ(limits.maxFileBytes, std::size_t(64) << 20);
  EXPECT_EQ(limits.maxXmlElements, 1000000u);
  EXPECT_EQ(limits.maxXmlDepth, 256u);
  EXPECT_EQ(limits.maxLinks, 10000u);
  EXPECT_EQ(limits.maxJoints, 10000u);
  EXPECT_EQ(limits.maxCollisionElements, 100000u);
  EXPECT_EQ(limits.maxMeshTriangles, 4000000u);
  EXPECT_EQ(limits.maxLength, 1000.0);
  EXPECT_TRUE(UrdfModel::humanoid().ok());
}

TEST(UrdfLimits, ALimitOfZeroOrADepthPastTheCeilingIsAnInvalidArgument) {
  UrdfLimits zero;
  zero.maxJoints = 0;
  const UrdfLoadResult r = UrdfModel::fromString(UrdfModel::humanoidUrdf(), withLimits(zero));
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument) << r.status.message();
  EXPECT_TRUE(has(r.status.message(), "UrdfLimits::maxJoints")) << r.status.message();
  UrdfLimits deep;
  deep.maxXmlDepth = 5000;
  const UrdfLoadResult d = UrdfModel::fromString(UrdfModel::humanoidUrdf(), withLimits(deep));
  EXPECT_EQ(d.status.code(), ErrorCode::InvalidArgument) << d.status.message();
  EXPECT_TRUE(has(d.status.message(), "UrdfLimits::maxXmlDepth")) << d.status.message();
}

TEST(UrdfLimits, LinksOverTheLimitAreRefusedNamingTheLimit) {
  UrdfLimits limits;
  limits.maxLinks = 4;
  EXPECT_TRUE(UrdfModel::fromString(chainUrdf(4), withLimits(limits)).ok());
  const UrdfLoadResult r = UrdfModel::fromString(chainUrdf(5), withLimits(limits));
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
  EXPECT_EQ(r.status.message(), "URDF has 5 links; the limit is 4 (UrdfLimits::maxLinks)");
  // The default: 10,000.
  const UrdfLoadResult big = UrdfModel::fromString(chainUrdf(10001));
  EXPECT_EQ(big.status.code(), ErrorCode::InvalidModel) << big.status.message();
  EXPECT_EQ(big.status.message(), "URDF has 10001 links; the limit is 10000 (UrdfLimits::maxLinks)");
}

TEST(UrdfLimits, JointsOverTheLimitAreRefusedNamingTheLimit) {
  UrdfLimits limits;
  limits.maxJoints = 3;
  EXPECT_TRUE(UrdfModel::fromString(chainUrdf(4), withLimits(limits)).ok());
  const UrdfLoadResult r = UrdfModel::fromString(chainUrdf(5), withLimits(limits));
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
  EXPECT_EQ(r.status.message(), "URDF has 4 joints; the limit is 3 (UrdfLimits::maxJoints)");
}

TEST(UrdfLimits, CollisionElementsOverTheLimitAreRefusedNamingTheLimit) {
  UrdfLimits limits;
  limits.maxCollisionElements = 6;  // of all links together
  const UrdfLoadResult fits = UrdfModel::fromString(spheresUrdf(3), withLimits(limits));
  ASSERT_TRUE(fits.ok()) << fits.status.message();
  EXPECT_EQ(fits.model->links()[0].shapes.size() + fits.model->links()[1].shapes.size(), 6u);
  const UrdfLoadResult r = UrdfModel::fromString(spheresUrdf(4), withLimits(limits));
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
  EXPECT_EQ(r.status.message(),
            "URDF has 8 collision elements; the limit is 6 (UrdfLimits::maxCollisionElements)");
}

TEST(UrdfLimits, XmlElementsOverTheLimitAreRefusedNamingTheLimit) {
  UrdfLimits limits;
  limits.maxXmlElements = 17;  // robot, 4 links, 3 joints of 4 elements each (joint, parent, child, origin)
  EXPECT_TRUE(UrdfModel::fromString(chainUrdf(4), withLimits(limits)).ok());
  limits.maxXmlElements = 10;
  const UrdfLoadResult r = UrdfModel::fromString(chainUrdf(4), withLimits(limits));
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
  EXPECT_TRUE(
      has(r.status.message(), "more than 10 XML elements; the limit is 10 (UrdfLimits::maxXmlElements)"))
      << r.status.message();
}

TEST(UrdfLimits, TextOverTheSizeLimitIsRefusedNamingTheLimit) {
  const std::string xml = chainUrdf(3);
  UrdfLimits limits;
  limits.maxFileBytes = xml.size();
  EXPECT_TRUE(UrdfModel::fromString(xml, withLimits(limits)).ok());
  limits.maxFileBytes = xml.size() - 1;
  const UrdfLoadResult r = UrdfModel::fromString(xml, withLimits(limits));
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
  EXPECT_EQ(r.status.message(), "URDF has " + std::to_string(xml.size()) + " bytes; the limit is " +
                                    std::to_string(xml.size() - 1) + " (UrdfLimits::maxFileBytes)");
}

TEST_F(UrdfLimitsFiles, AFileOverTheSizeLimitIsRefusedBeforeItIsRead) {
  const std::string xml = chainUrdf(3);
  const std::string small = write("small.urdf", xml);
  UrdfLimits limits;
  limits.maxFileBytes = xml.size();
  EXPECT_TRUE(UrdfModel::fromFile(small, withLimits(limits)).ok());
  limits.maxFileBytes = xml.size() - 1;
  const UrdfLoadResult r = UrdfModel::fromFile(small, withLimits(limits));
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
  EXPECT_TRUE(has(r.status.message(), "(UrdfLimits::maxFileBytes)")) << r.status.message();
  EXPECT_TRUE(has(r.status.message(), small)) << r.status.message();

  // 100 MB (a sparse file: its size alone is on disk) against the default 64 MiB. Read, it would be NUL
  // bytes: an empty document.
  const fs::path huge = dir_ / "huge.urdf";
  std::ofstream(huge, std::ios::binary) << xml;
  fs::resize_file(huge, 100000000);
  const UrdfLoadResult h = UrdfModel::fromFile(huge.string());
  EXPECT_EQ(h.status.code(), ErrorCode::InvalidModel) << h.status.message();
  EXPECT_TRUE(
      has(h.status.message(), "URDF has 100000000 bytes; the limit is 67108864 (UrdfLimits::maxFileBytes)"))
      << h.status.message();
}

TEST(UrdfLimits, NestingOneHundredThousandDeepIsRefusedNamingTheDepthLimit) {
  std::string xml = "<robot name=\"deep\">";
  for (int i = 0; i < 100000; ++i) xml += "<a>";
  for (int i = 0; i < 100000; ++i) xml += "</a>";
  xml += "</robot>";
  const UrdfLoadResult r = UrdfModel::fromString(xml);
  EXPECT_EQ(r.status.code(), ErrorCode::MalformedXml) << r.status.message();
  EXPECT_TRUE(
      has(r.status.message(), "nested deeper than 256 levels; the limit is 256 (UrdfLimits::maxXmlDepth)"))
      << r.status.message();
}

TEST(UrdfLimits, TheDepthLimitCanBeSet) {
  // robot > link > collision > geometry > sphere: 5 levels.
  UrdfLimits limits;
  limits.maxXmlDepth = 5;
  EXPECT_TRUE(UrdfModel::fromString(spheresUrdf(1), withLimits(limits)).ok());
  limits.maxXmlDepth = 4;
  const UrdfLoadResult r = UrdfModel::fromString(spheresUrdf(1), withLimits(limits));
  EXPECT_EQ(r.status.code(), ErrorCode::MalformedXml) << r.status.message();
  EXPECT_TRUE(
      has(r.status.message(), "nested deeper than 4 levels; the limit is 4 (UrdfLimits::maxXmlDepth)"))
      << r.status.message();
}

TEST(UrdfLimits, AThirtyThousandLinkChainLoadsOrIsRefusedInOnePass) {
  const std::string xml = chainUrdf(30000);
  const UrdfLoadResult refused = UrdfModel::fromString(xml);
  EXPECT_EQ(refused.status.code(), ErrorCode::InvalidModel) << refused.status.message();
  EXPECT_TRUE(has(refused.status.message(), "(UrdfLimits::maxLinks)")) << refused.status.message();
  // With the limits raised it loads (every graph check linear: the quadratic walk took minutes here).
  UrdfLimits limits;
  limits.maxLinks = limits.maxJoints = 30000;
  const UrdfLoadResult r = UrdfModel::fromString(xml, withLimits(limits));
  ASSERT_TRUE(r.ok()) << r.status.message();
  ASSERT_EQ(r.model->links().size(), 30000u);
  const int last = r.model->findLink("l29999");
  ASSERT_GE(last, 0);
  EXPECT_EQ(r.model->links()[static_cast<std::size_t>(last)].parentLink, r.model->findLink("l29998"));
}

TEST(UrdfLimits, AThirtyThousandLinkCycleIsNamedInABoundedMessage) {
  // A root, and beside it a cycle c0 <- c1 <- ... <- c29999 <- c0.
  std::string xml = "<robot name=\"loop\"><link name=\"root\"/>";
  const int n = 30000;
  for (int i = 0; i < n; ++i) {
    const std::string c = std::to_string(i), p = std::to_string((i + n - 1) % n);
    xml += "<link name=\"c" + c + "\"/><joint name=\"j" + c + "\" type=\"fixed\"><parent link=\"c" + p +
           "\"/><child link=\"c" + c + "\"/></joint>";
  }
  xml += "</robot>";
  UrdfLimits limits;
  limits.maxLinks = limits.maxJoints = 40000;
  const UrdfLoadResult r = UrdfModel::fromString(xml, withLimits(limits));
  EXPECT_EQ(r.status.code(), ErrorCode::NotATree) << r.status.message();
  EXPECT_TRUE(has(r.status.message(), "cycle of 30000 link(s)")) << r.status.message();
  EXPECT_LT(r.status.message().size(), 300u) << r.status.message();
}

TEST(UrdfLimits, ACycleOfThreeLinksIsNamedLinkByLink) {
  const UrdfLoadResult r = UrdfModel::fromString(R"(<robot name="c"><link name="root"/>
    <link name="hip"/><link name="knee"/><link name="ankle"/>
    <joint name="j1" type="fixed"><parent link="hip"/><child link="knee"/></joint>
    <joint name="j2" type="fixed"><parent link="knee"/><child link="ankle"/></joint>
    <joint name="j3" type="fixed"><parent link="ankle"/><child link="hip"/></joint></robot>)");
  EXPECT_EQ(r.status.code(), ErrorCode::NotATree) << r.status.message();
  const std::string& m = r.status.message();
  EXPECT_TRUE(has(m, "cycle of 3 link(s)")) << m;
  // Child -> parent, from any of the three.
  EXPECT_TRUE(has(m, "hip -> ankle -> knee -> hip") || has(m, "knee -> hip -> ankle -> knee") ||
              has(m, "ankle -> knee -> hip -> ankle"))
      << m;
}

TEST(UrdfLimits, AJointWithASecondEmptyParentIsRefusedBeforeUrdfdom) {
  // urdfdom reads the first <parent>: a self-loop a -> a, whose shared pointers it would never free.
  const UrdfLoadResult r = UrdfModel::fromString(R"(<robot name="p"><link name="a"/>
    <joint name="j" type="fixed"><parent link="a"/><child link="a"/><parent/></joint></robot>)");
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
  EXPECT_EQ(r.status.message(),
            "joint 'j' has more than one <parent> element; a joint has one parent and one child link");
  const UrdfLoadResult child = UrdfModel::fromString(R"(<robot name="p"><link name="a"/><link name="b"/>
    <joint name="k" type="fixed"><parent link="a"/><child link="b"/><child link="a"/></joint></robot>)");
  EXPECT_EQ(child.status.code(), ErrorCode::InvalidModel) << child.status.message();
  EXPECT_TRUE(has(child.status.message(), "joint 'k' has more than one <child> element"))
      << child.status.message();
  const UrdfLoadResult empty = UrdfModel::fromString(R"(<robot name="p"><link name="a"/><link name="b"/>
    <joint name="e" type="fixed"><parent link=" "/><child link="b"/></joint></robot>)");
  EXPECT_EQ(empty.status.code(), ErrorCode::InvalidModel) << empty.status.message();
  EXPECT_TRUE(has(empty.status.message(), "joint 'e': its <parent> element names no link"))
      << empty.status.message();
  const UrdfLoadResult none = UrdfModel::fromString(R"(<robot name="p"><link name="a"/><link name="b"/>
    <joint name="n" type="fixed"><parent link="a"/></joint></robot>)");
  EXPECT_EQ(none.status.code(), ErrorCode::InvalidModel) << none.status.message();
  EXPECT_TRUE(has(none.status.message(), "joint 'n' has no <child> element")) << none.status.message();
}

TEST(UrdfLimits, LinkNamesAreComparedAsUrdfdomReadsThem) {
  // &#97; is 'a': urdfdom would read a self-loop a -> a (and leak it); the check sees the same names.
  const UrdfLoadResult loop = UrdfModel::fromString(R"(<robot name="p"><link name="a"/>
    <joint name="j" type="fixed"><parent link="a"/><child link="&#97;"/></joint></robot>)");
  EXPECT_EQ(loop.status.code(), ErrorCode::NotATree) << loop.status.message();
  EXPECT_TRUE(has(loop.status.message(), "cycle of 1 link(s) (child -> parent): a -> a"))
      << loop.status.message();
  // Names written with references are the same links for the joints and for their shapes.
  const UrdfLoadResult named = UrdfModel::fromString(R"(<robot name="p"><link name="base"/>
    <link name="arm&amp;hand"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
    <joint name="j" type="fixed"><parent link="base"/><child link="arm&#x26;hand"/></joint></robot>)");
  ASSERT_TRUE(named.ok()) << named.status.message();
  const int arm = named.model->findLink("arm&hand");
  ASSERT_GE(arm, 0);
  EXPECT_EQ(named.model->links()[static_cast<std::size_t>(arm)].shapes.size(), 1u);
  const UrdfLoadResult bad = UrdfModel::fromString(R"(<robot name="p"><link name="a"/><link name="b"/>
    <joint name="j" type="fixed"><parent link="a"/><child link="&#0;"/></joint></robot>)");
  EXPECT_EQ(bad.status.code(), ErrorCode::InvalidModel) << bad.status.message();
}

TEST_F(UrdfLimitsFiles, MeshTrianglesOfTheWholeModelOverTheLimitAreRefusedNamingTheLimit) {
  write("one.stl", boxesStl(1));  // 12 triangles
  write("two.stl", boxesStl(2));  // 24 triangles
  const auto urdf = [](const std::string& first, const std::string& second) {
    return "<robot name=\"m\"><link name=\"a\"><collision><geometry><mesh filename=\"" + first +
           "\"/></geometry></collision></link><link name=\"b\"><collision><geometry><mesh filename=\"" +
           second +
           "\"/></geometry></collision></link><joint name=\"ab\" type=\"fixed\"><parent link=\"a\"/>"
           "<child link=\"b\"/></joint></robot>";
  };
  UrdfLoadOptions options;
  options.baseDir = dir_.string();
  options.limits.maxMeshTriangles = 24;
  const UrdfLoadResult fits = UrdfModel::fromString(urdf("one.stl", "one.stl"), options);
  ASSERT_TRUE(fits.ok()) << fits.status.message();
  EXPECT_EQ(fits.model->links()[1].shapes.at(0).type, ShapeType::ConvexHull);
  // The same file twice counts twice.
  const UrdfLoadResult sum = UrdfModel::fromString(urdf("one.stl", "two.stl"), options);
  EXPECT_EQ(sum.status.code(), ErrorCode::InvalidModel) << sum.status.message();
  EXPECT_TRUE(has(sum.status.message(), "at least 36 triangles")) << sum.status.message();
  EXPECT_TRUE(has(sum.status.message(), "link 'b'")) << sum.status.message();
  EXPECT_TRUE(has(sum.status.message(), "the limit is 24 (UrdfLimits::maxMeshTriangles"))
      << sum.status.message();
  // One mesh over the limit alone is refused while it is read.
  options.limits.maxMeshTriangles = 20;
  const UrdfLoadResult alone = UrdfModel::fromString(urdf("two.stl", "one.stl"), options);
  EXPECT_EQ(alone.status.code(), ErrorCode::InvalidModel) << alone.status.message();
  EXPECT_TRUE(
      has(alone.status.message(), "link 'a', collision element 'a#0', mesh 'two.stl' alone has more than 20"))
      << alone.status.message();
  EXPECT_TRUE(has(alone.status.message(), "(UrdfLimits::maxMeshTriangles")) << alone.status.message();
}

TEST(UrdfLimits, ElementsHiddenInADeclarationOrAProcessingInstructionAreNotReadByUrdfdom) {
  // Each ends, for TinyXML (urdfdom's parser), at its first '>', and what follows would be read as markup:
  // here a joint that makes link 'a' its own parent (which urdfdom would leak). The check skips them whole,
  // and so does urdfdom now: each model is the one link.
  const std::string selfLoop = R"(<joint name="j" type="fixed"><parent link="a"/><child link="a"/></joint>)";
  const std::string texts[] = {R"(<robot name="r"><link name="a"/><?pi >)" + selfLoop + R"( ?></robot>)",
                               R"(<robot name="r"><link name="a"/><!X [>)" + selfLoop + R"(]></robot>)",
                               R"(<!DOCTYPE r [<!ELEMENT r ANY><robot name="fake"><link name="a"/>)" +
                                   selfLoop +
                                   R"(</robot>]>
<robot name="r"><link name="a"/></robot>)"};
  for (const std::string& text : texts) {
    const UrdfLoadResult r = UrdfModel::fromString(text);
    ASSERT_TRUE(r.ok()) << text << ": " << r.status.message();
    EXPECT_EQ(r.model->name(), "r");
    EXPECT_EQ(r.model->links().size(), 1u);
    EXPECT_TRUE(r.model->joints().empty());
  }
}

TEST(UrdfLimits, LengthsBeyondAnyRobotAreRefusedNamingTheLimit) {
  // The shipped humanoid with a shoulder sphere of 1e30 m, or a shoulder 1e30 m from the torso: once a walk
  // that ran to exit 0 with 412 % strain.
  const std::string humanoid = UrdfModel::humanoidUrdf();
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = humanoid;
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? text : text.replace(at, from.size(), to);
  };
  const std::string cases[] = {
      replaced("<sphere radius=\"0.08\"/>", "<sphere radius=\"1e30\"/>"),
      replaced("xyz=\"0 0.22 0.57\"", "xyz=\"0 1e30 0.57\""),
      replaced("<sphere radius=\"0.08\"/>", "<box size=\"1 2.2e3 1\"/>"),
      replaced("<sphere radius=\"0.08\"/>", "<sphere radius=\"1001\"/>"),
  };
  for (const std::string& text : cases) {
    const UrdfLoadResult r = UrdfModel::fromString(text);
    EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
    EXPECT_TRUE(has(r.status.message(), "UrdfLimits::maxLength")) << r.status.message();
  }
  // Within the limit, or with it raised, the same file loads.
  EXPECT_TRUE(UrdfModel::fromString(replaced("<sphere radius=\"0.08\"/>", "<sphere radius=\"999\"/>")).ok());
  UrdfLimits wide;
  wide.maxLength = 1e31;
  EXPECT_TRUE(UrdfModel::fromString(cases[1], withLimits(wide)).ok());
  UrdfLimits bad;
  bad.maxLength = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(UrdfModel::fromString(humanoid, withLimits(bad)).status.code(), ErrorCode::InvalidArgument);
}

TEST(UrdfLimits, AJointAxisWhoseSquareOverflowsIsStillMadeAUnitVector) {
  // <axis xyz="1e300 -1 0">: its norm overflowed to inf and the axis came out (0, -0, 0), not a unit vector
  // (found by the urdf fuzz target; regressions/urdf/axis_1e300_not_unit.urdf).
  std::string text = UrdfModel::humanoidUrdf();
  const std::string joint = "name=\"right_hip_pitch\"";
  const std::size_t at = text.find("<axis xyz=\"", text.find(joint));
  ASSERT_NE(at, std::string::npos);
  text.replace(at, text.find("/>", at) - at, "<axis xyz=\"1e300 -1 0\"");
  const UrdfLoadResult r = UrdfModel::fromString(text);
  ASSERT_TRUE(r.ok()) << r.status.message();
  const JointDesc& j = r.model->joints()[static_cast<std::size_t>(r.model->findJoint("right_hip_pitch"))];
  EXPECT_NEAR(j.axis.norm(), 1.0, 1e-12);
  EXPECT_NEAR(j.axis.x(), 1.0, 1e-12);
  text.replace(text.find("<axis xyz=\"1e300 -1 0\""), 22, "<axis xyz=\"1e-300 0 0\"");
  EXPECT_EQ(UrdfModel::fromString(text).status.code(), ErrorCode::InvalidModel);
}
