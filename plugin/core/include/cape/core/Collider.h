/// \file
/// Colliders: analytic shapes the cape collides with, each with the pose it had at the start of the step
/// (`previous`) and the pose it has at its end (`current`). The solver interpolates between them across its
/// substeps and tests each particle against the collider's sweep, so fast motion cannot carry a particle
/// through.
#pragma once

#include "cape/core/Export.h"
#include "cape/core/Types.h"

#include <memory>
#include <string>
#include <vector>

namespace cape {

/// The kinds of collider (Collider gives each one's surface).
enum class ColliderShape : int {
  Sphere,        ///< A ball about the collider's origin.
  Capsule,       ///< A segment along an axis, rounded by a radius.
  Cylinder,      ///< A flat-ended cylinder along an axis.
  Box,           ///< An axis-aligned box in the collider's frame.
  Plane,         ///< A world half-space.
  ConvexHull,    ///< A convex polytope (ConvexHull).
  TriangleMesh,  ///< Two-sided triangles (TriangleSoup), no inside.
};
/// The shape's name: "sphere", "capsule", ...
CAPE_CORE_API const char* toString(ColliderShape shape);

/// A convex polytope in its collider's frame: the points it is the hull of, and its outward face planes
/// n . p = offset (n a unit vector; the solid is where every n . p <= offset). Built once and shared by every
/// collider (and every cape) that uses it; the Bullet adapter builds it from any convex shape.
struct CAPE_CORE_API ConvexHull {
  std::vector<Vec3> vertices;           ///< m, at least 4, not all in one plane.
  std::vector<Eigen::Vector4f> planes;  ///< (n.x, n.y, n.z, offset in m), at least 4.
  float radius = 0.0f;                  ///< m: the largest |vertex| (a bounding sphere about the origin).

  /// A hull from its vertices and planes; radius from the vertices.
  static std::shared_ptr<const ConvexHull> make(std::vector<Vec3> vertices,
                                                std::vector<Eigen::Vector4f> planes);
  /// Counts, finite values, unit normals, and every vertex on the solid side of every plane (within 0.1 mm).
  Status validate() const;
};

/// Triangles of a mesh near the cape, in their collider's frame: corners[3 t .. 3 t + 2] is triangle t, m.
/// Whoever gathers them (the Bullet adapter, from its mesh queries once per step) refills it between steps.
struct TriangleSoup {
  std::vector<Vec3> corners;  ///< m, three per triangle.
  /// The number of triangles.
  std::size_t size() const { return corners.size() / 3; }
};

/// One collider. All sizes are in metres and describe the true surface; `thickness` adds a skin the
/// particles are kept out of (on top of the cape's own collision thickness).
///
/// Local shapes (in the collider's own frame):
/// \verbatim
///   Sphere   |p| = radius
///   Capsule  points within `radius` of the segment from -halfHeight to +halfHeight along `axis`
///            (halfHeight is half the distance between the two sphere centres, as btCapsuleShape)
///   Cylinder radius `radius` about `axis`, from -halfHeight to +halfHeight along it
///   Box      |p_k| <= halfExtents_k
///   Plane    the half-space n . p <= constant is solid (n = `normal`, unit length)
///   ConvexHull    the intersection of `hull`'s half-spaces; its signed distance is the largest plane
///                 distance (exact inside and over a face, a lower bound beside edges and corners outside)
///   TriangleMesh  `triangles`, two-sided: each particle keeps the side of every nearby triangle it was on
///                 at the start of the step (so a thin wall or a floor cannot be passed through), at least
///                 the thicknesses away from it; no inside
/// \endverbatim
struct CAPE_CORE_API Collider {
  ColliderShape shape = ColliderShape::Sphere;    ///< Which surface the fields below describe.
  float radius = 0.0f;                            ///< m: sphere, capsule and cylinder.
  float halfHeight = 0.0f;                        ///< m: capsule and cylinder, along `axis`.
  int axis = 1;                                   ///< 0 = X, 1 = Y, 2 = Z (capsule and cylinder).
  Vec3 halfExtents = Vec3::Zero();                ///< m: box, along the collider's x, y, z.
  Vec3 normal = Vec3::UnitY();                    ///< Plane: unit normal, world (out of the solid).
  float constant = 0.0f;                          ///< Plane: n . x = constant on the surface, m.
  std::shared_ptr<const ConvexHull> hull;         ///< ConvexHull only.
  std::shared_ptr<const TriangleSoup> triangles;  ///< TriangleMesh only.
  float thickness = 0.0f;                         ///< m, >= 0.
  float friction = -1.0f;  ///< Coulomb coefficient; negative means "use the cape's setting".
  Pose previous;           ///< Pose at the start of the step.
  Pose current;            ///< Pose at the end of the step.
  std::string name;        ///< For reports only.

  /// A sphere of `radius` m at `pose` (both poses), not moving.
  static Collider sphere(float radius, const Pose& pose = Pose());
  /// A capsule: `radius` m around the segment +-`halfHeight` m along `axis` (0 = X, 1 = Y, 2 = Z).
  static Collider capsule(float radius, float halfHeight, int axis, const Pose& pose = Pose());
  /// A cylinder of `radius` m from -`halfHeight` to +`halfHeight` m along `axis` (0 = X, 1 = Y, 2 = Z).
  static Collider cylinder(float radius, float halfHeight, int axis, const Pose& pose = Pose());
  /// A box of `halfExtents` m along its x, y, z.
  static Collider box(const Vec3& halfExtents, const Pose& pose = Pose());
  /// The world plane n . x = constant, solid below (n is normalised here).
  static Collider plane(const Vec3& normal, float constant);
  /// A convex hull (shared, not copied) at `pose`.
  static Collider convexHull(std::shared_ptr<const ConvexHull> hull, const Pose& pose = Pose());
  /// Two-sided triangles (shared; the gatherer refills them between steps) at `pose`.
  static Collider triangleMesh(std::shared_ptr<const TriangleSoup> triangles, const Pose& pose = Pose());

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
/// A triangle mesh has no inside: the distance to its nearest triangle (+inf for an empty one).
struct SurfaceDistance {
  float distance;  ///< m, negative inside.
  Vec3 normal;     ///< Unit, outward, in the collider's frame.
};
/// The signed distance and normal of a point given in the collider's frame (see SurfaceDistance).
CAPE_CORE_API SurfaceDistance localSignedDistance(const Collider& collider, const Vec3& localPoint);

/// Signed distance from a world point to the collider's true surface at its current pose, m (negative
/// inside).
CAPE_CORE_API float signedDistance(const Collider& collider, const Vec3& worldPoint);

/// The nearest point of the collider's surface to a world point, at its current pose, m, world (the seed's
/// push-out target when the thickness is zero).
CAPE_CORE_API Vec3 closestSurfacePoint(const Collider& collider, const Vec3& worldPoint);

}  // namespace cape
