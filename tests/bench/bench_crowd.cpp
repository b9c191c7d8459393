// Google Benchmark of a crowd (issue 15): K simple-body characters (cape::BulletSimpleBody, kinematic Bullet
// bodies) on docs/SCENES.md's square grid 2 m apart (rows of ceil(sqrt K)), walking the walk's motion in one
// btDiscreteDynamicsWorld with a static ground plane, each wearing a 20 x 20 cape (cape::makeCapeRig, pinned
// at the corners to its shoulders) as a CapeAction, all in one cape::bullet::CapeGroup of T workers. One
// iteration is one 1/60 s frame, stepSimulation(1/60, 8, 1/240), after a simulated second of warm-up. P = 1:
// the capes' prepare runs on the pool too (CapeGroup::setParallelPrepare), not on the world's thread.
//
// Reported per frame (means over the timed frames; _p50 their medians):
//   cape_us           the capes' wall time: the group's updateAction calls (every cape's prepare on the
//                     calling thread, and the parallel advance), timed from outside the group
//   advance_us        the group's own lastStepMicroseconds, summed over the frame's internal steps (on
//                     one thread the advances alone; on more, the pool's part, the prepares on the calling
//                     thread that overlap it included)
//   cape_per_cape_us  cape_us / K
//   bullet_us         Bullet's own share: stepSimulation's wall time less cape_us
//   frame_us          stepSimulation's wall time
//   objects           collision objects in the world (5 per character and the ground)
//
// BM_CrowdFrameSpin: BM_CrowdFrame on 2 threads with the group's hand-offs spinning up to S us before they
// sleep (CapeGroup::setSpinMicroseconds; S = 0: sleep at once, the default).
#include "cape/bullet/CapeAction.h"
#include "cape/bullet/CapeGroup.h"
#include "cape/bullet/Convert.h"
#include "cape/scenes/BulletSimpleBody.h"
#include "cape/scenes/Scene.h"

#include <benchmark/benchmark.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <chrono>
#include <initializer_list>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double microsecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto k = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

double mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

/// docs/SCENES.md's crowd grid (as demos/src/BulletScene.cpp lays it out).
cape::Vec3 gridOffset(int k, int count) {
  int columns = 1;
  while (columns * columns < count) ++columns;
  const int rows = (count + columns - 1) / columns;
  return cape::Vec3(2.0f * (static_cast<float>(k % columns) - 0.5f * static_cast<float>(columns - 1)), 0.0f,
                    2.0f * (static_cast<float>(k / columns) - 0.5f * static_cast<float>(rows - 1)));
}

/// The group as the world sees it, its updateAction timed (wall clock).
class TimedGroup final : public btActionInterface {
 public:
  explicit TimedGroup(cape::bullet::CapeGroup& group) : group_(group) {}
  void updateAction(btCollisionWorld* world, btScalar dt) override {
    const auto start = Clock::now();
    group_.updateAction(world, dt);
    capeUs += microsecondsSince(start);
    advanceUs += group_.lastStepMicroseconds();
  }
  void debugDraw(btIDebugDraw*) override {}
  double capeUs = 0.0, advanceUs = 0.0;  ///< since they were last zeroed

 private:
  cape::bullet::CapeGroup& group_;
};

