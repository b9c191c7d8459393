#include "cape/core/Simd.h"

#include "SimdDispatch.h"

#include <atomic>

namespace cape {

namespace {

bool cpuHasAvx2() {
#if CAPE_HAVE_AVX2_KERNELS
  // The compiler's CPU model: AVX2 only where the processor has it and the operating system saves its
  // registers (XCR0), so the eight-wide kernels never fault.
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

// -1 until the first read, then the level in use.
std::atomic<int> gLevel{-1};

}  // namespace

SimdLevel simdAvailable() {
  static const SimdLevel available = cpuHasAvx2() ? SimdLevel::Avx2 : SimdLevel::Portable;
  return available;
}

SimdLevel simdLevel() {
  int level = gLevel.load(std::memory_order_relaxed);
  if (level < 0) {
    level = static_cast<int>(simdAvailable());
    int expected = -1;
    if (!gLevel.compare_exchange_strong(expected, level, std::memory_order_relaxed)) level = expected;
  }
  return static_cast<SimdLevel>(level);
}

Status setSimdLevel(SimdLevel level) {
  if (level != SimdLevel::Portable && level != SimdLevel::Avx2)
    return Status::error("setSimdLevel: not a SimdLevel");
  if (level == SimdLevel::Avx2 && simdAvailable() != SimdLevel::Avx2)
    return Status::error("setSimdLevel: this processor (or this build) has no AVX2 kernels");
  gLevel.store(static_cast<int>(level), std::memory_order_relaxed);
  return Status::success();
}

const char* simdLevelName(SimdLevel level) {
  return level == SimdLevel::Avx2 ? "avx2" : "portable";
}

namespace detail {

bool useAvx2Kernels() {
  return simdLevel() == SimdLevel::Avx2;
}

}  // namespace detail

}  // namespace cape
