// Finding the gait's joints in a URDF, by name, and their turning sense, by forward kinematics.
#include "cape/character/JointMapping.h"

#include "cape/character/Skeleton.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace cape::character {

const char* toString(GaitRole role) {
  switch (role) {
    case GaitRole::LeftHip:
      return "left hip";
    case GaitRole::RightHip:
      return "right hip";
    case GaitRole::LeftKnee:
      return "left knee";
    case GaitRole::RightKnee:
      return "right knee";
    case GaitRole::LeftAnkle:
      return "left ankle";
    case GaitRole::RightAnkle:
      return "right ankle";
    case GaitRole::LeftShoulder:
      return "left shoulder";
    case GaitRole::RightShoulder:
      return "right shoulder";
    case GaitRole::LeftElbow:
      return "left elbow";
    case GaitRole::RightElbow:
      return "right elbow";
    case GaitRole::LeftShoulderRoll:
      return "left shoulder roll";
    case GaitRole::RightShoulderRoll:
      return "right shoulder roll";
  }
  return "unknown role";
}

namespace {

// Roles come in left/right pairs: role = 2 * part + side (the shoulder roll is part 5).
constexpr const char* kParts[] = {"hip", "knee", "ankle", "shoulder", "elbow"};
constexpr int kShoulder = 3, kElbow = 4, kRollPart = 5;
constexpr int kLeft = 0, kRight = 1, kNoSide = -1;
// The arm hangs "down" for the arms-down warnings when within this of straight down (rad).
constexpr double kArmDownTolerance = 0.35;
constexpr double kPi = 3.14159265358979323846;

GaitRole roleOf(int part, int side) {
  return static_cast<GaitRole>(2 * part + side);
}

// Which way the links beyond a joint should move (URDF +x is forward) for a positive anatomical angle.
double wantedForwardMotion(GaitRole role) {
  return (role == GaitRole::LeftKnee || role == GaitRole::RightKnee) ? -1.0 : 1.0;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool startsWith(const std::string& s, const std::string& p) {
  return s.compare(0, p.size(), p) == 0;
}
bool endsWith(const std::string& s, const std::string& p) {
  return s.size() >= p.size() && s.compare(s.size() - p.size(), p.size(), p) == 0;
}

// Side of a joint named `n` (lower case) whose name contains `part` at `at`.
int sideOf(const std::string& n, std::size_t at) {
  const bool left = n.find("left") != std::string::npos;
  const bool right = n.find("right") != std::string::npos;
  if (left != right) return left ? kLeft : kRight;
  if (left && right) return kNoSide;
  for (const char* sep : {"_", "-", "."}) {
    const std::string s(sep);
    if (startsWith(n, "l" + s) || endsWith(n, s + "l") || n.find(s + "l" + s) != std::string::npos)
      return kLeft;
    if (startsWith(n, "r" + s) || endsWith(n, s + "r") || n.find(s + "r" + s) != std::string::npos)
      return kRight;
  }
  // "lknee", "j_rhip": a lone l or r right before the part.
  if (at > 0 && (n[at - 1] == 'l' || n[at - 1] == 'r') &&
      (at == 1 || !std::isalpha(static_cast<unsigned char>(n[at - 2])))) {
    return n[at - 1] == 'l' ? kLeft : kRight;
  }
  return kNoSide;
}

// Where a name (lower case) names a part, npos if it does not. The shoulder is also Atlas's "arm_sh".
std::size_t findPart(const std::string& n, int part) {
  const std::size_t at = n.find(kParts[part]);
  if (at != std::string::npos || part != kShoulder) return at;
  const std::size_t arm = n.find("arm_sh");
  return arm == std::string::npos ? arm : arm + 4;
}

bool contains(const std::string& n, const char* s) {
  return n.find(s) != std::string::npos;
}
// Names that say "shoulder roll" (abduction): left_shoulder_roll, LShoulderRoll, l_arm_shx, ...
bool saysRoll(const std::string& n) {
  return contains(n, "roll") || contains(n, "abd") || contains(n, "add") || contains(n, "shx") ||
         endsWith(n, "_x") || contains(n, "_x_");
}
// Names that say "pitch" (flexion): the tie-break between joints turning about the same axis.
bool saysPitch(const std::string& n) {
  return contains(n, "pitch") || contains(n, "flex") || contains(n, "shy") || endsWith(n, "_y") ||
         contains(n, "_y_");
}

// --- Names as tokens: robot abbreviations (Atlas's l_leg_hpy, Hubo's LHP) ---

struct Token {
  std::string text;   // lower case
  bool caps = false;  // written in capitals
};

// Splits a name at '_', '-', '.', digits and case changes: "LShoulderRoll" -> l shoulder roll, "l_leg_hpy" ->
// l leg hpy, "LHP" -> lhp (capitals stay together), "LF11" -> lf.
std::vector<Token> tokenize(const std::string& name) {
  std::vector<Token> out;
  std::string cur;
  bool caps = true;
  auto flush = [&]() {
    if (!cur.empty()) out.push_back({lower(cur), caps});
    cur.clear();
    caps = true;
  };
  for (std::size_t i = 0; i < name.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (!std::isalpha(c)) {
      flush();
      continue;
    }
    const bool up = std::isupper(c) != 0;
    if (!cur.empty()) {
      const bool prevUp = std::isupper(static_cast<unsigned char>(cur.back())) != 0;
      const bool nextLow = i + 1 < name.size() && std::islower(static_cast<unsigned char>(name[i + 1])) != 0;
      if ((!prevUp && up) || (prevUp && up && nextLow)) flush();  // "leftShoulder", "LShoulder"
    }
    cur.push_back(static_cast<char>(c));
    if (!up) caps = false;
  }
  flush();
  return out;
}

// What a name says, read as tokens: its part (-1: none), side, and whether it says pitch or roll.
struct NameInfo {
  int part = -1;
  int side = kNoSide;
  bool pitch = false;
  bool roll = false;
};

// An axis letter or word: 'p' pitch, 'r' roll, 'w' yaw, 0 none. Letters glued to a part (hpy, shx) and lone
// letters are axes (x roll, y pitch, z yaw) or p / r.
char axisOf(const std::string& t) {
  if (t == "pitch" || t == "p" || t == "y" || t == "flex") return 'p';
  if (t == "roll" || t == "r" || t == "x") return 'r';
  if (t == "yaw" || t == "z") return 'w';
  return 0;
}

int sideWord(const std::string& t) {
  if (t == "l" || t == "left") return kLeft;
  if (t == "r" || t == "right") return kRight;
  return kNoSide;
}

// A part token: the word, or its two-letter abbreviation with or without one axis letter (hp, hpy, kn, kny,
// ak, aky, sh, shx, el, elx). -1 if none.
int partToken(const std::string& t, char& axis) {
  struct Word {
    const char* full;
    const char* shortForm;
  };
  static const Word kWords[] = {
      {"hip", "hp"}, {"knee", "kn"}, {"ankle", "ak"}, {"shoulder", "sh"}, {"elbow", "el"}};
  axis = 0;
  for (int part = 0; part < 5; ++part) {
    const std::string shortForm = kWords[part].shortForm;
    if (t == kWords[part].full || t == shortForm) return part;
    if (t.size() == 3 && t.compare(0, 2, shortForm) == 0 &&
        std::string("xyzpr").find(t[2]) != std::string::npos) {
      axis = axisOf(std::string(1, t[2]));
      return part;
    }
  }
  return -1;
}

NameInfo tokenInfo(const std::string& name) {
  NameInfo info;
  const std::vector<Token> tokens = tokenize(name);
  if (tokens.empty()) return info;
  const int count = static_cast<int>(tokens.size());
  int at = -1;
  char axis = 0;
  for (int i = 0; i < count && at < 0; ++i) {
    const int part = partToken(tokens[static_cast<std::size_t>(i)].text, axis);
    if (part >= 0) {
      at = i;
      info.part = part;
    }
  }
  if (at < 0) {
    // A short code in capitals leading the name: side, part letter, axis letter (LHP, LKP, LSR, LEP, RAR).
    const Token& t = tokens.front();
    static const std::string kLetters = "hkase";
    if (!t.caps || t.text.size() < 2 || t.text.size() > 3 || sideWord(t.text.substr(0, 1)) == kNoSide)
      return info;
    const std::size_t part = kLetters.find(t.text[1]);
    if (part == std::string::npos) return info;
    if (t.text.size() == 3 && std::string("pry").find(t.text[2]) == std::string::npos) return info;
    info.part = static_cast<int>(part);
    info.side = sideWord(t.text.substr(0, 1));
    const char a = t.text.size() == 3 ? t.text[2] : 0;  // a code's y is yaw
    info.pitch = a == 'p';
    info.roll = a == 'r';
    return info;
  }
  // The side: a leading token, "left" or "right" anywhere, l / r right before the part, or a trailing one.
  int sideAt = -1;
  if (at > 0 && sideWord(tokens.front().text) != kNoSide) {
    sideAt = 0;
  } else {
    for (int i = 0; i < count && sideAt < 0; ++i)
      if (i != at && (tokens[static_cast<std::size_t>(i)].text == "left" ||
                      tokens[static_cast<std::size_t>(i)].text == "right"))
        sideAt = i;
    if (sideAt < 0 && at > 0 && sideWord(tokens[static_cast<std::size_t>(at - 1)].text) != kNoSide)
      sideAt = at - 1;
    if (sideAt < 0 && count - 1 > at && sideWord(tokens.back().text) != kNoSide) sideAt = count - 1;
  }
  if (sideAt >= 0) info.side = sideWord(tokens[static_cast<std::size_t>(sideAt)].text);
  for (int i = at + 1; i < count; ++i)
    if (i != sideAt && axis == 0) axis = axisOf(tokens[static_cast<std::size_t>(i)].text);
  info.pitch = axis == 'p';
  info.roll = axis == 'r';
  return info;
}

// Whether joint name `name` names `part` on `side`. The plain words first, as before (findPart, sideOf); a
// name that says nothing that way is read as tokens.
bool namesPart(const std::string& name, int part, int side) {
  const std::string n = lower(name);
  bool plain = false;
  for (int p = 0; p < 5; ++p) {
    const std::size_t at = findPart(n, p);
    if (at == std::string::npos || sideOf(n, at) == kNoSide) continue;
    if (p == part && sideOf(n, at) == side) return true;
    plain = true;
  }
  if (plain) return false;
  const NameInfo info = tokenInfo(name);
  return info.part == part && info.side == side;
}

bool namesRoll(const std::string& name) {
  return saysRoll(lower(name)) || tokenInfo(name).roll;
}
bool namesPitch(const std::string& name) {
  return saysPitch(lower(name)) || tokenInfo(name).pitch;
}

// Links in the subtree under (and including) `link`, in link order (parents before children). Walked down the
// child joints, so that it costs the subtree's size (times its log for the sort), not the model's.
std::vector<int> subtree(const UrdfModel& m, int link) {
  std::vector<int> out{link};
  for (std::size_t k = 0; k < out.size(); ++k)
    for (int j : m.links()[static_cast<std::size_t>(out[k])].childJoints)
      out.push_back(m.joints()[static_cast<std::size_t>(j)].childLink);
  std::sort(out.begin(), out.end());
  return out;
}

// The mean of a hull's vertices, in its shape frame.
Eigen::Vector3d hullCentre(const ShapeDesc& shape) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : shape.hull) mean += v;
  return mean / static_cast<double>(shape.hull.size());
}

