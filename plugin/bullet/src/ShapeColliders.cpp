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
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

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
      // Bullet's multi-sphere is the convex hull of its spheres, not their union: the spheres are swept by
      // the core (fast motion), and GJK keeps particles out of the hull between them after the step.
      out.convex.push_back({shape, local});
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
    out.convex.push_back({shape, local});
  } else if (isSupportedConcave(type)) {
    out.concave.push_back({shape, local});
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
