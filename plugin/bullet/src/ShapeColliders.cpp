// Bullet shapes -> core colliders, and signed distances to Bullet's own surfaces.
#include "cape/bullet/ShapeColliders.h"

#include "cape/bullet/Convert.h"
#include "cape/core/Geometry.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/CollisionShapes/btCylinderShape.h>
#include <BulletCollision/CollisionShapes/btMultiSphereShape.h>
#include <BulletCollision/CollisionShapes/btPolyhedralConvexShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>
#include <LinearMath/btConvexHullComputer.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace cape::bullet {

btVector3 closestOnTriangle(const btVector3& p, const btVector3& a, const btVector3& b, const btVector3& c,
                            bool* onFace) {
  const TriangleNearest w = nearestOnTriangle(toVec3(p), toVec3(a), toVec3(b), toVec3(c));
  if (onFace) *onFace = w.inFace;
  return a * btScalar(w.wa) + b * btScalar(w.wb) + c * btScalar(w.wc);
}

namespace {

void addPrimitive(ShapeConversion& out, Collider c, const btTransform& local, const char* name) {
  c.name = name;
  out.primitives.push_back({std::move(c), local});
}

/// 162 directions spread evenly over the sphere (a Fibonacci lattice): deterministic, no two alike.
const std::vector<btVector3>& sampleDirections() {
  static const std::vector<btVector3> directions = [] {
    constexpr int kCount = 162;
    std::vector<btVector3> d;
    const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < kCount; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / kCount, r = std::sqrt(1.0 - z * z), phi = golden * i;
      d.emplace_back(btScalar(r * std::cos(phi)), btScalar(r * std::sin(phi)), btScalar(z));
    }
    return d;
  }();
  return directions;
}

void addHull(ShapeConversion& out, const btConvexShape* shape, const btTransform& local) {
  std::shared_ptr<const ConvexHull> hull = convexHullOf(shape);
  if (!hull) {
    out.unsupported.push_back(std::string(shape->getName()) +
                              " (flat or degenerate: no volume to collide with)");
    return;
  }
  Collider c = Collider::convexHull(std::move(hull));
  c.thickness = float(shape->getMargin());  // Bullet's skin around the hull
  addPrimitive(out, std::move(c), local, shape->getName());
}

bool isSupportedConcave(int type) {
  return type == TRIANGLE_MESH_SHAPE_PROXYTYPE || type == SCALED_TRIANGLE_MESH_SHAPE_PROXYTYPE ||
         type == TERRAIN_SHAPE_PROXYTYPE || type == MULTIMATERIAL_TRIANGLE_MESH_PROXYTYPE;
}

