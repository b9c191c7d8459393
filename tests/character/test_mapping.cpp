// Joint mapping: the shipped names, the common-name fallback on another humanoid, signs found from the model,
// unmapped roles reported, and the shoulder rolls that bring T-pose and A-pose arms down (by name and by
// geometry, a ball shoulder of three revolute joints in any order). Robot abbreviations (Hubo's LHP, Atlas's
// l_leg_hpy) and, where names say nothing, the limbs found by structure, each walked through the gait.
#include "cape/character/Gait.h"
#include "cape/character/JointMapping.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
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

// --- Whole humanoids in the shapes public robots use ---

// One joint of a limb and the link it moves: name, axis ("0 1 0"), origin in the parent link, the child
// link's name and collision (empty: none), limits.
struct Piece {
  std::string joint, axis, xyz, link, collision;
  double lower = -2.6, upper = 2.6;
};

std::string cylinder(const std::string& xyz, const std::string& rpy, double radius, double length) {
  std::ostringstream o;
  o << "<collision><origin xyz=\"" << xyz << "\" rpy=\"" << rpy << "\"/><geometry><cylinder radius=\""
    << radius << "\" length=\"" << length << "\"/></geometry></collision>";
  return o.str();
}
std::string box(const std::string& xyz, const std::string& size) {
  return "<collision><origin xyz=\"" + xyz + "\"/><geometry><box size=\"" + size +
         "\"/></geometry></collision>";
}
std::string ball(const std::string& xyz, double radius) {
  return "<collision><origin xyz=\"" + xyz + "\"/><geometry><sphere radius=\"" + std::to_string(radius) +
         "\"/></geometry></collision>";
}

// A chain of pieces hung from `parent`, each piece's link the next one's parent.
std::string chainXml(std::string parent, const std::vector<Piece>& pieces) {
  std::ostringstream u;
  for (const Piece& p : pieces) {
    u << "<link name=\"" << p.link << "\">" << p.collision << "</link>\n"
      << "<joint name=\"" << p.joint << "\" type=\"revolute\"><parent link=\"" << parent
      << "\"/><child link=\"" << p.link << "\"/><origin xyz=\"" << p.xyz << "\"/><axis xyz=\"" << p.axis
      << "\"/><limit lower=\"" << p.lower << "\" upper=\"" << p.upper
      << "\" effort=\"1\" velocity=\"1\"/></joint>\n";
    parent = p.link;
  }
  return u.str();
}

// A humanoid: pelvis (the root), a waist joint up to the torso, a neck joint up to the head, and the chains
// given for the legs (hung from the pelvis) and the arms (from the torso), left then right.
std::string humanoidXml(const std::string& waist, const std::string& neck, const std::vector<Piece> legs[2],
                        const std::vector<Piece> arms[2]) {
  std::ostringstream u;
  u << "<robot name=\"walker\">\n"
    << "<link name=\"pelvis\">" << box("0 0 0", "0.2 0.3 0.14") << "</link>\n"
    << "<link name=\"torso\">" << box("0 0 0.3", "0.2 0.34 0.5") << "</link>\n"
    << "<link name=\"head\">" << ball("0 0 0.12", 0.1) << "</link>\n"
    << "<joint name=\"" << waist << "\" type=\"revolute\"><parent link=\"pelvis\"/><child link=\"torso\"/>"
    << "<origin xyz=\"0 0 0.08\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" "
    << "velocity=\"1\"/></joint>\n"
    << "<joint name=\"" << neck << "\" type=\"revolute\"><parent link=\"torso\"/><child link=\"head\"/>"
    << "<origin xyz=\"0 0 0.62\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" "
    << "velocity=\"1\"/></joint>\n";
  for (int k = 0; k < 2; ++k) u << chainXml("pelvis", legs[k]) << chainXml("torso", arms[k]);
  u << "</robot>";
  return u.str();
}

std::string axisOf(char a, bool flip = false) {
  const char* s = flip ? "-1" : "1";
  return a == 'x'   ? std::string(s) + " 0 0"
         : a == 'y' ? "0 " + std::string(s) + " 0"
                    : "0 0 " + std::string(s);
}

