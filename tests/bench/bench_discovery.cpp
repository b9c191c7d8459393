// Google Benchmark over collider discovery and the removed-body check against the size of the world (issue
// 12). One walking cape (docs/SCENES.md's walk on kinematic Bullet bodies: torso, shoulders and legs moved
// with the character frame, the cape pinned by its corners to the shoulder spheres, over the ground plane)
// in a Bullet world that also holds N small static boxes far away (a grid at x >= 60 m while the character
// walks along -Z from the origin: never near the cape, never discovered). One iteration is one frame,
// stepSimulation(1/60, 8, 1/240).
//
// Reported: wall time per frame (Bullet's own work included: it updates every object's AABB and island
// state at every internal step, which grows with N), cape_us, the cape's own time per frame
// (CapeAction::takeAccumulatedMicroseconds: prepare, with discovery and the removed-body check, then
// advance), and cape_us_p50, the median frame's cape time (robust to the preemption spikes of a busy
// machine). With discovery through the broadphase the cape's own work does not depend on N; what remains is
// Bullet's per-step pass over N objects evicting the cape's data from the CPU caches. The control world:1
// puts the same N boxes in a second world stepped once per internal step of the cape's world: the same
// Bullet work and cache traffic, none of it visible to the cape. world:2 is the cape's world with
// setForceUpdateAllAabbs(false), as Bullet recommends for large static scenes: Bullet's pass then skips the
// static boxes, and what is left of the growth with N is the cape's.
#include "../bullet/BulletFixture.h"

#include "cape/bullet/Convert.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

namespace {

using namespace capetest;

void BM_DiscoveryWalkFrame(benchmark::State& state) {
  const int distant = static_cast<int>(state.range(0));
  const bool apart = state.range(1) == 1;
  World w, other;
  // world:2 is the same world set up as Bullet suggests for a large static scene: only active objects get
  // their AABBs updated each step (setForceUpdateAllAabbs(false)); static boxes never change.
  if (state.range(1) == 2) w.world->setForceUpdateAllAabbs(false);
  World& boxes = apart ? other : w;
  for (int i = 0; i < distant; ++i) {
    const btVector3 at(btScalar(60 + i % 100), btScalar(0.1), btScalar(-50 + i / 100));
    boxes.addStatic(new btBoxShape(btVector3(0.1f, 0.1f, 0.1f)),
                    btTransform(btQuaternion::getIdentity(), at));
  }
  if (apart) {
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
  action.takeAccumulatedMicroseconds();
  std::vector<double> perFrame;
  perFrame.reserve(1 << 16);
  double capeMicroseconds = 0.0;
  for (auto _ : state) {
    advance();
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
  state.counters["world_objects"] = static_cast<double>(w.world->getNumCollisionObjects());
  state.counters["colliders"] = static_cast<double>(action.activeObjects().size());
  if (!action.positions().allFinite()) state.SkipWithError("the cape blew up");
}

}  // namespace

BENCHMARK(BM_DiscoveryWalkFrame)
    ->ArgNames({"objects", "world"})
    ->Args({10, 0})
    ->Args({10000, 0})
    ->Args({10000, 1})
    ->Args({10, 2})
    ->Args({10000, 2})
    ->Unit(benchmark::kMicrosecond);
