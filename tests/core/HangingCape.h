// The canonical cape (makeCapeRig) hung by its pins in front of a still torso box and two shoulder spheres:
// the sleeping and coarse-level tests' scene.
#pragma once

#include "cape/core/Cape.h"
#include "cape/scenes/Scene.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

namespace cape::test {

/// A pose at `position`, not turned.
inline Pose at(const Vec3& position) {
  Pose p;
  p.position = position;
  return p;
}

/// The canonical cape pinned by `layout` (its two top corners by default), at the walk's start placement.
struct Hanging {
  CapeRig rig;
  Cape cape;
  std::vector<Collider> colliders;

  explicit Hanging(const CapeSettings& settings, PinLayout layout = PinLayout::Corners)
      : rig(makeCapeRig(20, layout)), cape(rig.fabric, settings, capeStartPlacement(SceneKind::Walk)) {
    EXPECT_TRUE(cape.ok()) << cape.status().message();
    for (std::size_t k = 0; k < rig.pinnedParticles.size(); ++k)
      cape.pin(rig.pinnedParticles[k], rig.pinLocalPoints[k]);
    colliders.push_back(Collider::box(Vec3(0.18f, 0.3f, 0.1f), at(Vec3(0.0f, 1.2f, 0.0f))));
    colliders.push_back(Collider::sphere(0.08f, at(Vec3(-0.22f, 1.52f, 0.0f))));
    colliders.push_back(Collider::sphere(0.08f, at(Vec3(0.22f, 1.52f, 0.0f))));
  }
  /// Steps `count` frames of 1/60 s.
  void frames(int count) {
    for (int f = 0; f < count; ++f) cape.step(1.0f / 60.0f, colliders);
  }
  /// Moves every pin by `d` (the pins' targets at the end of the next step).
  void movePins(const Vec3& d) {
    for (std::size_t k = 0; k < cape.state().pins.size(); ++k)
      cape.movePin(k, cape.state().pins[k].target + d);
  }
};

}  // namespace cape::test