// A leg of side k (0 left): three hip joints at one point 5 cm below the pelvis, the thigh, the knee 0.4 m
// below, the shin, two ankle joints 0.4 m below that, the foot (link "<k>foot"). `joints` gives the six
// joints' names and axes ('x', 'y', 'z'; a capital flips it).
std::vector<Piece> legOf(int k, const std::vector<std::pair<std::string, char>>& joints) {
  const std::string p = k == 0 ? "l" : "r", y = k == 0 ? "0.1" : "-0.1";
  const std::string xyz[6] = {"0 " + y + " -0.05", "0 0 0", "0 0 0", "0 0 -0.4", "0 0 -0.4", "0 0 0"};
  const std::string link[6] = {p + "hip1", p + "hip2", p + "thigh", p + "shin", p + "ankle1", p + "foot"};
  const std::string shape[6] = {"",
                                "",
                                cylinder("0 0 -0.2", "0 0 0", 0.06, 0.4),
                                cylinder("0 0 -0.2", "0 0 0", 0.05, 0.4),
                                "",
                                box("0.05 0 -0.05", "0.22 0.1 0.05")};
  std::vector<Piece> out;
  for (int i = 0; i < 6; ++i) {
    const char a = joints[static_cast<std::size_t>(i)].second;
    const bool flip = std::isupper(static_cast<unsigned char>(a)) != 0;
    out.push_back({joints[static_cast<std::size_t>(i)].first,
                   axisOf(static_cast<char>(std::tolower(static_cast<unsigned char>(a))), flip), xyz[i],
                   link[i], shape[i]});
  }
  return out;
}

// An arm of side k hanging down from (0, +-0.2, 0.5) on the torso: three shoulder joints at one point, the
// upper arm, the elbow 0.3 m below, the forearm, a wrist joint 0.26 m below, the hand (link "<k>hand").
std::vector<Piece> armDownOf(int k, const std::vector<std::pair<std::string, char>>& joints) {
  const std::string p = k == 0 ? "l" : "r", y = k == 0 ? "0.2" : "-0.2";
  const std::string xyz[5] = {"0 " + y + " 0.5", "0 0 0", "0 0 0", "0 0 -0.3", "0 0 -0.26"};
  const std::string link[5] = {p + "sh1", p + "sh2", p + "upperarm", p + "forearm", p + "hand"};
  const std::string shape[5] = {ball("0 0 0", 0.05), "", cylinder("0 0 -0.15", "0 0 0", 0.04, 0.3),
                                cylinder("0 0 -0.13", "0 0 0", 0.035, 0.26), ball("0 0 -0.04", 0.04)};
  std::vector<Piece> out;
  for (int i = 0; i < 5; ++i) {
    const char a = joints[static_cast<std::size_t>(i)].second;
    out.push_back({joints[static_cast<std::size_t>(i)].first,
                   axisOf(static_cast<char>(std::tolower(static_cast<unsigned char>(a))),
                          std::isupper(static_cast<unsigned char>(a)) != 0),
                   xyz[i], link[i], shape[i]});
  }
  return out;
}

// Where a joint is and where a link is, in the URDF root frame.
Eigen::Vector3d jointAt(const Skeleton& s, int joint) {
  const int link = s.model().joints()[static_cast<std::size_t>(joint)].childLink;
  return Skeleton::urdfToWorld().transpose() * s.linkPose(link).translation();
}

