#include "cape/core/Collider.h"

#include "ShapeDistance.h"

#include <algorithm>
#include <cmath>

namespace cape {

const char* toString(ColliderShape shape) {
  switch (shape) {
    case ColliderShape::Sphere:
      return "sphere";
    case ColliderShape::Capsule:
      return "capsule";
    case ColliderShape::Cylinder:
      return "cylinder";
    case ColliderShape::Box:
      return "box";
    case ColliderShape::Plane:
      return "plane";
    case ColliderShape::ConvexHull:
      return "convex_hull";
    case ColliderShape::TriangleMesh:
      return "triangle_mesh";
  }
  return "?";
}

std::shared_ptr<const ConvexHull> ConvexHull::make(std::vector<Vec3> vertices,
                                                   std::vector<Eigen::Vector4f> planes) {
  auto hull = std::make_shared<ConvexHull>();
  hull->vertices = std::move(vertices);
  hull->planes = std::move(planes);
  for (const Vec3& v : hull->vertices) hull->radius = std::max(hull->radius, v.norm());
  return hull;
}

Status ConvexHull::validate() const {
  if (vertices.size() < 4 || planes.size() < 4)
    return Status::error("needs at least 4 vertices and 4 planes");
  for (const Vec3& v : vertices)
    if (!v.allFinite()) return Status::error("a vertex is not finite");
  for (const Eigen::Vector4f& p : planes) {
    if (!p.allFinite()) return Status::error("a plane is not finite");
    if (std::abs(p.head<3>().norm() - 1.0f) > 1e-3f)
      return Status::error("a plane normal is not a unit vector");
    for (const Vec3& v : vertices)
      if (p.head<3>().dot(v) - p[3] > 1e-4f) return Status::error("a vertex lies outside a face plane");
  }
  return Status::success();
}

Collider Collider::convexHull(std::shared_ptr<const ConvexHull> hull, const Pose& pose) {
  Collider c;
  c.shape = ColliderShape::ConvexHull;
  c.hull = std::move(hull);
  c.previous = c.current = pose;
  return c;
}

Collider Collider::triangleMesh(std::shared_ptr<const TriangleSoup> triangles, const Pose& pose) {
  Collider c;
  c.shape = ColliderShape::TriangleMesh;
  c.triangles = std::move(triangles);
  c.previous = c.current = pose;
  return c;
}

Collider Collider::sphere(float radius, const Pose& pose) {
  Collider c;
  c.shape = ColliderShape::Sphere;
  c.radius = radius;
  c.previous = c.current = pose;
  return c;
}

Collider Collider::capsule(float radius, float halfHeight, int axis, const Pose& pose) {
  Collider c;
  c.shape = ColliderShape::Capsule;
  c.radius = radius;
  c.halfHeight = halfHeight;
  c.axis = axis;
  c.previous = c.current = pose;
  return c;
}

Collider Collider::cylinder(float radius, float halfHeight, int axis, const Pose& pose) {
  Collider c = capsule(radius, halfHeight, axis, pose);
  c.shape = ColliderShape::Cylinder;
  return c;
}

Collider Collider::box(const Vec3& halfExtents, const Pose& pose) {
  Collider c;
  c.shape = ColliderShape::Box;
  c.halfExtents = halfExtents;
  c.previous = c.current = pose;
  return c;
}

Collider Collider::plane(const Vec3& normal, float constant) {
  Collider c;
  c.shape = ColliderShape::Plane;
  const float len = normal.norm();
  c.normal = len > 0.0f ? Vec3(normal / len) : normal;
  c.constant = len > 0.0f ? constant / len : constant;
  return c;
}

Status Collider::validate() const {
  auto bad = [this](const std::string& what) {
    return Status::error(std::string(toString(shape)) + " collider" +
                         (name.empty() ? "" : " '" + name + "'") + ": " + what);
  };
  auto positive = [](float v) { return std::isfinite(v) && v > 0.0f; };
  if (!previous.isFinite() || !current.isFinite()) return bad("pose is not finite (or rotation not unit)");
  if (!(std::isfinite(thickness) && thickness >= 0.0f)) return bad("thickness must be finite and >= 0");
  if (!std::isfinite(friction)) return bad("friction must be finite");
  switch (shape) {
    case ColliderShape::Sphere:
      if (!positive(radius)) return bad("radius must be finite and > 0");
      break;
    case ColliderShape::Capsule:
    case ColliderShape::Cylinder:
      if (!positive(radius)) return bad("radius must be finite and > 0");
      if (!(std::isfinite(halfHeight) && halfHeight >= 0.0f) ||
          (shape == ColliderShape::Cylinder && !(halfHeight > 0.0f)))
        return bad("half height must be finite and " +
                   std::string(shape == ColliderShape::Cylinder ? "> 0" : ">= 0"));
      if (axis < 0 || axis > 2) return bad("axis must be 0 (X), 1 (Y) or 2 (Z)");
      break;
    case ColliderShape::Box:
      if (!positive(halfExtents.x()) || !positive(halfExtents.y()) || !positive(halfExtents.z()))
        return bad("half extents must be finite and > 0");
      break;
    case ColliderShape::Plane:
      if (!normal.allFinite() || std::abs(normal.norm() - 1.0f) > 1e-3f)
        return bad("normal must be a unit vector");
      if (!std::isfinite(constant)) return bad("constant must be finite");
      break;
    case ColliderShape::ConvexHull:
      if (!hull) return bad("no hull");
      break;  // the hull itself is checked where it is built (ConvexHull::validate): it is shared
    case ColliderShape::TriangleMesh:
      if (!triangles) return bad("no triangles");
      break;
  }
  return Status::success();
}

SurfaceDistance localSignedDistance(const Collider& c, const Vec3& p) {
  using detail::shapeDistance;
  switch (c.shape) {
    case ColliderShape::Sphere:
      return shapeDistance<ColliderShape::Sphere>(c, p);
    case ColliderShape::Capsule:
      return shapeDistance<ColliderShape::Capsule>(c, p);
    case ColliderShape::Cylinder:
      return shapeDistance<ColliderShape::Cylinder>(c, p);
    case ColliderShape::Box:
      return shapeDistance<ColliderShape::Box>(c, p);
    case ColliderShape::Plane:
      return shapeDistance<ColliderShape::Plane>(c, p);
    case ColliderShape::ConvexHull:
      return shapeDistance<ColliderShape::ConvexHull>(c, p);
    case ColliderShape::TriangleMesh:
      return detail::meshDistance(*c.triangles, p);
  }
  return {0.0f, Vec3::UnitY()};
}

float signedDistance(const Collider& c, const Vec3& worldPoint) {
  return localSignedDistance(c, c.current.applyInverse(worldPoint)).distance;
}

Vec3 closestSurfacePoint(const Collider& c, const Vec3& worldPoint) {
  const Vec3 local = c.current.applyInverse(worldPoint);
  const SurfaceDistance s = localSignedDistance(c, local);
  return c.current.apply(local - s.distance * s.normal);
}

}  // namespace cape
