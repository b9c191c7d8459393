// BVH motion capture retargeted onto URDF humanoids (MotionFormats.h: readBvh, parseBvh). The BVH files are
// written here: a skeleton with the shipped humanoid's bones (from its forward kinematics in the zero pose),
// turned by known angles about each hinge's axis, in any unit and up axis; the retargeted clip must put the
// humanoid's knees and hands where forward kinematics with those angles puts them.
#include "BvhRoles.h"
#include "cape/character/MotionFormats.h"
#include "cape/character/Skeleton.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace cape::character {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kPi = 3.14159265358979323846;

/// One BVH joint of a test skeleton, described in the URDF frame (m, z up, x forward, y left).
struct Bone {
  std::string name;
  int parent = -1;
  Eigen::Vector3d at = Eigen::Vector3d::Zero();    ///< rest position
  std::string joint;                               ///< the URDF hinge it turns with, "" for none
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();  ///< that hinge's axis in the URDF frame at rest
  std::vector<Eigen::Vector3d> ends;               ///< End Site offsets
  std::string order = "ZXY";                       ///< its rotation channels, first to last
};

/// A turn about a URDF-frame axis (unit, one of +-x, +-y, +-z), rad.
using Turn = std::pair<Eigen::Vector3d, double>;

/// One frame: the hips (URDF frame, m), their yaw about z then pitch about y (rad), the hinges' angles (rad)
/// and other bones' local rotations as turns in their channels' order.
struct Frame {
  Eigen::Vector3d hips = Eigen::Vector3d(0.0, 0.0, 0.95);
  double yaw = 0.0, pitch = 0.0;
  std::map<std::string, double> angles;            ///< by URDF joint name
  std::map<std::string, std::vector<Turn>> turns;  ///< by bone name
};

/// How the BVH is written: `axes` takes URDF-frame vectors into the BVH's (its columns are the images of
/// URDF x, y, z and must be signed unit axes), `unit` metres per BVH unit.
struct Style {
  Eigen::Matrix3d axes;
  double unit = 0.01;
  std::map<std::string, std::string> rename;  ///< bone name -> name written
};

/// Y up, facing +Z (most mocap): URDF x -> BVH Z, y -> X, z -> Y.
Eigen::Matrix3d yUpAxes() {
  Eigen::Matrix3d m;
  m.col(0) = Eigen::Vector3d::UnitZ();
  m.col(1) = Eigen::Vector3d::UnitX();
  m.col(2) = Eigen::Vector3d::UnitY();
  return m;
}

/// Z up, facing -Y (Blender): URDF x -> BVH -Y, y -> X, z -> Z.
Eigen::Matrix3d zUpAxes() {
  Eigen::Matrix3d m;
  m.col(0) = -Eigen::Vector3d::UnitY();
  m.col(1) = Eigen::Vector3d::UnitX();
  m.col(2) = Eigen::Vector3d::UnitZ();
  return m;
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}

/// The BVH axis (0, 1, 2) and sign of a URDF-frame axis that `axes` takes onto a coordinate axis.
std::pair<int, double> bvhAxis(const Eigen::Matrix3d& axes, const Eigen::Vector3d& urdf) {
  const Eigen::Vector3d b = axes * urdf;
  int k = 0;
  b.cwiseAbs().maxCoeff(&k);
  return {k, b[k] > 0 ? 1.0 : -1.0};
}

std::string writeBvh(const std::vector<Bone>& bones, const std::vector<Frame>& frames, const Style& style,
                     double frameTime = 1.0 / 30.0) {
  const Eigen::Matrix3d& m = style.axes;
  const char* axisName[] = {"X", "Y", "Z"};
  const int yawAxis = bvhAxis(m, Eigen::Vector3d::UnitZ()).first;
  const int pitchAxis = bvhAxis(m, Eigen::Vector3d::UnitY()).first;
  const int rollAxis = 3 - yawAxis - pitchAxis;
  std::ostringstream out;
  const auto vec = [&](const Eigen::Vector3d& urdf) {
    const Eigen::Vector3d b = m * urdf / style.unit;
    return num(b.x()) + " " + num(b.y()) + " " + num(b.z());
  };
  const auto nameOf = [&](const Bone& b) {
    const auto r = style.rename.find(b.name);
    return r == style.rename.end() ? b.name : r->second;
  };
  // Depth-first, children in order: bones are listed parents first, so a bone's children follow it.
  std::vector<int> order, depth(bones.size(), 0);
  std::vector<int> stack = {0};
  while (!stack.empty()) {
    const int b = stack.back();
    stack.pop_back();
    order.push_back(b);
    for (int c = static_cast<int>(bones.size()) - 1; c >= 0; --c)
      if (bones[static_cast<std::size_t>(c)].parent == b) {
        depth[static_cast<std::size_t>(c)] = depth[static_cast<std::size_t>(b)] + 1;
        stack.push_back(c);
      }
  }
  out << "HIERARCHY\n";
  std::vector<int> open;
  for (int b : order) {
    const Bone& bone = bones[static_cast<std::size_t>(b)];
    while (static_cast<int>(open.size()) > depth[static_cast<std::size_t>(b)]) {
      out << std::string(2 * (open.size() - 1), ' ') << "}\n";
      open.pop_back();
    }
    const std::string pad(2 * open.size(), ' ');
    out << pad << (b == 0 ? "ROOT " : "JOINT ") << nameOf(bone) << "\n" << pad << "{\n";
    const Eigen::Vector3d offset =
        b == 0 ? bone.at : Eigen::Vector3d(bone.at - bones[static_cast<std::size_t>(bone.parent)].at);
    out << pad << "  OFFSET " << vec(offset) << "\n";
    if (b == 0)
      out << pad << "  CHANNELS 6 Xposition Yposition Zposition " << axisName[yawAxis] << "rotation "
          << axisName[pitchAxis] << "rotation " << axisName[rollAxis] << "rotation\n";
    else
      out << pad << "  CHANNELS 3 " << bone.order[0] << "rotation " << bone.order[1] << "rotation "
          << bone.order[2] << "rotation\n";
    for (const Eigen::Vector3d& e : bone.ends)
      out << pad << "  End Site\n"
          << pad << "  {\n"
          << pad << "    OFFSET " << vec(e) << "\n"
          << pad << "  }\n";
    open.push_back(b);
  }
  while (!open.empty()) {
    out << std::string(2 * (open.size() - 1), ' ') << "}\n";
    open.pop_back();
  }
  out << "MOTION\nFrames: " << frames.size() << "\nFrame Time: " << num(frameTime) << "\n";
  for (const Frame& f : frames) {
    for (int b : order) {
      const Bone& bone = bones[static_cast<std::size_t>(b)];
      if (b == 0) {
        const auto [ky, sy] = bvhAxis(m, Eigen::Vector3d::UnitZ());
        const auto [kp, sp] = bvhAxis(m, Eigen::Vector3d::UnitY());
        (void)ky, (void)kp;
        out << vec(f.hips) << " " << num(sy * f.yaw * 180.0 / kPi) << " " << num(sp * f.pitch * 180.0 / kPi)
            << " 0";
        continue;
      }
      std::vector<Turn> turns;
      if (const auto angle = f.angles.find(bone.joint); angle != f.angles.end())
        turns.emplace_back(bone.axis, angle->second);
      if (const auto turn = f.turns.find(bone.name); turn != f.turns.end()) turns = turn->second;
      double values[3] = {0.0, 0.0, 0.0};  // degrees, in the bone's channel order
      std::size_t last = 0;
      for (const auto& [axis, angle] : turns) {
        const auto [k, s] = bvhAxis(m, axis);
        const std::size_t at = bone.order.find(axisName[k][0]);
        EXPECT_TRUE(at >= last) << bone.name << ": turns out of the channels' order";
        last = at;
        values[at] = s * angle * 180.0 / kPi;
      }
      out << " " << num(values[0]) << " " << num(values[1]) << " " << num(values[2]);
    }
    out << "\n";
  }
  return out.str();
}

UrdfModelPtr humanoid() {
  static const UrdfModelPtr model = UrdfModel::humanoid().model;
  return model;
}

Eigen::Vector3d linkAt(const Skeleton& s, const char* link) {
  Eigen::Isometry3d p;
  EXPECT_TRUE(s.linkPose(link, p).ok()) << link;
  return p.translation();
}