// Walks a mapped humanoid through the gait (joints only, the root held at the origin) and checks that it
// moves sensibly: the feet alternate forward, the knees bend backwards, the arms hang below the shoulders
// standing, swing against the legs, and bend at the elbow (forward, unless `elbowsForward` is false).
void expectWalks(const UrdfModelPtr& model, const JointMapping& m, const std::string& what,
                 bool elbowsForward = true) {
  for (int r = 0; r < 10; ++r)
    ASSERT_GE(m.entries()[static_cast<std::size_t>(r)].joint, 0) << what << " " << r;
  Skeleton s(model);
  const Gait gait = Gait::forScene(cape::SceneKind::Walk);
  const double period = gait.period();
  auto poseAt = [&](double t) {
    s.resetJointPositions();
    Gait::setJoints(t < 0.0 ? gait.standingAngles() : gait.anglesAt(t), m, s);
  };
  auto at = [&](GaitRole role) { return jointAt(s, m[role].joint); };
  auto link = [&](const char* name) { return inUrdf(s, name); };
  auto ofSide = [](GaitRole left, int side) { return static_cast<GaitRole>(static_cast<int>(left) + side); };
  // Feet: the left one forward at a quarter period (left hip +A), behind at three quarters; the hands the
  // other way.
  poseAt(0.25 * period);
  EXPECT_GT(link("lfoot").x() - link("rfoot").x(), 0.3) << what;
  EXPECT_LT(link("lhand").x() - link("rhand").x(), -0.1) << what << ": the arms swing against the legs";
  poseAt(0.75 * period);
  EXPECT_LT(link("lfoot").x() - link("rfoot").x(), -0.3) << what;
  EXPECT_GT(link("lhand").x() - link("rhand").x(), 0.1) << what;
  for (int side = 0; side < 2; ++side) {
    // Knees: most bent at mid-swing (left at t = 0, right at half a period), the shin back from the thigh.
    poseAt(0.5 * side * period);
    const GaitRole knee = ofSide(GaitRole::LeftKnee, side);
    const Eigen::Vector3d thigh = (at(knee) - at(ofSide(GaitRole::LeftHip, side))).normalized();
    const Eigen::Vector3d shin = (at(ofSide(GaitRole::LeftAnkle, side)) - at(knee)).normalized();
    EXPECT_GT(thigh.cross(shin).y(), 0.5) << what << " side " << side << ": the knee bends backwards";
    EXPECT_GT(s.jointPosition(m[knee].joint) * m[knee].sign, 0.0) << what;
    // Arms: hanging standing; the elbow bent while walking (the forearm turned from the upper arm).
    const char* hand = side == 0 ? "lhand" : "rhand";
    const GaitRole shoulder = ofSide(GaitRole::LeftShoulder, side), elbow = ofSide(GaitRole::LeftElbow, side);
    // The upper arm from the shoulder roll when there is one (Atlas's pitch joint sits inboard, at the
    // clavicle).
    const GaitRole roll = ofSide(GaitRole::LeftShoulderRoll, side);
    const GaitRole top = m[roll].joint >= 0 ? roll : shoulder;
    auto bend = [&]() {
      const Eigen::Vector3d upper = (at(elbow) - at(top)).normalized();
      const Eigen::Vector3d fore = (link(hand) - at(elbow)).normalized();
      return std::make_pair(std::acos(std::clamp(upper.dot(fore), -1.0, 1.0)), upper.cross(fore));
    };
    poseAt(-1.0);
    EXPECT_LT(link(hand).z() - at(shoulder).z(), -0.45) << what << " side " << side << ": arm down";
    const double standing = bend().first;
    poseAt(0.25 * period);
    EXPECT_GT(bend().first, standing + 0.3) << what << " side " << side << ": elbow bent";
    if (elbowsForward) {
      EXPECT_LT(bend().second.y(), -0.3) << what << " side " << side << ": forward";
    }
    EXPECT_LT(link(hand).z(), at(shoulder).z()) << what;
  }
}

std::vector<std::string> notesByStructure(const JointMapping& m) {
  std::vector<std::string> out;
  for (const std::string& w : m.warnings())
    if (w.find("by structure") != std::string::npos) out.push_back(w);
  return out;
}

}  // namespace

