// Shared helpers of the core tests, after Jolt's PhysicsTestContext: build a cape, Simulate() it for a
// while at a fixed step, and PredictPosition() where a particle free of constraints must end up.
#pragma once

#include "cape/core/Cape.h"
#include "cape/core/Fabric.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace cape::test {

/// Settings with nothing acting but what a test switches on: no gravity, no damping, no skin, no
/// friction, one substep of 1/60 s (never refined), no tethers.
inline CapeSettings quietSettings() {
  CapeSettings s;
  s.gravity = Vec3::Zero();
  s.damping = 0.0f;
  s.collisionThickness = 0.0f;
  s.friction = 0.0f;
  s.substeps = 1;
  s.iterations = 1;
  s.useTethers = false;
  s.timeStep = 1.0f / 60.0f;
  s.strainLimit = 0.0f;
  return s;
}

/// A grid fabric; fails the calling test if it cannot be built.
inline FabricPtr makeGrid(int columns, int rows, float width = 0.6f, float height = 1.0f,
                          float totalMass = 0.4f, bool bend = true, std::vector<std::uint32_t> anchors = {}) {
  GridDesc g;
  g.columns = columns;
  g.rows = rows;
  g.width = width;
  g.height = height;
  g.totalMass = totalMass;
  g.bendSprings = bend;
  g.tetherAnchors = std::move(anchors);
  FabricResult r = Fabric::grid(g);
  EXPECT_TRUE(r.status.ok()) << r.status.message();
  return r.fabric;
}

/// A cape, its colliders and a fixed step: Simulate() advances it, PredictPosition() is the closed-form
/// motion of a particle that nothing but gravity and damping acts on.
class CapeTestContext {
 public:
  CapeTestContext(FabricPtr fabric, const CapeSettings& settings, const Pose& placement = Pose(),
                  float frameTime = 1.0f / 60.0f)
      : cape_(std::move(fabric), settings, placement), frameTime_(frameTime) {
    EXPECT_TRUE(cape_.ok()) << cape_.status().message();
  }

  Cape& cape() { return cape_; }
  std::vector<Collider>& colliders() { return colliders_; }
  float frameTime() const { return frameTime_; }

  /// Steps whole frames covering `seconds`.
  void simulate(float seconds) {
    const int frames = static_cast<int>(std::lround(seconds / frameTime_));
    for (int f = 0; f < frames; ++f) cape_.step(frameTime_, colliders_);
  }

  /// Position after `steps` substeps of h of a free particle under acceleration a with linear damping c,
  /// integrated as the XPBD mode does: predict v' = v + h a, x <- x + h v', then damp v <- v' / (1 + c h).
  static Vec3 predictPosition(Vec3 x, Vec3 v, const Vec3& a, float c, float h, int steps) {
    for (int k = 0; k < steps; ++k) {
      v += h * a;
      x += h * v;
      v /= 1.0f + c * h;
    }
    return x;
  }

 private:
  Cape cape_;
  std::vector<Collider> colliders_;
  float frameTime_;
};

/// 64-bit FNV-1a over the bytes of a matrix: a determinism fingerprint.
inline std::uint64_t hashPoints(const Points& p) {
  std::uint64_t h = 1469598103934665603ull;
  const auto* bytes = reinterpret_cast<const unsigned char*>(p.data());
  const std::size_t n = static_cast<std::size_t>(p.size()) * sizeof(float);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= bytes[i];
    h *= 1099511628211ull;
  }
  return h;
}

inline Vec3 row(const Points& p, Eigen::Index i) {
  return p.row(i).transpose();
}

}  // namespace cape::test
