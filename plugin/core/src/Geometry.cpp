#include "cape/core/Geometry.h"

#include <cmath>

namespace cape {

TriangleNearest nearestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return {1, 0, 0, false};  // corner a
  const Vec3 bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0f && d4 <= d3) return {0, 1, 0, false};  // corner b
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {  // edge ab
    const float v = d1 / (d1 - d3);
    return {1 - v, v, 0, false};
  }
  const Vec3 cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0f && d5 <= d6) return {0, 0, 1, false};  // corner c
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {  // edge ac
    const float w = d2 / (d2 - d6);
    return {1 - w, 0, w, false};
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {  // edge bc
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w, false};
  }
  const float denom = va + vb + vc;
  if (!(std::fabs(denom) > 0.0f)) return {1, 0, 0, false};
  const float v = vb / denom, w = vc / denom;
  return {1 - v - w, v, w, true};
}

}  // namespace cape