TEST(JointMapping, HuboAbbreviationsAreReadAsSidePartAxis) {
  // DRC-Hubo's names: L/R, a part letter (Hip, Knee, Ankle, Shoulder, Elbow), an axis letter (Pitch, Roll,
  // Yaw); wrist (W), waist (TSY) and neck (NKY) codes are no part. The right knee turns the other way.
  std::vector<Piece> legs[2], arms[2];
  for (int k = 0; k < 2; ++k) {
    const std::string s = k == 0 ? "L" : "R";
    legs[k] = legOf(k, {{s + "HY", 'z'},
                        {s + "HR", 'x'},
                        {s + "HP", 'y'},
                        {s + "KP", k == 0 ? 'y' : 'Y'},
                        {s + "AP", 'y'},
                        {s + "AR", 'x'}});
    arms[k] =
        armDownOf(k, {{s + "SP", 'y'}, {s + "SR", 'x'}, {s + "SY", 'z'}, {s + "EP", 'y'}, {s + "WP", 'y'}});
  }
  const UrdfModelPtr model = load(humanoidXml("TSY", "NKY", legs, arms));
  ASSERT_TRUE(model);
  const JointMapping m = JointMapping::automatic(model);
  const std::vector<std::string> expected = {"LHP", "RHP", "LKP", "RKP", "LAP", "RAP",
                                             "LSP", "RSP", "LEP", "REP", "LSR", "RSR"};
  for (int r = 0; r < kGaitRoleCount; ++r)
    EXPECT_EQ(jointName(*model, m, static_cast<GaitRole>(r)), expected[static_cast<std::size_t>(r)])
        << toString(static_cast<GaitRole>(r));
  EXPECT_TRUE(m.warnings().empty()) << joined(m.warnings());
  EXPECT_EQ(m[GaitRole::LeftKnee].sign, -m[GaitRole::RightKnee].sign);
  expectWalks(model, m, "hubo");
}

TEST(JointMapping, AtlasAbbreviationsAndAnElbowAboutTheForwardAxis) {
  // Atlas's names: l_leg_hpz / hpx / hpy (hip about z, x, y), kny, aky / akx; l_arm_shy (shoulder pitch),
  // shx (roll), ely (upper arm twist), elx (the elbow: about x), wry, wrx. Built in a T-pose, as Atlas is.
  std::vector<Piece> legs[2], arms[2];
  for (int k = 0; k < 2; ++k) {
    const std::string s = k == 0 ? "l" : "r", y = k == 0 ? "" : "-";
    const double sy = k == 0 ? 1.0 : -1.0;
    legs[k] = legOf(k, {{s + "_leg_hpz", 'z'},
                        {s + "_leg_hpx", 'x'},
                        {s + "_leg_hpy", 'y'},
                        {s + "_leg_kny", 'y'},
                        {s + "_leg_aky", 'y'},
                        {s + "_leg_akx", 'x'}});
    const std::string along = "1.5708 0 0";  // a cylinder along y
    auto out = [&](double d) { return "0 " + y + std::to_string(d) + " 0"; };
    arms[k] = {{s + "_arm_shy", "0 1 0", "0 " + y + "0.2 0.5", s + "clav", ball("0 0 0", 0.05), -1.57, 0.78},
               {s + "_arm_shx", "1 0 0", out(0.05), s + "scap", "", -1.5708, 1.5708},
               {s + "_arm_ely", "0 1 0", out(0.1), s + "upperarm", cylinder(out(0.075), along, 0.04, 0.15),
                0.0, 3.14},
               {s + "_arm_elx", "1 0 0", out(0.15), s + "forearm", cylinder(out(0.1), along, 0.035, 0.2),
                sy > 0 ? 0.0 : -2.356, sy > 0 ? 2.356 : 0.0},
               {s + "_arm_wry", "0 1 0", out(0.2), s + "wrist", "", 0.0, 3.14},
               {s + "_arm_wrx", "1 0 0", out(0.03), s + "hand", ball(out(0.04), 0.04), -1.1, 1.1}};
  }
  const UrdfModelPtr model = load(humanoidXml("back_bkz", "neck_ry", legs, arms));
  ASSERT_TRUE(model);
  const JointMapping m = JointMapping::automatic(model);
  const std::vector<std::string> expected = {"l_leg_hpy", "r_leg_hpy", "l_leg_kny", "r_leg_kny",
                                             "l_leg_aky", "r_leg_aky", "l_arm_shy", "r_arm_shy",
                                             "l_arm_elx", "r_arm_elx", "l_arm_shx", "r_arm_shx"};
  for (int r = 0; r < kGaitRoleCount; ++r)
    EXPECT_EQ(jointName(*model, m, static_cast<GaitRole>(r)), expected[static_cast<std::size_t>(r)])
        << toString(static_cast<GaitRole>(r)) << "\n"
        << joined(m.warnings());
  // By name but the elbows: once the roll has lowered the arm, ely lies along it and elx across it, so
  // neither turns about the side-to-side axis; structure takes elx, said once per side, and signs it by its
  // limits (it bends one way, out from the body).
  const std::vector<std::string> notes = notesByStructure(m);
  ASSERT_EQ(notes.size(), 2u) << joined(m.warnings());
  EXPECT_EQ(notes[0].rfind("left elbow: joint 'l_arm_elx' (by structure, left arm 'torso' to 'lhand': ", 0),
            0u)
      << notes[0];
  EXPECT_EQ(notes[1].rfind("right elbow: joint 'r_arm_elx' (by structure, right arm 'torso' to 'rhand': ", 0),
            0u)
      << notes[1];
  EXPECT_TRUE(hasWarningWith(m,
                             "left elbow: joint 'l_arm_elx' moves its links neither forward nor backward; "
                             "signed by its limits"))
      << joined(m.warnings());
  EXPECT_FALSE(hasWarningWith(m, "no candidate")) << joined(m.warnings());
  EXPECT_FALSE(hasWarningWith(m, "cannot tell")) << joined(m.warnings());
  EXPECT_EQ(m[GaitRole::LeftElbow].sign, 1.0);
  EXPECT_EQ(m[GaitRole::RightElbow].sign, -1.0);
  expectWalks(model, m, "atlas", false);
  // The bent elbows take the forearms out from the body, not across it.
  Skeleton s(model);
  Gait::setJoints(Gait::forScene(cape::SceneKind::Walk).anglesAt(0.3), m, s);
  EXPECT_GT(inUrdf(s, "lhand").y(), inUrdf(s, "lforearm").y());
  EXPECT_LT(inUrdf(s, "rhand").y(), inUrdf(s, "rforearm").y());
}

