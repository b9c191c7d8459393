// Finding where a cape hangs: shoulders from the joint mapping, the back from the collision shapes.
#include "cape/character/Anchors.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

namespace cape::character {

namespace {

struct Frame {
  Eigen::Matrix3d toScene;  // world -> Y-up scene directions
  Eigen::Vector3d local(const Eigen::Vector3d& world) const { return toScene * world; }
};

Frame characterFrame(const Skeleton& skeleton) {
  return Frame{Skeleton::sceneToWorld(skeleton.upAxis()).transpose()};
}

// The nearest link from `link` towards the root that has a body; -1 if none.
int withBody(const Character& c, int link) {
  const UrdfModel& m = c.skeleton().model();
  while (link >= 0 && c.bodies().bodyForLink(link) == nullptr)
    link = m.links()[static_cast<std::size_t>(link)].parentLink;
  return link;
}

// The nearest common ancestor of two links (a link is its own ancestor).
int commonAncestor(const UrdfModel& m, int a, int b) {
  std::vector<char> up(m.links().size(), 0);  // a and its ancestors: linear in depth
  for (int l = a; l >= 0; l = m.links()[static_cast<std::size_t>(l)].parentLink)
    up[static_cast<std::size_t>(l)] = 1;
  for (int l = b; l >= 0; l = m.links()[static_cast<std::size_t>(l)].parentLink)
    if (up[static_cast<std::size_t>(l)]) return l;
  return 0;
}

// From a shoulder joint up the arm chain: while the joint's parent link hangs by a movable joint and has no
// other child joint, that joint is part of the same shoulder (a ball joint split into revolute ones).
int chainStart(const UrdfModel& m, int joint) {
  for (;;) {
    const LinkDesc& parent =
        m.links()[static_cast<std::size_t>(m.joints()[static_cast<std::size_t>(joint)].parentLink)];
    if (parent.parentJoint < 0 || parent.childJoints.size() != 1) return joint;
    if (!m.joints()[static_cast<std::size_t>(parent.parentJoint)].isMovable()) return joint;
    joint = parent.parentJoint;
  }
}

// The back: the largest +Z (scene frame, relative to the shoulders' centre) of the shapes of the upper torso
// and its ancestors whose bounds reach into the 40 cm below the shoulders.
double backBehind(const Character& c, const Frame& f, int upperTorso, const Eigen::Vector3d& centre) {
  const Skeleton& sk = c.skeleton();
  double back = 0.0;
  bool found = false;
  for (int l = upperTorso; l >= 0; l = sk.model().links()[static_cast<std::size_t>(l)].parentLink) {
    for (const ShapeDesc& s : sk.shapes(l)) {
      Eigen::Isometry3d scenePose = sk.linkPose(l) * s.origin;
      scenePose.linear() = f.toScene * scenePose.linear();
      scenePose.translation() = f.local(scenePose.translation());
      const Eigen::AlignedBox3d b = shapeBounds(s, scenePose);
      if (b.max().y() < centre.y() - 0.4 * sk.scale() || b.min().y() > centre.y() + 0.05 * sk.scale())
        continue;
      back = found ? std::max(back, b.max().z() - centre.z()) : b.max().z() - centre.z();
      found = true;
    }
  }
  return found ? std::max(back, 0.0) : 0.0;
}

std::string linkName(const UrdfModel& m, int link) {
  return m.links()[static_cast<std::size_t>(link)].name;
}

void finish(const Character& c, const Frame& f, ShoulderAnchors& a) {
  const UrdfModel& m = c.skeleton().model();
  if (a.left.x() > a.right.x()) {
    std::swap(a.left, a.right);
    std::swap(a.leftLink, a.rightLink);
  }
  a.upperTorsoLink = withBody(c, commonAncestor(m, a.leftLink, a.rightLink));
  if (a.upperTorsoLink < 0) a.upperTorsoLink = a.leftLink;
  a.back = backBehind(c, f, a.upperTorsoLink, 0.5 * (a.left + a.right));
}

// The cape pinned where two shoulder joints turn from (their chains' first joints' parent links), at
// their centres; false when either has no link with a body.
bool anchorsAtJoints(const Character& c, const Frame& f, const int (&joints)[2], bool chains,
                     const std::string& how, ShoulderAnchors& a) {
  const Skeleton& sk = c.skeleton();
  const UrdfModel& m = sk.model();
  int links[2];
  Eigen::Vector3d points[2];
  for (int side = 0; side < 2; ++side) {
    const int start = chains ? chainStart(m, joints[side]) : joints[side];
    const JointDesc& j = m.joints()[static_cast<std::size_t>(start)];
    links[side] = withBody(c, j.parentLink);
    points[side] = f.local(sk.linkPose(j.childLink).translation());  // the joint's centre
  }
  if (links[0] < 0 || links[1] < 0) return false;
  a.leftLink = links[0];
  a.rightLink = links[1];
  a.left = points[0];
  a.right = points[1];
  finish(c, f, a);
  const std::string where = a.leftLink == a.rightLink ? "link '" + linkName(m, a.leftLink) + "'"
                                                      : "links '" + linkName(m, a.leftLink) + "' and '" +
                                                            linkName(m, a.rightLink) + "'";
  a.description = "cape pinned to " + where + " (" + how + ": joints '" +
                  m.joints()[static_cast<std::size_t>(joints[0])].name + "' and '" +
                  m.joints()[static_cast<std::size_t>(joints[1])].name + "')";
  return true;
}

bool namedLikeShoulder(const std::string& name) {
  std::string lower = name;
  for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return lower.find("shoulder") != std::string::npos;
}

}  // namespace

ShoulderAnchors findShoulderAnchors(const Character& c) {
  ShoulderAnchors a;
  const Skeleton& sk = c.skeleton();
  const UrdfModel& m = sk.model();
  const Frame f = characterFrame(sk);
  const int roles[2] = {c.mapping()[GaitRole::LeftShoulder].joint,
                        c.mapping()[GaitRole::RightShoulder].joint};
  if (roles[0] >= 0 && roles[1] >= 0 &&
      anchorsAtJoints(c, f, roles, true, "the shoulders of the joint mapping", a))
    return a;
  // Ball shoulders (spherical joints named like a shoulder, as PyBullet's DeepMimic humanoid has): the
  // gait's mapping holds only hinges, and the links named "shoulder" there are the upper arms, which swing.
  // The cape pins to the link the balls turn from (the chest), at the two farthest apart sideways.
  int balls[2] = {-1, -1};
  double side[2] = {0.0, 0.0};
  for (int j = 0; j < static_cast<int>(m.joints().size()); ++j) {
    const JointDesc& joint = m.joints()[static_cast<std::size_t>(j)];
    if (joint.type != JointType::Spherical || !namedLikeShoulder(joint.name)) continue;
    const double x = f.local(sk.linkPose(joint.childLink).translation()).x();
    if (balls[0] < 0 || x < side[0]) {
      balls[0] = j;
      side[0] = x;
    }
    if (balls[1] < 0 || x > side[1]) {
      balls[1] = j;
      side[1] = x;
    }
  }
  if (balls[0] >= 0 && balls[1] >= 0 && balls[0] != balls[1] &&
      anchorsAtJoints(c, f, balls, false, "ball joints named like \"shoulder\"", a))
    return a;
  const std::vector<std::string> named = m.linksContaining("shoulder");
  if (named.empty()) {
    a.status =
        Status::error(ErrorCode::UnknownLink,
                      "the joint mapping found no shoulder joints and no link is named like \"shoulder\"");
    return a;
  }
  a = shoulderAnchorsOnLinks(c, named);
  if (a.status.ok()) a.description += " (links named like \"shoulder\": the mapping has no shoulders)";
  return a;
}

ShoulderAnchors shoulderAnchorsOnLinks(const Character& c, const std::vector<std::string>& links) {
  ShoulderAnchors a;
  const Skeleton& sk = c.skeleton();
  const UrdfModel& m = sk.model();
  const Frame f = characterFrame(sk);
  bool first = true;
  // withBody of each link, remembered along the way up: many links under one body cost their depth once.
  std::vector<int> bodyOf(m.links().size(), -2);  // -2: not known yet
  auto withBodyOf = [&](int link) {
    int l = link;
    while (l >= 0 && bodyOf[static_cast<std::size_t>(l)] == -2 && c.bodies().bodyForLink(l) == nullptr)
      l = m.links()[static_cast<std::size_t>(l)].parentLink;
    const int found = l < 0                                       ? -1
                      : bodyOf[static_cast<std::size_t>(l)] == -2 ? l
                                                                  : bodyOf[static_cast<std::size_t>(l)];
    for (int k = link; k != l; k = m.links()[static_cast<std::size_t>(k)].parentLink)
      bodyOf[static_cast<std::size_t>(k)] = found;
    if (l >= 0) bodyOf[static_cast<std::size_t>(l)] = found;
    return found;
  };
  for (const std::string& name : links) {
    const int link = m.findLink(name);
    if (link < 0) {
      std::string known;
      for (const LinkDesc& l : m.links()) known += (known.empty() ? "" : ", ") + l.name;
      a.status = Status::error(ErrorCode::UnknownLink,
                               "unknown link \"" + name + "\" (the model's links: " + known + ")");
      return a;
    }
    if (withBodyOf(link) < 0) {
      a.status = Status::error(
          ErrorCode::InvalidArgument,
          "link \"" + name + "\" and its ancestors have no collision shape, so no body to pin to");
      return a;
    }
    const Eigen::Vector3d p = f.local(sk.linkPose(link).translation());
    if (first || p.x() < a.left.x()) {
      a.left = p;
      a.leftLink = withBodyOf(link);
    }
    if (first || p.x() > a.right.x()) {
      a.right = p;
      a.rightLink = withBodyOf(link);
    }
    first = false;
  }
  if (first) {
    a.status = Status::error(ErrorCode::InvalidArgument, "no link given to pin the cape to");
    return a;
  }
  finish(c, f, a);
  std::string list;
  for (const std::string& l : links) list += (list.empty() ? "'" : ", '") + l + "'";
  a.description = "cape pinned to " + list;
  return a;
}

}  // namespace cape::character