/// The shipped humanoid's bones as a BVH skeleton (CMU/Mixamo names), from its zero pose.
std::vector<Bone> humanoidBones() {
  const UrdfModelPtr model = humanoid();
  Skeleton s(model);
  s.setUpAxis(UpAxis::Z);
  const auto axisOf = [&](const std::string& joint) {
    return model->joints()[static_cast<std::size_t>(model->findJoint(joint))].axis;
  };
  std::vector<Bone> bones;
  const auto add = [&](const std::string& name, int parent, const Eigen::Vector3d& at,
                       const std::string& joint, std::vector<Eigen::Vector3d> ends = {}) {
    Bone b;
    b.name = name;
    b.parent = parent;
    b.at = at;
    b.joint = joint;
    if (!joint.empty()) b.axis = axisOf(joint);
    b.ends = std::move(ends);
    bones.push_back(b);
    return static_cast<int>(bones.size()) - 1;
  };
  const int hips = add("Hips", -1, linkAt(s, "pelvis"), "");
  const int spine = add("Spine", hips, linkAt(s, "torso"), "waist");
  add("Neck", spine, linkAt(s, "head"), "neck", {Eigen::Vector3d(0.0, 0.0, 0.09)});
  for (const char* side : {"left", "right"}) {
    const std::string Side = side[0] == 'l' ? "Left" : "Right";
    const std::string p = std::string(side) + "_";
    const int arm = add(Side + "Arm", spine, linkAt(s, (p + "upper_arm").c_str()), p + "shoulder_pitch");
    const int fore = add(Side + "ForeArm", arm, linkAt(s, (p + "forearm").c_str()), p + "elbow");
    add(Side + "Hand", fore, linkAt(s, (p + "forearm").c_str()) + Eigen::Vector3d(0.0, 0.0, -0.30), "",
        {Eigen::Vector3d(0.0, 0.0, -0.05)});
  }
  for (const char* side : {"left", "right"}) {
    const std::string Side = side[0] == 'l' ? "Left" : "Right";
    const std::string p = std::string(side) + "_";
    const int up = add(Side + "UpLeg", hips, linkAt(s, (p + "thigh").c_str()), p + "hip_pitch");
    const int leg = add(Side + "Leg", up, linkAt(s, (p + "shin").c_str()), p + "knee");
    add(Side + "Foot", leg, linkAt(s, (p + "foot").c_str()), p + "ankle",
        {Eigen::Vector3d(0.05, 0.0, -0.10)});
  }
  return bones;
}

/// Known poses, every angle inside the humanoid's limits; the hips move, turn (past +-pi too) and lean.
std::vector<Frame> knownFrames() {
  std::vector<Frame> frames(4);
  frames[1].hips = Eigen::Vector3d(0.10, -0.05, 0.93);
  frames[1].yaw = 0.4;
  frames[1].pitch = 0.1;
  frames[1].angles = {{"waist", 0.2},
                      {"neck", -0.3},
                      {"left_shoulder_pitch", 0.5},
                      {"left_elbow", 0.7},
                      {"right_shoulder_pitch", -0.4},
                      {"right_elbow", 1.1},
                      {"left_hip_pitch", 0.6},
                      {"left_knee", 0.9},
                      {"left_ankle", -0.2},
                      {"right_hip_pitch", -0.3},
                      {"right_knee", 0.4},
                      {"right_ankle", 0.3}};
  frames[2].hips = Eigen::Vector3d(0.45, 0.20, 0.90);
  frames[2].yaw = -2.5;
  frames[2].pitch = -0.2;
  frames[2].angles = {{"waist", -0.45},
                      {"neck", 0.5},
                      {"left_shoulder_pitch", -0.9},
                      {"left_elbow", 2.0},
                      {"right_shoulder_pitch", 2.2},
                      {"right_elbow", 0.1},
                      {"left_hip_pitch", 1.4},
                      {"left_knee", 2.1},
                      {"left_ankle", 0.45},
                      {"right_hip_pitch", -0.7},
                      {"right_knee", 0.05},
                      {"right_ankle", -0.6}};
  frames[3].hips = Eigen::Vector3d(-0.3, 0.6, 0.97);
  frames[3].yaw = 3.0;
  frames[3].angles = {{"left_knee", 1.0}, {"right_knee", 1.5}, {"left_elbow", 0.3}};
  return frames;
}

/// The humanoid's root link pose for a frame: its pelvis at the hips, turned by yaw then pitch.
Eigen::Isometry3d expectedRoot(const Frame& f) {
  Skeleton s(humanoid());
  s.setUpAxis(UpAxis::Z);
  Eigen::Isometry3d pelvisRest;
  EXPECT_TRUE(s.linkPose("pelvis", pelvisRest).ok());
  Eigen::Isometry3d pelvis = Eigen::Isometry3d::Identity();
  pelvis.linear() = (Eigen::AngleAxisd(f.yaw, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(f.pitch, Eigen::Vector3d::UnitY()))
                        .toRotationMatrix();
  pelvis.translation() = f.hips;
  return pelvis * pelvisRest.inverse();
}

/// A skeleton of `model` posed at sample k of `clip` (a URDF-frame clip) in a Z-up world.
Skeleton posed(const UrdfModelPtr& model, const MotionClip& clip, int k) {
  Skeleton s(model);
  s.setUpAxis(UpAxis::Z);
  Eigen::Isometry3d root = Eigen::Isometry3d::Identity();
  root.linear() = clip.rootRotations[static_cast<std::size_t>(k)].toRotationMatrix();
  root.translation() = clip.rootPositions[static_cast<std::size_t>(k)];
  s.setRootLinkPose(root);
  const std::size_t nj = clip.joints.size(), nb = clip.balls.size();
  for (std::size_t j = 0; j < nj; ++j) {
    const Status st = s.setJointPosition(clip.joints[j], clip.values[static_cast<std::size_t>(k) * nj + j]);
    EXPECT_TRUE(st.ok() || st.code() == ErrorCode::OutsideLimits) << st.message();
  }
  for (std::size_t b = 0; b < nb; ++b)
    EXPECT_TRUE(s.setJointRotation(clip.balls[b], clip.rotations[static_cast<std::size_t>(k) * nb + b]).ok());
  return s;
}

/// The humanoid where forward kinematics with the frame's known angles puts it.
Skeleton expectedPose(const Frame& f) {
  Skeleton s(humanoid());
  s.setUpAxis(UpAxis::Z);
  s.setRootLinkPose(expectedRoot(f));
  for (const auto& [joint, q] : f.angles) EXPECT_TRUE(s.setJointPosition(joint, q).ok()) << joint;
  return s;
}

/// Knees (the shins' origins), hands (the forearms' ends) and feet's toes, in the world.
std::vector<Eigen::Vector3d> landmarks(const Skeleton& s) {
  std::vector<Eigen::Vector3d> out;
  for (const char* side : {"left_", "right_"}) {
    const std::string p(side);
    out.push_back(linkAt(s, (p + "shin").c_str()));
    Eigen::Isometry3d fore, foot;
    EXPECT_TRUE(s.linkPose(p + "forearm", fore).ok());
    EXPECT_TRUE(s.linkPose(p + "foot", foot).ok());
    out.push_back(fore * Eigen::Vector3d(0.0, 0.0, -0.30));
    out.push_back(foot * Eigen::Vector3d(0.05, 0.0, -0.10));
    out.push_back(linkAt(s, "head"));
  }
  return out;
}

/// The known frames start at the rest pose, played as motion (BvhRestFrame::Auto would leave it out:
/// Bvh.AReferenceFrameBeforeTheMotionIsLeftOut), so these retargets keep it.
BvhOptions keepingRest(BvhOptions options = {}) {
  options.restFrame = BvhRestFrame::Keep;
  return options;
}

MotionClipResult retarget(const std::string& text, const BvhOptions& options = {},
                          const UrdfModelPtr& model = humanoid()) {
  MotionClipResult r = parseBvh(text, model, keepingRest(options), nullptr, 1.0, "test.bvh");
  EXPECT_TRUE(r.ok()) << r.status.message();
  return r;
}

/// Every sample's landmarks within 1 mm of where the known angles put them.
void expectFollows(const MotionClip& clip, const std::vector<Frame>& frames, double tolerance = 1e-3) {
  ASSERT_EQ(clip.sampleCount(), static_cast<int>(frames.size()));
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::vector<Eigen::Vector3d> want = landmarks(expectedPose(frames[k]));
    const std::vector<Eigen::Vector3d> got = landmarks(posed(humanoid(), clip, static_cast<int>(k)));
    for (std::size_t i = 0; i < want.size(); ++i)
      EXPECT_LT((want[i] - got[i]).norm(), tolerance)
          << "frame " << k << " landmark " << i << ": want " << want[i].transpose() << ", got "
          << got[i].transpose();
  }
}