TEST(JointMapping, AbbreviationsLeaveNamesThatWorkedAlone) {
  // JVRC-1's names (L_HIP_P, L_HIP_Y: yaw, L_KNEE, L_ANKLE_P, L_SHOULDER_P, the roll's trailing R,
  // L_ELBOW_P), H1's (left_hip_pitch_joint) and plain ones (l_hip_y, lknee, LShoulderRoll) map by name
  // alone, as before: nothing by structure.
  struct Case {
    const char* hip[3];
    const char* hipAxes;
    const char* knee;
    const char* ankle[2];
    const char* ankleAxes;
    const char* shoulder[3];  // about y, x, z
    const char* elbow;
    const char* expected[6];  // left hip, knee, ankle, shoulder, elbow, shoulder roll
  };
  const Case cases[] = {
      {{"L_HIP_P", "L_HIP_R", "L_HIP_Y"},
       "yxz",
       "L_KNEE",
       {"L_ANKLE_R", "L_ANKLE_P"},
       "xy",
       {"L_SHOULDER_P", "L_SHOULDER_R", "L_SHOULDER_Y"},
       "L_ELBOW_P",
       {"L_HIP_P", "L_KNEE", "L_ANKLE_P", "L_SHOULDER_P", "L_ELBOW_P", "L_SHOULDER_R"}},
      {{"left_hip_yaw_joint", "left_hip_roll_joint", "left_hip_pitch_joint"},
       "zxy",
       "left_knee_joint",
       {"left_ankle_joint", "left_ankle_roll_joint"},
       "yx",
       {"left_shoulder_pitch_joint", "left_shoulder_roll_joint", "left_shoulder_yaw_joint"},
       "left_elbow_joint",
       {"left_hip_pitch_joint", "left_knee_joint", "left_ankle_joint", "left_shoulder_pitch_joint",
        "left_elbow_joint", "left_shoulder_roll_joint"}},
      {{"l_hip_z", "l_hip_x", "l_hip_y"},
       "zxy",
       "lknee",
       {"l_ankle_y", "l_ankle_x"},
       "yx",
       {"LShoulderPitch", "LShoulderRoll", "LShoulderYaw"},
       "LElbow",
       {"l_hip_y", "lknee", "l_ankle_y", "LShoulderPitch", "LElbow", "LShoulderRoll"}},
  };
  for (const Case& c : cases) {
    auto mirror = [](std::string n) {
      // The right side's name: the leading l / L / left swapped.
      if (n.rfind("left", 0) == 0) return "right" + n.substr(4);
      n[0] = n[0] == 'L' ? 'R' : 'r';
      return n;
    };
    std::vector<Piece> legs[2], arms[2];
    for (int k = 0; k < 2; ++k) {
      auto name = [&](const char* n) { return k == 0 ? std::string(n) : mirror(n); };
      legs[k] = legOf(k, {{name(c.hip[0]), c.hipAxes[0]},
                          {name(c.hip[1]), c.hipAxes[1]},
                          {name(c.hip[2]), c.hipAxes[2]},
                          {name(c.knee), 'y'},
                          {name(c.ankle[0]), c.ankleAxes[0]},
                          {name(c.ankle[1]), c.ankleAxes[1]}});
      arms[k] = armDownOf(k, {{name(c.shoulder[0]), 'y'},
                              {name(c.shoulder[1]), 'x'},
                              {name(c.shoulder[2]), 'z'},
                              {name(c.elbow), 'y'},
                              {name("lwrist"), 'z'}});
    }
    const UrdfModelPtr model = load(humanoidXml("waist", "neck", legs, arms));
    ASSERT_TRUE(model);
    const JointMapping m = JointMapping::automatic(model);
    const GaitRole roles[6] = {GaitRole::LeftHip,      GaitRole::LeftKnee,  GaitRole::LeftAnkle,
                               GaitRole::LeftShoulder, GaitRole::LeftElbow, GaitRole::LeftShoulderRoll};
    for (int i = 0; i < 6; ++i) {
      EXPECT_EQ(jointName(*model, m, roles[i]), c.expected[i]) << c.knee;
      const auto right = static_cast<GaitRole>(static_cast<int>(roles[i]) + 1);
      EXPECT_EQ(jointName(*model, m, right), mirror(c.expected[i])) << c.knee;
    }
    EXPECT_TRUE(m.warnings().empty()) << joined(m.warnings());
    expectWalks(model, m, c.knee);
  }
}

