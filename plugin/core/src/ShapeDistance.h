// Internal: the signed distance kernels of each collider shape, inlined into the solver's per-shape loops.
#pragma once

#include "cape/core/Collider.h"
#include "cape/core/Geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cape::detail {

inline Vec3 axisVector(int axis) {
  return Vec3::Unit(axis);
}

// The unit vector of p, or a fixed fallback when p is (nearly) zero, so that the push-out direction is always
// defined and deterministic.
inline Vec3 directionOr(const Vec3& p, const Vec3& fallback) {
  const float n = p.norm();
  return n > 1e-12f ? Vec3(p / n) : fallback;
}

inline SurfaceDistance boxDistance(const Vec3& h, const Vec3& p) {
  const Vec3 q = p.cwiseAbs() - h;
  if (q.maxCoeff() <= 0.0f) {
    // Inside: the nearest face is the one with the largest (least negative) q.
    int k = 0;
    q.maxCoeff(&k);
    Vec3 n = Vec3::Zero();
    n[k] = p[k] >= 0.0f ? 1.0f : -1.0f;
    return {q[k], n};
  }
  const Vec3 outside = q.cwiseMax(0.0f);
  const float d = outside.norm();
  Vec3 n = outside.cwiseProduct(p.cwiseSign()) / d;
  // cwiseSign gives 0 on a coordinate plane, but then that component of `outside` is 0 too.
  return {d, n};
}

inline SurfaceDistance cylinderDistance(float r, float hh, int axis, const Vec3& p) {
  const float t = p[axis];
  Vec3 radial = p;
  radial[axis] = 0.0f;
  const float rho = radial.norm();
  const Vec3 radialDir = directionOr(radial, axis == 0 ? Vec3::UnitY() : Vec3::UnitX());
  const float dr = rho - r;           // > 0 outside the infinite cylinder
  const float da = std::abs(t) - hh;  // > 0 beyond the caps
  const Vec3 capNormal = (t >= 0.0f ? 1.0f : -1.0f) * axisVector(axis);
  if (dr <= 0.0f && da <= 0.0f) {
    if (dr > da) return {dr, radialDir};
    return {da, capNormal};
  }
  if (dr > 0.0f && da > 0.0f) {
    const float d = std::hypot(dr, da);
    return {d, Vec3((dr * radialDir + da * capNormal) / d)};
  }
  if (dr > 0.0f) return {dr, radialDir};
  return {da, capNormal};
}

/// The largest plane distance of a convex hull and that plane's normal: the exact signed distance inside and
/// over a face, a lower bound of it beside an edge or a corner outside (so pushing a point out to a margin
/// by it keeps the point at least that far from the true surface).
inline SurfaceDistance hullDistance(const ConvexHull& h, const Vec3& p) {
  float best = -std::numeric_limits<float>::infinity();
  std::size_t k = 0;
  for (std::size_t i = 0; i < h.planes.size(); ++i) {
    const Eigen::Vector4f& q = h.planes[i];
    const float d = q[0] * p.x() + q[1] * p.y() + q[2] * p.z() - q[3];
    if (d > best) {
      best = d;
      k = i;
    }
  }
  return {best, h.planes.empty() ? Vec3::UnitY() : Vec3(h.planes[k].head<3>())};
}

/// Unsigned distance to the nearest triangle of a soup (+inf when it has none), and the direction to the
/// point from there.
inline SurfaceDistance meshDistance(const TriangleSoup& m, const Vec3& p) {
  SurfaceDistance best{std::numeric_limits<float>::infinity(), Vec3::UnitY()};
  for (std::size_t t = 0; t < m.size(); ++t) {
    const Vec3 &a = m.corners[3 * t], &b = m.corners[3 * t + 1], &c = m.corners[3 * t + 2];
    const TriangleNearest w = nearestOnTriangle(p, a, b, c);
    const Vec3 e = p - (w.wa * a + w.wb * b + w.wc * c);
    const float d = e.norm();
    if (d < best.distance) best = {d, directionOr(e, (b - a).cross(c - a).normalized())};
  }
  return best;
}

template <ColliderShape S>
inline SurfaceDistance shapeDistance(const Collider& c, const Vec3& p) {
  if constexpr (S == ColliderShape::Sphere) {
    return {p.norm() - c.radius, directionOr(p, Vec3::UnitY())};
  } else if constexpr (S == ColliderShape::Capsule) {
    Vec3 onAxis = Vec3::Zero();
    onAxis[c.axis] = std::clamp(p[c.axis], -c.halfHeight, c.halfHeight);
    const Vec3 off = p - onAxis;
    return {off.norm() - c.radius, directionOr(off, c.axis == 0 ? Vec3::UnitY() : Vec3::UnitX())};
  } else if constexpr (S == ColliderShape::Cylinder) {
    return cylinderDistance(c.radius, c.halfHeight, c.axis, p);
  } else if constexpr (S == ColliderShape::Box) {
    return boxDistance(c.halfExtents, p);
  } else if constexpr (S == ColliderShape::ConvexHull) {
    return hullDistance(*c.hull, p);
  } else {
    static_assert(S == ColliderShape::Plane, "triangle meshes have no closed-form distance: meshDistance");
    return {c.normal.dot(p) - c.constant, c.normal};
  }
}

/// The signed distance alone (no normal: no division), for the cheap rejection test.
template <ColliderShape S>
inline float shapeDistanceOnly(const Collider& c, const Vec3& p) {
  if constexpr (S == ColliderShape::Sphere) {
    return p.norm() - c.radius;
  } else if constexpr (S == ColliderShape::Capsule) {
    Vec3 off = p;
    off[c.axis] -= std::clamp(p[c.axis], -c.halfHeight, c.halfHeight);
    return off.norm() - c.radius;
  } else if constexpr (S == ColliderShape::Box) {
    const Vec3 q = p.cwiseAbs() - c.halfExtents;
    return q.maxCoeff() <= 0.0f ? q.maxCoeff() : q.cwiseMax(0.0f).norm();
  } else {
    return shapeDistance<S>(c, p).distance;
  }
}

}  // namespace cape::detail