// Centroid of the link origins, shape centres and hull vertex centroids of `links`, in the URDF root frame
// (the skeleton's root is at the world origin with yaw 0, so undoing urdfToWorld is enough). A mesh's hull
// tells where a link is when its origin and its element's origin both sit on the joint (a foot).
Eigen::Vector3d centroid(const Skeleton& s, const std::vector<int>& links) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (int l : links) {
    const Eigen::Isometry3d& pose = s.linkPose(l);
    sum += pose.translation();
    ++count;
    for (const ShapeDesc& shape : s.shapes(l)) {
      sum += pose * shape.origin.translation();
      ++count;
      if (shape.hull.empty()) continue;
      sum += pose * (shape.origin * hullCentre(shape));
      ++count;
    }
  }
  return Skeleton::urdfToWorld().transpose() * (sum / count);
}

// Joint axis in the URDF root frame, at the skeleton's pose (its root at the world origin, yaw 0).
Eigen::Vector3d axisInRoot(const Skeleton& s, int joint) {
  const JointDesc& j = s.model().joints()[static_cast<std::size_t>(joint)];
  return Skeleton::urdfToWorld().transpose() * (s.linkPose(j.childLink).linear() * j.axis);
}

// A world point in the URDF root frame (the skeleton's root at the world origin, yaw 0).
Eigen::Vector3d pointInRoot(const Eigen::Vector3d& world) {
  return Skeleton::urdfToWorld().transpose() * world;
}

