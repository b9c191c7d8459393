// Google Benchmark of the walk far from the world's origin (issue 14): docs/SCENES.md's walk on kinematic
// Bullet bodies (tests/bullet/BulletFixture.h's SimpleWalk), the whole scene moved by `km` kilometres along
// -Z (the walking direction) or along every axis (`axes`:3), the cape in its own frame (the default,
// CapeActionSettings::frameSpacing = 16 m) or in the world's (`frame`:0, spacing 0). One iteration is one
// frame, stepSimulation(1/60, 8, 1/240), after a simulated second of warm-up.
//
// Reported: cape_us, the cape's own time per frame (prepare and advance), cape_us_p50 its median, and
// strain_p50 / strain_p95, the median and 95th percentile over the frames of the per-frame max structural
// strain (docs/SCENES.md). With its own frame the cape costs and stretches as at the origin, up to what
// Bullet's float poses carry out there (100 km: 4 mm steps); in the world's frame its particles take
// float's steps too (10 km: 1 mm against a 3.2 cm spring).
#include "../bullet/BulletFixture.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

namespace {

using namespace capetest;

double percentileOf(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

void BM_FarWalkFrame(benchmark::State& state) {
  const double km = static_cast<double>(state.range(0));
  const bool everyAxis = state.range(1) == 3;
  const bool ownFrame = state.range(2) == 1;
  const btScalar d = btScalar(1000.0 * km);
  World w;
  cape::bullet::CapeActionSettings settings;
  settings.frameSpacing = ownFrame ? btScalar(16) : btScalar(0);
  SimpleWalk walk(w, everyAxis ? btVector3(d, d, -d) : btVector3(0, 0, -d), settings);
  for (int k = 0; k < 60; ++k) walk.advance();
  walk.action->takeAccumulatedMicroseconds();
  std::vector<double> cape, strain;
  cape.reserve(1 << 16);
  strain.reserve(1 << 16);
  for (auto _ : state) {
    walk.advance();
    cape.push_back(walk.action->takeAccumulatedMicroseconds());
    strain.push_back(static_cast<double>(maxStructuralStrain(walk.action->cape())));
  }
  double sum = 0.0;
  for (double t : cape) sum += t;
  state.counters["cape_us"] = cape.empty() ? 0.0 : sum / static_cast<double>(cape.size());
  state.counters["cape_us_p50"] = percentileOf(cape, 0.5);
  state.counters["strain_p50"] = percentileOf(strain, 0.5);
  state.counters["strain_p95"] = percentileOf(strain, 0.95);
  if (!walk.action->positions().allFinite()) state.SkipWithError("the cape blew up");
}

}  // namespace

BENCHMARK(BM_FarWalkFrame)
    ->ArgNames({"km", "axes", "frame"})
    ->Args({0, 1, 1})
    ->Args({10, 1, 1})
    ->Args({100, 1, 1})
    ->Args({100, 3, 1})
    ->Args({10, 1, 0})
    ->Args({100, 1, 0})
    ->Iterations(540)
    ->Unit(benchmark::kMicrosecond);
