// Cape: one simulated cape — a shared Fabric, its own settings and state, and the solver's scratch memory,
// sized once so that stepping never allocates.
#pragma once

#include "cape/core/CapeSettings.h"
#include "cape/core/CapeState.h"
#include "cape/core/Collider.h"
#include "cape/core/Fabric.h"

#include <memory>
#include <vector>

namespace cape {

/// A view of the colliders for one step (the caller owns them; see Collider::moveTo).
struct ColliderSpan {
  const Collider* data = nullptr;
  std::size_t size = 0;
  ColliderSpan() = default;
  ColliderSpan(const Collider* d, std::size_t n) : data(d), size(n) {}
  ColliderSpan(const std::vector<Collider>& v) : data(v.data()), size(v.size()) {}  // NOLINT: implicit by design
  const Collider* begin() const { return data; }
  const Collider* end() const { return data + size; }
};

class Cape {
 public:
  /// Makes a cape at the fabric's rest shape placed by `placement` (world = placement * rest), at rest.
  /// Check `status()`: on bad settings or fabric the cape is empty and step() does nothing.
  Cape(FabricPtr fabric, const CapeSettings& settings, const Pose& placement = Pose());

  const Status& status() const { return status_; }
  bool ok() const { return status_.ok(); }

  const Fabric& fabric() const { return *fabric_; }
  const FabricPtr& fabricPtr() const { return fabric_; }
  const CapeSettings& settings() const { return settings_; }
  /// Changes the settings; rejected (returning the error, keeping the old settings) if invalid.
  Status setSettings(const CapeSettings& settings);
  const CapeState& state() const { return state_; }
  /// Direct access for tools and tests; keep inverse masses and pins consistent (use pin()/unpin()).
  CapeState& mutableState() { return state_; }

  /// Pins a particle to a world target (its inverse mass becomes 0). Returns the pin's index.
  /// The particle jumps to the target at the next step. Pinning a pinned particle retargets it.
  std::size_t pin(std::uint32_t particle, const Vec3& target);
  /// Releases a particle (its inverse mass is restored from the fabric's mass).
  void unpin(std::uint32_t particle);
  /// The pin has moved: its target at the end of the next step is `target`; the last target becomes the
  /// start of the sweep.
  void movePin(std::size_t pinIndex, const Vec3& target);
  /// Moves every particle and target rigidly by `delta` (pose applied to world positions) and rotates
  /// velocities with it: what a teleport of the character does to its cape, without stretching it.
  void teleport(const Pose& delta);

  /// Advances the cape by dt seconds against the colliders, which are swept from their previous to their
  /// current pose, in substeps of about settings().timeStep / settings().substeps (see CapeSettings::substeps).
  /// Non-finite or non-positive dt is ignored.
  void step(float dt, ColliderSpan colliders);

  /// A particle that touched a collider in this substep's collision pass (index into the step's colliders).
  struct Contact {
    std::uint32_t particle;
    std::uint32_t collider;
  };

  /// How many times the settings' substeps the next step takes (strain-adaptive substepping), and the max
  /// structural strain measured after the last step.
  int substepRefinement() const { return refinement_; }
  float lastMaxStrain() const { return lastMaxStrain_; }

  /// The self-collision thickness in use, m (the setting, or its automatic value).
  float selfCollisionThickness() const { return selfThickness(); }
  /// A predictive self-contact (Lewin 2018): a particle near a triangle it does not belong to, found at the
  /// start of the step, with the side of the triangle it was on then (+1, -1, or 0 while its nearest point
  /// is on the triangle's boundary). The solver keeps it on that side, at least the thickness away.
  struct SelfContact {
    std::uint32_t particle;
    std::uint32_t triangle;
    float side;
  };
  /// Self-contacts found by the last search (diagnostics, benchmarks and tests).
  const std::vector<SelfContact>& selfContacts() const { return selfContacts_; }
  std::size_t selfContactCount() const { return selfContacts_.size(); }
  /// Self-contact searches run so far (a search's contacts are kept over the steps its margin covers).
  std::uint64_t selfContactSearches() const { return selfSearches_; }

  /// Sum over particles of kinetic and gravitational potential energy plus spring (Hooke) energy, J.
  double energy() const;

 private:
  void stepXpbd(float h, float s0, float s1, ColliderSpan colliders);
  void stepExplicit(float h, float s0, float s1, ColliderSpan colliders);
  void movePinsTo(float s, float h);
  void adaptRefinement();
  void collide(float h, float s0, float s1, ColliderSpan colliders, bool explicitMode);
  void reprojectContacts(ColliderSpan colliders);
  void prepareSpringDenominators(float h);
  void solveSprings(float h);
  void solveTethers();
  void accumulateExternalAcceleration();
  float predictSelfMotion(float dt);
  void findSelfContacts();  ///< For the motion predictSelfMotion last predicted.
  void solveSelfContacts(const float* inverseMasses);
  float selfThickness() const;

