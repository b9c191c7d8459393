// Lowest collision points per shape type, and the root height that stands a character on the ground.
#include "cape/character/Grounding.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace cape::character {

namespace {

constexpr double kFloatingBase =
    0.3;  // m: a root origin this far above the lowest point is not on the ground
constexpr double kOnTheGround = 1e-6;  // m: a lift smaller than this is none (the bits stay)

std::string metres(double m) {
  std::ostringstream out;
  out << std::setprecision(3) << m << " m";
  return out.str();
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

}  // namespace

Eigen::AlignedBox3d shapeBounds(const ShapeDesc& s, const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d r = pose.linear();
  const Eigen::Vector3d c = pose.translation();
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  switch (s.type) {
    case ShapeType::Sphere:
      half.setConstant(s.radius);
      break;
    case ShapeType::Box:
      half = r.cwiseAbs() * s.halfExtents;
      break;
    case ShapeType::Cylinder:
    case ShapeType::Capsule: {
      // Along each world axis k: the axis' reach |a_k| h, plus the rim's r sqrt(1 - a_k^2) for a cylinder or
      // the end spheres' r for a capsule.
      const Eigen::Vector3d a = r.col(2);
      for (int k = 0; k < 3; ++k) {
        const double rim =
            s.type == ShapeType::Capsule ? s.radius : s.radius * std::sqrt(std::max(0.0, 1.0 - a[k] * a[k]));
        half[k] = std::fabs(a[k]) * s.halfLength + rim;
      }
      break;
    }
    case ShapeType::ConvexHull: {
      Eigen::AlignedBox3d box;
      for (const Eigen::Vector3d& v : s.hull) box.extend(pose * v);
      if (box.isEmpty()) return box;  // no vertices: empty bounds
      const Eigen::Vector3d grow = Eigen::Vector3d::Constant(s.radius);
      return Eigen::AlignedBox3d(box.min() - grow, box.max() + grow);
    }
  }
  return Eigen::AlignedBox3d(c - half, c + half);
}

Eigen::AlignedBox3d skeletonBounds(const Skeleton& skeleton, const Eigen::Matrix3d& turn) {
  Eigen::AlignedBox3d box;
  for (const WorldShape& w : skeleton.worldShapes()) {
    Eigen::Isometry3d p = w.pose;
    p.linear() = turn * p.linear();
    p.translation() = turn * p.translation();
    box.extend(shapeBounds(*w.shape, p));
  }
  return box;
}

double lowestPointY(const ShapeDesc& shape, const Eigen::Isometry3d& pose) {
  const Eigen::AlignedBox3d bounds = shapeBounds(shape, pose);
  return bounds.isEmpty() ? std::numeric_limits<double>::infinity() : bounds.min().y();
}

std::optional<double> lowestCollisionPoint(const Skeleton& skeleton) {
  const Eigen::AlignedBox3d box = skeletonBounds(skeleton, Eigen::Matrix3d::Identity());
  if (box.isEmpty()) return std::nullopt;
  return box.min().y();
}

GroundPlacement placeOnGround(const Skeleton& standing, const std::optional<double>& rootHeight) {
  GroundPlacement p;
  const UrdfModel& model = standing.model();
  const LinkDesc& root = model.links()[static_cast<std::size_t>(model.rootLink())];
  const std::optional<double> lowest = lowestCollisionPoint(standing);
  const std::string given =
      rootHeight ? "the root is placed at the given root height " + metres(*rootHeight) : std::string();
  if (!lowest) {
    p.rootHeight = rootHeight.value_or(0.0);
    p.warnings.push_back("no link of '" + model.name() + "' has a collision shape, so nothing can stand on " +
                         "the ground: " +
                         (rootHeight ? given
                                     : "the root link origin stays at height 0 (set "
                                       "CharacterSettings::rootHeight to place it)"));
    return p;
  }
  const double above = standing.rootTransform().translation().y() - *lowest;
  p.rootAboveLowest = above;
  const double lift = std::abs(above) < kOnTheGround ? 0.0 : above;
  p.rootHeight = rootHeight.value_or(lift);

  // A floating base, said with what was done about it.
  std::vector<std::string> reasons;
  if (above > kFloatingBase) {
    reasons.push_back("root link '" + root.name + "' is " + metres(above) +
                      " above the lowest collision point (a floating base)");
  }
  for (int j : root.childJoints) {
    const JointDesc& joint = model.joints()[static_cast<std::size_t>(j)];
    const std::string& child = model.links()[static_cast<std::size_t>(joint.childLink)].name;
    const bool dummy = lower(root.name) == "world" && root.shapes.empty();
    const std::string link = dummy ? "root link '" + root.name + "' is a dummy world link, and its "
                                   : "the root link '" + root.name + "'s ";
    if (joint.type == JointType::Floating) {
      reasons.push_back(link + "joint '" + joint.name + "' to '" + child +
                        "' is floating (a floating base; it is held at its origin)");
    } else if (joint.type == JointType::Fixed && dummy) {
      reasons.push_back(link + "joint '" + joint.name + "' to '" + child + "' is fixed (a floating base)");
    }
  }
  std::string done = given;
  if (!rootHeight) {
    done = p.rootHeight > 0.0 ? "the character is raised " + metres(p.rootHeight) + " to stand on the ground"
           : p.rootHeight < 0.0
               ? "the character is lowered " + metres(-p.rootHeight) + " to stand on the ground"
               : "it stands on the ground as it is";
  }
  for (const std::string& r : reasons) p.warnings.push_back(r + ": " + done);
  return p;
}

}  // namespace cape::character
