#include "cape/core/Types.h"

namespace cape {

bool Pose::isFinite() const {
  return position.allFinite() && rotation.coeffs().allFinite() &&
         std::abs(rotation.squaredNorm() - 1.0f) < 1e-3f;
}

Pose Pose::interpolate(const Pose& a, const Pose& b, float s) {
  if (s <= 0.0f) return a;
  if (s >= 1.0f) return b;
  Pose p;
  p.position = a.position + s * (b.position - a.position);
  p.rotation = a.rotation.slerp(s, b.rotation);  // Eigen's slerp takes the shortest arc.
  return p;
}

}  // namespace cape
