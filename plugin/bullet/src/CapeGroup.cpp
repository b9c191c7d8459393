#include "cape/bullet/CapeGroup.h"

#include <algorithm>
#include <chrono>

namespace cape::bullet {

CapeGroup::CapeGroup(int threadCount) : threadCount_(std::max(1, threadCount)) {
  threads_.reserve(static_cast<std::size_t>(threadCount_ - 1));
  for (int w = 1; w < threadCount_; ++w) threads_.emplace_back([this, w] { runWorker(w); });
}

CapeGroup::~CapeGroup() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  start_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void CapeGroup::add(CapeAction* cape) {
  if (cape != nullptr && std::find(capes_.begin(), capes_.end(), cape) == capes_.end())
    capes_.push_back(cape);
}

void CapeGroup::remove(CapeAction* cape) {
  capes_.erase(std::remove(capes_.begin(), capes_.end(), cape), capes_.end());
}

void CapeGroup::work(int worker) {
  for (std::size_t i = static_cast<std::size_t>(worker); i < capes_.size();
       i += static_cast<std::size_t>(threadCount_))
    capes_[i]->advance(dt_);
}

void CapeGroup::runWorker(int worker) {
  std::uint64_t seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    work(worker);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (--pending_ == 0) done_.notify_one();
    }
  }
}

void CapeGroup::updateAction(btCollisionWorld* world, btScalar dt) {
  // Reading the world (bodies, discovery) stays on this thread.
  for (CapeAction* cape : capes_) cape->prepare(world, dt);
  const auto start = std::chrono::steady_clock::now();
  dt_ = dt;
  if (threads_.empty() || capes_.size() < 2) {
    for (CapeAction* cape : capes_) cape->advance(dt);
  } else {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      pending_ = static_cast<int>(threads_.size());
      ++generation_;
    }
    start_.notify_all();
    work(0);
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return pending_ == 0; });
  }
  lastStepMicroseconds_ =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
}

void CapeGroup::debugDraw(btIDebugDraw* drawer) {
  for (CapeAction* cape : capes_) cape->debugDraw(drawer);
}

}  // namespace cape::bullet