TEST(JointMapping, MeaninglessNamesAreMappedByStructure) {
  // Joints j1..j24, declared in no helpful order: a T-pose humanoid whose shoulders turn about x (the
  // roll) first, then y, then z (as a human model's), so that arms down the z joint swings the arm; the
  // elbow about z (across the T-pose arm, forward once down). Hips z x y, knee, ankle y x; the right knee
  // and hip turn the other way. A waist and a neck, and a head reaching highest.
  std::vector<Piece> legs[2], arms[2];
  int next = 3;  // j1, j2: waist and neck
  auto j = [&]() { return "j" + std::to_string(next++); };
  for (int k = 0; k < 2; ++k) {
    const std::string y = k == 0 ? "" : "-";
    const std::string h1 = j(), h2 = j(), h3 = j(), kn = j(), a1 = j(), a2 = j();
    legs[k] = legOf(
        k, {{h1, 'z'}, {h2, 'x'}, {h3, k == 0 ? 'y' : 'Y'}, {kn, k == 0 ? 'y' : 'Y'}, {a1, 'y'}, {a2, 'x'}});
    auto out = [&](double d) { return "0 " + y + std::to_string(d) + " 0"; };
    const std::string along = "1.5708 0 0";
    const std::string s1 = j(), s2 = j(), s3 = j(), el = j(), wr = j();
    const std::string p = k == 0 ? "l" : "r";
    arms[k] = {{s1, "1 0 0", "0 " + y + "0.2 0.5", p + "sh1", ball("0 0 0", 0.05), -2.0, 2.0},
               {s2, "0 1 0", "0 0 0", p + "sh2", ""},
               {s3, "0 0 1", "0 0 0", p + "upperarm", cylinder(out(0.15), along, 0.04, 0.3)},
               {el, "0 0 1", out(0.3), p + "forearm", cylinder(out(0.13), along, 0.035, 0.26)},
               {wr, "1 0 0", out(0.26), p + "hand", ball(out(0.04), 0.04)}};
  }
  // Declared right side first.
  std::swap(legs[0], legs[1]);
  std::swap(arms[0], arms[1]);
  const UrdfModelPtr model = load(humanoidXml("j1", "j2", legs, arms));
  ASSERT_TRUE(model);
  const JointMapping m = JointMapping::automatic(model);
  // Left leg j3..j8, left arm j9..j13, right leg j14..j19, right arm j20..j24.
  const std::vector<std::string> expected = {"j5",  "j16", "j6",  "j17", "j7", "j18",
                                             "j11", "j22", "j12", "j23", "j9", "j20"};
  for (int r = 0; r < kGaitRoleCount; ++r)
    EXPECT_EQ(jointName(*model, m, static_cast<GaitRole>(r)), expected[static_cast<std::size_t>(r)])
        << toString(static_cast<GaitRole>(r)) << "\n"
        << joined(m.warnings());
  // Every role said once, by structure, in role order, and nothing else said.
  const std::vector<std::string> notes = notesByStructure(m);
  ASSERT_EQ(notes.size(), 12u) << joined(m.warnings());
  EXPECT_EQ(m.warnings().size(), 12u) << joined(m.warnings());
  EXPECT_EQ(
      notes[0],
      "left hip: joint 'j5' (by structure, left leg 'pelvis' to 'lfoot': its first side-to-side joint)");
  EXPECT_EQ(notes[3],
            "right knee: joint 'j17' (by structure, right leg 'pelvis' to 'rfoot': the next side-to-side "
            "joint beyond the hip)");
  EXPECT_EQ(notes[6].rfind("left shoulder: joint 'j11' (by structure, left arm 'torso' to 'lhand': ", 0), 0u)
      << notes[6];
  EXPECT_EQ(notes[10].rfind("left shoulder roll: joint 'j9' (by structure, left arm 'torso' to 'lhand': ", 0),
            0u)
      << notes[10];
  // byStructure alone finds the same joints, signs and neutrals.
  const JointMapping tree = JointMapping::byStructure(model);
  for (int r = 0; r < kGaitRoleCount; ++r) {
    EXPECT_EQ(tree.entries()[static_cast<std::size_t>(r)].joint,
              m.entries()[static_cast<std::size_t>(r)].joint);
    EXPECT_EQ(tree.entries()[static_cast<std::size_t>(r)].sign,
              m.entries()[static_cast<std::size_t>(r)].sign);
    EXPECT_EQ(tree.entries()[static_cast<std::size_t>(r)].neutral,
              m.entries()[static_cast<std::size_t>(r)].neutral);
  }
  EXPECT_EQ(m[GaitRole::LeftHip].sign, -m[GaitRole::RightHip].sign);
  EXPECT_EQ(m[GaitRole::LeftKnee].sign, -m[GaitRole::RightKnee].sign);
  expectWalks(model, m, "j1..j24");
}