void convertInto(ShapeConversion& out, const btCollisionShape* shape, const btTransform& local) {
  if (shape == nullptr) return;
  const int type = shape->getShapeType();
  switch (type) {
    case SPHERE_SHAPE_PROXYTYPE: {
      // getRadius() is the scaled radius; a sphere's margin is its radius, so it is the true surface.
      const auto* s = static_cast<const btSphereShape*>(shape);
      addPrimitive(out, Collider::sphere(float(s->getRadius())), local, "btSphereShape");
      return;
    }
    case BOX_SHAPE_PROXYTYPE: {
      // Bullet keeps the box's implicit dimensions shrunk by the margin; with it the box has the half extents
      // it was made with (times the scaling). Its edges are rounded by the margin in GJK, inside our box.
      const auto* b = static_cast<const btBoxShape*>(shape);
      addPrimitive(out, Collider::box(toVec3(b->getHalfExtentsWithMargin())), local, "btBoxShape");
      return;
    }
    case CAPSULE_SHAPE_PROXYTYPE: {
      // Radius and half height (half the distance between the sphere centres) are the scaled ones.
      const auto* c = static_cast<const btCapsuleShape*>(shape);
      addPrimitive(out, Collider::capsule(float(c->getRadius()), float(c->getHalfHeight()), c->getUpAxis()),
                   local, "btCapsuleShape");
      return;
    }
    case CYLINDER_SHAPE_PROXYTYPE: {
      const auto* c = static_cast<const btCylinderShape*>(shape);
      const int axis = c->getUpAxis();
      const btVector3 h = c->getHalfExtentsWithMargin();
      addPrimitive(out, Collider::cylinder(float(c->getRadius()), float(h[axis]), axis), local,
                   "btCylinderShape");
      return;
    }
    case MULTI_SPHERE_SHAPE_PROXYTYPE: {
      const auto* m = static_cast<const btMultiSphereShape*>(shape);
      const btVector3 scale = m->getLocalScaling();
      const btScalar radiusScale =
          std::max({std::fabs(scale.x()), std::fabs(scale.y()), std::fabs(scale.z())});
      for (int i = 0; i < m->getSphereCount(); ++i) {
        btTransform t = local;
        t.setOrigin(local * (m->getSpherePosition(i) * scale));
        addPrimitive(out, Collider::sphere(float(m->getSphereRadius(i) * radiusScale)), t,
                     "btMultiSphereShape");
      }
      // Bullet's multi-sphere is the convex hull of its spheres, not their union: the spheres are exact, and
      // the sampled hull covers the space between them.
      addHull(out, m, local);
      return;
    }
    case STATIC_PLANE_PROXYTYPE: {
      // The solid half-space n . p <= constant in the object's frame; the collider's pose carries it.
      const auto* p = static_cast<const btStaticPlaneShape*>(shape);
      Collider c = Collider::plane(toVec3(p->getPlaneNormal()), float(p->getPlaneConstant()));
      addPrimitive(out, std::move(c), local, "btStaticPlaneShape");
      return;
    }
    case COMPOUND_SHAPE_PROXYTYPE: {
      // Child transforms already include the compound's local scaling (setLocalScaling scales them and the
      // children's shapes), so only the nesting has to be composed.
      const auto* c = static_cast<const btCompoundShape*>(shape);
      for (int i = 0; i < c->getNumChildShapes(); ++i)
        convertInto(out, c->getChildShape(i), local * c->getChildTransform(i));
      return;
    }
    case EMPTY_SHAPE_PROXYTYPE:
      return;  // nothing to collide with (links without geometry)
    default:
      break;
  }
  if (shape->isConvex()) {
    addHull(out, static_cast<const btConvexShape*>(shape), local);
  } else if (isSupportedConcave(type)) {
    out.meshes.push_back({static_cast<const btConcaveShape*>(shape), local});
  } else {
    out.unsupported.emplace_back(shape->getName());
  }
}

struct NearestTriangle : btTriangleCallback {
  btVector3 point;
  btScalar best2 = std::numeric_limits<btScalar>::infinity();
  explicit NearestTriangle(const btVector3& p) : point(p) {}
  void processTriangle(btVector3* t, int, int) override {
    const btScalar d2 = (closestOnTriangle(point, t[0], t[1], t[2]) - point).length2();
    best2 = std::min(best2, d2);
  }
};

}  // namespace

