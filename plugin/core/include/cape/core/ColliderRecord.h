/// \file
/// ColliderRecord: a bit-for-bit record of a list of colliders, to know later, in a comparison of a few
/// hundred bytes, whether a list is still exactly that one. For whoever reuses what it computed from
/// colliders that have not changed: a sleeping cape (Cape::step) and the demos' metrics (FrameMeter).
#pragma once

#include "cape/core/Cape.h"
#include "cape/core/Export.h"

#include <cstdint>
#include <vector>

namespace cape {

/// Remembers colliders bit for bit: their shapes, sizes, skins, frictions, both poses, the shared hull (by
/// address: a ConvexHull is immutable) and a triangle mesh's corners (by value: its soup is refilled in
/// place between steps). Not their names.
class CAPE_CORE_API ColliderRecord {
 public:
  /// Remembers `colliders`. Allocates only when it remembers more than ever before.
  void remember(ColliderSpan colliders);
  /// Whether `colliders` are bit for bit the ones remembered, in the same order (NaNs of the same bits are
  /// the same; 0 and -0 are not).
  bool same(ColliderSpan colliders) const;

 private:
  // Padding-free: three 8-byte words, then 4-byte floats only (an even number of them), so that memcmp
  // compares values and nothing else.
  struct Key {
    std::uintptr_t hull;
    std::uintptr_t triangles;
    std::uint64_t cornerCount;
    float v[28];
  };
  static Key keyOf(const Collider& c);

  std::vector<Key> keys_;
  std::vector<Vec3> corners_;
};

}  // namespace cape