bool isRotary(const JointDesc& j) {
  return j.type == JointType::Revolute || j.type == JointType::Continuous;
}

// The arm beyond a joint, in the URDF root frame: from the joint's origin to the farthest link origin or
// shape centre beyond it (the hand or the wrist). Zero when nothing lies beyond.
Eigen::Vector3d armBeyond(const Skeleton& s, int joint) {
  const JointDesc& j = s.model().joints()[static_cast<std::size_t>(joint)];
  const Eigen::Vector3d origin = s.linkPose(j.childLink).translation();
  Eigen::Vector3d farthest = origin;
  double best = 0.0;
  for (int l : subtree(s.model(), j.childLink)) {
    const Eigen::Isometry3d& pose = s.linkPose(l);
    auto consider = [&](const Eigen::Vector3d& p) {
      const double d = (p - origin).squaredNorm();
      if (d > best) {
        best = d;
        farthest = p;
      }
    };
    consider(pose.translation());
    for (const ShapeDesc& shape : s.shapes(l)) consider(pose * shape.origin.translation());
  }
  return pointInRoot(farthest) - pointInRoot(origin);
}

// Angle (rad) between a direction and straight down (URDF -z).
double angleFromDown(const Eigen::Vector3d& v) {
  const double n = v.norm();
  return n > 0.0 ? std::acos(std::clamp(-v.z() / n, -1.0, 1.0)) : 0.0;
}

// v turned by `angle` about the unit axis a (Rodrigues).
Eigen::Vector3d turned(const Eigen::Vector3d& v, const Eigen::Vector3d& a, double angle) {
  return Eigen::AngleAxisd(angle, a) * v;
}

// Where a shoulder roll joint hangs its arm down, from the skeleton's pose (the rest pose).
struct ArmHold {
  bool ok = false;
  double neutral = 0.0;   ///< joint position that hangs the arm as near straight down as it can turn
  double sign = 1.0;      ///< +1 if a positive turn from there lifts the arm away from the body
  double residual = 0.0;  ///< rad from straight down that the joint's limits leave at the neutral
};

ArmHold armHold(const Skeleton& s, int joint, int side) {
  ArmHold h;
  const Eigen::Vector3d v = armBeyond(s, joint);
  if (v.norm() < 1e-6) return h;
  const Eigen::Vector3d a = axisInRoot(s, joint).normalized();
  // Turned by t about a: v(t) = v_par + cos t v_perp + sin t (a x v); its height is lowest at t below.
  const Eigen::Vector3d par = a * a.dot(v), perp = v - par, w = a.cross(v);
  if (std::hypot(perp.z(), w.z()) < 1e-9 * v.norm()) return h;  // the turn does not lower the arm
  const double t = std::atan2(-w.z(), -perp.z());
  const double q0 = s.jointPosition(joint);
  // The turn, or the same turn a full circle either way, whichever the limits keep closest.
  double neutral = q0 + t, gap = std::abs(s.clampToLimits(joint, neutral) - neutral);
  for (double k : {-2.0 * kPi, 2.0 * kPi}) {
    const double g = std::abs(s.clampToLimits(joint, q0 + t + k) - (q0 + t + k));
    if (g < gap) {
      gap = g;
      neutral = q0 + t + k;
    }
  }
  // Away from the body: the arm's end moving towards its own side (URDF +y for the left) as q grows.
  const double lateral = a.cross(turned(v, a, t)).y();
  h.ok = true;
  h.neutral = neutral;
  h.sign = (side == kLeft ? lateral : -lateral) >= 0.0 ? 1.0 : -1.0;
  h.residual = angleFromDown(turned(v, a, s.clampToLimits(joint, neutral) - q0));
  return h;
}

// The joints of one side's shoulder chain: revolute or continuous joints named like a shoulder on that side,
// and those between the first of them and that side's elbow.
std::vector<int> shoulderChain(const UrdfModel& m, int side) {
  const auto& joints = m.joints();
  std::vector<int> chain, elbows;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    if (!isRotary(joints[j])) continue;
    for (int part : {kShoulder, kElbow})
      if (namesPart(joints[j].name, part, side))
        (part == kShoulder ? chain : elbows).push_back(static_cast<int>(j));
  }
  if (chain.empty()) return chain;
  // The first shoulder joint: the one nearest the root (its parent link comes first in link order).
  const int top = *std::min_element(chain.begin(), chain.end(), [&](int a, int b) {
    return joints[static_cast<std::size_t>(a)].parentLink < joints[static_cast<std::size_t>(b)].parentLink;
  });
  std::vector<char> below(m.links().size(), 0), inChain(joints.size(), 0), walked(m.links().size(), 0);
  for (int l : subtree(m, joints[static_cast<std::size_t>(top)].childLink))
    below[static_cast<std::size_t>(l)] = 1;
  for (int j : chain) inChain[static_cast<std::size_t>(j)] = 1;
  for (int e : elbows) {
    // Walk up from the elbow to the top shoulder joint, collecting the joints on the way. A link walked from
    // an earlier elbow has had its way up collected already: each link is walked once.
    int link = joints[static_cast<std::size_t>(e)].parentLink;
    while (link >= 0 && below[static_cast<std::size_t>(link)] &&
           link != joints[static_cast<std::size_t>(top)].childLink &&
           !walked[static_cast<std::size_t>(link)]) {
      walked[static_cast<std::size_t>(link)] = 1;
      const int j = m.links()[static_cast<std::size_t>(link)].parentJoint;
      if (j < 0) break;
      if (isRotary(joints[static_cast<std::size_t>(j)]) && !inChain[static_cast<std::size_t>(j)]) {
        chain.push_back(j);
        inChain[static_cast<std::size_t>(j)] = 1;
      }
      link = m.links()[static_cast<std::size_t>(link)].parentLink;
    }
  }
  std::sort(chain.begin(), chain.end());
  return chain;
}

