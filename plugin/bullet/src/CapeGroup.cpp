#include "cape/bullet/CapeGroup.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#endif

namespace cape::bullet {

CapeGroup::CapeGroup(int threadCount) : threadCount_(std::max(1, threadCount)) {
  threads_.reserve(static_cast<std::size_t>(threadCount_ - 1));
  for (int w = 1; w < threadCount_; ++w) threads_.emplace_back([this] { runWorker(); });
}

namespace {

/// A hint to the core that this thread spins (lets its hyperthread sibling run, saves power).
inline void pause() {
#if defined(__SSE2__) || defined(_M_X64)
  _mm_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

}  // namespace

CapeGroup::~CapeGroup() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_.store(true, std::memory_order_release);
  }
  start_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void CapeGroup::add(CapeAction* cape) {
  if (cape != nullptr && std::find(capes_.begin(), capes_.end(), cape) == capes_.end()) {
    capes_.push_back(cape);
    if (!band_.empty()) band_.push_back(-1);  // its band is chosen at the next step
  }
}

void CapeGroup::remove(CapeAction* cape) {
  const auto it = std::find(capes_.begin(), capes_.end(), cape);
  if (it == capes_.end()) return;
  if (!band_.empty()) band_.erase(band_.begin() + (it - capes_.begin()));
  capes_.erase(it);
}

void CapeGroup::work() {
  // Claims the step's capes one at a time until none is left. The claim word holds the step's cape count
  // (high half) and the next cape (low half), set together at the start of each step: a claim made late,
  // by a worker still finishing the step before, reads either that step's word (no cape left) or this
  // step's (a cape of this step, whose inputs the word's release published), never a count of one step
  // with an index of another.
  for (;;) {
    const std::uint64_t word = claim_.fetch_add(1, std::memory_order_acq_rel);
    const std::uint64_t count = word >> 32, i = word & 0xffffffffu;
    if (i >= count) return;
    // A cape the calling thread prepares (the prepares not on the pool) is advanced once it is: a wait of
    // at most a few prepares, spent checking (and, should the calling thread have lost its core, giving
    // this one away).
    for (int k = 0; prepared_.load(std::memory_order_acquire) <= i; ++k) {
      pause();
      if ((k & 63) == 63) std::this_thread::yield();
    }
    CapeAction* cape = capes_[static_cast<std::size_t>(i)];
    if (world_ != nullptr) cape->prepare(world_, dt_);  // a parallel prepare
    cape->advance(dt_);
    // The last cape finished wakes the calling thread if it sleeps (under the mutex, which the calling
    // thread holds from its check until it sleeps: no lost wake-up).
    if (finished_.fetch_add(1, std::memory_order_acq_rel) + 1 == count) {
      std::lock_guard<std::mutex> lock(mutex_);
      done_.notify_one();
    }
  }
}

template <class Ready>
void CapeGroup::waitUntil(Ready ready, std::condition_variable& wake, double& budget) {
  // Spin while the budget lasts (the clock read every 64 checks: a check is a load, the clock tens of
  // nanoseconds), then sleep. A wait no longer than the setting doubles the next one's budget (up to the
  // setting) and a longer one halves it, so that where the waits are long, or the thread waited for has no
  // core of its own (more busy threads than cores: it runs a time slice later), the spin soon stops costing
  // anything and the thread sleeps at once; a sleeper is woken ahead of a thread that spins or yields.
  if (ready()) return;
  const double limit = spinMicroseconds_.load(std::memory_order_relaxed);
  const auto start = std::chrono::steady_clock::now();
  const auto waited = [&start] {
    return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  };
  bool done = false;
  while (limit > 0.0 && budget > 0.0) {
    for (int k = 0; k < 64 && !done; ++k) {
      pause();
      done = ready();
    }
    if (done || waited() > budget) break;
  }
  if (!done) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake.wait(lock, ready);
  }
  if (limit > 0.0)
    budget = waited() <= limit ? std::min(limit, 2.0 * budget + 1.0) : (budget > 1.0 ? 0.5 * budget : 0.0);
}

void CapeGroup::runWorker() {
  std::uint64_t seen = 0;
  double budget = 0.0;  // grows to the setting over the first short waits (waitUntil)
  const auto due = [&] {
    return stopping_.load(std::memory_order_acquire) || generation_.load(std::memory_order_acquire) != seen;
  };
  for (;;) {
    // The generation changes under the mutex and the sleep checks it under the mutex, so a step begun
    // between the spin and the sleep is not missed.
    waitUntil(due, start_, budget);
    if (stopping_.load(std::memory_order_acquire)) return;
    seen = generation_.load(std::memory_order_acquire);
    work();
  }
}

Status CapeGroup::setSpinMicroseconds(double microseconds) {
  if (!std::isfinite(microseconds) || microseconds < 0.0 || microseconds > 1e6)
    return Status::error("CapeGroup::setSpinMicroseconds: the spin must be finite, in [0, 1e6] us");
  spinMicroseconds_.store(microseconds, std::memory_order_relaxed);
  spinBudget_ = microseconds;  // the workers' budgets follow at their next short wait
  return Status::success();
}

