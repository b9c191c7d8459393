// Determinism: the same inputs give the same bits, whichever order capes are stepped in.
#include "CapeTestFixture.h"

#include "cape/scenes/Scene.h"

namespace cape {
namespace {

std::uint64_t runScene(SceneKind kind, const CapeSettings& s, int frames) {
  SimpleScene scene(kind, 16, PinLayout::Corners, s);
  EXPECT_TRUE(scene.status().ok());
  for (int i = 0; i < frames; ++i) scene.advanceFrame();
  return test::hashPoints(scene.cape().state().positions) ^
         (test::hashPoints(scene.cape().state().velocities) << 1);
}

TEST(Determinism, TwoRunsGiveIdenticalBits) {
  for (SceneKind kind : {SceneKind::Walk, SceneKind::SprintTurn, SceneKind::Hang}) {
    const std::uint64_t a = runScene(kind, CapeSettings(), 120);
    const std::uint64_t b = runScene(kind, CapeSettings(), 120);
    EXPECT_EQ(a, b) << toString(kind);
  }
  CapeSettings seed = CapeSettings::unitySeed();
  seed.timeStep = 1.0f / 60.0f;
  EXPECT_EQ(runScene(SceneKind::Walk, seed, 60), runScene(SceneKind::Walk, seed, 60));
}

TEST(Determinism, InterleavedCapesDoNotInfluenceEachOther) {
  const std::uint64_t alone = runScene(SceneKind::Walk, CapeSettings(), 60);
  SimpleScene a(SceneKind::Walk, 16, PinLayout::Corners, CapeSettings());
  SimpleScene b(SceneKind::SprintTurn, 16, PinLayout::Collar, CapeSettings());
  for (int i = 0; i < 60; ++i) {
    b.advanceFrame();
    a.advanceFrame();
  }
  EXPECT_EQ(
      test::hashPoints(a.cape().state().positions) ^ (test::hashPoints(a.cape().state().velocities) << 1),
      alone);
}

TEST(Determinism, DifferentInputsGiveDifferentBits) {
  CapeSettings stiff;
  stiff.structuralStiffness *= 2.0f;
  EXPECT_NE(runScene(SceneKind::Walk, CapeSettings(), 30), runScene(SceneKind::Walk, stiff, 30));
}

}  // namespace
}  // namespace cape