struct Crowd {
  Crowd(int count, int threads, bool parallelPrepare = false, double spin = 0.0)
      : group(threads), timed(group) {
    group.setParallelPrepare(parallelPrepare);
    (void)group.setSpinMicroseconds(spin);
    world.setGravity(btVector3(0, btScalar(-9.8), 0));
    world.addRigidBody(&ground);
    const cape::CapeRig rig = cape::makeCapeRig(20, cape::PinLayout::Corners);
    const cape::CapeSettings settings = cape::settingsForScene(cape::SceneKind::Walk, cape::CapeSettings());
    const cape::Pose start = cape::capeStartPlacement(cape::SceneKind::Walk);
    for (int k = 0; k < count; ++k) {
      const cape::Vec3 offset = gridOffset(k, count);
      bodies.push_back(std::make_unique<cape::BulletSimpleBody>(world, offset, cape::motionAt(motion, 0.0)));
      cape::Pose placement = start;
      placement.position += offset;
      auto cape =
          std::make_unique<cape::bullet::CapeAction>(rig.fabric, settings, cape::bullet::toBt(placement));
      for (std::size_t p = 0; p < rig.pinnedParticles.size(); ++p) {
        // Each corner to the shoulder on its side.
        const cape::Vec3 at = rig.pinLocalPoints[p] + offset;
        btRigidBody* shoulder = bodies.back()->rigidBody(
            at.x() < offset.x() ? cape::SimpleBody::kLeftShoulder : cape::SimpleBody::kRightShoulder);
        cape->attach(rig.pinnedParticles[p], shoulder,
                     shoulder->getWorldTransform().inverse() * cape::bullet::toBt(at));
      }
      group.add(cape.get());
      capes.push_back(std::move(cape));
    }
    world.addAction(&timed);
  }
  ~Crowd() {
    world.removeAction(&timed);
    for (auto& c : capes) group.remove(c.get());
    capes.clear();
    bodies.clear();
    world.removeRigidBody(&ground);
  }
  Crowd(const Crowd&) = delete;
  Crowd& operator=(const Crowd&) = delete;

  /// One frame; returns stepSimulation's wall time, µs.
  double advance() {
    ++frame;
    const cape::BodyPose pose = cape::motionAt(motion, frame / 60.0);
    for (auto& b : bodies) b->moveTo(pose);
    const auto start = Clock::now();
    world.stepSimulation(btScalar(1.0 / 60.0), 8, btScalar(1.0 / 240.0));
    return microsecondsSince(start);
  }
  bool finite() const {
    return std::all_of(capes.begin(), capes.end(), [](const auto& c) { return c->positions().allFinite(); });
  }

  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
  btStaticPlaneShape groundShape{btVector3(0, 1, 0), 0};
  btRigidBody ground{btScalar(0), nullptr, &groundShape};
  cape::MotionDesc motion = cape::MotionDesc::forScene(cape::SceneKind::Walk);
  cape::bullet::CapeGroup group;
  TimedGroup timed;
  std::vector<std::unique_ptr<cape::BulletSimpleBody>> bodies;
  std::vector<std::unique_ptr<cape::bullet::CapeAction>> capes;
  int frame = 0;
};

/// BM_CrowdFrame's body, with the group's hand-offs spinning up to `spin` us, and each cape stepping once
/// every `interval` internal steps (DetailLevel: the same fabric and substeps per frame).
void crowdFrame(benchmark::State& state, double spin, int interval = 1) {
  const int count = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  Crowd crowd(count, threads, state.range(2) != 0, spin);
  for (auto& cape : crowd.capes) {
    const cape::Status s = cape->setDetailLevel(cape::bullet::DetailLevel{interval, 0});
    if (!s.ok()) {
      state.SkipWithError(s.message().c_str());
      return;
    }
  }
  for (int k = 0; k < 60; ++k) crowd.advance();  // a simulated second of warm-up
  std::vector<double> cape, advance, bullet, frame;
  for (auto _ : state) {
    crowd.timed.capeUs = crowd.timed.advanceUs = 0.0;
    const double f = crowd.advance();
    frame.push_back(f);
    cape.push_back(crowd.timed.capeUs);
    advance.push_back(crowd.timed.advanceUs);
    bullet.push_back(std::max(0.0, f - crowd.timed.capeUs));
  }
  state.counters["cape_us"] = mean(cape);
  state.counters["cape_us_p50"] = median(cape);
  state.counters["advance_us"] = mean(advance);
  state.counters["cape_per_cape_us"] = mean(cape) / count;
  state.counters["bullet_us"] = mean(bullet);
  state.counters["bullet_us_p50"] = median(bullet);
  state.counters["frame_us"] = mean(frame);
  state.counters["objects"] = crowd.world.getNumCollisionObjects();
  if (!crowd.finite()) state.SkipWithError("a cape blew up");
}

void BM_CrowdFrame(benchmark::State& state) {
  crowdFrame(state, 0.0);
}

// Every cape stepping once a frame, over the frame's four internal steps together, with the same fabric and
// the same substeps a frame (DetailLevel{4, 0}): the capes' arrays are read once a frame, not four times.
void BM_CrowdFrameOnceAFrame(benchmark::State& state) {
  crowdFrame(state, 0.0, 4);
}

