/// \file
/// Forward kinematics of a URDF model in the Y-up world of docs/SCENES.md.
///
/// Frames, from the world inwards:
/// \verbatim
///   world (Y up, metres; the character faces -Z at yaw 0)
///     <- root transform: position on the ground + yaw about world +Y (setRoot)
///     <- urdfToWorld(): the fixed rotation taking the URDF's REP-103 axes into the world:
///          URDF +x (forward) -> world -Z,  URDF +y (left) -> world -X,  URDF +z (up) -> world +Y
///     <- the URDF root link, then each joint: origin (translation times scale) * motion(q)
/// \endverbatim
/// The uniform scale multiplies every length of the model (joint origins, prismatic travel, shape sizes);
/// link frames stay rigid (rotation matrices stay orthonormal), so a link pose is always a proper rigid
/// transform.
#pragma once

#include "cape/character/Export.h"
#include "cape/character/Status.h"
#include "cape/character/Urdf.h"

#include <Eigen/Geometry>

#include <cassert>
#include <string>
#include <vector>

namespace cape::character {

/// One collision shape placed in the world: for exporting colliders frame by frame.
struct WorldShape {
  int link = -1;                          ///< the link's index
  const std::string* linkName = nullptr;  ///< points into the model; valid while the Skeleton lives
  const ShapeDesc* shape = nullptr;       ///< sizes in world metres (scale applied); valid until setScale
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< the shape's frame in the world
};

/// Which world axis is up. Y: the world of docs/SCENES.md (y up, the character facing -Z at yaw 0). Z: the
/// world of ROS and PyBullet (REP 103: x forward, y left, z up), which is that world turned by
/// sceneToWorld(UpAxis::Z): a character at yaw 0 faces +X, and its URDF frame is the world's.
enum class UpAxis : int {
  Y,  ///< y up: docs/SCENES.md's world
  Z,  ///< z up: ROS's and PyBullet's world
};
/// "y" or "z".
CAPE_CHARACTER_API const char* toString(UpAxis up);

/// Forward kinematics of a URDF model: joint positions in, link poses and placed collision shapes out (see
/// Skeleton.h for the frames). Lengths in m, angles in rad.
class CAPE_CHARACTER_API Skeleton {
 public:
  /// The rotation taking URDF axes (x forward, y left, z up) into the Y-up scene frame (x right, y up, z
  /// backward).
  static Eigen::Matrix3d urdfToWorld();
  /// The rotation taking the Y-up scene frame into a world with the given up axis: the identity for Y,
  /// urdfToWorld()'s inverse for Z (scene +Y -> world +Z, scene -Z (forward) -> world +X).
  static Eigen::Matrix3d sceneToWorld(UpAxis up);

  /// `model` must not be null. Joints start at rest (see restPosition), the root at the world origin, yaw 0.
  explicit Skeleton(UrdfModelPtr model);

  /// The model.
  const UrdfModel& model() const { return *model_; }
  /// The model's shared pointer.
  const UrdfModelPtr& modelPtr() const { return model_; }
  /// The number of links.
  int linkCount() const { return static_cast<int>(model_->links().size()); }
  /// The number of joints.
  int jointCount() const { return static_cast<int>(model_->joints().size()); }

  /// Uniform scale of the whole model, > 0 (1 = the URDF's own size). InvalidArgument otherwise.
  Status setScale(double scale);
  /// The uniform scale (1 = the URDF's own size).
  double scale() const { return scale_; }

  // --- Joint positions (rad for revolute and continuous joints, URDF metres for prismatic ones)
  // ---------------
  /// Index of a joint, -1 if none.
  int jointIndex(const std::string& name) const { return model_->findJoint(name); }
  /// Sets a joint's position. Errors: UnknownJoint; NotMovable (fixed, floating, planar); InvalidArgument
  /// (not finite; nothing changes). A value outside the limits is clamped to them, applied, and reported as
  /// OutsideLimits so the caller can tell; every other success returns ok.
  Status setJointPosition(const std::string& name, double q);
  /// The same by joint index (UnknownJoint for an index out of range).
  Status setJointPosition(int joint, double q);
  /// UnknownJoint if there is no such joint.
  Status jointPosition(const std::string& name, double& q) const;
  /// A joint's position by index (rad, or m for a prismatic joint); the index must be valid.
  double jointPosition(int joint) const {
    assert(joint >= 0 && joint < jointCount() && "joint index out of range");
    return q_[static_cast<std::size_t>(joint)];
  }
  /// One value per joint, in model().joints() order (0 for joints that are not movable).
  const std::vector<double>& jointPositions() const { return q_; }
  /// Rest position of a joint: 0, or the nearest limit when 0 lies outside the limits.
  double restPosition(int joint) const;
  /// q clamped into the joint's limits (unchanged for joints without limits).
  double clampToLimits(int joint, double q) const;
  /// Every joint back to its rest position (spherical joints to the identity).
  void resetJointPositions();

