// Google Benchmark over the cape step in the canonical scenes of docs/SCENES.md (simple body, no
// Bullet), for N x N capes. One benchmark iteration is one 1/60 s frame: the body and pins move, then the
// cape steps. BM_WalkFrame keeps the substeps fixed (3 per frame: the cost of the step itself, and how it
// scales with N); BM_WalkFrameAdaptive uses the default strain-adaptive substepping, which refines larger
// capes (more rows for one Gauss-Seidel pass to carry) to hold the strain under 5 %. Reported: time per frame
// and particles per second.
#include "cape/core/FabricPresets.h"
#include "cape/core/Simd.h"
#include "cape/scenes/Scene.h"

#include <benchmark/benchmark.h>

namespace {

using namespace cape;

void runFrames(benchmark::State& state, SceneKind kind, const CapeSettings& settings) {
  const int n = static_cast<int>(state.range(0));
  SimpleScene scene(kind, n, PinLayout::Corners, settings);
  if (!scene.status().ok()) {
    state.SkipWithError(scene.status().message().c_str());
    return;
  }
  // Warm up one simulated second so that the cape is in contact with the body, as in the demos.
  for (int f = 0; f < 60; ++f) scene.advanceFrame();
  int frames = 0;
  const std::uint64_t searchesBefore = scene.cape().selfContactSearches();
  const std::uint64_t provenBefore = scene.cape().selfContactSearchesProvenApart();
  std::uint64_t searches = 0, proven = 0;  // the scene restarts every 540 frames: counted across restarts
  for (auto _ : state) {
    scene.advanceFrame();
    benchmark::DoNotOptimize(scene.cape().state().positions.data());
    // Loop the 10 s scene so long runs measure the same motion.
    if (++frames % 540 == 0) {
      searches += scene.cape().selfContactSearches();
      proven += scene.cape().selfContactSearchesProvenApart();
      scene = SimpleScene(kind, n, PinLayout::Corners, settings);
    }
  }
  state.counters["particles"] = static_cast<double>(n) * n;
  if (settings.selfCollision && frames > 0) {
    // Self-contact searches per frame: one while the cape is calm, more while it outruns a spacing per frame.
    searches += scene.cape().selfContactSearches();
    proven += scene.cape().selfContactSearchesProvenApart();
    state.counters["searches_per_frame"] = static_cast<double>(searches - searchesBefore) / frames;
    // Of those, the ones the flat proof passed over (SelfCollision::provenApart).
    state.counters["proven_apart_per_frame"] = static_cast<double>(proven - provenBefore) / frames;
  }
  state.counters["particles_per_s"] = benchmark::Counter(
      static_cast<double>(n) * n * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

CapeSettings fixedSubsteps() {
  CapeSettings s;
  s.strainLimit = 0.0f;
  return s;
}

void BM_WalkFrame(benchmark::State& state) {
  runFrames(state, SceneKind::Walk, fixedSubsteps());
}
void BM_WalkFrameAdaptive(benchmark::State& state) {
  runFrames(state, SceneKind::Walk, CapeSettings());
}
void BM_WalkFrame4Substeps(benchmark::State& state) {
  CapeSettings s = fixedSubsteps();
  s.substeps = 4;
  runFrames(state, SceneKind::Walk, s);
}
// The walk's fixed-substep frame with the kernels of one instruction set (Simd.h), the second argument: 0
// portable (four lanes), 1 AVX2 (eight lanes; skipped where the processor has none). The same bits either
// way.
void BM_WalkFrameSimd(benchmark::State& state) {
  const SimdLevel level = state.range(1) == 1 ? SimdLevel::Avx2 : SimdLevel::Portable;
  const SimdLevel before = simdLevel();
  if (!setSimdLevel(level).ok()) {
    state.SkipWithError("this processor has no AVX2 kernels");
    return;
  }
  runFrames(state, SceneKind::Walk, fixedSubsteps());
  (void)setSimdLevel(before);
}
// The walk in wool (FabricPresets.h), as cape_walk's default cape is: the linear bending hinges on, the bend
// springs off; fixed substeps. The material at the grid's mean spacing (the scene's cape is 0.6 x 1 m).
void BM_WalkFrameWool(benchmark::State& state) {
  const float spacing = 0.8f / static_cast<float>(state.range(0) - 1);
  runFrames(state, SceneKind::Walk, applyFabric(*findFabric("wool"), spacing, fixedSubsteps()));
}
// Self-collision on (issue 6: at most twice the step without it), the walk and the sprint-turn.
void BM_WalkFrameSelfCollision(benchmark::State& state) {
  CapeSettings s = fixedSubsteps();
  s.selfCollision = true;
  runFrames(state, SceneKind::Walk, s);
}
void BM_SprintTurnFrameSelfCollision(benchmark::State& state) {
  CapeSettings s;
  s.selfCollision = true;
  runFrames(state, SceneKind::SprintTurn, s);
}
// The sprint-turn without self-collision at the sizes the self-collision benchmark also runs (its ratio's
// denominator; BM_SprintTurnFrame runs the 20 x 20 cape only).
void BM_SprintTurnFrameSelfCollisionOff(benchmark::State& state) {
  runFrames(state, SceneKind::SprintTurn, CapeSettings());
}
void BM_SprintTurnFrame(benchmark::State& state) {
  runFrames(state, SceneKind::SprintTurn, CapeSettings());
}
void BM_SprintTurnFrameFixed(benchmark::State& state) {
  runFrames(state, SceneKind::SprintTurn, fixedSubsteps());
}
// Strain limiting (CapeSettings::strainCeiling, 10 %, one pass) beside BM_SprintTurnFrame and
// BM_WalkFrame: what the pass costs, and what the refinement it spares saves.
void BM_SprintTurnFrameStrainCeiling(benchmark::State& state) {
  CapeSettings s;
  s.strainCeiling = 0.1f;
  runFrames(state, SceneKind::SprintTurn, s);
}
void BM_WalkFrameStrainCeiling(benchmark::State& state) {
  CapeSettings s = fixedSubsteps();
  s.strainCeiling = 0.1f;
  runFrames(state, SceneKind::Walk, s);
}
void BM_WalkFrameSeedExplicit(benchmark::State& state) {
  CapeSettings s = CapeSettings::unitySeed();
  s.timeStep = 1.0f / 60.0f;
  s.substeps =
      8;  // the seed's 0.00875 s step would need ~2 steps per 1/60 s frame; 8 keeps it stable at N = 64
  runFrames(state, SceneKind::Walk, s);
}

// Sleeping (CapeSettings::sleepSpeed): the hang scene settled for 20 s, then one frame, asleep (the default)
// against never sleeping. Counter "asleep": 1 when the timed frames slept.
void BM_HangSettled(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  CapeSettings settings;
  if (state.range(1) == 0) settings.sleepSpeed = 0.0f;
  SimpleScene scene(SceneKind::Hang, n, PinLayout::Corners, settingsForScene(SceneKind::Hang, settings));
  if (!scene.status().ok()) {
    state.SkipWithError(scene.status().message().c_str());
    return;
  }
  for (int f = 0; f < 1200; ++f) scene.advanceFrame();
  for (auto _ : state) {
    scene.advanceFrame();
    benchmark::DoNotOptimize(scene.cape().state().positions.data());
  }
  state.counters["asleep"] = scene.cape().isAsleep() ? 1.0 : 0.0;
}

}  // namespace

BENCHMARK(BM_HangSettled)
    ->ArgNames({"n", "sleep"})
    ->ArgsProduct({{20, 64}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WalkFrame)->Arg(20)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WalkFrameAdaptive)->Arg(20)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WalkFrameWool)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WalkFrame4Substeps)->Arg(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WalkFrameSimd)
    ->ArgNames({"n", "avx2"})
    ->Args({20, 0})
    ->Args({20, 1})
    ->Args({64, 0})
    ->Args({64, 1})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WalkFrameSelfCollision)->Arg(20)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SprintTurnFrameSelfCollision)->Arg(20)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SprintTurnFrameSelfCollisionOff)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SprintTurnFrame)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SprintTurnFrameFixed)->Arg(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SprintTurnFrameStrainCeiling)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WalkFrameStrainCeiling)->Arg(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WalkFrameSeedExplicit)->Arg(20)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
