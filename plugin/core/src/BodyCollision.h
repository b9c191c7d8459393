// BodyCollision: the body-collision stage of a substep and its scratch memory. Every free particle is tested
// against every collider's sweep over the substep (its pose interpolated from the step's start to its end),
// pushed out to the collider's surface plus the thicknesses, with the collider's Coulomb friction; the
// contacts are kept for the reprojection passes after the constraint solve.
#pragma once

#include "cape/core/Cape.h"

#include <vector>

namespace cape::detail {

/// The particle arrays a collision pass reads and writes (columns of CapeState and the substep's start).
struct CollisionArrays {
  float* px;
  float* py;
  float* pz;
  const float* sx;  ///< positions at the start of the substep
  const float* sy;
  const float* sz;
  const float* w;  ///< inverse masses (0: pinned, never moved)
  float* vx;       ///< velocities, corrected only in the explicit mode
  float* vy;
  float* vz;
  Eigen::Index n;
};

/// A triangle a particle may meet in this step, with the side of its plane (+1 front, -1 back, by the
/// corners' counter-clockwise order) the particle was on at the step's start.
struct MeshCandidate {
  std::uint32_t triangle;
  float side;
};

class BodyCollision {
 public:
  explicit BodyCollision(std::size_t particles);

  /// Once per step, before the substeps: every free particle's candidate triangles of every triangle-mesh
  /// collider (the other shapes need nothing). `slack`, m, covers how far the solver's corrections may carry
  /// a particle beyond its predicted path.
  void beginStep(const CapeState& state, ColliderSpan colliders, const CapeSettings& settings, float dt,
                 float slack);

  /// The substep [s0, s1] of the step (fractions of it; h seconds long): every free particle of `p` against
  /// every valid collider's sweep. An invalid collider (NaN pose, bad size) is skipped. In the explicit
  /// mode the velocities follow the position corrections.
  void collide(const CollisionArrays& p, const CapeSettings& settings, float h, float s0, float s1,
               ColliderSpan colliders, bool explicitMode);
  /// Pushes each contact's particle back out of its collider (at its pose at the substep's end) if the
  /// passes since collide() moved it into the skin.
  void reproject(const CollisionArrays& p, const CapeSettings& settings, ColliderSpan colliders);
  /// Contacts of the last collide(): particle and index into its colliders.
  const std::vector<Cape::Contact>& contacts() const { return contacts_; }

 private:
  std::vector<Pose> colliderEnd_;               ///< Collider poses at the end of the substep.
  std::vector<Cape::Contact> contacts_;         ///< Contacts of the substep's collision pass.
  Eigen::ArrayXf distance2_;                    ///< Broad-phase scratch, one per particle.
  std::vector<std::uint32_t> candidates_;       ///< Broad-phase scratch.
  std::vector<Eigen::Vector4f> blocks_;         ///< Broad-phase culling: per block of particles, a sphere.
  std::vector<Eigen::Vector4f> contactPlanes_;  ///< Per contact: a mesh's contact plane (n, offset), else 0.
  // Triangle meshes: per mesh (in collider order), particle i's candidates are
  // meshCandidates_[meshStart_[slot * (n + 1) + i] .. meshStart_[slot * (n + 1) + i + 1]).
  std::vector<int> meshSlot_;  ///< Per collider of the step: its mesh slot, or -1.
  std::vector<std::uint32_t> meshStart_;
  std::vector<MeshCandidate> meshCandidates_;

  void gatherTriangles(const TriangleSoup& soup, const Vec3& p0, const Vec3& lo, const Vec3& hi);
  void collideMesh(const Collider& c, const CollisionArrays& p, std::uint32_t collider, float s0, float s1,
                   float margin, float mu, float invH, bool explicitMode);
};

}  // namespace cape::detail
