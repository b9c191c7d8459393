// What a sleeping cape remembers of the colliders it fell asleep among, to know on every later step, in a
// comparison of a few hundred bytes, whether they are still exactly those (internal to the core).
#pragma once

#include "cape/core/Cape.h"

#include <cstdint>
#include <cstring>
#include <vector>

namespace cape::detail {

class SleepRecord {
 public:
  /// Remembers the colliders (their shapes, sizes, materials, current poses and shared data, a triangle
  /// mesh's corners included). Allocates only when a cape first falls asleep among more than before.
  void remember(ColliderSpan colliders) {
    keys_.clear();
    corners_.clear();
    for (const Collider& c : colliders) {
      keys_.push_back(keyOf(c));
      if (c.triangles)
        corners_.insert(corners_.end(), c.triangles->corners.begin(), c.triangles->corners.end());
    }
  }
  /// Whether `colliders` are bit for bit the ones remembered, in the same order.
  bool same(ColliderSpan colliders) const {
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

 private:
  // Padding-free: three 8-byte words, then 4-byte floats only (an even number of them), so memcmp compares
  // values and nothing else.
  struct Key {
    std::uintptr_t hull;
    std::uintptr_t triangles;
    std::uint64_t cornerCount;
    float v[22];
  };
  static_assert(sizeof(Key) == 3 * 8 + 22 * 4, "Key has no padding");

  static Key keyOf(const Collider& c) {
    Key k;
    k.hull = reinterpret_cast<std::uintptr_t>(c.hull.get());
    k.triangles = reinterpret_cast<std::uintptr_t>(c.triangles.get());
    k.cornerCount = c.triangles ? c.triangles->corners.size() : 0;
    const float v[22] = {static_cast<float>(c.shape),
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
                         0.0f,
                         0.0f};
    std::memcpy(k.v, v, sizeof(v));
    return k;
  }

  std::vector<Key> keys_;
  std::vector<Vec3> corners_;
};

}  // namespace cape::detail