// The shoulder roll of one side: in its shoulder chain, the joint turning most nearly about the forward axis
// (URDF x; at least cos 45 degrees), one whose name says roll first. `exclude` is a joint taken already. -1
// if none.
int findShoulderRoll(const Skeleton& rest, int side, int exclude) {
  const auto& joints = rest.model().joints();
  int best = -1;
  bool bestNamed = false;
  double bestForward = 0.0;
  for (int j : shoulderChain(rest.model(), side)) {
    if (j == exclude) continue;
    const double forward = std::abs(axisInRoot(rest, j).x());
    if (forward < std::sqrt(0.5)) continue;
    const bool named = namesRoll(joints[static_cast<std::size_t>(j)].name);
    if (best < 0 || (named && !bestNamed) || (named == bestNamed && forward > bestForward + 1e-9)) {
      best = j;
      bestNamed = named;
      bestForward = forward;
    }
  }
  return best;
}

// Puts every mapped shoulder roll of `entries` at its neutral (clamped): the arms-down pose.
void holdArms(const std::array<JointMapping::Entry, kGaitRoleCount>& entries, Skeleton& s) {
  for (GaitRole role : {GaitRole::LeftShoulderRoll, GaitRole::RightShoulderRoll}) {
    const JointMapping::Entry& e = entries[static_cast<std::size_t>(role)];
    if (e.joint >= 0) (void)s.setJointPosition(e.joint, s.clampToLimits(e.joint, e.neutral));
  }
}

// --- Structure: the limbs from the kinematic tree and the rest pose ---

// A link's points in the URDF root frame: its origin, its shapes' centres, its hulls' vertex centroids.
void linkPoints(const Skeleton& s, int l, std::vector<Eigen::Vector3d>& out) {
  out.clear();
  const Eigen::Isometry3d& pose = s.linkPose(l);
  out.push_back(pointInRoot(pose.translation()));
  for (const ShapeDesc& shape : s.shapes(l)) {
    out.push_back(pointInRoot(pose * shape.origin.translation()));
    if (!shape.hull.empty()) out.push_back(pointInRoot(pose * (shape.origin * hullCentre(shape))));
  }
}

// A limb: its revolute and continuous joints from the body outwards, and its end link (a foot, a hand).
struct Limb {
  std::vector<int> joints;
  int end = -1;
  std::string from;  // the link it hangs from, for what is said
};
struct Limbs {
  std::array<Limb, 2> legs, arms;  // by side
  int pelvis = -1;                 // where the legs meet; -1 when no legs were found
};

// The lowest link that is `a` or an ancestor of it and `b` or an ancestor of it; -1 if none. Linear in depth.
int commonAncestor(const UrdfModel& m, int a, int b) {
  std::vector<char> up(m.links().size(), 0);
  for (int l = a; l >= 0; l = m.links()[static_cast<std::size_t>(l)].parentLink)
    up[static_cast<std::size_t>(l)] = 1;
  for (int l = b; l >= 0; l = m.links()[static_cast<std::size_t>(l)].parentLink)
    if (up[static_cast<std::size_t>(l)]) return l;
  return -1;
}

// The child of `top` on the way down to its descendant `bottom`.
int childToward(const UrdfModel& m, int top, int bottom) {
  int l = bottom;
  while (l >= 0 && m.links()[static_cast<std::size_t>(l)].parentLink != top)
    l = m.links()[static_cast<std::size_t>(l)].parentLink;
  return l;
}

// The rotary joints on the way down from `top` to its descendant `bottom`, top first.
std::vector<int> jointsDown(const UrdfModel& m, int top, int bottom) {
  std::vector<int> out;
  for (int l = bottom; l >= 0 && l != top; l = m.links()[static_cast<std::size_t>(l)].parentLink) {
    const int j = m.links()[static_cast<std::size_t>(l)].parentJoint;
    if (j >= 0 && isRotary(m.joints()[static_cast<std::size_t>(j)])) out.push_back(j);
  }
  std::reverse(out.begin(), out.end());
  return out;
}