/// Two clips alike: the same joints, values and root poses.
void expectSameClip(const MotionClip& a, const MotionClip& b, double tolerance = 1e-9) {
  ASSERT_EQ(a.joints, b.joints);
  ASSERT_EQ(a.balls, b.balls);
  ASSERT_EQ(a.values.size(), b.values.size());
  ASSERT_EQ(a.rootPositions.size(), b.rootPositions.size());
  for (std::size_t i = 0; i < a.values.size(); ++i) EXPECT_NEAR(a.values[i], b.values[i], tolerance) << i;
  for (std::size_t i = 0; i < a.rootPositions.size(); ++i) {
    EXPECT_LT((a.rootPositions[i] - b.rootPositions[i]).norm(), tolerance) << i;
    EXPECT_LT(a.rootRotations[i].angularDistance(b.rootRotations[i]), tolerance) << i;
  }
}

double valueOf(const MotionClip& clip, const std::string& joint, int k) {
  for (std::size_t j = 0; j < clip.joints.size(); ++j)
    if (clip.joints[j] == joint) return clip.values[static_cast<std::size_t>(k) * clip.joints.size() + j];
  ADD_FAILURE() << "joint '" << joint << "' is not in the clip";
  return NAN;
}

bool saysSomething(const std::vector<std::string>& warnings, const std::string& part) {
  for (const std::string& w : warnings)
    if (w.find(part) != std::string::npos) return true;
  return false;
}

// --- (1) the shipped humanoid's own bones -----------------------------------------------------------------

TEST(Bvh, HumanoidBonesPutKneesAndHandsWhereTheKnownAnglesDo) {
  const std::vector<Frame> frames = knownFrames();
  const MotionClipResult r = retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}));
  ASSERT_TRUE(r.ok());
  const MotionClip& clip = r.clip;
  EXPECT_EQ(clip.frame, MotionFrame::Urdf);
  EXPECT_EQ(clip.name, "test.bvh");
  EXPECT_TRUE(clip.loop);
  EXPECT_TRUE(clip.balls.empty());
  EXPECT_EQ(clip.joints.size(), 12u);  // every movable joint of the humanoid is driven
  ASSERT_EQ(clip.times.size(), 4u);
  EXPECT_NEAR(clip.times[3], 3 * 0.0333333333333, 1e-15);  // k times the Frame Time as written
  EXPECT_TRUE(clip.check().ok()) << clip.check().message();
  expectFollows(clip, frames);
  // The hinges come back exactly: each BVH joint turns about its URDF hinge's axis.
  for (std::size_t k = 0; k < frames.size(); ++k)
    for (const auto& [joint, q] : frames[k].angles)
      EXPECT_NEAR(valueOf(clip, joint, static_cast<int>(k)), q, 1e-9);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const Eigen::Isometry3d want = expectedRoot(frames[k]);
    EXPECT_LT((clip.rootPositions[k] - want.translation()).norm(), 1e-9);
    EXPECT_LT(clip.rootRotations[k].angularDistance(Eigen::Quaterniond(want.linear())), 1e-9);
  }
  for (const std::string& w : r.warnings) EXPECT_THAT(w, ::testing::Not(HasSubstr("role"))) << w;
}

TEST(Bvh, NonLoopingAndTheFrameTimeHonoured) {
  BvhOptions options;
  options.loop = false;
  const MotionClipResult r =
      retarget(writeBvh(humanoidBones(), knownFrames(), {yUpAxes(), 0.01, {}}, 0.008333333), options);
  EXPECT_FALSE(r.clip.loop);
  EXPECT_NEAR(r.clip.times[2], 2 * 0.008333333, 1e-15);
  EXPECT_NEAR(r.clip.duration(), 3 * 0.008333333, 1e-15);
}

// --- (2) units
// ----------------------------------------------------------------------------------------------

TEST(Bvh, CentimetresInchesAndMetresGiveTheSameClipGuessedOrGiven) {
  const std::vector<Frame> frames = knownFrames();
  const MotionClipResult cm = retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}));
  EXPECT_TRUE(saysSomething(cm.warnings, "centimetres")) << ::testing::PrintToString(cm.warnings);
  for (const auto& [unit, word] : {std::pair{0.0254, "inches"}, {1.0, "metres"}}) {
    const std::string text = writeBvh(humanoidBones(), frames, {yUpAxes(), unit, {}});
    for (bool scaleRootToLegs : {true, false}) {
      BvhOptions guessed;
      guessed.scaleRootToLegs = scaleRootToLegs;
      const MotionClipResult g = retarget(text, guessed);
      EXPECT_TRUE(saysSomething(g.warnings, word)) << word;
      expectSameClip(g.clip, cm.clip);
      BvhOptions given = guessed;
      given.scale = unit;
      const MotionClipResult s = retarget(text, given);
      EXPECT_FALSE(saysSomething(s.warnings, "guessed from")) << word;
      expectSameClip(s.clip, cm.clip);
    }
  }
}

TEST(Bvh, AWrongScaleMovesTheRootOnlyWithoutLegScaling) {
  const std::string text = writeBvh(humanoidBones(), knownFrames(), {yUpAxes(), 0.01, {}});
  BvhOptions doubled;
  doubled.scale = 0.02;
  const MotionClipResult legs = retarget(text, doubled);
  const MotionClipResult right = retarget(text);
  expectSameClip(legs.clip, right.clip);  // the legs' ratio does not care what a unit is
  doubled.scaleRootToLegs = false;
  const MotionClipResult raw = retarget(text, doubled);
  const std::vector<Frame> frames = knownFrames();
  for (std::size_t k = 0; k < frames.size(); ++k)  // the hips twice as far from the origin, the rest alike
    EXPECT_LT((raw.clip.rootPositions[k] - right.clip.rootPositions[k] - frames[k].hips).norm(), 1e-9);
  EXPECT_EQ(raw.clip.values, right.clip.values);
}

TEST(Bvh, TheRootFollowsTheLegsOfALargerCharacter) {
  const std::vector<Frame> frames = knownFrames();
  const MotionClipResult r = parseBvh(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}), humanoid(),
                                      keepingRest(), nullptr, 2.0, "big.bvh");
  ASSERT_TRUE(r.ok()) << r.status.message();
  const MotionClipResult one = retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}));
  for (std::size_t k = 0; k < frames.size(); ++k)
    EXPECT_LT((r.clip.rootPositions[k] - 2.0 * one.clip.rootPositions[k]).norm(), 1e-9);
}

// --- (3) up axes
// --------------------------------------------------------------------------------------------

TEST(Bvh, YUpAndZUpGiveTheSameClipGuessedOrGiven) {
  const std::vector<Frame> frames = knownFrames();
  const MotionClipResult y = retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}));
  EXPECT_TRUE(saysSomething(y.warnings, "up axis guessed: y"));
  const std::string zText = writeBvh(humanoidBones(), frames, {zUpAxes(), 0.01, {}});
  const MotionClipResult z = retarget(zText);
  EXPECT_TRUE(saysSomething(z.warnings, "up axis guessed: z"));
  expectSameClip(z.clip, y.clip);
  expectFollows(z.clip, frames);
  BvhOptions given;
  given.up = BvhUp::Z;
  expectSameClip(retarget(zText, given).clip, y.clip);
  given.up = BvhUp::Y;
  expectSameClip(retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}), given).clip, y.clip);
}

TEST(Bvh, AnyFacingIsTurnedOntoForward) {
  // The same skeleton facing +X with Y up (URDF x -> BVH X, y -> -Z, z -> Y).
  Eigen::Matrix3d m;
  m.col(0) = Eigen::Vector3d::UnitX();
  m.col(1) = -Eigen::Vector3d::UnitZ();
  m.col(2) = Eigen::Vector3d::UnitY();
  const std::vector<Frame> frames = knownFrames();
  expectFollows(retarget(writeBvh(humanoidBones(), frames, {m, 0.01, {}})).clip, frames);
}

