// Colliders: analytic shapes the cape collides with, each with the pose it had at the start of the step
// (`previous`) and the pose it has at its end (`current`). The solver interpolates between them across its
// substeps and tests each particle against the collider's sweep, so fast motion cannot carry a particle
// through.
#pragma once

#include "cape/core/Types.h"

#include <string>
#include <vector>

namespace cape {

enum class ColliderShape : int { Sphere, Capsule, Cylinder, Box, Plane };
const char* toString(ColliderShape shape);

/// One collider. All sizes are in metres and describe the true surface; `thickness` adds a skin the
/// particles are kept out of (on top of the cape's own collision thickness).
///
/// Local shapes (in the collider's own frame):
///   Sphere   |p| = radius
///   Capsule  points within `radius` of the segment from -halfHeight to +halfHeight along `axis`
///            (halfHeight is half the distance between the two sphere centres, as btCapsuleShape)
///   Cylinder radius `radius` about `axis`, from -halfHeight to +halfHeight along it
///   Box      |p_k| <= halfExtents_k
///   Plane    the half-space n . p <= constant is solid (n = `normal`, unit length)
struct Collider {
  ColliderShape shape = ColliderShape::Sphere;
  float radius = 0.0f;
  float halfHeight = 0.0f;
  int axis = 1;  ///< 0 = X, 1 = Y, 2 = Z (capsule and cylinder).
  Vec3 halfExtents = Vec3::Zero();
  Vec3 normal = Vec3::UnitY();
  float constant = 0.0f;
  float thickness = 0.0f;  ///< m, >= 0.
  float friction = -1.0f;  ///< Coulomb coefficient; negative means "use the cape's setting".
  Pose previous;           ///< Pose at the start of the step.
  Pose current;            ///< Pose at the end of the step.
  std::string name;        ///< For reports only.

  static Collider sphere(float radius, const Pose& pose = Pose());
  static Collider capsule(float radius, float halfHeight, int axis, const Pose& pose = Pose());
  static Collider cylinder(float radius, float halfHeight, int axis, const Pose& pose = Pose());
  static Collider box(const Vec3& halfExtents, const Pose& pose = Pose());
  /// The world plane n . x = constant, solid below (n is normalised here).
  static Collider plane(const Vec3& normal, float constant);

  /// The collider has moved: the pose at the end of the last step becomes the start of the next.
  void moveTo(const Pose& pose) {
    previous = current;
    current = pose;
  }
  /// Jump without sweeping (a teleport): both poses become `pose`.
  void teleportTo(const Pose& pose) { previous = current = pose; }

  /// Checks sizes (finite, > 0), axis, normal and poses.
  Status validate() const;
};

/// Signed distance from a point in the collider's local frame to its true surface (negative inside), and the
/// outward unit normal of the nearest surface point (the nearest surface point is p - distance * normal).
struct SurfaceDistance {
  float distance;
  Vec3 normal;
};
SurfaceDistance localSignedDistance(const Collider& collider, const Vec3& localPoint);

/// Signed distance from a world point to the collider's true surface at its current pose.
float signedDistance(const Collider& collider, const Vec3& worldPoint);

/// The nearest point of the collider's surface to a world point, at its current pose (the seed's push-out
/// target when the thickness is zero).
Vec3 closestSurfacePoint(const Collider& collider, const Vec3& worldPoint);

}  // namespace cape
