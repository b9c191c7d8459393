// Google Benchmark over the per-frame metrics the demos measure every frame (measureFrame), the old way
// against the new: the self-intersection count by the old sweep and prune along x (which degenerates for a
// vertical cape, every column overlapping every other in x) against the spatial hash of
// SelfIntersectionCounter, and the penetration over every particle and collider against the culled
// maxPenetration. The old ones live here only, for this comparison; each benchmark checks that both give the
// same figure.
//
// States: the 20 x 20 cape of the walk after 2 s, and the 64 x 64 cape of the sprint-turn (self-collision
// off, so that it folds through itself) in its turn after 1.9 s, both on the simple body's colliders;
// BM_CountRun counts every frame of those runs in turn, with the count's flat proof (proof:1) and without it
// (proof:0).
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace {

using namespace cape;

// --- The old implementations ---------------------------------------------------------------------------

/// The count as it was: boxes sorted by their least x, each against the following ones while they overlap
/// in x.
class SweepAndPruneCounter {
 public:
  int count(const Fabric& fabric, const Points& x) {
    const std::vector<std::uint32_t>& tri = fabric.triangles();
    const std::size_t nt = tri.size() / 3;
    boxes_.resize(nt);
    for (std::size_t t = 0; t < nt; ++t) {
      const Vec3 a = x.row(tri[3 * t]), b = x.row(tri[3 * t + 1]), c = x.row(tri[3 * t + 2]);
      boxes_[t] = {a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c), static_cast<std::uint32_t>(t)};
    }
    std::sort(boxes_.begin(), boxes_.end(), [](const Box& l, const Box& r) {
      return l.lo.x() < r.lo.x() || (l.lo.x() == r.lo.x() && l.triangle < r.triangle);
    });
    int found = 0;
    for (std::size_t i = 0; i < nt; ++i) {
      const Box& bi = boxes_[i];
      const std::uint32_t* ti = &tri[3 * bi.triangle];
      for (std::size_t j = i + 1; j < nt && boxes_[j].lo.x() <= bi.hi.x(); ++j) {
        const Box& bj = boxes_[j];
        if (bj.lo.y() > bi.hi.y() || bj.hi.y() < bi.lo.y() || bj.lo.z() > bi.hi.z() || bj.hi.z() < bi.lo.z())
          continue;
        const std::uint32_t* tj = &tri[3 * bj.triangle];
        bool shares = false;
        for (int a = 0; a < 3 && !shares; ++a)
          for (int b = 0; b < 3; ++b) shares = shares || ti[a] == tj[b];
        if (shares) continue;
        if (trianglesIntersect(x.row(ti[0]), x.row(ti[1]), x.row(ti[2]), x.row(tj[0]), x.row(tj[1]),
                               x.row(tj[2])))
          ++found;
      }
    }
    return found;
  }

 private:
  struct Box {
    Eigen::Vector3f lo, hi;
    std::uint32_t triangle;
  };
  std::vector<Box> boxes_;
};

/// The penetration as it was: every particle against every valid collider.
float unculledPenetration(const Points& x, ColliderSpan colliders) {
  float worst = 0.0f;
  for (const Collider& c : colliders) {
    if (!c.validate().ok()) continue;
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      worst = std::max(worst, -signedDistance(c, x.row(i).transpose()));
  }
  return worst;
}

/// measureFrame as it was, from the old pieces and the library's unchanged ones.
FrameMetrics oldMeasureFrame(const Fabric& fabric, const Points& x, const Points& v,
                             const std::vector<Pin>& pins, ColliderSpan bodyColliders,
                             const Vec3& torsoCentre, SweepAndPruneCounter& counter) {
  FrameMetrics m;
  m.blowUp = isBlownUp(x, torsoCentre);
  if (m.blowUp) return m;
  const StrainStats s = structuralStrain(fabric, x);
  m.maxStrain = s.max;
  m.meanStrain = s.mean;
  m.maxPenetration = unculledPenetration(x, bodyColliders);
  m.pinError = maxPinError(x, pins);
  m.meanSpeed = v.rows() > 0 ? static_cast<float>(v.rowwise().norm().mean()) : 0.0f;
  m.selfIntersections = counter.count(fabric, x);
  return m;
}