// --- (4) a T-pose rest pose
// ---------------------------------------------------------------------------------

TEST(Bvh, TPoseRestDrivesTheArmsDownHumanoid) {
  std::vector<Bone> bones = humanoidBones();
  // Arms straight out sideways from the shoulders at rest.
  for (Bone& b : bones) {
    const double side = b.name.rfind("Left", 0) == 0 ? 1.0 : -1.0;
    const Eigen::Vector3d shoulder = bones[3].at.cwiseProduct(Eigen::Vector3d(1.0, side, 1.0));
    if (b.name.find("ForeArm") != std::string::npos) b.at = shoulder + Eigen::Vector3d(0.0, side * 0.30, 0.0);
    if (b.name.find("Hand") != std::string::npos) {
      b.at = shoulder + Eigen::Vector3d(0.0, side * 0.60, 0.0);
      b.ends = {Eigen::Vector3d(0.0, side * 0.05, 0.0)};
    }
  }
  // Frame 0: the T-pose itself. Frame 1: each arm lowered (a quarter turn about forward), then swung
  // forward by phi about -y; the forearm bent by eps about its hinge, which in the lowered arm's own frame is
  // -z (left) or +z (right).
  const double phi = 0.6, eps = 0.8;
  std::vector<Frame> frames(2);
  for (Bone& b : bones) {
    if (b.name != "LeftArm" && b.name != "RightArm" && b.name != "LeftForeArm" && b.name != "RightForeArm")
      continue;
    const double side = b.name[0] == 'L' ? 1.0 : -1.0;
    b.joint.clear();
    if (b.name.find("Fore") == std::string::npos) {
      b.order = "XZY";  // BVH X is URDF y, Z is URDF x
      frames[1].turns[b.name] = {{-Eigen::Vector3d::UnitY(), phi},
                                 {Eigen::Vector3d::UnitX(), -side * kPi / 2}};
    } else {
      frames[1].turns[b.name] = {{-Eigen::Vector3d::UnitZ(), side * eps}};
    }
  }
  const std::string text = writeBvh(bones, frames, {yUpAxes(), 0.01, {}});
  const MotionClipResult r = retarget(text);
  ASSERT_TRUE(r.ok());
  for (const char* side : {"left_", "right_"}) {
    const std::string p(side);
    // At the T-pose frame the arms hang down: the humanoid cannot lift them sideways, and its rest is down.
    EXPECT_NEAR(valueOf(r.clip, p + "shoulder_pitch", 0), 0.0, 1e-9);
    EXPECT_NEAR(valueOf(r.clip, p + "elbow", 0), 0.0, 1e-9);
    const Skeleton rest = posed(humanoid(), r.clip, 0);
    Eigen::Isometry3d fore;
    ASSERT_TRUE(rest.linkPose(p + "forearm", fore).ok());
    const Eigen::Vector3d hand = fore * Eigen::Vector3d(0.0, 0.0, -0.30);
    EXPECT_LT(hand.z(), linkAt(rest, (p + "shoulder").c_str()).z() - 0.55) << side;
    // Lowered and swung, the BVH arm is the humanoid's: shoulder phi, elbow eps.
    EXPECT_NEAR(valueOf(r.clip, p + "shoulder_pitch", 1), phi, 1e-9);
    EXPECT_NEAR(valueOf(r.clip, p + "elbow", 1), eps, 1e-9);
  }
}

// --- (5) names --------------------------------------------------------------------------------------------

/// The humanoid's bones with extra joints the naming schemes have (clavicles, a lower back, two neck
/// joints, hip joints), of zero length and no motion, so that the retarget must come out as the plain one.
std::vector<Bone> withExtraJoints(const std::map<std::string, std::string>& names) {
  std::vector<Bone> plain = humanoidBones();
  std::vector<Bone> out;
  std::map<std::string, int> index;
  const auto add = [&](const std::string& key, const std::string& parentKey, const Bone& like) {
    Bone b = like;
    b.name = names.at(key);
    b.parent = parentKey.empty() ? -1 : index.at(parentKey);
    index[key] = static_cast<int>(out.size());
    out.push_back(b);
  };
  const auto bone = [&](const std::string& n) {
    for (const Bone& b : plain)
      if (b.name == n) return b;
    ADD_FAILURE() << n;
    return Bone{};
  };
  const auto still = [&](const std::string& at) {
    Bone b = bone(at);
    b.joint.clear();
    b.ends.clear();
    return b;
  };
  add("Hips", "", bone("Hips"));
  add("LowerBack", "Hips", still("Spine"));
  add("Spine", "LowerBack", still("Spine"));
  add("Spine1", "Spine", bone("Spine"));  // the chest: the spine joint the neck and arms hang from
  add("Neck", "Spine1", still("Neck"));
  add("Head", "Neck", bone("Neck"));
  for (const std::string side : {"Left", "Right"}) {
    Bone clavicle = still(side + "Arm");
    add(side + "Shoulder", "Spine1", clavicle);
    add(side + "Arm", side + "Shoulder", bone(side + "Arm"));
    add(side + "ForeArm", side + "Arm", bone(side + "ForeArm"));
    add(side + "Hand", side + "ForeArm", bone(side + "Hand"));
    add(side + "HipJoint", "Hips", still("Hips"));
    add(side + "UpLeg", side + "HipJoint", bone(side + "UpLeg"));
    add(side + "Leg", side + "UpLeg", bone(side + "Leg"));
    add(side + "Foot", side + "Leg", bone(side + "Foot"));
  }
  return out;
}

std::map<std::string, std::string> namesOf(const std::vector<std::pair<std::string, std::string>>& pairs) {
  return std::map<std::string, std::string>(pairs.begin(), pairs.end());
}

TEST(Bvh, CmuMixamoAndAsfNamesAreMatched) {
  const std::vector<Frame> frames = knownFrames();
  const MotionClipResult plain = retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}));
  std::vector<std::pair<std::string, std::string>> cmu;
  for (const char* n : {"Hips", "LowerBack", "Spine", "Spine1", "Neck", "Head"}) cmu.emplace_back(n, n);
  for (const std::string side : {"Left", "Right"})
    for (const char* part : {"Shoulder", "Arm", "ForeArm", "Hand", "HipJoint", "UpLeg", "Leg", "Foot"})
      cmu.emplace_back(side + part, side + part);
  std::vector<std::pair<std::string, std::string>> mixamo;
  for (const auto& [k, v] : cmu) mixamo.emplace_back(k, "mixamorig:" + v);
  const std::vector<std::pair<std::string, std::string>> asf = {{"Hips", "hip"},
                                                                {"LowerBack", "lowerback"},
                                                                {"Spine", "upperback"},
                                                                {"Spine1", "thorax"},
                                                                {"Neck", "lowerneck"},
                                                                {"Head", "head"},
                                                                {"LeftShoulder", "lclavicle"},
                                                                {"LeftArm", "lhumerus"},
                                                                {"LeftForeArm", "lradius"},
                                                                {"LeftHand", "lhand"},
                                                                {"LeftHipJoint", "lhipjoint"},
                                                                {"LeftUpLeg", "lfemur"},
                                                                {"LeftLeg", "ltibia"},
                                                                {"LeftFoot", "lfoot"},
                                                                {"RightShoulder", "rclavicle"},
                                                                {"RightArm", "rhumerus"},
                                                                {"RightForeArm", "rradius"},
                                                                {"RightHand", "rhand"},
                                                                {"RightHipJoint", "rhipjoint"},
                                                                {"RightUpLeg", "rfemur"},
                                                                {"RightLeg", "rtibia"},
                                                                {"RightFoot", "rfoot"}};
  for (const auto& scheme : {cmu, mixamo, asf}) {
    const std::vector<Bone> bones = withExtraJoints(namesOf(scheme));
    const MotionClipResult r = retarget(writeBvh(bones, frames, {yUpAxes(), 0.01, {}}));
    ASSERT_TRUE(r.ok()) << bones[0].name;
    for (const std::string& w : r.warnings) EXPECT_THAT(w, ::testing::Not(HasSubstr("role"))) << w;
    expectSameClip(r.clip, plain.clip);
  }
}

