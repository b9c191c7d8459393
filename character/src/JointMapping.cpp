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

// Links in the subtree under (and including) `link`.
std::vector<int> subtree(const UrdfModel& m, int link) {
  std::vector<char> in(m.links().size(), 0);
  in[static_cast<std::size_t>(link)] = 1;
  std::vector<int> out{link};
  for (std::size_t l = static_cast<std::size_t>(link) + 1; l < m.links().size(); ++l) {
    const int p = m.links()[l].parentLink;
    if (p >= 0 && in[static_cast<std::size_t>(p)]) {
      in[l] = 1;
      out.push_back(static_cast<int>(l));
    }
  }
  return out;
}

// Centroid of the link origins and shape centres of `links`, in the URDF root frame (the skeleton's root is
// at the world origin with yaw 0, so undoing urdfToWorld is enough).
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
    const std::string n = lower(joints[j].name);
    for (int part : {kShoulder, kElbow}) {
      const std::size_t at = findPart(n, part);
      if (at != std::string::npos && sideOf(n, at) == side)
        (part == kShoulder ? chain : elbows).push_back(static_cast<int>(j));
    }
  }
  if (chain.empty()) return chain;
  // The first shoulder joint: the one nearest the root (its parent link comes first in link order).
  const int top = *std::min_element(chain.begin(), chain.end(), [&](int a, int b) {
    return joints[static_cast<std::size_t>(a)].parentLink < joints[static_cast<std::size_t>(b)].parentLink;
  });
  const std::vector<int> below = subtree(m, joints[static_cast<std::size_t>(top)].childLink);
  auto inBelow = [&](int link) { return std::find(below.begin(), below.end(), link) != below.end(); };
  for (int e : elbows) {
    // Walk up from the elbow to the top shoulder joint, collecting the joints on the way.
    int link = joints[static_cast<std::size_t>(e)].parentLink;
    while (link >= 0 && inBelow(link) && link != joints[static_cast<std::size_t>(top)].childLink) {
      const int j = m.links()[static_cast<std::size_t>(link)].parentJoint;
      if (j < 0) break;
      if (isRotary(joints[static_cast<std::size_t>(j)]) &&
          std::find(chain.begin(), chain.end(), j) == chain.end())
        chain.push_back(j);
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
    const bool named = saysRoll(lower(joints[static_cast<std::size_t>(j)].name));
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
  JointMapping m;
  const Skeleton rest(model);
  const auto& joints = model->joints();
  // Shoulder rolls first, and their arms-down pose, in which the other joints are chosen.
  for (int side = kLeft; side <= kRight; ++side) {
    Entry& e = m.entries_[static_cast<std::size_t>(roleOf(kRollPart, side))];
    e.joint = findShoulderRoll(rest, side, -1);
    if (e.joint >= 0) e.neutral = armHold(rest, e.joint, side).neutral;
  }
  Skeleton held(model);
  holdArms(m.entries_, held);
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
        if (ji == m[GaitRole::LeftShoulderRoll].joint || ji == m[GaitRole::RightShoulderRoll].joint) continue;
        const std::string n = lower(joints[j].name);
        const std::size_t at = findPart(n, part);
        if (at == std::string::npos || sideOf(n, at) != side) continue;
        // Side to side is URDF y. Several joints for one part (roll, pitch, yaw): take the pitch-like one.
        const double lateral = std::abs(axisInRoot(held, ji).y());
        const bool pitch = saysPitch(n);
        candidates += (candidates.empty() ? "" : ", ") + joints[j].name;
        if (lateral > bestLateral + 1e-6 || (lateral > bestLateral - 1e-6 && pitch && !bestPitch)) {
          bestLateral = lateral;
          bestPitch = pitch;
          best = ji;
        }
      }
      if (best >= 0 && bestLateral < 0.5) {
        m.warnings_.push_back(std::string(toString(role)) +
                              ": no candidate turns about the side-to-side axis (" + candidates + ")");
        best = -1;
      }
      m.entries_[static_cast<std::size_t>(role)].joint = best;
    }
  }
  m.finish(model);
  return m;
}

JointMapping JointMapping::automatic(const UrdfModelPtr& model) {
  auto names = shippedHumanoidNames();
  const bool all = std::all_of(names.begin(), names.end(),
                               [&](const std::string& n) { return n.empty() || model->findJoint(n) >= 0; });
  if (!all) return byCommonNames(model);
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
      warnings_.push_back(std::string(toString(role)) + ": no joint found; it stays at rest");
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
      warnings_.push_back(std::string(toString(role)) + ": cannot tell which way joint '" + j.name +
                          "' turns (its links do not move forward or backward); assuming positive");
      e.sign = 1.0;
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