// --- The states ----------------------------------------------------------------------------------------

/// A scene stepped to its measured frame: range 20 is the walk's 20 x 20 cape at frame 120, range 64 the
/// sprint-turn's 64 x 64 cape at frame 114 (mid-turn), self-collision off.
const SimpleScene& sceneFor(int n) {
  static std::vector<std::pair<int, std::unique_ptr<SimpleScene>>> scenes;
  for (const auto& s : scenes)
    if (s.first == n) return *s.second;
  CapeSettings settings;
  settings.selfCollision = false;
  const SceneKind kind = n == 20 ? SceneKind::Walk : SceneKind::SprintTurn;
  auto scene = std::make_unique<SimpleScene>(kind, n, PinLayout::Corners, settings);
  const int frames = n == 20 ? 120 : 114;
  for (int f = 0; f < frames; ++f) scene->advanceFrame();
  scenes.emplace_back(n, std::move(scene));
  return *scenes.back().second;
}

void report(benchmark::State& state, const SimpleScene& scene, double figure) {
  state.counters["particles"] = static_cast<double>(scene.cape().state().positions.rows());
  state.counters["figure"] = figure;
}

// --- The benchmarks ------------------------------------------------------------------------------------

void BM_CountOld(benchmark::State& state) {
  const SimpleScene& scene = sceneFor(static_cast<int>(state.range(0)));
  const Fabric& f = scene.cape().fabric();
  const Points& x = scene.cape().state().positions;
  SweepAndPruneCounter old;
  int found = 0;
  for (auto _ : state) benchmark::DoNotOptimize(found = old.count(f, x));
  report(state, scene, found);
}

void BM_CountNew(benchmark::State& state) {
  const SimpleScene& scene = sceneFor(static_cast<int>(state.range(0)));
  const Fabric& f = scene.cape().fabric();
  const Points& x = scene.cape().state().positions;
  SelfIntersectionCounter counter;
  SweepAndPruneCounter old;
  if (counter.count(f, x) != old.count(f, x)) {
    state.SkipWithError("the counts differ");
    return;
  }
  int found = 0;
  for (auto _ : state) benchmark::DoNotOptimize(found = counter.count(f, x));
  report(state, scene, found);
}

void BM_PenetrationOld(benchmark::State& state) {
  const SimpleScene& scene = sceneFor(static_cast<int>(state.range(0)));
  const Points& x = scene.cape().state().positions;
  float worst = 0.0f;
  for (auto _ : state) benchmark::DoNotOptimize(worst = unculledPenetration(x, scene.body().bodyColliders()));
  report(state, scene, worst);
}

void BM_PenetrationNew(benchmark::State& state) {
  const SimpleScene& scene = sceneFor(static_cast<int>(state.range(0)));
  const Points& x = scene.cape().state().positions;
  if (maxPenetration(x, scene.body().bodyColliders()) !=
      unculledPenetration(x, scene.body().bodyColliders())) {
    state.SkipWithError("the penetrations differ");
    return;
  }
  float worst = 0.0f;
  for (auto _ : state) benchmark::DoNotOptimize(worst = maxPenetration(x, scene.body().bodyColliders()));
  report(state, scene, worst);
}

void BM_MeasureFrameOld(benchmark::State& state) {
  const SimpleScene& scene = sceneFor(static_cast<int>(state.range(0)));
  const CapeState& st = scene.cape().state();
  SweepAndPruneCounter old;
  FrameMetrics m;
  for (auto _ : state) {
    m = oldMeasureFrame(scene.cape().fabric(), st.positions, st.velocities, st.pins,
                        scene.body().bodyColliders(), scene.body().torsoCentre(), old);
    benchmark::DoNotOptimize(m);
  }
  report(state, scene, m.selfIntersections);
}