TEST(Bvh, SideAndPartSpellings) {
  using namespace bvh;
  const std::vector<std::pair<std::string, int>> cases = {{"LeftUpLeg", kLeftHip},
                                                          {"mixamorig:RightForeArm", kRightElbow},
                                                          {"lfemur", kLeftHip},
                                                          {"rtibia", kRightKnee},
                                                          {"L_Hip", kLeftHip},
                                                          {"Hip_R", kRightHip},
                                                          {"l_knee", kLeftKnee},
                                                          {"LThigh", kLeftHip},
                                                          {"Bip01 L Thigh", kLeftHip},
                                                          {"Bip01 R Calf", kRightKnee},
                                                          {"upperarm.L", kLeftShoulder},
                                                          {"ankle_r", kRightAnkle},
                                                          {"LeftArm", kLeftShoulder},
                                                          {"lradius", kLeftElbow},
                                                          {"Spine2", kSpine},
                                                          {"lowerback", kSpine},
                                                          {"thorax", kSpine},
                                                          {"Head", kNeck},
                                                          {"Neck1", kNeck},
                                                          {"Hips", kHips},
                                                          {"pelvis", kHips},
                                                          {"RightShoulder", kRightShoulder},
                                                          {"Armature|LeftFoot", kLeftAnkle},
                                                          {"LeftHand", -1},
                                                          {"lhipjoint", -1},
                                                          {"LeftToeBase", -1},
                                                          {"lclavicle", -1},
                                                          {"Reference", -1},
                                                          {"LeftHandIndex1", -1}};
  for (const auto& [name, role] : cases) EXPECT_EQ(roleOfBvhName(name).role, role) << name;
  // Mixamo's LeftShoulder is the clavicle: LeftArm, when there, ranks before it.
  EXPECT_LT(roleOfBvhName("LeftArm").rank, roleOfBvhName("LeftShoulder").rank);
  EXPECT_LT(roleOfBvhName("Head").rank, roleOfBvhName("Neck").rank);
  EXPECT_EQ(roleFromName("left_knee"), kLeftKnee);
  EXPECT_EQ(roleFromName("knee"), -1);
}

TEST(Bvh, AUserRoleMapNamesAnySkeleton) {
  const std::vector<Frame> frames = knownFrames();
  const MotionClipResult plain = retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}));
  const std::vector<Bone> bones = humanoidBones();
  Style style{yUpAxes(), 0.01, {}};
  BvhOptions options;
  const std::map<std::string, std::string> roleOf = {{"Hips", "hips"},
                                                     {"Spine", "spine"},
                                                     {"Neck", "neck"},
                                                     {"LeftArm", "left_shoulder"},
                                                     {"LeftForeArm", "left_elbow"},
                                                     {"RightArm", "right_shoulder"},
                                                     {"RightForeArm", "right_elbow"},
                                                     {"LeftUpLeg", "left_hip"},
                                                     {"LeftLeg", "left_knee"},
                                                     {"LeftFoot", "left_ankle"},
                                                     {"RightUpLeg", "right_hip"},
                                                     {"RightLeg", "right_knee"},
                                                     {"RightFoot", "right_ankle"}};
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const std::string code = "J" + std::to_string(b);
    style.rename[bones[b].name] = code;
    const auto role = roleOf.find(bones[b].name);
    if (role != roleOf.end()) options.roles.emplace_back(code, role->second);
  }
  const std::string text = writeBvh(bones, frames, style);
  const MotionClipResult unnamed = parseBvh(text, humanoid(), {}, nullptr, 1.0, "codes.bvh");
  ASSERT_TRUE(unnamed.ok());
  EXPECT_TRUE(saysSomething(unnamed.warnings, "BVH role 'left_knee'"));
  const MotionClipResult mapped = retarget(text, options);
  expectSameClip(mapped.clip, plain.clip);

  BvhOptions badRole = options;
  badRole.roles.emplace_back("J1", "tail");
  const MotionClipResult r1 = parseBvh(text, humanoid(), badRole, nullptr, 1.0, "codes.bvh");
  EXPECT_EQ(r1.status.code(), ErrorCode::InvalidArgument);
  EXPECT_THAT(r1.status.message(), HasSubstr("unknown role 'tail'"));
  BvhOptions badJoint = options;
  badJoint.roles.emplace_back("Tail", "spine");
  const MotionClipResult r2 = parseBvh(text, humanoid(), badJoint, nullptr, 1.0, "codes.bvh");
  EXPECT_EQ(r2.status.code(), ErrorCode::InvalidArgument);
  EXPECT_THAT(r2.status.message(), HasSubstr("no joint 'Tail'"));
}

TEST(Bvh, UnmatchedRolesAreSaid) {
  // Legs only: the spine, neck and arms of the humanoid stay where they are, and each such role is said.
  std::vector<Bone> bones;
  for (const Bone& b : humanoidBones())
    if (b.name == "Hips" || b.name.find("Leg") != std::string::npos ||
        b.name.find("Foot") != std::string::npos)
      bones.push_back(b);
  for (Bone& b : bones) {
    // Re-index the parents: Hips 0, then each leg's three joints in order.
    if (b.name == "Hips") continue;
    b.parent = b.name.find("UpLeg") != std::string::npos ? 0 : -2;
  }
  for (std::size_t b = 1; b < bones.size(); ++b)
    if (bones[b].parent == -2) bones[b].parent = static_cast<int>(b) - 1;
  const MotionClipResult r = retarget(writeBvh(bones, knownFrames(), {yUpAxes(), 0.01, {}}));
  ASSERT_TRUE(r.ok());
  for (const char* role : {"spine", "neck", "left_shoulder", "right_elbow"})
    EXPECT_TRUE(saysSomething(r.warnings, "BVH role '" + std::string(role) + "'")) << role;
  EXPECT_EQ(r.clip.joints.size(), 6u);  // hips, knees, ankles
}

// --- compound joints
// ----------------------------------------------------------------------------------------

/// The humanoid with its left hip made of three hinges in series at one point: yaw (z), roll (x), pitch (-y).
UrdfModelPtr humanoidWithBallHip() {
  std::string text = UrdfModel::humanoidUrdf();
  const std::size_t from = text.find("<joint name=\"left_hip_pitch\"");
  const std::size_t to = text.find("</joint>", from) + 8;
  const auto hinge = [](const std::string& name, const std::string& parent, const std::string& child,
                        const std::string& origin, const std::string& axis, const std::string& limits) {
    return "<joint name=\"" + name + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" +
           child + "\"/><origin xyz=\"" + origin + "\" rpy=\"0 0 0\"/><axis xyz=\"" + axis + "\"/><limit " +
           limits + " effort=\"200\" velocity=\"8\"/></joint>\n";
  };
  const std::string wide = "lower=\"-1.5\" upper=\"1.5\"";
  text.replace(from, to - from,
               hinge("left_hip_yaw", "pelvis", "left_hip_yaw_link", "0 0.10 0", "0 0 1", wide) +
                   "<link name=\"left_hip_yaw_link\"/>\n" +
                   hinge("left_hip_roll", "left_hip_yaw_link", "left_hip_roll_link", "0 0 0", "1 0 0", wide) +
                   "<link name=\"left_hip_roll_link\"/>\n" +
                   hinge("left_hip_pitch", "left_hip_roll_link", "left_thigh", "0 0 0", "0 -1 0",
                         "lower=\"-0.8\" upper=\"1.6\""));
  const UrdfLoadResult r = UrdfModel::fromString(text);
  EXPECT_TRUE(r.ok()) << r.status.message();
  return r.model;
}