TEST(JointMapping, StructureFindsTheShippedHumanoidsJointsAndNoLegsWhereThereAreNone) {
  // Names ignored, the shipped humanoid's limbs give its own joints, signs and neutrals back.
  const UrdfModelPtr model = UrdfModel::humanoid().model;
  const JointMapping names = JointMapping::automatic(model), tree = JointMapping::byStructure(model);
  for (int r = 0; r < kGaitRoleCount; ++r) {
    EXPECT_EQ(tree.entries()[static_cast<std::size_t>(r)].joint,
              names.entries()[static_cast<std::size_t>(r)].joint)
        << toString(static_cast<GaitRole>(r));
    EXPECT_EQ(tree.entries()[static_cast<std::size_t>(r)].sign,
              names.entries()[static_cast<std::size_t>(r)].sign);
  }
  EXPECT_EQ(notesByStructure(tree).size(), 10u) << joined(tree.warnings());
  // A torso with arms and no legs: its hands are the lowest links, but they hang from the top of the model,
  // so they are no feet; the arms are found, the legs stay unmapped.
  const UrdfModelPtr arms = load(armsModel(0.0, {{"a1", 'y'}}, {{"a2", 'y'}}));
  ASSERT_TRUE(arms);
  const JointMapping m = JointMapping::byStructure(arms);
  EXPECT_EQ(jointName(*arms, m, GaitRole::LeftShoulder), "a1");
  EXPECT_EQ(jointName(*arms, m, GaitRole::RightShoulder), "a2");
  EXPECT_EQ(jointName(*arms, m, GaitRole::LeftElbow), "left_elbow");
  for (GaitRole role : {GaitRole::LeftHip, GaitRole::RightHip, GaitRole::LeftKnee, GaitRole::RightKnee,
                        GaitRole::LeftAnkle, GaitRole::RightAnkle})
    EXPECT_EQ(m[role].joint, -1) << toString(role);
}

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