void BM_MeasureFrameNew(benchmark::State& state) {
  const SimpleScene& scene = sceneFor(static_cast<int>(state.range(0)));
  SelfIntersectionCounter counter;
  FrameMetrics m;
  for (auto _ : state) {
    m = measureFrame(scene.cape(), scene.body().bodyColliders(), scene.body().torsoCentre(), &counter);
    benchmark::DoNotOptimize(m);
  }
  report(state, scene, m.selfIntersections);
}

// The fold statistics (FoldMeter: every interior edge's dihedral angle and its change), which cape_walk
// measures on its first cape every frame.
void BM_FoldMeter(benchmark::State& state) {
  const SimpleScene& scene = sceneFor(static_cast<int>(state.range(0)));
  FoldMeter folds;
  FoldStats f;
  for (auto _ : state) {
    f = folds.measure(scene.cape().fabric(), scene.cape().state().positions);
    benchmark::DoNotOptimize(f);
  }
  report(state, scene, static_cast<double>(f.meanDihedral));
}

// FrameMeter on a frame whose inputs are the last one's (a cape asleep among still bodies): the comparison
// that replaces measuring it.
void BM_FrameMeterReused(benchmark::State& state) {
  const SimpleScene& scene = sceneFor(static_cast<int>(state.range(0)));
  FrameMeter meter(true);
  FrameMetrics m = meter.measure(scene.cape(), scene.body().bodyColliders(), scene.body().torsoCentre());
  for (auto _ : state) {
    m = meter.measure(scene.cape(), scene.body().bodyColliders(), scene.body().torsoCentre());
    benchmark::DoNotOptimize(m);
  }
  if (!meter.lastReused()) state.SkipWithError("the frame was measured again");
  report(state, scene, m.maxStrain);
}

/// A whole run: the walk's 20 x 20 cape (10 s) or the sprint-turn's 64 x 64 cape (4 s), self-collision
/// off, its fabric and every frame's positions.
struct Run {
  FabricPtr fabric;
  std::vector<Points> frames;
};
const Run& runFor(int n) {
  static std::vector<std::pair<int, Run>> runs;
  for (const auto& r : runs)
    if (r.first == n) return r.second;
  CapeSettings settings;
  settings.selfCollision = false;
  SimpleScene scene(n == 20 ? SceneKind::Walk : SceneKind::SprintTurn, n, PinLayout::Corners, settings);
  std::vector<Points> frames;
  for (int f = 0; f < (n == 20 ? 600 : 240); ++f) {
    scene.advanceFrame();
    frames.push_back(scene.cape().state().positions);
  }
  runs.emplace_back(n, Run{scene.cape().fabricPtr(), std::move(frames)});
  return runs.back().second;
}

// The count frame after frame over a run (each iteration the next frame, from the first again after the
// last), as the demos count: the states of a whole walk or sprint-turn rather than one.
void BM_CountRun(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Run& run = runFor(n);
  const std::vector<Points>& frames = run.frames;
  const Fabric& fabric = *run.fabric;
  SelfIntersectionCounter counter;
  counter.setFlatProof(state.range(1) != 0);
  std::size_t next = 0;
  std::int64_t found = 0;
  for (auto _ : state) {
    found += counter.count(fabric, frames[next]);
    next = next + 1 == frames.size() ? 0 : next + 1;
  }
  benchmark::DoNotOptimize(found);
  state.counters["particles"] = static_cast<double>(frames.front().rows());
  state.counters["proven"] =  // the share of counts the flat proof settled
      static_cast<double>(counter.countsProvenApart()) /
      static_cast<double>(std::max<benchmark::IterationCount>(state.iterations(), 1));
  state.counters["figure"] =  // intersecting pairs a frame, on average over the frames counted
      static_cast<double>(found) /
      static_cast<double>(std::max<benchmark::IterationCount>(state.iterations(), 1));
}

BENCHMARK(BM_CountOld)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CountNew)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CountRun)
    ->ArgNames({"n", "proof"})
    ->Args({20, 0})
    ->Args({20, 1})
    ->Args({64, 0})
    ->Args({64, 1})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PenetrationOld)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PenetrationNew)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MeasureFrameOld)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MeasureFrameNew)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FoldMeter)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FrameMeterReused)->Arg(20)->Arg(64)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