  /// A spherical (ball) joint's rotation: the child's joint frame turned by `q` about the joint origin, in
  /// the joint frame (as PyBullet's resetJointStateMultiDof). `q` is normalised. Errors: UnknownJoint;
  /// NotMovable (not spherical); InvalidArgument (not finite, or of norm below 1e-9; nothing changes).
  Status setJointRotation(int joint, const Eigen::Quaterniond& q);
  /// The same by joint name.
  Status setJointRotation(const std::string& name, const Eigen::Quaterniond& q);
  /// The identity for every joint that is not spherical.
  const Eigen::Quaterniond& jointRotation(int joint) const {
    assert(joint >= 0 && joint < jointCount() && "joint index out of range");
    return rotations_[static_cast<std::size_t>(joint)];
  }

  // --- Root
  // ----------------------------------------------------------------------------------------------------
  /// The character frame: `position` in the world (m; the URDF origin, for the shipped humanoid the ground
  /// point between the feet), `yaw` in rad about world +Y (0 faces -Z, as motionAt in cape/scenes/Scene.h).
  void setRoot(const Eigen::Vector3d& position, double yaw);
  /// Any rigid character frame (the URDF-to-world rotation is applied inside it).
  void setRootTransform(const Eigen::Isometry3d& root);
  /// The character frame in the Y-up scene frame (m).
  const Eigen::Isometry3d& rootTransform() const { return root_; }
  /// Puts the URDF root link's frame at `pose` in the world (the frame every pose here is reported in: with
  /// setUpAxis, Y-up or Z-up), the uniform scale not applied to it: the inverse of linkPose(0). Sets the
  /// root transform that gives it. A pose whose rotation is not orthonormal is orthonormalised.
  void setRootLinkPose(const Eigen::Isometry3d& pose);
  /// The world's up axis (Y by default). The root (setRoot, setRootTransform) stays in the Y-up scene frame;
  /// every pose this skeleton reports is turned by sceneToWorld(up) into the world.
  void setUpAxis(UpAxis up);
  /// The world's up axis.
  UpAxis upAxis() const { return up_; }

  // --- Poses
  // ---------------------------------------------------------------------------------------------------
  /// World pose of a link's frame (computed on demand after any change; not safe to call from two threads at
  /// once on one Skeleton).
  const Eigen::Isometry3d& linkPose(int link) const;
  /// UnknownLink if there is no such link.
  Status linkPose(const std::string& name, Eigen::Isometry3d& pose) const;
  /// A link's collision shapes with the scale applied (origins in the link frame).
  const std::vector<ShapeDesc>& shapes(int link) const {
    assert(link >= 0 && link < linkCount() && "link index out of range");
    return shapes_[static_cast<std::size_t>(link)];
  }
  /// Every collision shape of every link placed in the world, in link order; `out` is reused (no allocation
  /// once it has grown).
  void worldShapes(std::vector<WorldShape>& out) const;
  /// The same in a new vector.
  std::vector<WorldShape> worldShapes() const;

 private:
  void updatePoses() const;
  void rebuildShapes();

  UrdfModelPtr model_;
  double scale_ = 1.0;
  std::vector<double> q_;
  std::vector<Eigen::Quaterniond> rotations_;  ///< per joint; the identity but for spherical joints
  Eigen::Isometry3d root_ = Eigen::Isometry3d::Identity();
  UpAxis up_ = UpAxis::Y;
  std::vector<std::vector<ShapeDesc>> shapes_;    ///< per link, scaled
  mutable std::vector<Eigen::Isometry3d> poses_;  ///< per link, world
  mutable bool dirty_ = true;
};

}  // namespace cape::character
