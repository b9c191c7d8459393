// Motion clips end to end through cape_walk --motion: a walking and a running clip in each of the three
// formats (joint-trajectory CSV, DeepMimic, BVH), written by the test from one stride model, played on the
// shipped humanoid and on a humanoid of another origin (a Y-up model in the shape of PyBullet's DeepMimic
// humanoid: ball joints, four times too large, loaded with --model-up y --scale 0.25). The measures of the
// motion issue: the cape stays on the back, no particle deeper than 1 mm in any collider, p95 per-frame max
// strain <= 5 % in the walk, zero self-intersections with self-collision on, no blow-up.
#include "DemoTestSupport.h"

#include "cape/character/Grounding.h"
#include "cape/character/MotionFormats.h"
#include "cape/character/Skeleton.h"
#include "cape/character/Urdf.h"

#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <sstream>

namespace cape::demo_test {
namespace {

namespace fs = std::filesystem;
using character::MotionClip;
using character::Skeleton;
using character::UrdfLoadOptions;
using character::UrdfModel;
using character::UrdfModelPtr;
using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;
constexpr double kRate = 30.0;  // samples per second of every clip

// --- One stride model: the angles of a gait cycle, flexion positive (thigh and arm forward, shin back) -----

struct Stride {
  const char* name;
  double period;    // s, one left and one right step
  double speed;     // m/s forward
  double hip;       // rad, amplitude of the thigh's swing
  double knee;      // rad, knee bend at mid-swing on top of kneeBase
  double kneeBase;  // rad
  double ankle;     // rad
  double shoulder;  // rad, amplitude of the arm's swing
  double elbow;     // rad, mean elbow bend
  double seconds;   // length of the cape_walk run
};

const Stride kWalk{"walk", 1.1, 1.2, 0.40, 0.75, 0.08, 0.15, 0.30, 0.35, 4.0};
const Stride kRun{"run", 0.7, 3.0, 0.65, 1.40, 0.25, 0.25, 0.60, 1.30, 3.0};

struct Side {
  double hip, knee, ankle, shoulder, elbow;
};

// The angles of one side at time t; the right side is half a cycle behind the left.
Side sideAt(const Stride& s, double t, bool left) {
  const double phase = 2.0 * kPi * t / s.period + (left ? 0.0 : kPi);
  const double swing = 0.5 * (1.0 + std::cos(phase));  // 1 at mid-swing, when the thigh passes forward
  Side a;
  a.hip = s.hip * std::sin(phase);
  a.knee = s.kneeBase + s.knee * swing * swing;
  a.ankle = s.ankle * std::sin(phase + 0.5);
  a.shoulder = -s.shoulder * std::sin(phase);  // the arm swings against the leg of its side
  a.elbow = s.elbow + 0.15 * swing;
  return a;
}

// Two cycles, the last sample equal to the first in every angle (a loop), kRate samples per second.
int sampleCount(const Stride& s) {
  return static_cast<int>(std::lround(2.0 * s.period * kRate)) + 1;
}
double sampleTime(int k) {
  return k / kRate;
}

// The root height (m, world y, of the URDF root link) that puts the skeleton's lowest collision point on
// the ground in its current pose.
double footOnGround(Skeleton& skeleton) {
  skeleton.setRootTransform(Eigen::Isometry3d::Identity());  // standing: the URDF's z up the world's y
  const std::optional<double> lowest = character::lowestCollisionPoint(skeleton);
  return lowest ? -*lowest : 0.0;
}

// --- The shipped humanoid's joints: a CSV clip in the URDF frame ----------------------------------------

MotionClip shippedHumanoidClip(const Stride& s) {
  const UrdfModelPtr model = UrdfModel::humanoid().model;
  Skeleton skeleton(model);
  MotionClip clip;
  clip.name = s.name;
  for (const char* side : {"left", "right"})
    for (const char* j : {"_hip_pitch", "_knee", "_ankle", "_shoulder_pitch", "_elbow"})
      clip.joints.push_back(std::string(side) + j);
  clip.joints.push_back("waist");
  for (int k = 0; k < sampleCount(s); ++k) {
    const double t = sampleTime(k);
    std::vector<double> row;
    for (bool left : {true, false}) {
      const Side a = sideAt(s, t, left);
      for (double v : {a.hip, a.knee, a.ankle, a.shoulder, a.elbow}) row.push_back(v);
    }
    row.push_back(0.08 * std::sin(2.0 * kPi * t / s.period));  // the pelvis turns with the stride
    for (std::size_t j = 0; j < row.size(); ++j)
      EXPECT_TRUE(skeleton.setJointPosition(clip.joints[j], row[j]).ok());
    clip.times.push_back(t);
    clip.rootPositions.emplace_back(s.speed * t, 0.0, footOnGround(skeleton));  // x forward, z up
    clip.rootRotations.push_back(Eigen::Quaterniond::Identity());
    clip.values.insert(clip.values.end(), row.begin(), row.end());
  }
  return clip;
}

// --- A humanoid of another origin: PyBullet's DeepMimic humanoid's layout, written here ----------------
// Y up, x forward, z right; 4x metres (PyBullet loads it with globalScaling 0.25); chest, neck, hips,
// ankles and shoulders spherical; knees (bend negative) and elbows (bend positive) revolute about z;
// spheres for the pelvis, chest and head, capsules along the limbs, boxes for the feet.

std::string deepMimicLikeUrdf() {
  std::ostringstream u;
  u << "<?xml version=\"1.0\"?>\n<robot name=\"dumpUrdf\">\n<link name=\"base\"/>\n"
       "<joint name=\"root\" type=\"fixed\"><parent link=\"base\"/><child link=\"root\"/>"
       "<origin rpy=\"0 0 0\" xyz=\"0 0 0\"/></joint>\n";
  const auto link = [&](const std::string& name, const std::string& geometry, const std::string& xyz,
                        const std::string& rpy) {
    u << "<link name=\"" << name
      << "\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" "
      << "iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial><collision><origin rpy=\"" << rpy << "\" xyz=\""
      << xyz << "\"/><geometry>" << geometry << "</geometry></collision></link>\n";
  };
  const auto joint = [&](const std::string& name, const std::string& type, const std::string& parent,
                         const std::string& xyz, const std::string& limits) {
    u << "<joint name=\"" << name << "\" type=\"" << type << "\"><parent link=\"" << parent
      << "\"/><child link=\"" << name << "\"/><origin rpy=\"0 0 0\" xyz=\"" << xyz << "\"/>";
    if (type == "revolute")
      u << "<limit effort=\"1000\" " << limits << " velocity=\"10\"/><axis xyz=\"0 0 1\"/>";
    u << "</joint>\n";
  };
  const auto sphere = [](const char* r) { return std::string("<sphere radius=\"") + r + "\"/>"; };
  const auto capsule = [](const char* l, const char* r) {
    return std::string("<capsule length=\"") + l + "\" radius=\"" + r + "\"/>";
  };
  const std::string down = "-1.570796 0 0";  // a capsule's z along y
  link("root", sphere("0.36"), "0 0.28 0", "0 0 0");
  joint("chest", "spherical", "root", "0 0.944604 0", "");
  link("chest", sphere("0.44"), "0 0.48 0", "0 0 0");
  joint("neck", "spherical", "chest", "0 0.895576 0", "");
  link("neck", sphere("0.41"), "0 0.7 0", "0 0 0");
  for (const char* side : {"right", "left"}) {
    const std::string s(side), z = s == "right" ? "" : "-";
    joint(s + "_hip", "spherical", "root", "0 0 " + z + "0.339548", "");
    link(s + "_hip", capsule("1.2", "0.22"), "0 -0.84 0", down);
    joint(s + "_knee", "revolute", s + "_hip", "0 -1.686184 0", "lower=\"-3.14\" upper=\"0\"");
    link(s + "_knee", capsule("1.24", "0.2"), "0 -0.8 0", down);
    joint(s + "_ankle", "spherical", s + "_knee", "0 -1.63948 0", "");
    link(s + "_ankle", "<box size=\"0.708 0.22 0.36\"/>", "0.18 -0.09 0", "0 0 0");
    joint(s + "_shoulder", "spherical", "chest", "-0.0962 0.974 " + z + "0.73244", "");
    link(s + "_shoulder", capsule("0.72", "0.18"), "0 -0.56 0", down);
    joint(s + "_elbow", "revolute", s + "_shoulder", "0 -1.099152 0", "lower=\"0\" upper=\"3.14\"");
    link(s + "_elbow", capsule("0.54", "0.16"), "0 -0.48 0", down);
  }
  u << "</robot>\n";
  return u.str();
}

constexpr double kDeepMimicScale = 0.25;

UrdfModelPtr loadDeepMimicLike(const fs::path& urdf) {
  UrdfLoadOptions load;
  load.modelUp = UrdfLoadOptions::Up::Y;
  const character::UrdfLoadResult loaded = UrdfModel::fromFile(urdf.string(), load);
  EXPECT_TRUE(loaded.ok()) << loaded.status.message();
  return loaded.model;
}

Eigen::Quaterniond aboutZ(double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
}

// The DeepMimic text of the stride on that humanoid: per frame the duration, the root (m of the scaled
// humanoid, Y up), its rotation (w x y z), then chest, neck, right_hip, right_knee, right_ankle,
// right_shoulder, right_elbow and the same on the left; flexion is a rotation about z there.
std::string deepMimicText(const Stride& s, const UrdfModelPtr& model) {
  Skeleton skeleton(model);
  EXPECT_TRUE(skeleton.setScale(kDeepMimicScale).ok());
  json frames = json::array();
  const auto put = [](json& f, const Eigen::Quaterniond& q) {
    for (double v : {q.w(), q.x(), q.y(), q.z()}) f.push_back(v);
  };
  for (int k = 0; k < sampleCount(s); ++k) {
    const double t = sampleTime(k);
    const double twist = 0.08 * std::sin(2.0 * kPi * t / s.period);
    EXPECT_TRUE(skeleton
                    .setJointRotation("chest",
                                      Eigen::Quaterniond(Eigen::AngleAxisd(-twist, Eigen::Vector3d::UnitY())))
                    .ok());
    for (bool left : {true, false}) {
      const std::string side = left ? "left" : "right";
      const Side a = sideAt(s, t, left);
      EXPECT_TRUE(skeleton.setJointRotation(side + "_hip", aboutZ(a.hip)).ok());
      EXPECT_TRUE(skeleton.setJointPosition(side + "_knee", -a.knee).ok());
      EXPECT_TRUE(skeleton.setJointRotation(side + "_ankle", aboutZ(-a.ankle)).ok());
      EXPECT_TRUE(skeleton.setJointRotation(side + "_shoulder", aboutZ(a.shoulder)).ok());
      EXPECT_TRUE(skeleton.setJointPosition(side + "_elbow", a.elbow).ok());
    }
    json f = json::array({k + 1 < sampleCount(s) ? 1.0 / kRate : 0.0});
    for (double v : {s.speed * t, footOnGround(skeleton), 0.0}) f.push_back(v);
    put(f, Eigen::Quaterniond::Identity());
    put(f, skeleton.jointRotation(skeleton.jointIndex("chest")));
    put(f, Eigen::Quaterniond::Identity());  // neck
    for (const char* side : {"right", "left"}) {
      const std::string p(side);
      put(f, skeleton.jointRotation(skeleton.jointIndex(p + "_hip")));
      f.push_back(skeleton.jointPositions()[static_cast<std::size_t>(skeleton.jointIndex(p + "_knee"))]);
      put(f, skeleton.jointRotation(skeleton.jointIndex(p + "_ankle")));
      put(f, skeleton.jointRotation(skeleton.jointIndex(p + "_shoulder")));
      f.push_back(skeleton.jointPositions()[static_cast<std::size_t>(skeleton.jointIndex(p + "_elbow"))]);
    }
    frames.push_back(f);
  }
  return json({{"Loop", "wrap"}, {"Frames", frames}}).dump();
}

// --- BVH: a made-up skeleton in centimetres, Mixamo's joint names, Y up, facing +z ----------------------
// Flexion of the thigh, the arm and the forearm is a negative rotation about x, of the shin a positive one.

std::string bvhText(const Stride& s) {
  std::ostringstream b;
  b << "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation "
       "Xrotation Yrotation\n";
  const auto open = [&](const char* name, const char* offset) {
    b << "JOINT " << name << "\n{\n OFFSET " << offset << "\n CHANNELS 3 Zrotation Xrotation Yrotation\n";
  };
  const auto end = [&](const char* offset) { b << "End Site\n{\n OFFSET " << offset << "\n}\n"; };
  open("Spine", "0 10 0");
  open("Neck", "0 45 0");
  open("Head", "0 10 0");
  end("0 18 0");
  b << "}\n}\n";
  for (const char* side : {"Left", "Right"}) {
    const std::string x = std::string(side) == "Left" ? "" : "-";
    open((std::string(side) + "Arm").c_str(), (x + "18 40 0").c_str());
    open((std::string(side) + "ForeArm").c_str(), "0 -28 0");
    open((std::string(side) + "Hand").c_str(), "0 -26 0");
    end("0 -8 0");
    b << "}\n}\n}\n";
  }
  b << "}\n";
  for (const char* side : {"Left", "Right"}) {
    const std::string x = std::string(side) == "Left" ? "" : "-";
    open((std::string(side) + "UpLeg").c_str(), (x + "9 -4 0").c_str());
    open((std::string(side) + "Leg").c_str(), "0 -42 0");
    open((std::string(side) + "Foot").c_str(), "0 -41 0");
    end("0 -6 14");
    b << "}\n}\n}\n";
  }
  b << "}\nMOTION\nFrames: " << sampleCount(s) << "\nFrame Time: " << 1.0 / kRate << "\n";
  const double deg = 180.0 / kPi;
  for (int k = 0; k < sampleCount(s); ++k) {
    const double t = sampleTime(k);
    const Side l = sideAt(s, t, true), r = sideAt(s, t, false);
    // The hips over the lower ankle: 4 cm below the hips to the thigh, the legs' lengths, the foot's 6 cm.
    const auto height = [](const Side& a) {
      return 42.0 * std::cos(a.hip) + 41.0 * std::cos(a.hip - a.knee);
    };
    const double hips = 4.0 + std::max(height(l), height(r)) + 6.0;
    b << "0 " << hips << " " << 100.0 * s.speed * t << " 0 0 "
      << -0.08 * deg * std::sin(2.0 * kPi * t / s.period);
    b << " 0 0 0  0 0 0  0 0 0";  // spine, neck, head
    for (const Side& a : {l, r})
      b << "  0 " << -a.shoulder * deg << " 0  0 " << -a.elbow * deg << " 0  0 0 0";
    for (const Side& a : {l, r})
      b << "  0 " << -a.hip * deg << " 0  0 " << a.knee * deg << " 0  0 " << a.ankle * deg << " 0";
    b << "\n";
  }
  return b.str();
}

// --- Running cape_walk and measuring ---------------------------------------------------------------------

struct Play {
  std::string what;
  fs::path urdf;  // empty: the shipped humanoid
  std::string modelOptions;
  fs::path clip;
  const Stride* stride;
};

std::vector<std::array<double, 3>> objVertices(const fs::path& file) {
  std::vector<std::array<double, 3>> out;
  for (const std::string& l : lines(file)) {
    if (l.rfind("v ", 0) != 0) continue;
    std::istringstream in(l.substr(2));
    std::array<double, 3> p{};
    in >> p[0] >> p[1] >> p[2];
    out.push_back(p);
  }
  return out;
}

// The mean horizontal (x, z) position of the character's colliders in one colliders.jsonl line.
std::array<double, 2> bodyCentre(const json& line) {
  std::array<double, 2> sum{0.0, 0.0};
  int n = 0;
  for (const json& c : line["colliders"]) {
    if (c["type"] == "plane" || !c.contains("position")) continue;
    sum[0] += c["position"][0].get<double>();
    sum[1] += c["position"][2].get<double>();
    ++n;
  }
  return {sum[0] / std::max(n, 1), sum[1] / std::max(n, 1)};
}

// Runs the clip with self-collision on, every 10th frame written, and checks the measures; the cape
// is on the back when, in every written frame, its particles' mean is at least 3 cm behind the body's
// colliders' mean along the way the body went.
json playAndMeasure(const fs::path& dir, const Play& p) {
  const fs::path out = dir / "run";
  std::string command = std::string(CAPE_WALK) + " --cape canonical --motion " + p.clip.string() +
                        " --self-collision" + " --seconds " + std::to_string(p.stride->seconds) +
                        " --frames-every 10 --out " + out.string();
  if (!p.urdf.empty()) command += " --urdf " + p.urdf.string() + " " + p.modelOptions;
  const Result r = run(command);
  EXPECT_EQ(r.exitCode, 0) << p.what << "\n" << r.output;
  EXPECT_NE(r.output.find(" samples, "), std::string::npos) << p.what << "\n" << r.output;
  // On the DeepMimic-like humanoid the cape hangs from the chest, where the ball shoulders turn from (the
  // links named "shoulder" there are the upper arms).
  if (!p.urdf.empty()) {
    EXPECT_NE(r.output.find("cape pinned to link 'chest'"), std::string::npos) << p.what << "\n" << r.output;
  } else {  // fitted standing, as for the gait: docs/SCENES.md's 15 cm behind the shoulders
    EXPECT_NE(r.output.find("its top 15 cm behind the shoulders"), std::string::npos) << p.what << "\n"
                                                                                      << r.output;
  }
  std::ifstream in(out / "summary.json");
  if (!in) {
    ADD_FAILURE() << p.what << ": no summary\n" << r.output;
    return json();
  }
  const json s = json::parse(in);
  const json& q = s["summary"];
  const std::string what = p.what + "\n" + q.dump(1);
  EXPECT_FALSE(q["blow_up"].get<bool>()) << what;
  EXPECT_LE(q["max_penetration_m"].get<double>(), 0.001) << what;
  EXPECT_EQ(q["self_intersections_max"].get<int>(), 0) << what;
  if (p.stride == &kWalk) {
    EXPECT_LE(q["p95_frame_max_strain"].get<double>(), 0.05) << what;
  }
  // No frame tears it: the cape is fitted to the standing character and carried with its upper torso into
  // the clip's first pose, not laid flat through a leg that starts raised behind it (298 % in the DeepMimic
  // run's first frame before).
  EXPECT_LT(q["max_strain"].get<double>(), 0.3) << what;

  const std::vector<std::string> colliders = lines(out / "colliders.jsonl");
  EXPECT_GE(colliders.size(), 8u) << what;
  if (colliders.size() < 2) return s;
  const std::array<double, 2> first = bodyCentre(json::parse(colliders.front()));
  const std::array<double, 2> last = bodyCentre(json::parse(colliders.back()));
  const double travel = std::hypot(last[0] - first[0], last[1] - first[1]);
  // The character walked its clip's speed (the root carried over each loop): within 15 %.
  const double seconds = 10.0 * static_cast<double>(colliders.size() - 1) / 60.0;
  EXPECT_NEAR(travel / seconds, p.stride->speed, 0.15 * p.stride->speed) << what;
  const double forward[2] = {(last[0] - first[0]) / travel, (last[1] - first[1]) / travel};
  double leastBehind = 1e9;
  for (std::size_t i = 0; i < colliders.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%05zu.obj", 10 * (i + 1));
    const std::vector<std::array<double, 3>> cape = objVertices(out / "frames" / name);
    if (cape.empty()) {
      ADD_FAILURE() << p.what << ": no " << name;
      break;
    }
    double mean[2] = {0.0, 0.0};
    for (const auto& v : cape) {
      mean[0] += v[0] / static_cast<double>(cape.size());
      mean[1] += v[2] / static_cast<double>(cape.size());
    }
    const std::array<double, 2> body = bodyCentre(json::parse(colliders[i]));
    const double behind = -((mean[0] - body[0]) * forward[0] + (mean[1] - body[1]) * forward[1]);
    leastBehind = std::min(leastBehind, behind);
  }
  EXPECT_GT(leastBehind, 0.03) << what;
  std::printf(
      "[ measures ] %s: p95 strain %.2f %%, max %.2f %%, deepest %.2f mm, self-intersections %d, "
      "cape >= %.0f cm behind\n",
      p.what.c_str(), 100.0 * q["p95_frame_max_strain"].get<double>(), 100.0 * q["max_strain"].get<double>(),
      1000.0 * q["max_penetration_m"].get<double>(), q["self_intersections_max"].get<int>(),
      100.0 * leastBehind);
  return s;
}

fs::path writeText(const fs::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary) << text;
  return file;
}

const std::string kDeepMimicOptions = "--model-up y --scale " + std::to_string(kDeepMimicScale);

TEST(MotionClips, CsvWalkAndRunOnTheShippedHumanoid) {
  const fs::path dir = freshDir();
  for (const Stride* s : {&kWalk, &kRun}) {
    const fs::path clip =
        writeText(dir / (std::string(s->name) + ".csv"), character::writeMotionCsv(shippedHumanoidClip(*s)));
    playAndMeasure(dir / s->name,
                   {std::string("CSV ") + s->name + " on the shipped humanoid", {}, "", clip, s});
  }
}

// The DeepMimic file, and the same clip as CSV in the URDF frame (x forward, y left, z up; its ball joints
// as .qx .. .qw columns): the two give the same run to the bit.
TEST(MotionClips, DeepMimicAndCsvWalkAndRunOnAHumanoidOfAnotherOrigin) {
  const fs::path dir = freshDir();
  const fs::path urdf = writeText(dir / "humanoid.urdf", deepMimicLikeUrdf());
  const UrdfModelPtr model = loadDeepMimicLike(urdf);
  ASSERT_TRUE(model);
  for (const Stride* s : {&kWalk, &kRun}) {
    const std::string text = deepMimicText(*s, model);
    const fs::path deepMimic = writeText(dir / (std::string("humanoid3d_") + s->name + ".txt"), text);
    const json a = playAndMeasure(dir / (std::string("dm_") + s->name),
                                  {std::string("DeepMimic ") + s->name + " on the DeepMimic-like humanoid",
                                   urdf, kDeepMimicOptions, deepMimic, s});

    character::MotionClipResult read = character::parseDeepMimic(text);
    ASSERT_TRUE(read.ok()) << read.status.message();
    MotionClip clip = read.clip;
    ASSERT_EQ(clip.frame, character::MotionFrame::YUp);
    clip.frame = character::MotionFrame::Urdf;
    for (std::size_t k = 0; k < clip.times.size(); ++k) {
      const Eigen::Vector3d p = clip.rootPositions[k];  // x forward, y up, z right
      clip.rootPositions[k] = Eigen::Vector3d(p.x(), -p.z(), p.y());
      ASSERT_TRUE(clip.rootRotations[k].isApprox(Eigen::Quaterniond::Identity()));  // the same turned
    }
    ASSERT_EQ(clip.balls.size(), 8u);
    const fs::path csv = writeText(dir / (std::string(s->name) + ".csv"), character::writeMotionCsv(clip));
    const json b = playAndMeasure(dir / (std::string("csv_") + s->name),
                                  {std::string("CSV ") + s->name + " on the DeepMimic-like humanoid", urdf,
                                   kDeepMimicOptions + " --motion-frame urdf", csv, s});
    ASSERT_TRUE(a.contains("state_hashes") && b.contains("state_hashes"));
    EXPECT_EQ(a["state_hashes"], b["state_hashes"]) << s->name;
  }
}

TEST(MotionClips, BvhWalkAndRunRetargetedOntoBothHumanoids) {
  const fs::path dir = freshDir();
  const fs::path urdf = writeText(dir / "humanoid.urdf", deepMimicLikeUrdf());
  for (const Stride* s : {&kWalk, &kRun}) {
    const fs::path clip = writeText(dir / (std::string(s->name) + ".bvh"), bvhText(*s));
    playAndMeasure(dir / (std::string("shipped_") + s->name),
                   {std::string("BVH ") + s->name + " on the shipped humanoid", {}, "", clip, s});
    playAndMeasure(dir / (std::string("dm_") + s->name),
                   {std::string("BVH ") + s->name + " on the DeepMimic-like humanoid", urdf,
                    kDeepMimicOptions, clip, s});
  }
}

}  // namespace
}  // namespace cape::demo_test

