// Stored determinism hashes of the canonical scenes on the simple body: a refactor of the solver must keep
// every bit of them. A change of behaviour on purpose updates the table in the same commit and says why in
// its message. (Hashes are of this toolchain's IEEE single-precision arithmetic with -ffp-contract=off: the
// same on every x86-64 build of the core, Release or Debug, and at every instruction set of the kernels.)
#include "cape/core/Simd.h"
#include "cape/scenes/Scene.h"

#include <gtest/gtest.h>

#include <cinttypes>
#include <cstdio>

namespace cape {
namespace {

struct StoredScene {
  SceneKind kind;
  bool selfCollision;
  std::uint64_t hash;
};

// 20 x 20 canonical cape, corner attachment, default settings, 180 frames of 1/60 s (a sprint-turn's first
// turn is in frames 90..120).
constexpr StoredScene kStored[] = {
    {SceneKind::Hang, false, 0xa3645b1981244dbeull},
    {SceneKind::Hang, true, 0xa3645b1981244dbeull},
    {SceneKind::Walk, false, 0x5faab71c43d1e6baull},
    {SceneKind::Walk, true, 0x5faab71c43d1e6baull},
    {SceneKind::SprintTurn, false, 0x2fcd9ebd0d75753dull},
    {SceneKind::SprintTurn, true, 0x59156db563773d5cull},
    {SceneKind::Wind, false, 0x7132717a08c6698aull},
    {SceneKind::Wind, true, 0x6fafb93a52a5ffc7ull},
};

std::uint64_t runScene(SceneKind kind, bool selfCollision) {
  CapeSettings settings;
  settings.selfCollision = selfCollision;
  SimpleScene scene(kind, 20, PinLayout::Corners, settingsForScene(kind, settings));
  EXPECT_TRUE(scene.status().ok());
  for (int f = 0; f < 180; ++f) scene.advanceFrame();
  return stateHash(scene.cape().state());
}

TEST(StoredHashes, EveryCanonicalSceneKeepsItsBits) {
  // With the portable kernels, and with the eight-wide ones where this processor has them (Simd.h): the
  // same table, since every level gives the same bits.
  const SimdLevel before = simdLevel();
  for (const SimdLevel level : {SimdLevel::Portable, SimdLevel::Avx2}) {
    if (!setSimdLevel(level).ok()) continue;
    for (const StoredScene& s : kStored) {
      const std::uint64_t h = runScene(s.kind, s.selfCollision);
      EXPECT_EQ(h, s.hash) << toString(s.kind) << (s.selfCollision ? " with" : " without")
                           << " self-collision, " << simdLevelName(level) << " kernels: 0x" << std::hex << h;
    }
  }
  ASSERT_TRUE(setSimdLevel(before).ok());
}

}  // namespace
}  // namespace cape
