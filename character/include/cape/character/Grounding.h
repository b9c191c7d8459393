/// \file
/// Standing on the ground: the lowest point of a character's collision shapes, exactly per shape type, and
/// where its root must go for that point to touch the ground (world y = 0), with what was found on the way (a
/// floating base).
///
/// Every height here is world y (Y up, docs/SCENES.md), in metres.
#pragma once

#include "cape/character/Export.h"
#include "cape/character/Skeleton.h"
#include "cape/character/Urdf.h"

#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace cape::character {

/// The lowest world y of a collision shape whose frame is at `pose` in the world (sizes as in the shape):
/// \verbatim
///   sphere    centre - r
///   box       the lowest of its 8 corners
///   cylinder  the lowest rim point: centre - h |a_y| - r sqrt(1 - a_y^2), for its axis a (local z) and half
///             length h
///   capsule   the lower of its two sphere centres (centre +- h a) - r
///   hull      its lowest vertex - radius (its rounding); +infinity for a hull without vertices
/// \endverbatim
CAPE_CHARACTER_API double lowestPointY(const ShapeDesc& shape, const Eigen::Isometry3d& pose);

/// The exact axis-aligned bounds of one collision shape placed at `pose` (m, in whatever frame pose is in):
/// lowestPointY is its min().y().
CAPE_CHARACTER_API Eigen::AlignedBox3d shapeBounds(const ShapeDesc& shape, const Eigen::Isometry3d& pose);

/// The bounds of every collision shape of the skeleton at its current pose, in the frame `turn` takes the
/// world into (the identity: the world; Skeleton::urdfToWorld().transpose(): the URDF's axes). Empty when
/// it has no shapes.
CAPE_CHARACTER_API Eigen::AlignedBox3d skeletonBounds(const Skeleton& skeleton, const Eigen::Matrix3d& turn);

/// The lowest world y over every collision shape of the skeleton at its current pose; none when it has no
/// shapes (or only empty hulls).
CAPE_CHARACTER_API std::optional<double> lowestCollisionPoint(const Skeleton& skeleton);

/// Where a character's root goes.
struct GroundPlacement {
  /// m: the height of the URDF root link origin above the ground (before the gait's bob).
  double rootHeight = 0.0;
  /// m: the lowest collision point below the root origin (root y - lowest y); none without shapes.
  std::optional<double> rootAboveLowest;
  /// What a person should know: a floating base and what was done about it, no shapes at all.
  std::vector<std::string> warnings;
};

/// The root height that puts `standing` (the skeleton in the pose to stand in; its root anywhere) on the
/// ground: minus its lowest point's height below the root origin, exactly 0 when that is under 1e-6 m (a
/// model whose root is on the ground already keeps its bits), or `rootHeight` when given. No shapes: the
/// root stays at 0 (or `rootHeight`) with a warning. A floating base is said: the root origin more than
/// 0.3 m above the lowest point (a root at the pelvis), a floating joint out of the root link, or a root that
/// is a dummy link named "world" without shapes.
CAPE_CHARACTER_API GroundPlacement placeOnGround(const Skeleton& standing,
                                                 const std::optional<double>& rootHeight = {});

}  // namespace cape::character