namespace cape::demo_test {
namespace {

// The example clips in demos/clips/ (the README's) are this test's BVH walk and run, byte for byte.
TEST(MotionClips, TheShippedExampleClipsAreTheTestsOwn) {
  for (const Stride* s : {&kWalk, &kRun}) {
    const fs::path file = fs::path(CAPE_CLIPS_DIR) / (std::string(s->name) + ".bvh");
    std::ifstream in(file, std::ios::binary);
    ASSERT_TRUE(in) << file;
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_TRUE(text == bvhText(*s)) << file << " differs from what bvhText writes";
  }
}

// cape_compare plays the same clip under both capes: ours and btSoftBody's see one motion.
TEST(MotionClips, CapeCompareTakesTheSameOptions) {
  const fs::path dir = freshDir();
  const fs::path clip = writeText(dir / "walk.csv", character::writeMotionCsv(shippedHumanoidClip(kWalk)));
  const Result r =
      run(std::string(CAPE_COMPARE) + " --motion " + clip.string() +
          " --motion-speed 1.5 --size 10 --seconds 1 --no-plots --out " + (dir / "out").string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find(" samples, "), std::string::npos) << r.output;
  std::ifstream in(dir / "out" / "compare.json");
  const json j = json::parse(in);
  EXPECT_NE(j.dump().find("playing " + clip.string()), std::string::npos) << j.dump(1);
  ASSERT_EQ(j["solvers"].size(), 2u);
  EXPECT_FALSE(j["solvers"][0]["blow_up"].get<bool>());
  EXPECT_LE(j["solvers"][0]["max_penetration_m"].get<double>(), 0.001);
}

// A clip that is not a cycle (half a stride) is said to jump every loop; --motion-once plays it once and
// holds its last pose, which ends the walk where the clip does.
TEST(MotionClips, AClipThatIsNotACycleIsSaidAndCanBePlayedOnce) {
  const fs::path dir = freshDir();
  MotionClip clip = shippedHumanoidClip(kWalk);
  const std::size_t keep = static_cast<std::size_t>(sampleCount(kWalk) / 4);  // a quarter: 0.55 s
  clip.times.resize(keep), clip.rootPositions.resize(keep), clip.rootRotations.resize(keep);
  clip.values.resize(keep * clip.joints.size());
  const fs::path file = writeText(dir / "quarter.csv", character::writeMotionCsv(clip));
  const std::string base = std::string(CAPE_WALK) + " --cape canonical --motion " + file.string() +
                           " --seconds 2 --frames-every 60 --no-render --out ";
  const Result looped = run(base + (dir / "looped").string());
  ASSERT_EQ(looped.exitCode, 0) << looped.output;
  EXPECT_NE(looped.output.find("every loop jumps there"), std::string::npos) << looped.output;
  const Result once = run(base + (dir / "once").string() + " --motion-once");
  ASSERT_EQ(once.exitCode, 0) << once.output;
  EXPECT_EQ(once.output.find("every loop jumps there"), std::string::npos) << once.output;
  EXPECT_NE(once.output.find("its ends held"), std::string::npos) << once.output;
  // Held: the body stands where the clip ends (0.53 s at 1.2 m/s: 0.64 m from where it started).
  const std::vector<std::string> c = lines(dir / "once" / "colliders.jsonl");
  ASSERT_EQ(c.size(), 2u);
  const std::array<double, 2> a = bodyCentre(json::parse(c[0])), b = bodyCentre(json::parse(c[1]));
  EXPECT_LT(std::hypot(b[0] - a[0], b[1] - a[1]), 1e-6);  // seconds 1 and 2: held still
  // The clip's longest gap, in the words of the warning: a joint named, in rad.
  const character::LoopGap gap = character::loopGap(clip);
  EXPECT_GT(gap.value, 0.35);
  EXPECT_NE(looped.output.find("at '" + gap.where + "'"), std::string::npos) << looped.output;
}

TEST(MotionClips, BadClipsAndOptionsFailWithAReason) {
  const fs::path dir = freshDir();
  const fs::path walk = writeText(dir / "walk.csv", character::writeMotionCsv(shippedHumanoidClip(kWalk)));
  std::string unknown = character::writeMotionCsv(shippedHumanoidClip(kWalk));
  unknown.replace(unknown.find("waist"), 5, "spine");
  const fs::path unknownJoint = writeText(dir / "unknown.csv", unknown);
  const fs::path truncated = writeText(dir / "truncated.bvh", bvhText(kWalk).substr(0, 900));
  const fs::path nan = writeText(dir / "nan.txt", "{\"Loop\": \"wrap\", \"Frames\": [[0.1, NaN]]}");
  const fs::path bvh = writeText(dir / "walk.bvh", bvhText(kWalk));
  struct Case {
    std::string options;
    std::string says;
    int exitCode;
  };
  const std::vector<Case> cases = {
      {"--motion " + unknownJoint.string(), "spine", 1},           // unknown joint: the model's are listed
      {"--motion " + unknownJoint.string(), "left_hip_pitch", 1},  // ... listed
      {"--motion " + truncated.string(), "truncated.bvh", 1},      // the file named
      {"--motion " + nan.string(), "nan.txt", 1},                  //
      {"--motion " + walk.string() + " --simple-body", "simple body", 1},     // nothing to play on
      {"--motion " + walk.string() + " --motion-format bvh", "walk.csv", 1},  // read as the format given
      {"--motion " + bvh.string() + " --motion-map Hips", "bvh_joint=role", 1},
      {"--motion " + bvh.string() + " --motion-map Hips=tail", "tail", 1},
      {"--motion " + (dir / "missing.csv").string(), "missing.csv", 105},  // CLI11: no such file
      {"--motion " + walk.string() + " --motion-speed 0", "motion-speed", 105},
      {"--motion " + walk.string() + " --motion-speed nan", "motion-speed", 105},
      {"--motion " + walk.string() + " --motion-format fbx", "motion-format", 105},
  };
  for (const Case& c : cases) {
    const Result r = run(std::string(CAPE_WALK) + " " + c.options + " --seconds 0.1 --no-frames --out " +
                         (dir / "out").string());
    EXPECT_NE(r.exitCode, 0) << c.options << "\n" << r.output;
    EXPECT_TRUE(c.exitCode != 1 || r.exitCode == 1) << c.options << "\n" << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.options << "\n" << r.output;
  }
}

}  // namespace
}  // namespace cape::demo_test
