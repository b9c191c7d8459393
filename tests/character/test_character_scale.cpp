// Characters of 10,000 links (the URDF loader's link limit): a chain, a star, long limbs and hostile joint
// names each build a Character, its shoulder anchors and a frame (issue 14: every graph check linear in the
// model). No timing assertion: a quadratic step shows as the test's timeout (ctest TIMEOUT).
#include "CharacterTestWorld.h"

#include "cape/character/Anchors.h"
#include "cape/character/Character.h"
#include "cape/character/Urdf.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

namespace {

using namespace cape::character;

const std::string kBox = "<collision><geometry><box size=\"0.1 0.2 0.3\"/></geometry></collision>";

std::string link(const std::string& name, const std::string& body = kBox) {
  return "<link name=\"" + name + "\">" + body + "</link>";
}

std::string joint(const std::string& name, const std::string& type, const std::string& parent,
                  const std::string& child, const std::string& xyz, const std::string& axis = "0 1 0") {
  return "<joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent +
         "\"/><child link=\"" + child + "\"/><origin xyz=\"" + xyz + "\"/><axis xyz=\"" + axis +
         "\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
}

std::string robot(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<robot name=\"r\">" + body + "</robot>\n";
}

// `links` links in a line, each 1 cm above the last.
std::string chain(int links, const std::string& type) {
  std::string body = link("l0");
  for (int i = 1; i < links; ++i) {
    body += link("l" + std::to_string(i));
    body += joint("j" + std::to_string(i), type, "l" + std::to_string(i - 1), "l" + std::to_string(i),
                  "0 0 0.01");
  }
  return robot(body);
}

// A root and `links - 1` children on a circle around it.
std::string star(int links, const std::string& type) {
  std::string body = link("l0");
  for (int i = 1; i < links; ++i) {
    const double a = 2.0 * 3.14159265358979 * i / links;
    body += link("l" + std::to_string(i));
    body += joint("j" + std::to_string(i), type, "l0", "l" + std::to_string(i),
                  std::to_string(std::cos(a)) + " " + std::to_string(std::sin(a)) + " 0.5");
  }
  return robot(body);
}

// A torso with two legs (down, off the midline) and two arms (out to the sides), each a chain of a quarter of
// the links: the limb finder's and the mapping's walks along long limbs. With `named`, the arm joints are
// named like shoulders and elbows, and the leg joints like hips and knees, in turn.
std::string limbs(int links, bool named) {
  std::string body = link("torso");
  const int each = (links - 1) / 4;
  const char* sides[2] = {"left", "right"};
  for (int s = 0; s < 2; ++s) {
    const std::string y = s == 0 ? "0.01" : "-0.01";
    for (int limb = 0; limb < 2; ++limb) {  // 0 leg, 1 arm
      std::string parent = "torso";
      for (int i = 0; i < each; ++i) {
        const std::string name = std::string(sides[s]) + (limb == 0 ? "_leg" : "_arm") + std::to_string(i);
        std::string jname = name + "_j";
        if (named) {
          const char* part = limb == 0 ? (i % 2 ? "knee" : "hip") : (i % 2 ? "elbow" : "shoulder");
          jname = std::string(sides[s]) + "_" + part + "_" + std::to_string(i);
        }
        const std::string xyz = limb == 0 ? (i == 0 ? "0 " + y + " -0.1" : "0 0 -0.01")
                                          : (i == 0 ? "0 " + y + " 0.5" : "0 " + y + " 0");
        body += link(name);
        body += joint(jname, "revolute", parent, name, xyz, i % 3 == 1 ? "1 0 0" : "0 1 0");
        parent = name;
      }
    }
  }
  return robot(body);
}

void build(const std::string& what, const std::string& text, int links) {
  const auto t0 = std::chrono::steady_clock::now();
  UrdfLoadResult model = UrdfModel::fromString(text);
  ASSERT_TRUE(model.ok()) << what << ": " << model.status.message();
  ASSERT_EQ(model.model->links().size(), static_cast<std::size_t>(links)) << what;
  const auto t1 = std::chrono::steady_clock::now();
  capetest::World w;
  CharacterResult made = Character::create(model.model, w.world, Gait::forScene(cape::SceneKind::Walk));
  ASSERT_TRUE(made.status.ok()) << what << ": " << made.status.message();
  const auto t2 = std::chrono::steady_clock::now();
  Character& c = *made.character;
  (void)findShoulderAnchors(c);
  c.advanceTo(1.0 / 60.0);
  w.world.stepSimulation(1.0f / 60.0f, 1, 1.0f / 60.0f);
  const auto t3 = std::chrono::steady_clock::now();
  EXPECT_EQ(c.skeleton().linkCount(), links) << what;
  EXPECT_TRUE(std::isfinite(c.rootHeight())) << what;
  int bodies = 0;
  for (int l = 0; l < links; ++l) {
    const Eigen::Isometry3d& pose = c.skeleton().linkPose(l);
    ASSERT_TRUE(pose.matrix().allFinite()) << what << ": link " << l;
    if (c.bodies().bodyForLink(l) != nullptr) ++bodies;
  }
  EXPECT_EQ(bodies, links) << what;  // every link has a box
  std::vector<WorldShape> shapes;
  c.skeleton().worldShapes(shapes);
  EXPECT_EQ(shapes.size(), static_cast<std::size_t>(links)) << what;
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  std::printf("%-22s load %7.1f ms, Character::create %7.1f ms, anchors + frame %7.1f ms\n", what.c_str(),
              ms(t0, t1), ms(t1, t2), ms(t2, t3));
}

constexpr int kLinks = 10000;

TEST(CharacterScale, RevoluteChain) {
  build("revolute chain", chain(kLinks, "revolute"), kLinks);
}
TEST(CharacterScale, FixedChain) {
  build("fixed chain", chain(kLinks, "fixed"), kLinks);
}
TEST(CharacterScale, RevoluteStar) {
  build("revolute star", star(kLinks, "revolute"), kLinks);
}
TEST(CharacterScale, FixedStar) {
  build("fixed star", star(kLinks, "fixed"), kLinks);
}
TEST(CharacterScale, LongLimbs) {
  build("long limbs", limbs(kLinks, false), 1 + 4 * ((kLinks - 1) / 4));
}
TEST(CharacterScale, LongNamedLimbs) {
  build("long named limbs", limbs(kLinks, true), 1 + 4 * ((kLinks - 1) / 4));
}

}  // namespace