// Legs: the lowest link on each side (centre more than 2% of the height off the midline, its lowest point
// within 10% of the height of the model's lowest), up to where the two meet (the pelvis), which must be no
// higher than three quarters of the height. Arms: among the links of neither leg, those whose centres lie
// farthest to the left and to the right, up to where the two meet (the chest), and down to the link beyond
// farthest from the arm's first link (the hand). With three or more branches at the chest, the one reaching
// highest is the head: it is no arm.
Limbs findLimbs(const Skeleton& rest) {
  const UrdfModel& m = rest.model();
  const int n = rest.linkCount();
  Limbs out;
  std::vector<Eigen::Vector3d> centre(static_cast<std::size_t>(n)), points;
  std::vector<double> low(static_cast<std::size_t>(n)), high(static_cast<std::size_t>(n));
  double zMin = 0.0, zMax = 0.0;
  for (int l = 0; l < n; ++l) {
    linkPoints(rest, l, points);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double lo = points.front().z(), hi = lo;
    for (const Eigen::Vector3d& p : points) {
      sum += p;
      lo = std::min(lo, p.z());
      hi = std::max(hi, p.z());
    }
    const auto k = static_cast<std::size_t>(l);
    centre[k] = sum / static_cast<double>(points.size());
    low[k] = lo;
    high[k] = hi;
    zMin = l == 0 ? lo : std::min(zMin, lo);
    zMax = l == 0 ? hi : std::max(zMax, hi);
  }
  const double height = zMax - zMin;
  if (!(height > 1e-6)) return out;
  auto sideOffset = [&](int l, int side) {
    return side == kLeft ? centre[static_cast<std::size_t>(l)].y() : -centre[static_cast<std::size_t>(l)].y();
  };
  auto z = [&](int l) { return pointInRoot(rest.linkPose(l).translation()).z(); };
  auto name = [&](int l) { return m.links()[static_cast<std::size_t>(l)].name; };

  // Legs.
  std::vector<char> taken(static_cast<std::size_t>(n), 0);
  std::array<int, 2> foot{-1, -1};
  for (int l = 0; l < n; ++l)
    for (int side = kLeft; side <= kRight; ++side) {
      int& f = foot[static_cast<std::size_t>(side)];
      if (sideOffset(l, side) > 0.02 * height &&
          (f < 0 || low[static_cast<std::size_t>(l)] < low[static_cast<std::size_t>(f)] - 1e-9))
        f = l;
    }
  if (foot[0] >= 0 && foot[1] >= 0 &&
      std::max(low[static_cast<std::size_t>(foot[0])], low[static_cast<std::size_t>(foot[1])]) <=
          zMin + 0.1 * height) {
    const int pelvis = commonAncestor(m, foot[0], foot[1]);
    bool ok = pelvis >= 0 && pelvis != foot[0] && pelvis != foot[1];
    std::array<Limb, 2> legs;
    for (int side = kLeft; side <= kRight && ok; ++side) {
      const int f = foot[static_cast<std::size_t>(side)];
      const int top = childToward(m, pelvis, f);
      Limb& leg = legs[static_cast<std::size_t>(side)];
      leg.joints = jointsDown(m, pelvis, f);
      leg.end = f;
      leg.from = name(pelvis);
      ok = !leg.joints.empty() && z(top) - zMin <= 0.75 * height;
      for (int l : subtree(m, top)) taken[static_cast<std::size_t>(l)] = 1;
    }
    if (ok) {
      out.legs = legs;
      out.pelvis = pelvis;
    } else {
      std::fill(taken.begin(), taken.end(), 0);
    }
  }

  // Arms.
  auto extremes = [&]() {
    std::array<int, 2> e{-1, -1};
    for (int l = 0; l < n; ++l) {
      if (taken[static_cast<std::size_t>(l)]) continue;
      for (int side = kLeft; side <= kRight; ++side) {
        int& x = e[static_cast<std::size_t>(side)];
        if (sideOffset(l, side) > 0.02 * height &&
            (x < 0 || sideOffset(l, side) > sideOffset(x, side) + 1e-9))
          x = l;
      }
    }
    return e;
  };
  std::array<int, 2> hand = extremes();
  if (hand[0] < 0 || hand[1] < 0) return out;
  int chest = commonAncestor(m, hand[0], hand[1]);
  if (chest < 0) return out;
  std::vector<int> branches;
  for (int j : m.links()[static_cast<std::size_t>(chest)].childJoints) {
    const int c = m.joints()[static_cast<std::size_t>(j)].childLink;
    if (!taken[static_cast<std::size_t>(c)]) branches.push_back(c);
  }
  if (branches.size() >= 3) {
    int head = -1;
    double top = 0.0;
    for (int b : branches) {
      double reach = high[static_cast<std::size_t>(b)];
      for (int l : subtree(m, b)) reach = std::max(reach, high[static_cast<std::size_t>(l)]);
      if (head < 0 || reach > top) {
        head = b;
        top = reach;
      }
    }
    const std::vector<int> headLinks = subtree(m, head);
    auto inHead = [&](int l) { return std::find(headLinks.begin(), headLinks.end(), l) != headLinks.end(); };
    if (inHead(hand[0]) || inHead(hand[1])) {
      for (int l : headLinks) taken[static_cast<std::size_t>(l)] = 1;
      hand = extremes();
      if (hand[0] < 0 || hand[1] < 0) return out;
      chest = commonAncestor(m, hand[0], hand[1]);
    }
  }
  if (chest < 0 || chest == hand[0] || chest == hand[1]) return out;
  std::array<Limb, 2> arms;
  for (int side = kLeft; side <= kRight; ++side) {
    const int top = childToward(m, chest, hand[static_cast<std::size_t>(side)]);
    // The hand: the link beyond the arm's first one farthest from it.
    const Eigen::Vector3d start = pointInRoot(rest.linkPose(top).translation());
    int end = top;
    for (int l : subtree(m, top))
      if ((centre[static_cast<std::size_t>(l)] - start).norm() >
          (centre[static_cast<std::size_t>(end)] - start).norm() + 1e-9)
        end = l;
    Limb& arm = arms[static_cast<std::size_t>(side)];
    arm.joints = jointsDown(m, chest, end);
    arm.end = end;
    arm.from = name(chest);
    // An arm leaves the upper body: above the pelvis, when there are legs.
    if (arm.joints.empty() || (out.pelvis >= 0 && z(top) <= z(out.pelvis))) return out;
  }
  out.arms = arms;
  return out;
}

// The shoulder roll of one side's arm by structure: among the arm's first three joints, those with a forward
// axis (URDF x, at least cos 45 degrees), the one that hangs the arm nearest straight down (the first of
// those within 0.05 rad of the best). -1 if none.
int rollByStructure(const Skeleton& rest, const std::vector<int>& arm, int side) {
  int best = -1;
  double bestResidual = 0.0;
  for (std::size_t k = 0; k < arm.size() && k < 3; ++k) {
    const int j = arm[k];
    if (std::abs(axisInRoot(rest, j).x()) < std::sqrt(0.5)) continue;
    const ArmHold h = armHold(rest, j, side);
    if (!h.ok) continue;
    if (best < 0 || h.residual < bestResidual - 0.05) {
      best = j;
      bestResidual = h.residual;
    }
  }
  return best;
}

// Joint origin in the URDF root frame (the skeleton's root at the world origin, yaw 0).
Eigen::Vector3d jointOrigin(const Skeleton& s, int joint) {
  return pointInRoot(s.linkPose(s.model().joints()[static_cast<std::size_t>(joint)].childLink).translation());
}