TEST(Bvh, HingesInSeriesTakeAnyThighRotationTogether) {
  const UrdfModelPtr model = humanoidWithBallHip();
  ASSERT_TRUE(model);
  std::vector<Bone> bones = humanoidBones();
  for (Bone& b : bones)
    if (b.name == "LeftUpLeg") b.order = "YZX";  // BVH Y is URDF z (yaw), Z is x (roll), X is y (pitch)
  std::vector<Frame> frames = knownFrames();
  const double ypr[4][3] = {{0.0, 0.0, 0.0}, {0.3, 0.2, 0.5}, {-0.6, -0.4, 1.2}, {1.0, 0.5, -0.5}};
  for (std::size_t k = 0; k < frames.size(); ++k) {
    frames[k].angles.erase("left_hip_pitch");
    frames[k].turns["LeftUpLeg"] = {{Eigen::Vector3d::UnitZ(), ypr[k][0]},
                                    {Eigen::Vector3d::UnitX(), ypr[k][1]},
                                    {-Eigen::Vector3d::UnitY(), ypr[k][2]}};
  }
  const MotionClipResult r = retarget(writeBvh(bones, frames, {yUpAxes(), 0.01, {}}), {}, model);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.clip.joints.size(), 14u);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const int at = static_cast<int>(k);
    EXPECT_NEAR(valueOf(r.clip, "left_hip_yaw", at), ypr[k][0], 1e-6) << k;
    EXPECT_NEAR(valueOf(r.clip, "left_hip_roll", at), ypr[k][1], 1e-6) << k;
    EXPECT_NEAR(valueOf(r.clip, "left_hip_pitch", at), ypr[k][2], 1e-6) << k;
    Skeleton want(model);
    want.setUpAxis(UpAxis::Z);
    want.setRootLinkPose(expectedRoot(frames[k]));
    for (const auto& [joint, q] : frames[k].angles) ASSERT_TRUE(want.setJointPosition(joint, q).ok());
    ASSERT_TRUE(want.setJointPosition("left_hip_yaw", ypr[k][0]).ok());
    ASSERT_TRUE(want.setJointPosition("left_hip_roll", ypr[k][1]).ok());
    ASSERT_TRUE(want.setJointPosition("left_hip_pitch", ypr[k][2]).ok());
    const std::vector<Eigen::Vector3d> a = landmarks(want), b = landmarks(posed(model, r.clip, at));
    for (std::size_t i = 0; i < a.size(); ++i)
      EXPECT_LT((a[i] - b[i]).norm(), 1e-6) << "frame " << k << " " << i;
  }
}

// --- (6) malformed files -----------------------------------------------------------------------------------

std::string goodText() {
  return writeBvh(humanoidBones(), knownFrames(), {yUpAxes(), 0.01, {}});
}

Status parseError(const std::string& text, const BvhOptions& options = {}) {
  const MotionClipResult r = parseBvh(text, humanoid(), options, nullptr, 1.0, "bad.bvh");
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument);
  EXPECT_THAT(r.status.message(), StartsWith("bad.bvh:"));
  return r.status;
}

std::string replaceFirst(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(Bvh, MalformedHierarchiesAreClearErrors) {
  const std::string good = goodText();
  const std::string hierarchy = good.substr(0, good.find("MOTION"));
  EXPECT_THAT(parseError(good.substr(0, good.find("JOINT LeftLeg"))).message(),
              HasSubstr("truncated hierarchy"));
  EXPECT_THAT(parseError(hierarchy).message(), HasSubstr("truncated"));
  EXPECT_THAT(parseError(hierarchy.substr(0, hierarchy.rfind('}')) + "MOTION\n").message(),
              HasSubstr("truncated hierarchy"));
  EXPECT_THAT(parseError("").message(), HasSubstr("no HIERARCHY"));
  EXPECT_THAT(parseError("MOTION\n").message(), HasSubstr("expected HIERARCHY"));
  EXPECT_THAT(parseError(replaceFirst(good, "JOINT LeftLeg", "JIONT LeftLeg")).message(),
              HasSubstr("unknown keyword 'JIONT'"));
  EXPECT_THAT(parseError(replaceFirst(good, "Zrotation Xrotation Yrotation", "Zrotation Wrotation Yrotation"))
                  .message(),
              HasSubstr("unknown channel 'Wrotation'"));
  EXPECT_THAT(parseError(replaceFirst(good, "CHANNELS 3 Zrotation", "CHANNELS 4 Zrotation")).message(),
              HasSubstr("CHANNELS 4 names 3"));
  EXPECT_THAT(parseError(replaceFirst(good, "Zrotation Xrotation Yrotation", "Zrotation Zrotation Yrotation"))
                  .message(),
              HasSubstr("given twice"));
  const Status offset = parseError(replaceFirst(good, "OFFSET 0 95 0", "OFFSET 0 nan 0"));
  EXPECT_THAT(offset.message(), HasSubstr("not a finite number"));
  EXPECT_THAT(offset.message(), StartsWith("bad.bvh:4:"));  // HIERARCHY, ROOT, {, OFFSET
  EXPECT_THAT(parseError(replaceFirst(good, "OFFSET 0 95 0", "OFFSET 0 95")).message(),
              HasSubstr("3 numbers"));
  EXPECT_THAT(parseError(hierarchy + "ROOT Again\n{\n}\n" + good.substr(good.find("MOTION"))).message(),
              HasSubstr("a second ROOT"));
}

TEST(Bvh, MalformedMotionIsAClearError) {
  const std::string good = goodText();
  const std::string head = good.substr(0, good.find("Frames:"));
  const std::string rows = good.substr(good.find('\n', good.find("Frame Time:")) + 1);
  std::istringstream in(rows);
  std::vector<std::string> row;
  for (std::string l; std::getline(in, l);) row.push_back(l);
  ASSERT_EQ(row.size(), 4u);
  const std::string time = "Frame Time: 0.0333333\n";
  const Status truncated = parseError(head + "Frames: 6\n" + time + row[0] + "\n" + row[1] + "\n");
  EXPECT_THAT(truncated.message(), HasSubstr("Frames: 6 but the file ends after 2 rows (truncated motion)"));
  const Status giant =
      parseError(head + "Frames: 999999\n" + time + row[0] + "\n" + row[1] + "\n" + row[2] + "\n");
  EXPECT_THAT(giant.message(), HasSubstr("Frames: 999999 but the file ends after 3 rows"));
  EXPECT_THAT(parseError(head + "Frames: 1000000000000\n" + time + row[0] + "\n").message(),
              HasSubstr("MotionLimits::maxSamples"));
  EXPECT_THAT(parseError(head + "Frames: 0\n" + time).message(), HasSubstr("Frames: 0"));
  EXPECT_THAT(parseError(head + "Frames: -3\n" + time).message(), HasSubstr("not a whole number"));
  EXPECT_THAT(parseError(head + "Frames: 1\nFrame Time: 0\n" + row[0] + "\n").message(),
              HasSubstr("Frame Time"));
  EXPECT_THAT(parseError(head + "Frames: 1\nFrame Time: -0.1\n" + row[0] + "\n").message(),
              HasSubstr("Frame Time"));
  EXPECT_THAT(parseError(head + "Frames: 1\nFrame Time: inf\n" + row[0] + "\n").message(),
              HasSubstr("Frame Time"));
  EXPECT_THAT(parseError(head + "Frames: 1\n").message(), HasSubstr("Frame Time"));
  const std::string oneFrame = head + "Frames: 1\n" + time;
  const std::string shortRow = row[1].substr(0, row[1].rfind(' '));
  const Status wrongCount = parseError(oneFrame + shortRow + "\n");
  EXPECT_THAT(wrongCount.message(), HasSubstr("frame 0 has"));
  EXPECT_THAT(wrongCount.message(), HasSubstr("the hierarchy has"));
  const auto withValue = [&](const std::string& v) {
    std::string r = row[1];
    r.replace(r.rfind(' ') + 1, std::string::npos, v);
    return oneFrame + r + "\n";
  };
  EXPECT_THAT(parseError(withValue("nan")).message(), HasSubstr("'nan' is not a finite number"));
  EXPECT_THAT(parseError(withValue("-inf")).message(), HasSubstr("not a finite number"));
  EXPECT_THAT(parseError(withValue("1e999")).message(), HasSubstr("not a finite number"));
  EXPECT_THAT(parseError(withValue("abc")).message(), HasSubstr("'abc' is not a number"));
  EXPECT_THAT(parseError(withValue("1.5x")).message(), HasSubstr("'1.5x' is not a number"));
  EXPECT_THAT(parseError(withValue("--1")).message(), HasSubstr("is not a number"));
  // Rows past Frames are said, not read.
  const MotionClipResult extra = retarget(oneFrame + row[0] + "\n" + row[1] + "\n");
  EXPECT_EQ(extra.clip.sampleCount(), 1);
  EXPECT_TRUE(saysSomething(extra.warnings, "1 lines after the last of the 1 frames ignored"));
}

TEST(Bvh, ADepthBombIsACleanErrorWithoutRecursion) {
  std::string text =
      "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation "
      "Xrotation Yrotation\n";
  for (int i = 0; i < 100000; ++i)
    text += "JOINT j\n{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n";
  EXPECT_THAT(parseError(text).message(), HasSubstr("MotionLimits::maxDepth"));
  // With the limits raised past the bomb the reader still holds its stack on the heap: a truncated hierarchy.
  BvhOptions roomy;
  roomy.limits.maxDepth = 200000;
  roomy.limits.maxJoints = 200000;
  EXPECT_THAT(parseError(text, roomy).message(), HasSubstr("truncated hierarchy"));
  roomy.limits.maxDepth = 1000;
  EXPECT_THAT(parseError(text, roomy).message(), HasSubstr("deeper than 1000"));
  BvhOptions fewJoints;
  fewJoints.limits.maxJoints = 10;
  EXPECT_THAT(parseError(text, fewJoints).message(), HasSubstr("MotionLimits::maxJoints"));
}

TEST(Bvh, FilesAreReadWithTheirSizeChecked) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "cape_test_bvh";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "walk.bvh").string();
  {
    std::ofstream out(path, std::ios::binary);
    out << goodText();
  }
  const MotionClipResult r = readBvh(path, humanoid(), keepingRest());
  ASSERT_TRUE(r.ok()) << r.status.message();
  EXPECT_EQ(r.clip.name, "walk.bvh");
  expectSameClip(r.clip, retarget(goodText()).clip);
  BvhOptions small;
  small.limits.maxFileBytes = 100;
  const MotionClipResult big = readBvh(path, humanoid(), small);
  EXPECT_EQ(big.status.code(), ErrorCode::InvalidArgument);
  EXPECT_THAT(big.status.message(), HasSubstr("MotionLimits::maxFileBytes"));
  EXPECT_EQ(readBvh((dir / "none.bvh").string(), humanoid()).status.code(), ErrorCode::FileNotFound);
  EXPECT_EQ(readBvh(dir.string(), humanoid()).status.code(), ErrorCode::FileNotFound);
  const MotionClipResult noModel = parseBvh(goodText(), nullptr);
  EXPECT_EQ(noModel.status.code(), ErrorCode::InvalidArgument);
  std::filesystem::remove_all(dir);
}

