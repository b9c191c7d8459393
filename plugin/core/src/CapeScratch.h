// The scratch memory of one cape's step, sized once when the cape is made: the step's particle buffers and
// the two collision subsystems. Internal to the core: the public Cape.h holds only a pointer to it.
#pragma once

#include "BodyCollision.h"
#include "SelfCollision.h"

#include "cape/core/ColliderRecord.h"

namespace cape::detail {

struct CapeScratch {
  explicit CapeScratch(const Fabric& fabric);

  Points startPositions;            ///< Positions at the start of the substep, m.
  Points acceleration;              ///< External acceleration per particle (gravity + wind), m/s^2.
  Points airVelocity;               ///< The wind's velocity at each particle for this step, m/s.
  Eigen::VectorXf freeMask;         ///< 1 for free particles, 0 for pinned, refreshed each step.
  Eigen::VectorXf lambda;           ///< XPBD Lagrange multipliers of every spring (iterations > 1).
  Eigen::VectorXf hingeLambda;      ///< XPBD multipliers of the bending hinges (iterations > 1).
  Eigen::VectorXf selfWeight;       ///< Inverse masses for the last self-contact pass, 1/kg.
  std::vector<std::uint32_t> lost;  ///< The numerical guard's finds in one step (capacity: every particle).
  BodyCollision body;
  SelfCollision self;
  ColliderRecord sleep;  ///< The colliders a sleeping cape fell asleep among.
};

}  // namespace cape::detail
