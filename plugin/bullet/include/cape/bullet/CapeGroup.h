// CapeGroup: several capes stepped with one Bullet world, in parallel. Add the group to the world
// (world->addAction(&group)) instead of each cape. Every internal step, the group prepares each cape on the
// calling thread (reading the world is not shared out), then advances them on a small persistent pool:
// cape i always runs on worker i % threadCount (a fixed static partition). Each cape is independent and its
// own computation is sequential, so the results are bitwise identical whatever the thread count.
#pragma once

#include "cape/bullet/CapeAction.h"
#include "cape/bullet/Export.h"

#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace cape::bullet {

class CAPE_BULLET_API CapeGroup : public btActionInterface {
 public:
  /// threadCount >= 1 workers in all, the calling thread included (threadCount - 1 threads are started).
  explicit CapeGroup(int threadCount = 1);
  ~CapeGroup() override;
  CapeGroup(const CapeGroup&) = delete;
  CapeGroup& operator=(const CapeGroup&) = delete;

  /// Adds a cape (not owned; it must outlive its membership and must not be added to the world itself).
  void add(CapeAction* cape);
  void remove(CapeAction* cape);
  const std::vector<CapeAction*>& capes() const { return capes_; }
  int threadCount() const { return threadCount_; }

  void updateAction(btCollisionWorld* world, btScalar dt) override;
  void debugDraw(btIDebugDraw* drawer) override;
  /// Wall time of the last parallel advance of all capes, microseconds.
  double lastStepMicroseconds() const { return lastStepMicroseconds_; }

 private:
  void work(int worker);
  void runWorker(int worker);

  std::vector<CapeAction*> capes_;
  int threadCount_ = 1;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  std::uint64_t generation_ = 0;  ///< Incremented for every parallel step.
  int pending_ = 0;               ///< Workers (threads) still busy with the current step.
  bool stopping_ = false;
  btScalar dt_ = 0;
  double lastStepMicroseconds_ = 0.0;
};

}  // namespace cape::bullet