  FabricPtr fabric_;
  CapeSettings settings_;
  int refinement_ = 1;          ///< Substep multiplier of the next step (1, 2, 4, ...).
  float lastMaxStrain_ = 0.0f;  ///< Max structural strain after the last step.
  CapeState state_;
  Status status_ = Status::success();

  // Scratch, sized once in the constructor.
  Points startPositions_;        ///< Positions at the start of the substep.
  Points acceleration_;          ///< External acceleration per particle (gravity + wind), m/s^2.
  Eigen::VectorXf freeMask_;     ///< 1 for free particles, 0 for pinned, refreshed each step.
  Eigen::VectorXf lambda_;       ///< XPBD Lagrange multipliers of every spring, per substep.
  Eigen::VectorXf invDenominator_;  ///< 1 / (w_i + w_j + alpha~) of every spring, per step.
  std::vector<float> familyCompliance_;
  Points airVelocity_;           ///< The wind's velocity at each particle for this step, m/s.
  Eigen::VectorXf particleArea_; ///< Each particle's share of the rest area, m^2 (the seed's wind).
  std::vector<Pose> colliderEnd_;   ///< Collider poses at the end of the substep.
  std::vector<Contact> contacts_;   ///< Contacts of the substep's collision pass.
  Eigen::ArrayXf distance2_;        ///< Broad-phase scratch, one per particle.
  std::vector<std::uint32_t> candidates_;  ///< Broad-phase scratch.

  std::vector<SelfContact> selfContacts_;
  double selfContactsValidUntil_ = -1.0;     ///< s: the contacts cover the motion until this time.
  std::uint64_t selfSearches_ = 0;           ///< Searches so far (diagnostics).
  std::vector<std::uint32_t> hashStart_;     ///< Spatial hash: bucket offsets (buckets + 1).
  /// A cluster of triangles in a bucket of the spatial hash, with its grown box inline: the search reads
  /// entries in order and rejects most by the box without touching the triangles.
  struct alignas(16) HashEntry {
    float lo[4];  ///< [3]: the cluster's index, as float bits
    float hi[4];  ///< [3]: +inf
  };
  std::vector<HashEntry> hashEntries_;       ///< Spatial hash: clusters of triangles sorted by bucket.
  std::vector<std::uint32_t> bucketHits_;    ///< Search scratch: one bucket's entries that overlap (hashEntries_ size).
  /// The particles a triangle never makes contacts with: its corners and, for each edge, the far corner of
  /// the triangle across it (~0u on the border); padded to 8 for a two-compare test.
  struct alignas(16) LocalSet {
    std::uint32_t v[8];
  };
  std::vector<LocalSet> triangleLocal_;
  std::vector<float> triangleMotion_;        ///< Per triangle: the largest motion of its corners in the search, m.
  std::vector<std::uint32_t> triangleStamp_; ///< Last particle that met each triangle in the search.
  std::vector<std::uint32_t> largeTriangles_; ///< Triangles whose grown box is too big to bin.
  /// Triangles binned together: cluster g is [clusterStart_[g], clusterStart_[g + 1]), two consecutive
  /// triangles that share an edge (a grid cell's halves, whose boxes are the cell's) or one.
  std::vector<std::uint32_t> clusterStart_;
  std::vector<float> clusterBoxes_;                ///< Per cluster: the union of its grown boxes, m.
  /// Per cluster: particles local to every one of its triangles (a grid cell's four corners; ~0u padding),
  /// which meet nothing in it. Four, aligned for one compare.
  struct alignas(16) ClusterLocal {
    std::uint32_t v[4];
  };
  std::vector<ClusterLocal> clusterLocal_;
  std::vector<std::uint32_t> triangleBuckets_;     ///< The buckets each binned cluster went into...
  std::vector<std::uint32_t> triangleBucketStart_; ///< ...from this offset per cluster (clusters + 1).
  std::vector<std::uint32_t> bucketCluster_;       ///< The last cluster binned into each bucket, per search.
  Points stepMotion_;                        ///< Predicted displacement over the step, less a rigid motion, m.
  Eigen::VectorXf selfWeight_;               ///< Inverse masses for the last self-contact pass, 1/kg.
  Eigen::VectorXf stepMotionNorm_;           ///< |stepMotion_| per particle, m.
  float meanSpacing_ = 0.0f;                 ///< Mean structural rest length, m (sizes the hash cells).
};

}  // namespace cape