// The farthest point beyond a joint (link origins, shape centres, hull centroids of its subtree): its link
// and where it lies in that link's frame. For telling a bend from a stretch.
std::pair<int, Eigen::Vector3d> farthestBeyond(const Skeleton& s, int joint) {
  const JointDesc& j = s.model().joints()[static_cast<std::size_t>(joint)];
  const Eigen::Vector3d origin = jointOrigin(s, joint);
  std::pair<int, Eigen::Vector3d> best{j.childLink, Eigen::Vector3d::Zero()};
  double far = 0.0;
  std::vector<Eigen::Vector3d> points;
  for (int l : subtree(s.model(), j.childLink)) {
    linkPoints(s, l, points);
    const Eigen::Isometry3d toLink = s.linkPose(l).inverse();
    for (const Eigen::Vector3d& p : points) {
      const double d = (p - origin).norm();
      if (d > far) {
        far = d;
        best = {l, toLink * (Skeleton::urdfToWorld() * p)};
      }
    }
  }
  return best;
}

// +1 if turning `joint` from q- to q+ brings the farthest point beyond it nearer the first link origin above
// it at least 2 cm away (a bend), -1 if farther, 0 if neither clearly (less than 0.3 of the point's motion).
// `pose(joint, q)` puts the skeleton in the probing pose with the joint at q.
template <class Pose>
double bendSign(const UrdfModelPtr& model, int joint, double qPlus, double qMinus, Pose& pose, Skeleton& s) {
  const JointDesc& j = model->joints()[static_cast<std::size_t>(joint)];
  pose(joint, s.restPosition(joint));
  const Eigen::Vector3d at = jointOrigin(s, joint);
  int above = j.parentLink;
  while (above >= 0 && (pointInRoot(s.linkPose(above).translation()) - at).norm() < 0.02)
    above = model->links()[static_cast<std::size_t>(above)].parentLink;
  if (above < 0) return 0.0;
  // Plain variables, not structured bindings: a lambda may capture those only from C++20 (clang 14 refuses).
  const std::pair<int, Eigen::Vector3d> farthest = farthestBeyond(s, joint);
  const int link = farthest.first;
  const Eigen::Vector3d local = farthest.second;
  auto place = [&](double q, Eigen::Vector3d& end, Eigen::Vector3d& top) {
    pose(joint, q);
    end = pointInRoot(s.linkPose(link) * local);
    top = pointInRoot(s.linkPose(above).translation());
  };
  Eigen::Vector3d endPlus, topPlus, endMinus, topMinus;
  place(qPlus, endPlus, topPlus);
  place(qMinus, endMinus, topMinus);
  const double change = (endPlus - topPlus).norm() - (endMinus - topMinus).norm();
  const double motion = (endPlus - endMinus).norm();
  if (motion < 1e-9 || std::abs(change) < 0.3 * motion) return 0.0;
  return change < 0.0 ? 1.0 : -1.0;
}

}  // namespace

std::array<std::string, kGaitRoleCount> JointMapping::shippedHumanoidNames() {
  return {
      "left_hip_pitch",      "right_hip_pitch",      "left_knee",  "right_knee",  "left_ankle", "right_ankle",
      "left_shoulder_pitch", "right_shoulder_pitch", "left_elbow", "right_elbow", "",           ""};
}

JointMapping JointMapping::fromNames(const UrdfModelPtr& model,
                                     const std::array<std::string, kGaitRoleCount>& names) {
  JointMapping m;
  for (int r = 0; r < kGaitRoleCount; ++r) {
    const std::string& name = names[static_cast<std::size_t>(r)];
    if (name.empty()) continue;
    const int j = model->findJoint(name);
    if (j < 0) {
      m.warnings_.push_back(std::string(toString(static_cast<GaitRole>(r))) + ": no joint named '" + name +
                            "'");
      continue;
    }
    if (!isRotary(model->joints()[static_cast<std::size_t>(j)])) {
      m.warnings_.push_back(std::string(toString(static_cast<GaitRole>(r))) + ": joint '" + name +
                            "' is not revolute or continuous");
      continue;
    }
    m.entries_[static_cast<std::size_t>(r)].joint = j;
  }
  m.finish(model);
  return m;
}

JointMapping JointMapping::byCommonNames(const UrdfModelPtr& model) {
  return build(model, true, false);
}

JointMapping JointMapping::byStructure(const UrdfModelPtr& model) {
  return build(model, false, true);
}

