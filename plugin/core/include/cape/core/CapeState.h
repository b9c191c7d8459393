/// \file
/// CapeState: the per-cape runtime state as structure of arrays.
#pragma once

#include "cape/core/Export.h"
#include "cape/core/Types.h"

#include <cstdint>
#include <vector>

namespace cape {

/// A particle driven to a moving target. Pinned particles have inverse mass 0: nothing else moves them.
/// Within a step the target moves from `previousTarget` (start of the step) to `target` (end of the step).
struct Pin {
  std::uint32_t particle = 0;          ///< The pinned particle's index.
  Vec3 previousTarget = Vec3::Zero();  ///< m, in the cape's frame (see CapeState).
  Vec3 target = Vec3::Zero();          ///< m, in the cape's frame (see CapeState).
};

/// The per-cape runtime state, one row (or entry) per particle. Positions and pin targets are in the cape's
/// frame: relative to the world point Cape::origin(), so world coordinates while that is zero (the default).
struct CapeState {
  Points positions;               ///< m, in the cape's frame.
  Points velocities;              ///< m/s.
  Eigen::VectorXf inverseMasses;  ///< 1/kg; 0 locks the particle (pins).
  std::vector<Pin> pins;          ///< At most one pin per particle.
  double time = 0.0;              ///< s of simulated time since the start.
};

/// FNV-1a over the bits of the positions and then the velocities: equal states give equal hashes, and a
/// refactor that keeps the solver's arithmetic keeps them (the tests store hashes of the canonical scenes).
CAPE_CORE_API std::uint64_t stateHash(const CapeState& state);

}  // namespace cape
