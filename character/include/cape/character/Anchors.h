/// \file
/// Where a cape hangs on a character that nobody described to us: the links its shoulders hang from, the
/// shoulder points, the upper torso, and how far its back lies behind the shoulders. Found from the joint
/// mapping (the joints it takes for the shoulders) and the collision shapes, so any URDF humanoid whose
/// shoulders are mapped gets a cape without naming a link.
#pragma once

#include "cape/character/Character.h"
#include "cape/character/Export.h"
#include "cape/character/Grounding.h"
#include "cape/character/Status.h"

#include <Eigen/Geometry>

#include <string>

namespace cape::character {

/// Where a cape hangs on a character: the links, the shoulder points and the back (see Anchors.h).
struct ShoulderAnchors {
  Status status;  ///< an error (NotMovable, UnknownLink) when no shoulders could be found
  /// The links the shoulders hang from, each the nearest link (walking to the root) that has a body: the
  /// shipped humanoid's left_shoulder / right_shoulder, or a robot's torso.
  int leftLink = -1;
  int rightLink = -1;  ///< the right shoulder's link (see leftLink)
  /// Their nearest common ancestor with a body (the upper torso): what a collar pins to.
  int upperTorsoLink = -1;
  /// The shoulder joints' centres in the Y-up scene frame of docs/SCENES.md (the world turned back by
  /// Skeleton::sceneToWorld: x right and y up for a character at yaw 0, the ground at y = 0), m.
  Eigen::Vector3d left = Eigen::Vector3d::Zero();
  Eigen::Vector3d right = Eigen::Vector3d::Zero();  ///< the right shoulder's centre, m (see left)
  /// m: how far behind the shoulders' centre (+Z) the back's surface is, around shoulder height (the largest
  /// +Z of the shapes of the upper torso and its ancestors within 40 cm below the shoulders).
  double back = 0.0;
  /// One line saying what was chosen and why, for the user.
  std::string description;
};

/// Anchors from the character's joint mapping: each side's mapped shoulder joint, walked up the arm chain
/// (through links with a single movable child joint) to the link the arm hangs from. With no mapped
/// shoulder on a side, two spherical joints named like "shoulder" (ball shoulders, as PyBullet's DeepMimic
/// humanoid's: the two farthest apart sideways) pin it to the link they turn from, at their centres; with
/// none, the links named like "shoulder" (left/right by their x) are used instead; with none, an error.
/// Measured at the character's current pose (call right after Character::create).
CAPE_CHARACTER_API ShoulderAnchors findShoulderAnchors(const Character& character);

/// Anchors on links the user named (1 or more: the leftmost and rightmost by x are the shoulders; the
/// shoulder points are the links' origins). UnknownLink naming the model's links when one does not exist;
/// InvalidArgument when a link has no body and no ancestor with one.
CAPE_CHARACTER_API ShoulderAnchors shoulderAnchorsOnLinks(const Character& character,
                                                          const std::vector<std::string>& links);

}  // namespace cape::character