JointMapping JointMapping::build(const UrdfModelPtr& model, bool byName, bool byTree) {
  JointMapping m;
  const Skeleton rest(model);
  const auto& joints = model->joints();
  const Limbs limbs = byTree ? findLimbs(rest) : Limbs();
  std::array<std::string, kGaitRoleCount> byStructureSaid{}, noCandidate{};
  auto entry = [&](int part, int side) -> Entry& {
    return m.entries_[static_cast<std::size_t>(roleOf(part, side))];
  };
  auto used = [&](int j) {
    return std::any_of(m.entries_.begin(), m.entries_.end(), [&](const Entry& e) { return e.joint == j; });
  };
  auto limbName = [&](const Limb& limb, bool leg, int side) {
    return std::string(side == kLeft ? "left " : "right ") + (leg ? "leg" : "arm") + " '" + limb.from +
           "' to '" + model->links()[static_cast<std::size_t>(limb.end)].name + "': ";
  };

  // Shoulder rolls first, and their arms-down pose, in which the other joints are chosen.
  for (int side = kLeft; side <= kRight; ++side) {
    Entry& e = entry(kRollPart, side);
    if (byName) e.joint = findShoulderRoll(rest, side, -1);
    const Limb& arm = limbs.arms[static_cast<std::size_t>(side)];
    if (e.joint < 0 && arm.end >= 0) {
      e.joint = rollByStructure(rest, arm.joints, side);
      if (e.joint >= 0)
        byStructureSaid[static_cast<std::size_t>(roleOf(kRollPart, side))] =
            limbName(arm, false, side) +
            "the joint among its first three with a forward axis that hangs it nearest straight down";
    }
    if (e.joint >= 0) e.neutral = armHold(rest, e.joint, side).neutral;
  }
  Skeleton held(model);
  holdArms(m.entries_, held);

  if (byName) {
    for (int part = 0; part < 5; ++part) {
      for (int side = kLeft; side <= kRight; ++side) {
        const auto role = roleOf(part, side);
        int best = -1;
        double bestLateral = -1.0;
        bool bestPitch = false;
        std::string candidates;
        for (std::size_t j = 0; j < joints.size(); ++j) {
          if (!isRotary(joints[j])) continue;
          const int ji = static_cast<int>(j);
          if (ji == m[GaitRole::LeftShoulderRoll].joint || ji == m[GaitRole::RightShoulderRoll].joint)
            continue;
          if (!namesPart(joints[j].name, part, side)) continue;
          // Side to side is URDF y. Several joints for one part (roll, pitch, yaw): take the pitch-like one.
          const double lateral = std::abs(axisInRoot(held, ji).y());
          const bool pitch = namesPitch(joints[j].name);
          candidates += (candidates.empty() ? "" : ", ") + joints[j].name;
          if (lateral > bestLateral + 1e-6 || (lateral > bestLateral - 1e-6 && pitch && !bestPitch)) {
            bestLateral = lateral;
            bestPitch = pitch;
            best = ji;
          }
        }
        if (best >= 0 && bestLateral < 0.5) {
          noCandidate[static_cast<std::size_t>(role)] = std::string(toString(role)) +
                                                        ": no candidate turns about the side-to-side axis (" +
                                                        candidates + ")";
          best = -1;
        }
        m.entries_[static_cast<std::size_t>(role)].joint = best;
      }
    }
  }

  // Structure fills what the names left: in each limb, role after role from the body outwards, the next
  // side-to-side joint beyond the previous role's joint (and before the next role's, if that one is mapped).
  auto lateral = [&](int j) { return std::abs(axisInRoot(held, j).y()) > 0.7; };
  auto fill = [&](const Limb& limb, const std::vector<int>& parts, int side, bool leg) {
    const std::vector<int>& chain = limb.joints;
    const int size = static_cast<int>(chain.size());
    auto posOf = [&](int j) {
      const auto it = std::find(chain.begin(), chain.end(), j);
      return it == chain.end() ? -1 : static_cast<int>(it - chain.begin());
    };
    int from = 0;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      Entry& e = entry(parts[i], side);
      if (e.joint >= 0) {
        if (posOf(e.joint) >= 0) from = posOf(e.joint) + 1;
        continue;
      }
      int to = size;
      for (std::size_t k = i + 1; k < parts.size(); ++k) {
        const int p = posOf(entry(parts[k], side).joint);
        if (p >= 0) {
          to = p;
          break;
        }
      }
      std::string how;
      for (int k = from; k < to && e.joint < 0; ++k) {
        if (used(chain[static_cast<std::size_t>(k)]) || !lateral(chain[static_cast<std::size_t>(k)]))
          continue;
        e.joint = chain[static_cast<std::size_t>(k)];
        from = k + 1;
        static const char* const kWhich[] = {
            "its first side-to-side joint", "the next side-to-side joint beyond the hip",
            "the next side-to-side joint beyond the knee", "its first side-to-side joint, arms down",
            "the next side-to-side joint beyond the shoulder"};
        how = limbName(limb, leg, side) + kWhich[parts[i]];
      }
      if (e.joint < 0 && parts[i] == kElbow) {
        // A bent or T-pose arm: the first joint beyond the shoulder, away from it, that turns across the
        // upper arm (the way in from the last joint before it elsewhere) and across what it moves.
        const int shoulder = entry(kShoulder, side).joint;
        const Eigen::Vector3d top = jointOrigin(held, shoulder >= 0 ? shoulder : chain.front());
        const double length = (pointInRoot(held.linkPose(limb.end).translation()) - top).norm();
        for (int k = from; k < to && e.joint < 0 && length > 1e-6; ++k) {
          const int j = chain[static_cast<std::size_t>(k)];
          if (used(j)) continue;
          // The cheap tests first: what lies beyond a joint costs its subtree.
          const Eigen::Vector3d at = jointOrigin(held, j);
          if ((at - top).norm() < 0.2 * length) continue;
          Eigen::Vector3d in = Eigen::Vector3d::Zero();
          for (int b = k - 1; b >= 0 && in.norm() < 0.01; --b)
            in = at - jointOrigin(held, chain[static_cast<std::size_t>(b)]);
          const Eigen::Vector3d axis = axisInRoot(held, j).normalized();
          if (in.norm() < 0.01 || std::abs(axis.dot(in.normalized())) > 0.5) continue;
          const Eigen::Vector3d out = armBeyond(held, j);
          if (out.norm() < 0.2 * length || std::abs(axis.dot(out.normalized())) > 0.5) continue;
          e.joint = j;
          from = k + 1;
          how = limbName(limb, leg, side) +
                "the first joint beyond the shoulder turning across the upper arm and the forearm";
        }
      }
      if (e.joint >= 0) byStructureSaid[static_cast<std::size_t>(roleOf(parts[i], side))] = how;
    }
  };
  for (int side = kLeft; side <= kRight; ++side) {
    if (limbs.legs[static_cast<std::size_t>(side)].end >= 0)
      fill(limbs.legs[static_cast<std::size_t>(side)], {0, 1, 2}, side, true);
    if (limbs.arms[static_cast<std::size_t>(side)].end >= 0)
      fill(limbs.arms[static_cast<std::size_t>(side)], {kShoulder, kElbow}, side, false);
  }

  for (int r = 0; r < kGaitRoleCount; ++r) {
    const auto k = static_cast<std::size_t>(r);
    if (!noCandidate[k].empty() && m.entries_[k].joint < 0) m.warnings_.push_back(noCandidate[k]);
  }
  for (int r = 0; r < kGaitRoleCount; ++r) {
    const auto k = static_cast<std::size_t>(r);
    if (byStructureSaid[k].empty() || m.entries_[k].joint < 0) continue;
    m.warnings_.push_back(std::string(toString(static_cast<GaitRole>(r))) + ": joint '" +
                          joints[static_cast<std::size_t>(m.entries_[k].joint)].name + "' (by structure, " +
                          byStructureSaid[k] + ")");
  }
  m.finish(model);
  return m;
}

