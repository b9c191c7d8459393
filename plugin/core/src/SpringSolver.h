// The constraint kernels of the solve: XPBD distance constraints over one family's springs, run by run, and
// the long-range tethers (internal to the core; Cape::solveSprings and Cape::solveTethers call them,
// tests/core/test_spring_solver.cpp checks the vector paths against the scalar loops bit for bit).
#pragma once

#include "cape/core/Fabric.h"

#include <cstdint>

namespace cape::detail {

/// The arrays one family's solve reads and writes: positions as three columns, inverse masses, and per
/// spring (indexed like the SpringSet) its rest length and XPBD multiplier. `lambda` may be null: every
/// multiplier is then taken as zero and none is kept (one iteration per substep, where the multipliers start
/// at zero and are never read again), which saves the array and its traffic and gives the same positions.
struct SpringSolveArrays {
  float* px = nullptr;
  float* py = nullptr;
  float* pz = nullptr;
  const float* inverseMass = nullptr;
  const std::uint32_t* first = nullptr;
  const std::uint32_t* second = nullptr;
  const float* restLength = nullptr;
  float* lambda = nullptr;
  /// Per spring, a factor on the compliance (the inverse of a stiffness scale, Cape::setStiffnessScale);
  /// null: 1 for every spring (the kernels then do not read it: the same bits as before scales existed).
  const float* complianceScale = nullptr;
};

/// XPBD distance constraints C = |xj - xi| - L with compliance alpha (Macklin et al. 2016):
///   dlambda = (-C - alpha~ lambda) / (wi + wj + alpha~),  alpha~ = alpha / h^2,
///   xi -= wi dlambda n,  xj += wj dlambda n,  n = (xj - xi) / |xj - xi|,
/// for springs [begin, end) one after another. The division is a multiplication by 1 / (wi + wj + alpha~)
/// (0 when both ends are pinned), taken per spring as it is solved: reading the inverse masses the spring
/// needs anyway costs less than a per-step table of denominators would in memory traffic, and a world
/// stepping the cape once per substep pays no pass over the springs before the solve. A spring of zero (or
/// non-finite) length has no direction and is left alone. `alphaTilde` is alpha / h^2.
void solveSpringsScalar(const SpringSolveArrays& a, std::uint32_t begin, std::uint32_t end, float alphaTilde);

/// The same over a run, four springs at a time with vector loads and stores where the run's layout allows
/// (SSE2 on x86-64; elsewhere one at a time), or eight (two blocks of the run) with the AVX2 kernels
/// (cape/core/Simd.h). Bit for bit the result of solveSpringsScalar over the run: the springs of a run's
/// blocks share no particle and every lane does the scalar loop's operations in its order (the core is
/// built without floating-point contraction, and the AVX2 kernels use no fused multiply-add).
void solveSpringRun(const SpringSolveArrays& a, const SpringRun& run, float alphaTilde);

/// The largest squared stretch of a set's springs, max over springs of |x_j - x_i|^2 / L^2 (0 for an empty
/// set; a spring whose value is NaN is passed over, as std::max(worst, value) passes it over), read run by
/// run with the solver's vector loads. The same value as the scalar loop: every lane divides as it does, and
/// a maximum does not depend on the order it is taken in.
float maxSquaredStretch(const float* px, const float* py, const float* pz, const SpringSet& set);

/// The scalar loop of maxSquaredStretch over springs [begin, end), from `worst`.
float maxSquaredStretchScalar(const float* px, const float* py, const float* pz, const SpringSet& set,
                              std::size_t begin, std::size_t end, float worst = 0.0f);

/// Unilateral tethers |x_p - x_a| <= maxLength while the anchor a is pinned (w_a = 0): a taut tether moves p
/// straight towards a, onto the sphere of radius maxLength. One tether after another.
void solveTethersScalar(float* px, float* py, float* pz, const float* inverseMass, const TetherSet& tethers,
                        std::size_t begin, std::size_t end);

/// The same over all tethers, four (eight with the AVX2 kernels) at a time where as many consecutive tethers
/// move consecutive particles (the fabric lists every particle's nearest anchor, then every particle's second
/// nearest...). Bit for bit the scalar loop: anchors are never tethered particles, so the tethers of a block
/// read nothing the others write.
void solveTethers(float* px, float* py, float* pz, const float* inverseMass, const TetherSet& tethers);

/// Strain limiting: for each spring of the set in order, one whose length is above `stretch` times its rest
/// length (stretch = 1 + the ceiling) is brought back to that length, its ends moved along it in proportion
/// to their inverse masses (Provot 1995). One-sided: a spring at or under the ceiling, with both ends
/// pinned, or of a NaN length is left alone. Each vector run's blocks of four are checked with vector loads
/// (SSE2 on x86-64) and only a block with a spring beyond the ceiling goes through the scalar loop: bit for
/// bit limitStretchScalar over the whole set.
void limitStretch(float* px, float* py, float* pz, const float* inverseMass, const SpringSet& set,
                  float stretch);

/// limitStretch's scalar loop over springs [begin, end).
void limitStretchScalar(float* px, float* py, float* pz, const float* inverseMass, const SpringSet& set,
                        std::size_t begin, std::size_t end, float stretch);

/// The linear bending hinges (Fabric.h's HingeSet) as XPBD constraints C = |d| - restBend, with d the
/// hinge's curvature vector and the gradients w1 n, w2 n, -(w1 + w2) n at its first, second and middle
/// particle (n = d / |d|, w1, w2 its arm weights), and the compliance 1 / (bendingRigidity areaOverLength2):
///   dlambda = (-C - alpha~ lambda) / (m1 w1^2 + m2 w2^2 + mm (w1 + w2)^2 + alpha~),
/// with m the inverse masses; one hinge after another in the set's order (level after level), four at a
/// time within a level (SSE2 on x86-64; elsewhere one at a time): bit for bit solveHingesScalar over the
/// whole set, since the hinges of a level share no particle and every lane does the scalar loop's operations
/// in its order. A hinge with |d| below 1e-12 (a straight line) has no direction and is left alone. `lambda`
/// may be null, as SpringSolveArrays'. `invH2` is 1 / h^2.
void solveHinges(float* px, float* py, float* pz, const float* inverseMass, const HingeSet& hinges,
                 float bendingRigidity, float invH2, float* lambda, const float* stiffnessScale = nullptr);

/// solveHinges' scalar loop over hinges [begin, end).
void solveHingesScalar(float* px, float* py, float* pz, const float* inverseMass, const HingeSet& hinges,
                       float bendingRigidity, float invH2, float* lambda, const float* stiffnessScale,
                       std::size_t begin, std::size_t end);

/// `stiffnessScale`, when not null, multiplies each hinge's stiffness (Cape::setStiffnessScale).
///
/// The hinges' elastic forces for the explicit integrator, -k C grad C with k = bendingRigidity
/// areaOverLength2, added to the accelerations (times the inverse masses).
void addHingeForces(const float* px, const float* py, const float* pz, const float* inverseMass,
                    const HingeSet& hinges, float bendingRigidity, float* ax, float* ay, float* az,
                    const float* stiffnessScale = nullptr);

/// The hinges' elastic energy, J: sum of 1/2 k C^2.
double hingeEnergy(const Points& positions, const HingeSet& hinges, float bendingRigidity,
                   const float* stiffnessScale = nullptr);

}  // namespace cape::detail
