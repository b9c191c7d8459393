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

#include "cape/core/CapeState.h"

namespace cape {

namespace {
void fnv1a(std::uint64_t& h, const Points& p) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(p.data());
  const std::size_t n = static_cast<std::size_t>(p.size()) * sizeof(float);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= bytes[i];
    h *= 1099511628211ull;
  }
}
}  // namespace

std::uint64_t stateHash(const CapeState& state) {
  std::uint64_t h = 1469598103934665603ull;
  fnv1a(h, state.positions);
  fnv1a(h, state.velocities);
  return h;
}

}  // namespace cape
