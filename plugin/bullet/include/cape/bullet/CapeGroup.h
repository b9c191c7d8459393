/// \file
/// CapeGroup: several capes stepped with one Bullet world, in parallel. Add the group to the world
/// (world->addAction(&group)) instead of each cape. Every internal step, the group prepares each cape on the
/// calling thread (reading the world is not shared out), then advances them on a small persistent pool:
/// cape i always runs on worker i % threadCount (a fixed static partition). Each cape is independent and its
/// own computation is sequential, so the results are bitwise identical whatever the thread count. The
/// hand-offs between the calling thread and the workers (every internal step) spin for a while before they
/// sleep (setSpinMicroseconds): a wake-up from sleep costs tens of microseconds, as much as a small crowd's
/// step.
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
  void add(CapeAction* cape);
  /// Removes a cape from the group (not destroyed; nothing happens if it is not a member). It keeps the
  /// level of detail it had.
  void remove(CapeAction* cape);
  /// The member capes, in the order they were added (cape i runs on worker i % threadCount()).
  const std::vector<CapeAction*>& capes() const { return capes_; }
  /// Workers in all, the calling thread included.
  int threadCount() const { return threadCount_; }

  /// One internal step of the world (dt s): every cape's prepare() on this thread, then their advance() on
  /// the pool.
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
  /// Prepare the capes on the pool too (off by default): each worker prepares and then advances its own
  /// capes, with no wait between the two halves, instead of every prepare() running first on the calling
  /// thread. The results are the same bits. It needs the world's shapes to answer queries from several
  /// threads at once, as Bullet's own do during actions: the broadphase's AABB test keeps its traversal
  /// stack on the caller's stack, and btBvhTriangleMeshShape's and btHeightfieldTerrainShape's
  /// processAllTriangles only read (a mesh interface of your own that locks or caches must allow it). The
  /// capes' warnings are held back and given to their handlers on the calling thread, cape by cape, after
  /// the step.
  void setParallelPrepare(bool parallel) { parallelPrepare_ = parallel; }
  /// Whether the capes are prepared on the pool (setParallelPrepare).
  bool parallelPrepare() const { return parallelPrepare_; }

  // --- Hand-offs ---------------------------------------------------------------------------------------
  /// How long a worker waiting for the next internal step, and the calling thread waiting for the workers to
  /// finish one, spin (checking a flag, with a pause instruction) before they sleep on a condition variable,
  /// microseconds; 0: sleep at once. Spinning keeps the hand-offs of one frame's internal steps from paying
  /// a sleep's wake-up each; it costs a core while it lasts, so a machine with fewer cores than the group's
  /// threads and other busy threads may want 0. The results are the same bits either way. An error,
  /// keeping the value in use, for a value not finite or outside [0, 1e6]. Default: kDefaultSpinMicroseconds.
  Status setSpinMicroseconds(double microseconds);
  /// The spin before sleeping, microseconds (setSpinMicroseconds).
  double spinMicroseconds() const { return spinMicroseconds_.load(std::memory_order_relaxed); }
  static constexpr double kDefaultSpinMicroseconds = 200.0;

  /// Wall time of the last parallel advance of all capes (with their prepare under setParallelPrepare),
  /// microseconds.
  double lastStepMicroseconds() const { return lastStepMicroseconds_; }

 private:
  void work(int worker);
  void runWorker(int worker);
  /// Spins up to spinMicroseconds_ until `ready()`; true if it came true (then no sleep is needed).
  template <class Ready>
  bool spinUntil(Ready ready) const;
  void applyDetailPolicy();

  std::vector<CapeAction*> capes_;
  int threadCount_ = 1;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  /// Incremented for every parallel step (written under mutex_, read by spinning workers without it).
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<int> pending_{0};        ///< Workers (threads) still busy with the current step.
  std::atomic<bool> stopping_{false};  ///< Written under mutex_.
  /// Read by the workers while they wait, so atomic (relaxed: it orders nothing).
  std::atomic<double> spinMicroseconds_{kDefaultSpinMicroseconds};
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
