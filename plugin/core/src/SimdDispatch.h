// Whether this build has the eight-wide kernels (x86-64 with GCC or Clang, whose target attribute compiles
// AVX2 functions into a portable binary), and the one question the kernels ask (Simd.h).
#pragma once

#if defined(__x86_64__) && defined(__SSE2__) && (defined(__GNUC__) || defined(__clang__))
#define CAPE_HAVE_AVX2_KERNELS 1
#else
#define CAPE_HAVE_AVX2_KERNELS 0
#endif

namespace cape::detail {

/// True while the kernels are to use the AVX2 paths (cape::simdLevel() is Avx2).
bool useAvx2Kernels();

}  // namespace cape::detail
