#include "cape/core/ColliderRecord.h"

#include <cstring>

namespace cape {

static_assert(sizeof(std::uintptr_t) <= 8, "a pointer fits the key's 8-byte words");

ColliderRecord::Key ColliderRecord::keyOf(const Collider& c) {
  static_assert(sizeof(Key) == 3 * 8 + 28 * 4, "Key has no padding");
  Key k;
  k.hull = reinterpret_cast<std::uintptr_t>(c.hull.get());
  k.triangles = reinterpret_cast<std::uintptr_t>(c.triangles.get());
  k.cornerCount = c.triangles ? c.triangles->corners.size() : 0;
  const float v[28] = {static_cast<float>(c.shape),
                       c.radius,
                       c.halfHeight,
                       static_cast<float>(c.axis),
                       c.halfExtents.x(),
                       c.halfExtents.y(),
                       c.halfExtents.z(),
                       c.normal.x(),
                       c.normal.y(),
                       c.normal.z(),
                       c.constant,
                       c.thickness,
                       c.friction,
                       c.current.position.x(),
                       c.current.position.y(),
                       c.current.position.z(),
                       c.current.rotation.x(),
                       c.current.rotation.y(),
                       c.current.rotation.z(),
                       c.current.rotation.w(),
                       c.previous.position.x(),
                       c.previous.position.y(),
                       c.previous.position.z(),
                       c.previous.rotation.x(),
                       c.previous.rotation.y(),
                       c.previous.rotation.z(),
                       c.previous.rotation.w(),
                       0.0f};
  std::memcpy(k.v, v, sizeof(v));
  return k;
}

void ColliderRecord::remember(ColliderSpan colliders) {
  keys_.clear();
  corners_.clear();
  for (const Collider& c : colliders) {
    keys_.push_back(keyOf(c));
    if (c.triangles)
      corners_.insert(corners_.end(), c.triangles->corners.begin(), c.triangles->corners.end());
  }
}

bool ColliderRecord::same(ColliderSpan colliders) const {
  if (colliders.size != keys_.size()) return false;
  std::size_t corner = 0;
  for (std::size_t k = 0; k < colliders.size; ++k) {
    const Collider& c = colliders.data[k];
    const Key key = keyOf(c);
    if (std::memcmp(&key, &keys_[k], sizeof(Key)) != 0) return false;
    if (c.triangles) {
      const std::vector<Vec3>& v = c.triangles->corners;
      if (!v.empty() && std::memcmp(v.data(), corners_.data() + corner, v.size() * sizeof(Vec3)) != 0)
        return false;
      corner += v.size();
    }
  }
  return true;
}

}  // namespace cape