std::shared_ptr<const ConvexHull> convexHullOf(const btConvexShape* shape) {
  if (shape == nullptr) return nullptr;
  std::vector<btVector3> points;
  const auto* poly = shape->isPolyhedral() ? static_cast<const btPolyhedralConvexShape*>(shape) : nullptr;
  if (poly != nullptr && poly->getNumVertices() >= 4) {
    for (int i = 0; i < poly->getNumVertices(); ++i) {
      btVector3 v;
      poly->getVertex(i, v);  // scaled, without margin
      points.push_back(v);
    }
  } else {
    for (const btVector3& d : sampleDirections())
      points.push_back(shape->localGetSupportingVertexWithoutMargin(d));
  }
  for (const btVector3& p : points)
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) return nullptr;
  btConvexHullComputer computer;
  computer.compute(&points[0].x(), sizeof(btVector3), static_cast<int>(points.size()), btScalar(0),
                   btScalar(0));
  if (computer.vertices.size() < 4 || computer.faces.size() < 4) return nullptr;
  std::vector<Vec3> vertices;
  Vec3 centre = Vec3::Zero();
  for (int i = 0; i < computer.vertices.size(); ++i) {
    vertices.push_back(toVec3(computer.vertices[i]));
    centre += vertices.back() / float(computer.vertices.size());
  }
  std::vector<Eigen::Vector4f> planes;
  for (int f = 0; f < computer.faces.size(); ++f) {
    // Newell's normal over the face's vertices (robust for faces of many nearly coplanar points).
    const btConvexHullComputer::Edge* start = &computer.edges[computer.faces[f]];
    const btConvexHullComputer::Edge* e = start;
    Eigen::Vector3d n = Eigen::Vector3d::Zero(), mean = Eigen::Vector3d::Zero();
    int count = 0;
    do {
      const Eigen::Vector3d a = vertices[std::size_t(e->getSourceVertex())].cast<double>();
      const Eigen::Vector3d b = vertices[std::size_t(e->getTargetVertex())].cast<double>();
      n += Eigen::Vector3d((a.y() - b.y()) * (a.z() + b.z()), (a.z() - b.z()) * (a.x() + b.x()),
                           (a.x() - b.x()) * (a.y() + b.y()));
      mean += a;
      ++count;
      e = e->getNextEdgeOfFace();
    } while (e != start && count < 1024);
    if (!(n.norm() > 1e-12)) continue;
    n.normalize();
    mean /= count;
    double offset = n.dot(mean);
    if (n.dot(centre.cast<double>()) > offset) {  // keep the normals outward
      n = -n;
      offset = -offset;
    }
    // Every vertex on the solid side (the face's points are coplanar only to rounding).
    for (const Vec3& v : vertices) offset = std::max(offset, n.dot(v.cast<double>()));
    planes.emplace_back(float(n.x()), float(n.y()), float(n.z()), float(offset));
  }
  std::shared_ptr<const ConvexHull> hull = ConvexHull::make(std::move(vertices), std::move(planes));
  return hull->validate().ok() ? hull : nullptr;
}

ShapeConversion convertShape(const btCollisionShape* shape, const btTransform& local) {
  ShapeConversion out;
  convertInto(out, shape, local);
  return out;
}

bool convexSignedDistance(const btConvexShape* shape, const btTransform& world, const btVector3& point,
                          btScalar& distance, btVector3& normal) {
  btGjkEpaSolver2::sResults r;
  const btScalar d = btGjkEpaSolver2::SignedDistance(point, btScalar(0), shape, world, r);
  if (!(d < std::numeric_limits<btScalar>::infinity()) || !std::isfinite(d)) return false;
  const btScalar len2 = r.normal.length2();
  if (!(len2 > btScalar(0.5)) || !std::isfinite(len2)) return false;
  // Outside the margin-less core GJK gives the distance to the surface with its margin; inside it, EPA runs
  // with the margins on (SignedDistance's default), so both are distances to the true surface.
  distance = d;
  normal = r.normal;
  return true;
}

btScalar shapeSignedDistance(const btCollisionShape* shape, const btTransform& world,
                             const btVector3& point) {
  constexpr btScalar kInf = std::numeric_limits<btScalar>::infinity();
  if (shape == nullptr) return kInf;
  const int type = shape->getShapeType();
  if (type == COMPOUND_SHAPE_PROXYTYPE) {
    const auto* c = static_cast<const btCompoundShape*>(shape);
    btScalar best = kInf;
    for (int i = 0; i < c->getNumChildShapes(); ++i)
      best = std::min(best, shapeSignedDistance(c->getChildShape(i), world * c->getChildTransform(i), point));
    return best;
  }
  if (type == STATIC_PLANE_PROXYTYPE) {
    const auto* p = static_cast<const btStaticPlaneShape*>(shape);
    return p->getPlaneNormal().dot(world.invXform(point)) - p->getPlaneConstant();
  }
  if (shape->isConvex()) {
    btScalar d = kInf;
    btVector3 n;
    return convexSignedDistance(static_cast<const btConvexShape*>(shape), world, point, d, n) ? d : kInf;
  }
  if (isSupportedConcave(type)) {
    const btVector3 p = world.invXform(point);
    const btVector3 reach(1, 1, 1);
    NearestTriangle nearest(p);
    static_cast<const btConcaveShape*>(shape)->processAllTriangles(&nearest, p - reach, p + reach);
    return std::sqrt(nearest.best2) - shape->getMargin();
  }
  return kInf;
}

}  // namespace cape::bullet
