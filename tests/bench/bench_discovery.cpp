// Google Benchmark over collider discovery and the removed-body check against the size of the world (issue
// 12). One walking cape (docs/SCENES.md's walk on kinematic Bullet bodies: torso, shoulders and legs moved
// with the character frame, the cape pinned by its corners to the shoulder spheres, over the ground plane)
// in a Bullet world that also holds small static boxes far away (a grid at x >= 60 m while the character
// walks along -Z from the origin: never near the cape, never discovered). One iteration is one frame,
// stepSimulation(1/60, 8, 1/240).
//
// Arguments: `seen`, the boxes in the cape's own world, and `unseen`, boxes in a second world stepped once
// per internal step of the cape's world (from its tick callback), which the cape never sees. Bullet's own
// per-step passes go over every object of both worlds (each object's AABB, the islands), and that traffic
// evicts the cape's code and data from the CPU caches whether or not the cape could see the objects. So:
// - seen:10 against seen:10000 (unseen:0) is the raw comparison: it includes the eviction by Bullet's work;
// - seen:10/unseen:10000 against seen:10000/unseen:10 steps the same 10,010 boxes in the same two worlds, and
//   differs only in which of them the cape's broadphase query and removed-body check could reach: the cost
//   of discovery against the size of the world, with Bullet's traffic held equal.
//
// Reported: wall time per frame (Bullet's own work included), cape_us, the cape's own time per frame
// (CapeAction::takeAccumulatedMicroseconds: prepare, with discovery and the removed-body check, then
// advance), and cape_us_p50, the median frame's cape time (robust to the preemption spikes of a busy
// machine). Run the variants interleaved (--benchmark_enable_random_interleaving=true with repetitions) so
// that a slow phase of a shared machine does not fall on one of them.
#include "../bullet/BulletFixture.h"

#include "cape/bullet/Convert.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

namespace {

using namespace capetest;

/// The timed frames of a benchmark: `frame()` once per iteration, and the action's own time per frame as
/// the counters cape_us (mean) and cape_us_p50 (median).
template <class Frame>
void timeFrames(benchmark::State& state, cape::bullet::CapeAction& action, Frame frame) {
  action.takeAccumulatedMicroseconds();
  std::vector<double> perFrame;
  perFrame.reserve(1 << 16);
  double capeMicroseconds = 0.0;
  for (auto _ : state) {
    frame();
    const double t = action.takeAccumulatedMicroseconds();
    capeMicroseconds += t;
    perFrame.push_back(t);
    benchmark::DoNotOptimize(action.positions().data());
  }
  if (!perFrame.empty()) {
    std::nth_element(perFrame.begin(), perFrame.begin() + perFrame.size() / 2, perFrame.end());
    state.counters["cape_us_p50"] = perFrame[perFrame.size() / 2];
  }
  state.counters["cape_us"] = benchmark::Counter(capeMicroseconds, benchmark::Counter::kAvgIterations);
}

void BM_DiscoveryWalkFrame(benchmark::State& state) {
  const int seen = static_cast<int>(state.range(0));
  const int unseen = static_cast<int>(state.range(1));
  World w, other;
  const auto addBoxes = [](World& to, int count) {
    for (int i = 0; i < count; ++i) {
      const btVector3 at(btScalar(60 + i % 100), btScalar(0.1), btScalar(-50 + i / 100));
      to.addStatic(new btBoxShape(btVector3(0.1f, 0.1f, 0.1f)), btTransform(btQuaternion::getIdentity(), at));
    }
  };
  addBoxes(w, seen);
  addBoxes(other, unseen);
  if (unseen > 0) {
    w.world->setInternalTickCallback(
        [](btDynamicsWorld* world, btScalar dt) {
          static_cast<btDynamicsWorld*>(world->getWorldUserInfo())->stepSimulation(dt, 0);
        },
        other.world.get(), true);
  }
  // The walk goes on without restarting (a restart would teleport the cape): the boxes stay >= 60 m away.
  SimpleWalk walk(w, btVector3(0, 0, 0), cape::bullet::CapeActionSettings(), true);
  cape::bullet::CapeAction& action = *walk.action;
  const auto advance = [&]() { walk.advance(); };
  // Warm up one simulated second so that the cape is in contact with the body, as in the other benchmarks.
  for (int k = 0; k < 60; ++k) advance();
  timeFrames(state, action, advance);
  state.counters["world_objects"] = static_cast<double>(w.world->getNumCollisionObjects());
  state.counters["unseen_objects"] = static_cast<double>(other.world->getNumCollisionObjects());
  state.counters["colliders"] = static_cast<double>(action.activeObjects().size());
  if (!action.positions().allFinite()) state.SkipWithError("the cape blew up");
}

// Sleeping in a Bullet world (CapeSettings::sleepSpeed): the same character standing still on the ground
// (its kinematic bodies never moved), its cape settled for 20 s, then one frame, asleep (sleep:1, the
// default) against never sleeping (sleep:0). Reported as above: cape_us, cape_us_p50 (the action's own time
// per frame: its four prepares, which check the world, and the core's steps), and asleep.
void BM_ActionHangSettled(benchmark::State& state) {
  World w;
  cape::bullet::CapeActionSettings settings;
  SimpleWalk hang(w, btVector3(0, 0, 0), settings, true);
  cape::bullet::CapeAction& action = *hang.action;
  if (state.range(0) == 0) {
    cape::CapeSettings s = action.cape().settings();
    s.sleepSpeed = 0.0f;
    if (!action.cape().setSettings(s).ok()) {
      state.SkipWithError("settings refused");
      return;
    }
  }
  const auto frame = [&]() { w.world->stepSimulation(kFrame, 8, kFixed); };
  for (int k = 0; k < 1200; ++k) frame();
  timeFrames(state, action, frame);
  state.counters["asleep"] = action.cape().isAsleep() ? 1.0 : 0.0;
  if (!action.positions().allFinite()) state.SkipWithError("the cape blew up");
}

}  // namespace

BENCHMARK(BM_DiscoveryWalkFrame)
    ->ArgNames({"seen", "unseen"})
    ->Args({10, 0})
    ->Args({10000, 0})
    ->Args({10, 10000})
    ->Args({10000, 10})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ActionHangSettled)->ArgName("sleep")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
