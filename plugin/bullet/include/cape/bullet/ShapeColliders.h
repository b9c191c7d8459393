/// \file
/// Bullet collision shapes as cape colliders, all resolved by the core inside its substeps. Shapes the core
/// knows analytically (sphere, box, capsule, cylinder, a static plane; compounds, nested) become those
/// colliders; every other convex shape becomes a core convex hull (a btConvexHullShape's own points, any
/// other shape's support mapping sampled in 162 directions), its collision margin the collider's thickness;
/// triangle meshes (btBvhTriangleMeshShape, btScaledBvhTriangleMeshShape, heightfields) become core
/// triangle-mesh colliders whose triangles near the cape the action gathers with Bullet's mesh queries once
/// per step.
#pragma once

#include "cape/bullet/Export.h"
#include "cape/core/Collider.h"

#include <BulletCollision/CollisionShapes/btCollisionShape.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/CollisionShapes/btConvexShape.h>
#include <LinearMath/btTransform.h>

#include <memory>
#include <string>
#include <vector>

namespace cape::bullet {

/// What one Bullet shape becomes. Every part carries its transform in the shape's (the object's) frame, so
/// that its world pose is objectWorldTransform * local.
struct ShapeConversion {
  /// An analytic shape or a convex hull.
  struct Primitive {
    Collider collider;  ///< Sizes filled in; poses are set every step.
    btTransform local;  ///< Its pose in the object's frame (m).
  };
  /// A triangle mesh or a heightfield.
  struct Mesh {
    const btConcaveShape* shape;  ///< Queried for its triangles near the cape every step.
    btTransform local;            ///< Its pose in the object's frame (m).
  };
  std::vector<Primitive> primitives;     ///< Analytic shapes and convex hulls, swept by the core.
  std::vector<Mesh> meshes;              ///< Triangle meshes and heightfields.
  std::vector<std::string> unsupported;  ///< Names (btCollisionShape::getName) of shapes left out, and why.
  /// True when the shape gave nothing to collide with.
  bool empty() const { return primitives.empty() && meshes.empty(); }
};

/// Converts a shape (with local scaling and collision margins: the sizes describe the surface Bullet's own
/// collision detection uses) into colliders. `local` places the shape in the object frame (compounds pass
/// their child transforms down). btEmptyShape gives nothing and is not reported as unsupported.
///
/// Scaling: btSphereShape, btBoxShape, btCapsuleShape and btCylinderShape report their scaled sizes; a
/// btMultiSphereShape's sphere centres are scaled per axis and its radii by the largest scale component
/// (exact for uniform scaling); a btStaticPlaneShape's scaling is ignored (a plane has no size).
/// A btMultiSphereShape is the convex hull of its spheres: its spheres are core colliders, and its sampled
/// hull keeps particles out of the space between them.
CAPE_BULLET_API ShapeConversion convertShape(const btCollisionShape* shape,
                                             const btTransform& local = btTransform::getIdentity());

/// The core convex hull of a convex shape without its margin (a btPolyhedralConvexShape's vertices, scaled;
/// any other shape's support points without margin in 162 directions spread over the sphere), through
/// Bullet's btConvexHullComputer; the shape's margin is for the collider's thickness. nullptr for a flat
/// or degenerate shape (fewer than four points off one plane).
CAPE_BULLET_API std::shared_ptr<const ConvexHull> convexHullOf(const btConvexShape* shape);

/// Signed distance from a world point to a convex shape's true surface (margin included), m, negative
/// inside, and the outward unit normal at the nearest surface point. Uses Bullet's GJK (outside and within
/// the margin) and EPA (deeper inside). Returns false when GJK/EPA fails (the outputs are then unchanged).
CAPE_BULLET_API bool convexSignedDistance(const btConvexShape* shape, const btTransform& world,
                                          const btVector3& point, btScalar& distance, btVector3& normal);

/// Signed distance from a world point to any shape this adapter understands, m (the minimum over a
/// compound's children; triangle meshes give the unsigned distance to the nearest triangle minus the shape
/// margin). For metrics and tests: the "true Bullet surface" of docs/SCENES.md's penetration metric.
/// Returns +infinity for shapes it cannot measure.
CAPE_BULLET_API btScalar shapeSignedDistance(const btCollisionShape* shape, const btTransform& world,
                                             const btVector3& point);

/// The point of triangle abc nearest to p (cape::nearestOnTriangle in Bullet's types); `onFace`, when given,
/// says whether it lies inside the face rather than on an edge or a corner.
CAPE_BULLET_API btVector3 closestOnTriangle(const btVector3& p, const btVector3& a, const btVector3& b,
                                            const btVector3& c, bool* onFace = nullptr);

}  // namespace cape::bullet
