/// \file
/// CapeGroup: several capes stepped with one Bullet world, in parallel. Add the group to the world
/// (world->addAction(&group)) instead of each cape. Every internal step, the group prepares each cape on the
/// calling thread, in order (reading the world is not shared out), while a small persistent pool advances
/// the capes already prepared: its threads (the calling one among them, once it has prepared them all)
/// take the capes one at a time until none is left, so a worker that wakes late or a cape that costs more
/// does not hold the others up. Each cape is independent and stepped whole by one thread, so the results
/// are bitwise identical whatever the thread count and whichever thread steps it. The hand-offs between the
/// calling thread and the workers (every internal step) sleep on condition variables, or spin for a while
/// first (setSpinMicroseconds).
#pragma once

#include "cape/bullet/CapeAction.h"
#include "cape/bullet/Export.h"

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace cape::bullet {

/// One band of a level-of-detail policy (CapeGroup::setDetailPolicy): capes farther than `distance` from
/// the viewpoint step at `level`.
struct DetailBand {
  btScalar distance = 0;  ///< m from the viewpoint.
  DetailLevel level;      ///< The level of the capes beyond `distance`.
};

/// Several capes stepped with one Bullet world on a persistent thread pool, bitwise identical results on any
/// thread count (see CapeGroup.h). Add the group to the world instead of its capes.
class CAPE_BULLET_API CapeGroup : public btActionInterface {
 public:
  /// threadCount >= 1 workers in all, the calling thread included (threadCount - 1 threads are started).
  explicit CapeGroup(int threadCount = 1);
  ~CapeGroup() override;
  CapeGroup(const CapeGroup&) = delete;
  CapeGroup& operator=(const CapeGroup&) = delete;

  /// Adds a cape (not owned; it must outlive its membership and must not be added to the world itself).
  /// Members are added and removed between steps, not from inside one (a cape's warning handler, called
  /// during the step, must not change the group: the other capes are being stepped on the pool).
  void add(CapeAction* cape);
  /// Removes a cape from the group (not destroyed; nothing happens if it is not a member). It keeps the
  /// level of detail it had. Between steps, as add().
  void remove(CapeAction* cape);
  /// The member capes, in the order they were added.
  const std::vector<CapeAction*>& capes() const { return capes_; }
  /// Workers in all, the calling thread included.
  int threadCount() const { return threadCount_; }

  /// One internal step of the world (dt s): every cape's prepare() on this thread, in order, and their
  /// advance() on the pool as soon as each is prepared.
  void updateAction(btCollisionWorld* world, btScalar dt) override;
  /// Draws every member cape (CapeAction::debugDraw).
  void debugDraw(btIDebugDraw* drawer) override;
  // --- Level of detail ---------------------------------------------------------------------------------
  /// Levels of detail by distance from a viewpoint (a camera; m, world). Before every internal step each
  /// member cape's distance (CapeAction::detailPoint) picks its band: the farthest band it is beyond, full
  /// detail nearer than all. With a hysteresis of `hysteresis` m: a cape moves out to a farther band only
  /// once beyond its distance + hysteresis, and back in only once nearer than its distance - hysteresis,
  /// so a cape at an edge does not switch back and forth. An error, keeping the policy in use, for bands
  /// not in strictly increasing distance, a distance, viewpoint or hysteresis not finite or negative, or a
  /// level DetailLevel::validate refuses. No bands: the group sets every cape back to full detail once and
  /// then leaves their levels alone.
  Status setDetailPolicy(const btVector3& viewpoint, std::vector<DetailBand> bands,
                         btScalar hysteresis = btScalar(0.5));
  /// Moves the viewpoint (a camera moving every frame); ignored unless finite.
  void setViewpoint(const btVector3& viewpoint);
  /// The bands of the policy in use (empty: none).
  const std::vector<DetailBand>& detailBands() const { return bands_; }
  /// How many member capes were in each band at the last internal step: [0] full detail, [k] bands[k - 1]
  /// (empty without a policy).
  const std::vector<std::size_t>& detailCounts() const { return bandCounts_; }

  // --- Parallel prepare --------------------------------------------------------------------------------
  /// Prepare the capes on the pool too (off by default): the thread that takes a cape prepares and then
  /// advances it, instead of every prepare() running on the calling thread. The results are the same bits. It
  /// needs the world's shapes to answer queries from several threads at once, as Bullet's own do during
  /// actions: the broadphase's AABB test keeps its traversal stack on the caller's stack, and
  /// btBvhTriangleMeshShape's and btHeightfieldTerrainShape's processAllTriangles only read (a mesh interface
  /// of your own that locks or caches must allow it). The capes' warnings are held back and given to their
  /// handlers on the calling thread, cape by cape, after the step.
  void setParallelPrepare(bool parallel) { parallelPrepare_ = parallel; }
  /// Whether the capes are prepared on the pool (setParallelPrepare).
  bool parallelPrepare() const { return parallelPrepare_; }

  // --- Hand-offs ---------------------------------------------------------------------------------------
  /// How long a worker waiting for the next internal step, and the calling thread waiting for the workers to
  /// finish one, may spin (checking a flag, with a pause instruction) before they sleep on a condition
  /// variable, microseconds; 0 (the default): sleep at once. A wake-up from sleep costs tens of microseconds
  /// at every hand-off, as much as a small crowd's step, and spinning saves it where the group's threads
  /// have cores of their own; where they have not (more busy threads than cores), a spinning thread holds
  /// the core that the one it waits for needs. Each thread adapts its own spin: a wait longer than the
  /// setting halves its next spin, a shorter one doubles it (up to the setting). The results are the same
  /// bits either way. An error, keeping the value in use, for a value not finite or outside [0, 1e6].
  Status setSpinMicroseconds(double microseconds);
  /// The longest spin before sleeping, microseconds (setSpinMicroseconds).
  double spinMicroseconds() const { return spinMicroseconds_.load(std::memory_order_relaxed); }
  /// The spin a group starts with: none (sleep at once), as spinning costs where other threads need the
  /// cores.
  static constexpr double kDefaultSpinMicroseconds = 0.0;

  /// Wall time of the last internal step's work on the pool, microseconds: from the hand-off to the last
  /// cape's finish, the prepares on the calling thread that overlap it included. With one thread (or fewer
  /// than two capes), the advances alone.
  double lastStepMicroseconds() const { return lastStepMicroseconds_; }

 private:
  /// Steps the capes of the current step that no thread has taken yet, one at a time.
  void work();
  void runWorker();
  /// Waits until `ready()`: spins up to `budget` us, then sleeps on `wake` (under mutex_); then sets
  /// `budget` for the next wait (see the definition).
  template <class Ready>
  void waitUntil(Ready ready, std::condition_variable& wake, double& budget);
  void applyDetailPolicy();

  std::vector<CapeAction*> capes_;
  int threadCount_ = 1;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  /// Incremented for every parallel step (written under mutex_, read by spinning workers without it).
  std::atomic<std::uint64_t> generation_{0};
  /// The current step's claims: its cape count (high 32 bits) and the next cape to take (low 32 bits).
  std::atomic<std::uint64_t> claim_{0};
  std::atomic<std::uint64_t> finished_{0};  ///< Capes of the current step finished.
  std::atomic<std::uint64_t> prepared_{0};  ///< Capes of the current step prepared (the first ones).
  std::atomic<bool> stopping_{false};       ///< Written under mutex_.
  /// Read by the workers while they wait, so atomic (relaxed: it orders nothing).
  std::atomic<double> spinMicroseconds_{kDefaultSpinMicroseconds};
  double spinBudget_ =
      kDefaultSpinMicroseconds;  ///< The calling thread's (waitUntil); the workers keep theirs.
  btScalar dt_ = 0;
  btCollisionWorld* world_ = nullptr;  ///< The world of the step in progress (parallel prepare).
  bool parallelPrepare_ = false;
  btVector3 viewpoint_{0, 0, 0};
  std::vector<DetailBand> bands_;
  btScalar hysteresis_ = 0;
  std::vector<std::size_t> bandCounts_;
  std::vector<int> band_;  ///< Each member's band, as capes_ (0: full detail; -1: not chosen yet).
  double lastStepMicroseconds_ = 0.0;
};

}  // namespace cape::bullet
