// Finding the gait's joints in a URDF, by name, and their turning sense, by forward kinematics.
#include "cape/character/JointMapping.h"

#include "cape/character/Skeleton.h"

#include <algorithm>
#include <cctype>
#include <cmath>

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
  }
  return "unknown role";
}

namespace {

// Roles come in left/right pairs: role = 2 * part + side.
constexpr const char* kParts[] = {"hip", "knee", "ankle", "shoulder", "elbow"};
constexpr int kLeft = 0, kRight = 1, kNoSide = -1;

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

// Joint axis in the URDF root frame at rest.
Eigen::Vector3d axisInRoot(const Skeleton& s, int joint) {
  const JointDesc& j = s.model().joints()[static_cast<std::size_t>(joint)];
  return Skeleton::urdfToWorld().transpose() * (s.linkPose(j.childLink).linear() * j.axis);
}

bool isRotary(const JointDesc& j) {
  return j.type == JointType::Revolute || j.type == JointType::Continuous;
}

}  // namespace

std::array<std::string, kGaitRoleCount> JointMapping::shippedHumanoidNames() {
  return {"left_hip_pitch", "right_hip_pitch", "left_knee",           "right_knee",
          "left_ankle",     "right_ankle",     "left_shoulder_pitch", "right_shoulder_pitch",
          "left_elbow",     "right_elbow"};
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
  for (int part = 0; part < 5; ++part) {
    for (int side = kLeft; side <= kRight; ++side) {
      const auto role = static_cast<GaitRole>(2 * part + side);
      int best = -1;
      double bestLateral = -1.0;
      std::string candidates;
      for (std::size_t j = 0; j < joints.size(); ++j) {
        if (!isRotary(joints[j])) continue;
        const std::string n = lower(joints[j].name);
        const std::size_t at = n.find(kParts[part]);
        if (at == std::string::npos || sideOf(n, at) != side) continue;
        // Side to side is URDF y. Several joints for one part (roll, pitch, yaw): take the pitch-like one.
        const double lateral = std::abs(axisInRoot(rest, static_cast<int>(j)).y());
        candidates += (candidates.empty() ? "" : ", ") + joints[j].name;
        if (lateral > bestLateral) {
          bestLateral = lateral;
          best = static_cast<int>(j);
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
  const auto names = shippedHumanoidNames();
  const bool all =
      std::all_of(names.begin(), names.end(), [&](const std::string& n) { return model->findJoint(n) >= 0; });
  return all ? fromNames(model, names) : byCommonNames(model);
}

void JointMapping::finish(const UrdfModelPtr& model) {
  Skeleton probe(model);
  for (int r = 0; r < kGaitRoleCount; ++r) {
    Entry& e = entries_[static_cast<std::size_t>(r)];
    const auto role = static_cast<GaitRole>(r);
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
    probe.resetJointPositions();
    (void)probe.setJointPosition(e.joint, qPlus);
    const Eigen::Vector3d cPlus = centroid(probe, moved);
    (void)probe.setJointPosition(e.joint, qMinus);
    const Eigen::Vector3d d = centroid(probe, moved) - cPlus;  // motion from q+ to q-: the negative direction
    probe.resetJointPositions();
    if (qPlus <= qMinus || d.norm() < 1e-9 || std::abs(d.x()) < 0.3 * d.norm()) {
      warnings_.push_back(std::string(toString(role)) + ": cannot tell which way joint '" + j.name +
                          "' turns (its links do not move forward or backward); assuming positive");
      e.sign = 1.0;
      continue;
    }
    const double forwardPerPositive = d.x() < 0.0 ? 1.0 : -1.0;  // d is the motion for decreasing q
    e.sign = forwardPerPositive * wantedForwardMotion(role);
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