JointMapping JointMapping::automatic(const UrdfModelPtr& model) {
  auto names = shippedHumanoidNames();
  const bool all = std::all_of(names.begin(), names.end(),
                               [&](const std::string& n) { return n.empty() || model->findJoint(n) >= 0; });
  if (!all) return build(model, true, true);
  const Skeleton rest(model);
  for (int side = kLeft; side <= kRight; ++side) {
    const int shoulder = model->findJoint(names[static_cast<std::size_t>(roleOf(kShoulder, side))]);
    const int roll = findShoulderRoll(rest, side, shoulder);
    if (roll >= 0)
      names[static_cast<std::size_t>(roleOf(kRollPart, side))] =
          model->joints()[static_cast<std::size_t>(roll)].name;
  }
  return fromNames(model, names);
}

void JointMapping::finish(const UrdfModelPtr& model) {
  Skeleton probe(model);
  // Shoulder rolls: where each hangs its arm down (from the rest pose), and which way lifts it out.
  for (int side = kLeft; side <= kRight; ++side) {
    const auto role = roleOf(kRollPart, side);
    Entry& e = entries_[static_cast<std::size_t>(role)];
    if (e.joint < 0) continue;
    const JointDesc& j = model->joints()[static_cast<std::size_t>(e.joint)];
    const ArmHold hold = armHold(probe, e.joint, side);
    if (!hold.ok) {
      warnings_.push_back(std::string(toString(role)) + ": joint '" + j.name +
                          "' does not lower the arm (nothing beyond it, or it turns about the vertical)" +
                          "; it stays at rest");
      e.joint = -1;
      continue;
    }
    e.neutral = hold.neutral;
    e.sign = hold.sign;
    if (hold.residual > kArmDownTolerance) {
      std::ostringstream msg;
      msg << toString(role) << ": the limits of joint '" << j.name << "' keep the arm "
          << std::setprecision(2) << hold.residual << " rad from hanging straight down";
      warnings_.push_back(msg.str());
    }
  }
  // The other roles are signed in the arms-down pose.
  auto pose = [&](int joint, double q) {
    probe.resetJointPositions();
    holdArms(entries_, probe);
    if (joint >= 0) (void)probe.setJointPosition(joint, q);
  };
  for (int r = 0; r < kGaitRoleCount; ++r) {
    Entry& e = entries_[static_cast<std::size_t>(r)];
    const auto role = static_cast<GaitRole>(r);
    if (isShoulderRoll(role)) continue;
    if (e.joint < 0) {
      warnings_.push_back(std::string(toString(role)) +
                          ": no joint found; the gait leaves that limb at rest");
      continue;
    }
    const JointDesc& j = model->joints()[static_cast<std::size_t>(e.joint)];
    const std::vector<int> moved = subtree(*model, j.childLink);
    // Turn 0.05 rad either side of rest (inside the limits) and see which way the links beyond move.
    const double rest = probe.restPosition(e.joint);
    const double qPlus = probe.clampToLimits(e.joint, rest + 0.05);
    const double qMinus = probe.clampToLimits(e.joint, rest - 0.05);
    pose(e.joint, qPlus);
    const Eigen::Vector3d cPlus = centroid(probe, moved);
    pose(e.joint, qMinus);
    const Eigen::Vector3d d = centroid(probe, moved) - cPlus;  // motion from q+ to q-: the negative direction
    if (qPlus <= qMinus || d.norm() < 1e-9 || std::abs(d.x()) < 0.3 * d.norm()) {
      // A knee or an elbow bends: the way that brings the limb's end nearer the link above the joint (a bent
      // arm), else the way its limits let it turn (one way only: an arm bending sideways).
      const bool bends = role == GaitRole::LeftKnee || role == GaitRole::RightKnee ||
                         role == GaitRole::LeftElbow || role == GaitRole::RightElbow;
      double sign = 0.0;
      if (bends && qPlus > qMinus) sign = bendSign(model, e.joint, qPlus, qMinus, pose, probe);
      if (bends && sign == 0.0 && j.hasLimits) {
        const double up = j.upper - rest, down = rest - j.lower;
        if (std::max(up, down) > 0.5 && std::min(up, down) < 0.25 * std::max(up, down)) {
          sign = up > down ? 1.0 : -1.0;
          warnings_.push_back(
              std::string(toString(role)) + ": joint '" + j.name +
              "' moves its links neither forward nor backward; signed by its limits (it turns " +
              (sign > 0.0 ? "positive" : "negative") + " from rest)");
        }
      }
      if (sign == 0.0) {
        warnings_.push_back(std::string(toString(role)) + ": cannot tell which way joint '" + j.name +
                            "' turns (its links do not move forward or backward); assuming positive");
        sign = 1.0;
      }
      e.sign = sign;
      continue;
    }
    const double forwardPerPositive = d.x() < 0.0 ? 1.0 : -1.0;  // d is the motion for decreasing q
    e.sign = forwardPerPositive * wantedForwardMotion(role);
  }
  // An arm that does not hang down and has no roll joint to lower it stays where the URDF puts it: say so.
  pose(-1, 0.0);
  for (int side = kLeft; side <= kRight; ++side) {
    const Entry& shoulder = entries_[static_cast<std::size_t>(roleOf(kShoulder, side))];
    if (entries_[static_cast<std::size_t>(roleOf(kRollPart, side))].joint >= 0 || shoulder.joint < 0)
      continue;
    const double off = angleFromDown(armBeyond(probe, shoulder.joint));
    if (off > kArmDownTolerance) {
      std::ostringstream msg;
      msg << (side == kLeft ? "left" : "right") << " arm: " << std::setprecision(2) << off
          << " rad from hanging straight down at rest, and no shoulder roll joint was found to lower it";
      warnings_.push_back(msg.str());
    }
  }
}

std::vector<GaitRole> JointMapping::unmappedRoles() const {
  std::vector<GaitRole> out;
  for (int r = 0; r < kGaitRoleCount; ++r) {
    if (entries_[static_cast<std::size_t>(r)].joint < 0) out.push_back(static_cast<GaitRole>(r));
  }
  return out;
}

}  // namespace cape::character
