/// \file
/// SimdLevel: which instruction set the solver's vector kernels use (the springs and the tethers). Every
/// level gives the same bits: the wider kernels do each lane's operations in the portable kernels' order,
/// without fused multiply-add (which rounds once where a multiply and an add round twice), so a cape's
/// results are identical on any x86-64 processor and any thread count, and the stored determinism hashes
/// hold on all of them. The level is one setting for the whole process.
#pragma once

#include "cape/core/Export.h"
#include "cape/core/Types.h"

namespace cape {

/// The instruction sets of the vector kernels.
enum class SimdLevel {
  Portable,  ///< Four lanes (SSE2, which every x86-64 processor has; scalar loops on other processors).
  Avx2,      ///< Eight lanes (AVX2), on x86-64 processors that have it.
};

/// The widest level this processor runs (Avx2 where the CPU reports AVX2, else Portable).
CAPE_CORE_API SimdLevel simdAvailable();

/// The level the kernels use now: simdAvailable() unless setSimdLevel chose another.
CAPE_CORE_API SimdLevel simdLevel();

/// Chooses the level for every cape of the process from the next kernel call on (Portable: the portable
/// build's kernels, to time them or to run exactly the code every machine runs). An error, keeping the
/// level in use, for a level this processor does not have. Safe at any time from any thread: every level
/// gives the same bits.
CAPE_CORE_API Status setSimdLevel(SimdLevel level);

/// "portable" or "avx2".
CAPE_CORE_API const char* simdLevelName(SimdLevel level);

}  // namespace cape