void BM_CrowdFrameSpin(benchmark::State& state) {
  crowdFrame(state, static_cast<double>(state.range(3)));
}

/// The same crowd seen from a camera 4 m in front of its middle at eye height, with levels of detail by
/// distance (CapeGroup::setDetailPolicy): full detail within 8 m, every second internal step to 16 m, once a
/// frame to 32 m, and beyond that with 2 substeps; C = 1: the last two bands on the fabric's coarse level
/// (10 x 10, DetailLevel::coarseFabric). Reported besides: the capes in each band.
void BM_CrowdFrameDetail(benchmark::State& state) {
  const int count = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  Crowd crowd(count, threads, state.range(2) != 0);
  const bool coarse = state.range(3) != 0;
  btScalar front = 0;
  for (int k = 0; k < count; ++k) front = std::max(front, btScalar(gridOffset(k, count).z()));
  using cape::bullet::DetailLevel;
  const cape::Status policy = crowd.group.setDetailPolicy(
      btVector3(0, btScalar(1.6), front + 4),
      {{8, DetailLevel{2, 0}}, {16, DetailLevel{4, 0, coarse}}, {32, DetailLevel{4, 2, coarse}}});
  if (!policy.ok()) {
    state.SkipWithError(policy.message().c_str());
    return;
  }
  for (int k = 0; k < 60; ++k) crowd.advance();
  std::vector<double> cape, bullet;
  for (auto _ : state) {
    crowd.timed.capeUs = 0.0;
    const double f = crowd.advance();
    cape.push_back(crowd.timed.capeUs);
    bullet.push_back(std::max(0.0, f - crowd.timed.capeUs));
  }
  state.counters["cape_us"] = mean(cape);
  state.counters["cape_us_p50"] = median(cape);
  state.counters["cape_per_cape_us"] = mean(cape) / count;
  state.counters["bullet_us"] = mean(bullet);
  const std::vector<std::size_t>& bands = crowd.group.detailCounts();
  for (std::size_t b = 0; b < bands.size(); ++b)
    state.counters["band" + std::to_string(b)] = static_cast<double>(bands[b]);
  if (!crowd.finite()) state.SkipWithError("a cape blew up");
}

}  // namespace

/// K in `counts` on 1 thread, on 2, and on 2 with the prepare on the pool too (P:
/// CapeGroup::setParallelPrepare).
void crowdArgs(benchmark::internal::Benchmark* b, std::initializer_list<int> counts) {
  b->ArgNames({"K", "T", "P"});
  for (int k : counts)
    for (const auto& [threads, parallel] : {std::pair{1, 0}, std::pair{2, 0}, std::pair{2, 1}})
      b->Args({k, threads, parallel});
  b->Iterations(120)->Unit(benchmark::kMillisecond);
}

BENCHMARK(BM_CrowdFrameDetail)->Apply([](benchmark::internal::Benchmark* b) {
  b->ArgNames({"K", "T", "P", "C"});
  for (int coarse : {0, 1})
    for (int k : {100, 1000})
      for (const auto& [threads, parallel] : {std::pair{1, 0}, std::pair{2, 0}, std::pair{2, 1}})
        b->Args({k, threads, parallel, coarse});
  b->Iterations(120)->Unit(benchmark::kMillisecond);
});
BENCHMARK(BM_CrowdFrame)->Apply([](benchmark::internal::Benchmark* b) { crowdArgs(b, {16, 100, 1000}); });
BENCHMARK(BM_CrowdFrameOnceAFrame)->Apply([](benchmark::internal::Benchmark* b) {
  crowdArgs(b, {16, 100, 1000});
});
BENCHMARK(BM_CrowdFrameSpin)->Apply([](benchmark::internal::Benchmark* b) {
  b->ArgNames({"K", "T", "P", "S"});
  for (int k : {16, 100})
    for (int parallel : {0, 1})
      for (int spin : {0, 200}) b->Args({k, 2, parallel, spin});
  b->Iterations(120)->Unit(benchmark::kMillisecond);
});
BENCHMARK_MAIN();