Status CapeGroup::setDetailPolicy(const btVector3& viewpoint, std::vector<DetailBand> bands,
                                  btScalar hysteresis) {
  const auto finite = [](const btVector3& v) {
    return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
  };
  if (!finite(viewpoint)) return Status::error("CapeGroup::setDetailPolicy: the viewpoint is not finite");
  if (!std::isfinite(hysteresis) || hysteresis < 0)
    return Status::error("CapeGroup::setDetailPolicy: hysteresis must be finite and >= 0 m");
  for (std::size_t k = 0; k < bands.size(); ++k) {
    const btScalar d = bands[k].distance;
    if (!std::isfinite(d) || d < 0 || (k > 0 && !(d > bands[k - 1].distance)))
      return Status::error("CapeGroup::setDetailPolicy: band " + std::to_string(k) +
                           "'s distance must be finite, >= 0 m and beyond the band before it");
    if (Status s = bands[k].level.validate(); !s.ok())
      return Status::error("CapeGroup::setDetailPolicy: band " + std::to_string(k) + ": " + s.message());
  }
  const bool had = !bands_.empty();
  viewpoint_ = viewpoint;
  bands_ = std::move(bands);
  hysteresis_ = hysteresis;
  band_.clear();  // every cape's band is chosen afresh at the next step
  bandCounts_.clear();
  if (bands_.empty() && had)
    for (CapeAction* cape : capes_) cape->setDetailLevel(DetailLevel());
  return Status::success();
}

void CapeGroup::setViewpoint(const btVector3& viewpoint) {
  if (std::isfinite(viewpoint.x()) && std::isfinite(viewpoint.y()) && std::isfinite(viewpoint.z()))
    viewpoint_ = viewpoint;
}

void CapeGroup::applyDetailPolicy() {
  const int n = static_cast<int>(bands_.size());
  band_.resize(capes_.size(), -1);
  bandCounts_.assign(static_cast<std::size_t>(n) + 1, 0);
  for (std::size_t i = 0; i < capes_.size(); ++i) {
    const btScalar d = (capes_[i]->detailPoint() - viewpoint_).length();
    int b = band_[i];
    if (b < 0) {
      b = 0;  // no band yet: the plain rule, no hysteresis
      while (b < n && d > bands_[static_cast<std::size_t>(b)].distance) ++b;
    } else {
      while (b < n && d > bands_[static_cast<std::size_t>(b)].distance + hysteresis_) ++b;
      while (b > 0 && d < bands_[static_cast<std::size_t>(b - 1)].distance - hysteresis_) --b;
    }
    if (b != band_[i]) {
      // Validated with the policy; a cape that was not made refuses, and stays as it is. A cape whose
      // fabric has no coarse level takes the band's interval and substeps on its own fabric.
      DetailLevel level = b == 0 ? DetailLevel() : bands_[static_cast<std::size_t>(b - 1)].level;
      if (level.coarseFabric && capes_[i]->ok() && !capes_[i]->cape().fabric().coarseLevel())
        level.coarseFabric = false;
      capes_[i]->setDetailLevel(level);
      band_[i] = b;
    }
    ++bandCounts_[static_cast<std::size_t>(b)];
  }
}

void CapeGroup::updateAction(btCollisionWorld* world, btScalar dt) {
  if (!bands_.empty()) applyDetailPolicy();
  dt_ = dt;
  if (threads_.empty() || capes_.size() < 2) {
    for (CapeAction* cape : capes_) cape->prepare(world, dt);
    const auto start = std::chrono::steady_clock::now();
    for (CapeAction* cape : capes_) cape->advance(dt);
    lastStepMicroseconds_ =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    return;
  }
  // Reading the world (bodies, discovery) stays on this thread, unless asked otherwise.
  const bool parallel = parallelPrepare_;
  world_ = parallel ? world : nullptr;
  for (CapeAction* cape : capes_) cape->deferWarnings_ = parallel;
  // Whoever is free takes the next cape: a worker that wakes late leaves its share to the others instead of
  // holding the step up. Each cape is stepped whole by one thread, in its own state, so the results do not
  // depend on which. Unless the prepares are on the pool, this thread prepares the capes in order while the
  // workers advance those already prepared (work() waits for a cape's prepare), then takes what is left.
  const std::uint64_t count = capes_.size();
  finished_.store(0, std::memory_order_relaxed);
  prepared_.store(parallel ? count : 0, std::memory_order_relaxed);
  const auto start = std::chrono::steady_clock::now();
  claim_.store(count << 32, std::memory_order_release);  // publishes the step's inputs to late claims
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.fetch_add(1, std::memory_order_release);
  }
  start_.notify_all();
  if (!parallel) {
    for (std::uint64_t i = 0; i < count; ++i) {
      capes_[static_cast<std::size_t>(i)]->prepare(world, dt);
      prepared_.store(i + 1, std::memory_order_release);
    }
  }
  work();
  const auto finished = [&] { return finished_.load(std::memory_order_acquire) == count; };
  waitUntil(finished, done_, spinBudget_);
  world_ = nullptr;
  for (CapeAction* cape : capes_) {
    cape->deferWarnings_ = false;
    cape->sayDeferredWarnings();
  }
  lastStepMicroseconds_ =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
}

void CapeGroup::debugDraw(btIDebugDraw* drawer) {
  for (CapeAction* cape : capes_) cape->debugDraw(drawer);
}

}  // namespace cape::bullet