TEST(Bvh, ARootAboveTheHipsCarriesTheMotion) {
  // Exporters often put a "Reference" joint above the hips: it has the position and rotation channels here,
  // the hips (at the same point) only rotations that stay zero.
  std::vector<Bone> bones = humanoidBones();
  for (Bone& b : bones) b.parent = b.parent < 0 ? 0 : b.parent + 1;
  Bone reference = bones[0];
  reference.name = "Reference";
  reference.parent = -1;
  bones.insert(bones.begin(), reference);
  const std::vector<Frame> frames = knownFrames();
  const MotionClipResult r = retarget(writeBvh(bones, frames, {yUpAxes(), 0.01, {}}));
  ASSERT_TRUE(r.ok());
  expectSameClip(r.clip, retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}})).clip);
}

TEST(Bvh, BadOptionsAreRefused) {
  BvhOptions negative;
  negative.scale = -0.01;
  EXPECT_EQ(parseBvh(goodText(), humanoid(), negative).status.code(), ErrorCode::InvalidArgument);
  BvhOptions nan;
  nan.scale = NAN;
  EXPECT_EQ(parseBvh(goodText(), humanoid(), nan).status.code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(parseBvh(goodText(), humanoid(), {}, nullptr, 0.0).status.code(), ErrorCode::InvalidArgument);
  BvhOptions zeroLimit;
  zeroLimit.limits.maxDepth = 0;
  EXPECT_EQ(parseBvh(goodText(), humanoid(), zeroLimit).status.code(), ErrorCode::InvalidArgument);
}

TEST(Bvh, CorruptedFilesNeverCrash) {
  // Deterministic corruptions of a good file (cuts, repeats, stray characters): each is read or refused.
  const std::string good = goodText();
  const std::string junk = "{}\n \t-.0123456789eE+nanifJOINTEnd SiteOFFSETCHANNELS 6 Xrotation:";
  unsigned state = 12345u;
  const auto next = [&](std::size_t n) {
    state = state * 1103515245u + 12345u;
    return static_cast<std::size_t>((state >> 8) % n);
  };
  int read = 0, refused = 0;
  for (int i = 0; i < 300; ++i) {
    std::string text = good;
    for (int edits = 1 + static_cast<int>(next(4)); edits > 0; --edits) {
      const std::size_t at = next(text.size()), len = 1 + next(40);
      switch (next(3)) {
        case 0:
          text.erase(at, len);
          break;
        case 1:
          text.insert(at, text.substr(next(text.size()), len));
          break;
        default:
          for (std::size_t k = at; k < std::min(text.size(), at + len); k += 1 + next(8))
            text[k] = junk[next(junk.size())];
      }
    }
    const MotionClipResult r = parseBvh(text, humanoid(), {}, nullptr, 1.0, "bad.bvh");
    if (r.ok()) {
      ++read;
      EXPECT_TRUE(r.clip.check().ok());
    } else {
      ++refused;
      EXPECT_FALSE(r.status.message().empty());
    }
  }
  EXPECT_GT(refused, 0);
  EXPECT_EQ(read + refused, 300);
}

// --- (7) a humanoid of ball joints ------------------------------------------------------------------------

/// PyBullet's DeepMimic humanoid's joint names and kinds in a small Y-up model (x forward, y up, z right):
/// chest, neck, hips, ankles and shoulders spherical; knees and elbows revolute about z.
std::string deepMimicLikeUrdf() {
  std::ostringstream u;
  u << "<robot name=\"dm\">\n<link name=\"base\"/>\n"
       "<joint name=\"root\" type=\"fixed\"><parent link=\"base\"/><child link=\"root\"/>"
       "<origin xyz=\"0 0 0\"/></joint>\n";
  const auto link = [&](const std::string& name, const std::string& centre) {
    u << "<link name=\"" << name << "\"><collision><origin xyz=\"" << centre
      << "\"/><geometry><sphere radius=\"0.05\"/></geometry></collision></link>\n";
  };
  const auto joint = [&](const std::string& name, const std::string& type, const std::string& parent,
                         const std::string& origin, const std::string& limits) {
    u << "<joint name=\"" << name << "\" type=\"" << type << "\"><parent link=\"" << parent
      << "\"/><child link=\"" << name << "\"/><origin xyz=\"" << origin << "\"/>";
    if (type == "revolute")
      u << "<axis xyz=\"0 0 1\"/><limit lower=\"" << limits << "\" effort=\"100\" velocity=\"10\"/>";
    u << "</joint>\n";
  };
  link("root", "0 0 0");
  joint("chest", "spherical", "root", "0 0.24 0", "");
  link("chest", "0 0.12 0");
  joint("neck", "spherical", "chest", "0 0.22 0", "");
  link("neck", "0 0.10 0");
  for (const char* side : {"right", "left"}) {
    const std::string s(side);
    const double z = s == "right" ? 1.0 : -1.0;
    joint(s + "_hip", "spherical", "root", "0 0 " + std::to_string(0.085 * z), "");
    link(s + "_hip", "0 -0.2 0");
    joint(s + "_knee", "revolute", s + "_hip", "0 -0.42 0", "-3.14\" upper=\"0");
    link(s + "_knee", "0 -0.2 0");
    joint(s + "_ankle", "spherical", s + "_knee", "0 -0.41 0", "");
    link(s + "_ankle", "0.045 -0.0225 0");
    joint(s + "_shoulder", "spherical", "chest", "0 0.24 " + std::to_string(0.18 * z), "");
    link(s + "_shoulder", "0 -0.14 0");
    joint(s + "_elbow", "revolute", s + "_shoulder", "0 -0.27 0", "0\" upper=\"3.14");
    link(s + "_elbow", "0 -0.26 0");
  }
  u << "</robot>\n";
  return u.str();
}

TEST(Bvh, RetargetsOntoBallJointsOfAYUpModel) {
  UrdfLoadOptions load;
  load.modelUp = UrdfLoadOptions::Up::Y;
  const UrdfLoadResult loaded = UrdfModel::fromString(deepMimicLikeUrdf(), load);
  ASSERT_TRUE(loaded.ok()) << loaded.status.message();
  ASSERT_TRUE(loaded.model->turnedOntoZ());
  const std::vector<Frame> frames = knownFrames();
  const MotionClipResult r =
      retarget(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}), {}, loaded.model);
  ASSERT_TRUE(r.ok());
  const MotionClip& clip = r.clip;
  std::vector<std::string> scalars = clip.joints;
  std::sort(scalars.begin(), scalars.end());
  EXPECT_EQ(scalars, (std::vector<std::string>{"left_elbow", "left_knee", "right_elbow", "right_knee"}));
  EXPECT_EQ(clip.balls.size(), 8u);
  for (const char* ball : {"chest", "neck", "right_hip", "right_ankle", "right_shoulder", "left_hip",
                           "left_ankle", "left_shoulder"})
    EXPECT_NE(std::find(clip.balls.begin(), clip.balls.end(), ball), clip.balls.end()) << ball;
  EXPECT_TRUE(clip.check().ok());

  const UrdfModelPtr& model = loaded.model;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const Skeleton dm = posed(model, clip, static_cast<int>(k));
    const Skeleton human = expectedPose(frames[k]);
    for (const char* side : {"left", "right"}) {
      const std::string s(side);
      // The knee's angle is the BVH's bend, signed by its axis against the humanoid's (in the world, posed).
      const int knee = model->findJoint(s + "_knee");
      const JointDesc& kj = model->joints()[static_cast<std::size_t>(knee)];
      const Eigen::Vector3d axis = dm.linkPose(kj.parentLink).linear() * kj.origin.linear() * kj.axis;
      Eigen::Isometry3d thighPose;
      ASSERT_TRUE(human.linkPose(s + "_thigh", thighPose).ok());
      const double sign = axis.dot(thighPose.linear() * Eigen::Vector3d::UnitY());
      EXPECT_NEAR(std::abs(sign), 1.0, 1e-9);
      const auto bend = frames[k].angles.find(s + "_knee");
      const double want = bend == frames[k].angles.end() ? 0.0 : bend->second;
      EXPECT_NEAR(valueOf(clip, s + "_knee", static_cast<int>(k)), sign * want, 1e-6)
          << side << " frame " << k;
      // The thigh and shin point where the humanoid's do.
      const auto dir = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        return (b - a).normalized();
      };
      const Eigen::Vector3d thigh = dir(linkAt(dm, (s + "_hip").c_str()), linkAt(dm, (s + "_knee").c_str()));
      const Eigen::Vector3d shin = dir(linkAt(dm, (s + "_knee").c_str()), linkAt(dm, (s + "_ankle").c_str()));
      EXPECT_LT(
          (thigh - dir(linkAt(human, (s + "_thigh").c_str()), linkAt(human, (s + "_shin").c_str()))).norm(),
          1e-6);
      EXPECT_LT(
          (shin - dir(linkAt(human, (s + "_shin").c_str()), linkAt(human, (s + "_foot").c_str()))).norm(),
          1e-6);
    }
    // Its hips are where the humanoid's are, scaled by the legs (0.83 m over the BVH's 0.80 m).
    const Eigen::Vector3d hips = 0.5 * (linkAt(dm, "left_hip") + linkAt(dm, "right_hip"));
    EXPECT_LT((hips - frames[k].hips * (0.83 / 0.80)).norm(), 1e-9);
  }
}

// --- (8) quirks of real files ------------------------------------------------------------------------

// Many exporters write the reference pose (every rotation 0) as frame 0 before the motion (CMU's BVH
// conversions do, with the root already where the motion starts): by default it is left out and said; the
// clip starts at the next frame, at time 0. A clip that starts at rest and stays there a frame keeps it.
// Every rotation value of one row of a BVH's motion moved by `delta` degrees (a captured frame: no angle
// exactly 0); the root's position kept.
std::string turnedRow(const std::string& text, int row, double delta) {
  std::istringstream in(text);
  std::ostringstream out;
  int motionRow = -1;
  for (std::string line; std::getline(in, line);) {
    if (motionRow >= 0 && motionRow++ == row) {
      std::istringstream values(line);
      double v;
      for (int c = 0; values >> v; ++c) out << (c == 0 ? "" : " ") << (c < 3 ? v : v + delta);
      out << "\n";
      continue;
    }
    if (line.rfind("Frame Time", 0) == 0) motionRow = 0;
    out << line << "\n";
  }
  return out.str();
}

TEST(Bvh, AReferenceFrameBeforeTheMotionIsLeftOut) {
  const std::vector<Frame> frames = knownFrames();  // frame 0 is the rest pose
  const std::string text = turnedRow(writeBvh(humanoidBones(), frames, {yUpAxes(), 0.01, {}}), 1, 0.5);
  const MotionClipResult all = retarget(text);  // kept
  const MotionClipResult r = parseBvh(text, humanoid(), {}, nullptr, 1.0, "ref.bvh");
  ASSERT_TRUE(r.ok()) << r.status.message();
  ASSERT_EQ(r.clip.sampleCount(), all.clip.sampleCount() - 1);
  EXPECT_TRUE(saysSomething(r.warnings, "frame 0 is a reference pose"));
  EXPECT_EQ(r.clip.times.front(), 0.0);
  for (int k = 0; k < r.clip.sampleCount(); ++k) {
    const std::size_t n = r.clip.joints.size();
    for (std::size_t j = 0; j < n; ++j)
      EXPECT_EQ(r.clip.values[static_cast<std::size_t>(k) * n + j],
                all.clip.values[static_cast<std::size_t>(k + 1) * n + j]);
    EXPECT_EQ(r.clip.rootPositions[static_cast<std::size_t>(k)],
              all.clip.rootPositions[static_cast<std::size_t>(k + 1)]);
  }
  // Rest twice: the clip starts at rest (nothing left out).
  std::vector<Frame> still = frames;
  still.insert(still.begin() + 1, frames[0]);
  const MotionClipResult s = parseBvh(writeBvh(humanoidBones(), still, {yUpAxes(), 0.01, {}}), humanoid(), {},
                                      nullptr, 1.0, "s.bvh");
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s.clip.sampleCount(), static_cast<int>(still.size()));
  EXPECT_FALSE(saysSomething(s.warnings, "reference pose"));
  // Two frames: nothing left out either.
  const std::vector<Frame> two(frames.begin(), frames.begin() + 2);
  const MotionClipResult t =
      parseBvh(writeBvh(humanoidBones(), two, {yUpAxes(), 0.01, {}}), humanoid(), {}, nullptr, 1.0, "t.bvh");
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(t.clip.sampleCount(), 2);
}

// A capture's foot bone runs from the ankle to the toe base, a little below the horizontal; the URDF's from
// the ankle to its foot's shapes, well below it. Both feet stand flat at rest, so at rest the ankle is at 0
// (not turned by the difference of the two directions, which would hold it at a limit).
TEST(Bvh, FeetAtRestStayFlatWhateverTheirBonesDirection) {
  std::vector<Bone> bones = humanoidBones();
  for (Bone& b : bones)
    if (b.name == "LeftFoot" || b.name == "RightFoot") b.ends = {Eigen::Vector3d(0.12, 0.0, -0.01)};
  std::vector<Frame> frames(3);
  frames[1].angles = {{"left_knee", 0.3}};
  frames[2].angles = {{"left_ankle", 0.3}, {"right_ankle", -0.4}};
  const MotionClipResult r = retarget(writeBvh(bones, frames, {yUpAxes(), 0.01, {}}));
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(valueOf(r.clip, "left_ankle", 0), 0.0, 1e-9);
  EXPECT_NEAR(valueOf(r.clip, "right_ankle", 0), 0.0, 1e-9);
  EXPECT_NEAR(valueOf(r.clip, "left_ankle", 2), 0.3, 1e-6);
  EXPECT_NEAR(valueOf(r.clip, "right_ankle", 2), -0.4, 1e-6);
  EXPECT_FALSE(saysSomething(r.warnings, "held at its limits"));
}

}  // namespace
}  // namespace cape::character
