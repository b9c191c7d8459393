/// \file
/// Cape: one simulated cape — a shared Fabric, its own settings and state — and its staged step. The solver's
/// scratch memory (the step's buffers, the body- and self-collision subsystems) lives in the core's sources,
/// sized once when the cape is made, so that stepping never allocates.
#pragma once

#include "cape/core/CapeSettings.h"
#include "cape/core/CapeState.h"
#include "cape/core/Collider.h"
#include "cape/core/Export.h"
#include "cape/core/Fabric.h"

#include <array>
#include <cstddef>
#include <memory>
#include <vector>

namespace cape {

namespace detail {
struct CapeScratch;
}

/// Per-particle constraints of a cape to its animated pose (NvCloth's motion and separation constraints,
/// Chaos Cloth's max distance, backstop and anim drive): each particle's animated position is where the
/// animation puts it, by default the fabric's rest shape fitted to the pins at the end of each step (so it
/// rides with the body the cape is pinned to), or positions the caller gives every step (a skinning:
/// Cape::setAnimatedPositions). An empty array switches its constraint off; otherwise it has one value per
/// particle (a weight map). Pinned particles are not moved by them. Applied in every substep after the
/// collisions, the max distance last: at the end of every step no particle is farther than its max
/// distance from its animated position.
struct MotionConstraints {
  /// m: the farthest each particle may be from its animated position; +inf: no limit for it.
  Eigen::VectorXf maxDistance;
  /// m: the radius of each particle's backstop, a sphere behind its animated position that it may not enter
  /// (0: none for it). Behind is against the animated surface's normal (the counter-clockwise side, as
  /// CapeMesh's normals), or along it when backstopAlongNormal.
  Eigen::VectorXf backstopRadius;
  /// m: how far behind the animated position the backstop's surface lies (its centre is backstopDistance
  /// plus backstopRadius behind it); empty: 0 for every particle.
  Eigen::VectorXf backstopDistance;
  /// Put the backstops on the side the normals point to instead of the other.
  bool backstopAlongNormal = false;
  /// 0..1: the anim drive, the part of the way to its animated position each particle is moved per 1/60 s
  /// (whatever the substeps); 1 holds it there exactly.
  Eigen::VectorXf drive;
};

/// A view of the colliders for one step (the caller owns them; see Collider::moveTo).
struct ColliderSpan {
  const Collider* data = nullptr;  ///< The first collider.
  std::size_t size = 0;            ///< How many there are.
  ColliderSpan() = default;        ///< No colliders.
  /// `n` colliders from `d`.
  ColliderSpan(const Collider* d, std::size_t n) : data(d), size(n) {}
  /// Every collider of `v` (which must outlive the span).
  ColliderSpan(const std::vector<Collider>& v)
      : data(v.data()), size(v.size()) {}  // NOLINT: implicit by design
  /// The first collider, for range-for.
  const Collider* begin() const { return data; }
  /// One past the last collider.
  const Collider* end() const { return data + size; }
};

/// One simulated cape: a shared Fabric, its own CapeSettings and CapeState, and the staged step (prediction,
/// constraints, collisions, velocities over substeps; docs/SOLVER.md). Positions are in the cape's frame
/// (origin()), m. Movable, not copyable; stepping never allocates.
class CAPE_CORE_API Cape {
 public:
  /// Makes a cape at the fabric's rest shape placed by `placement` (world = placement * rest), at rest.
  /// Check `status()`: on bad settings or fabric the cape is empty and step() does nothing.
  Cape(FabricPtr fabric, const CapeSettings& settings, const Pose& placement = Pose());
  ~Cape();
  /// Moves the cape (fabric, settings, state and scratch) into this one; use only the new one.
  Cape(Cape&&) noexcept;
  /// Moves the cape (fabric, settings, state and scratch) into this one; use only the new one.
  Cape& operator=(Cape&&) noexcept;
  Cape(const Cape&) = delete;
  Cape& operator=(const Cape&) = delete;

  /// Why the cape is empty, or success.
  const Status& status() const { return status_; }
  /// True when the cape was made (status() is success).
  bool ok() const { return status_.ok(); }

  /// The shared fabric (only while ok()).
  const Fabric& fabric() const { return *fabric_; }
  /// The shared fabric's pointer.
  const FabricPtr& fabricPtr() const { return fabric_; }
  /// The settings in use.
  const CapeSettings& settings() const { return settings_; }
  /// Changes the settings; rejected (returning the error, keeping the old settings) if invalid.
  Status setSettings(const CapeSettings& settings);
  /// Level of detail: substeps per settings().timeStep for the next steps in place of settings().substeps
  /// (1..1000; 0: the settings' own), e.g. fewer for a cape far from the camera. The state stays as it
  /// is, so a switch either way moves no particle. The strain refinement still multiplies the substeps, and
  /// the explicit integrator still takes as many as its stability bound needs. An error for a count out of
  /// range, keeping the one in use.
  Status setSubstepOverride(int substeps);
  /// The substep override in use (0: none, settings().substeps apply).
  int substepOverride() const { return substepOverride_; }
  /// Level of detail by fabric: while on, each step simulates the fabric's coarse level
  /// (Fabric::coarseLevel: a 20 x 20 grid's 10 x 10, with the same settings, pins and colliders) in this
  /// cape's place, and this cape's particles follow it: positions and velocities interpolated bilinearly
  /// over the grid from the coarse particles, pinned particles on their pins. The switch moves no particle
  /// at once: switching on, the coarse level starts from this cape's state sampled at its particles, and the
  /// fine detail the coarse grid cannot hold (folds between its particles) fades out linearly over
  /// kCoarseBlendTime of simulated time; switching off, this cape steps on from the interpolated state it
  /// shows. A cape with a mass or stiffness scale, motion constraints or animated positions set steps its
  /// own fabric while they are set (they are per particle of it). An error, changing nothing, for a fabric
  /// without a coarse level (built by Fabric::fromMesh, or a grid under 3 x 3).
  Status setCoarseLevel(bool on);
  /// Whether the coarse level is on (setCoarseLevel).
  bool coarseLevel() const { return coarseOn_; }
  /// True when the last step simulated the coarse level.
  bool steppedCoarse() const { return steppedCoarse_; }
  /// s of simulated time over which the fine detail left at a switch to the coarse level fades out.
  static constexpr float kCoarseBlendTime = 0.25f;
  /// Gravity for the next steps (m/s^2, world frame), e.g. the world's, read before every step. Not finite:
  /// an error, and the gravity stays what it was.
  Status setGravity(const Vec3& gravity);
  /// Positions, velocities, inverse masses, pins and time (frame coordinates, m, m/s, 1/kg, s).
  const CapeState& state() const { return state_; }
  /// Direct access for tools and tests; keep inverse masses and pins consistent (use pin()/unpin()). Wakes
  /// the cape (whatever is done with the state may move it).
  CapeState& mutableState() {
    wake();
    markCoarseStale();
    return state_;
  }

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
  /// Sets the motion constraints (MotionConstraints): an error, keeping the old ones, when an array that is
  /// not empty has another size than the particles, or a value out of range (max distance not >= 0, a
  /// backstop radius or distance negative or not finite, a drive outside 0..1).
  Status setMotionConstraints(const MotionConstraints& constraints);
  /// The motion constraints in use.
  const MotionConstraints& motionConstraints() const { return motion_; }
  /// A per-particle mass scale (a weight map, as WeightMap.h paints): particle i weighs
  /// fabric().masses()[i] * scale[i] (a heavier hem, a lighter collar), and its inverse mass is the inverse
  /// of that while it is free; energy() counts the scaled masses. Empty: the fabric's masses. An error,
  /// keeping the old scale, for another size than the particles, a value not finite in (0, 1e6], or (the
  /// explicit integrator) a substep the lighter particles would make unstable.
  Status setMassScale(const Eigen::VectorXf& scale);
  /// The mass scale in use (empty: none).
  const Eigen::VectorXf& massScale() const { return massScale_; }
  /// A per-particle stiffness scale (a weight map): every spring's stiffness times the mean of its two ends'
  /// values, every bending hinge's times its middle particle's (tethers, pins and collisions are not
  /// scaled). Empty: none (the same bits as before it was set). The same errors as setMassScale().
  Status setStiffnessScale(const Eigen::VectorXf& scale);
  /// The stiffness scale in use (empty: none).
  const Eigen::VectorXf& stiffnessScale() const { return stiffnessScale_; }
  /// The animated position of every particle for the next step and those after (frame coordinates, m, one
  /// row per particle): a skinning the caller gives, again whenever it moves. An empty matrix goes back to
  /// the default, the rest shape fitted to the pins at the end of each step. An error on a wrong size or a
  /// position that is not finite.
  Status setAnimatedPositions(const Points& positions);
  /// The animated positions of the last step (frame coordinates, m) and their vertex normals.
  const Points& animatedPositions() const { return animated_; }
  /// The animated surface's area-weighted vertex normals of the last step (unit, counter-clockwise side).
  const Points& animatedNormals() const { return animatedNormals_; }

  /// Puts the cape back in its reference pose: the rest shape fitted to the pins' targets (referencePose(),
  /// refitted here), every free particle at rest there, every pinned particle at rest on its pin's target
  /// (the pin's sweep starting there), the self-contacts searched afresh at the next step. What a teleport
  /// does with CapeActionSettings::teleportMode Reset after carrying the cape; also for a game's own resets
  /// (a respawn, a cut).
  void resetToReference();
  /// Carries every particle, and the start of every pin's sweep, by x -> rotation (x - centre) + centre +
  /// shift, velocities turned by the rotation; the pins' targets at the end of the next step stay. What a
  /// character-cloth "inertia" below 1 does before a step: the part of the body's motion the cape should not
  /// feel (CapeActionSettings::linearInertia). Ignored unless every input is finite.
  void carry(const Eigen::Matrix3f& rotation, const Vec3& centre, const Vec3& shift);

  /// The cape's frame (local space, as NvCloth's): every position the cape takes and gives (particles,
  /// pins, colliders, the centres of carry() and teleport()) is relative to this world point, m. Zero unless
  /// set, and then frame and world are one. A cape far from the world's origin keeps its float coordinates
  /// small, and so their precision that of a cape at the origin, by moving its frame along (the Bullet
  /// adapter does: CapeActionSettings::frameGrid).
  const Eigen::Vector3d& origin() const { return origin_; }
  /// Moves the frame to `origin`; the cape stays where it is in the world (its frame coordinates change by
  /// the difference, rounded to float once). Ignored unless finite.
  void setOrigin(const Eigen::Vector3d& origin);
  /// Moves the frame to `origin` and the cape with it: frame coordinates stay, world positions move by the
  /// difference (a teleport by a pure translation, exact however far). Ignored unless finite.
  void relocate(const Eigen::Vector3d& origin);

  /// The longest step simulated, s: a longer dt (a stalled game) is simulated as this long.
  static constexpr float kMaxStep = 1.0f;
  /// Advances the cape by dt seconds against the colliders, which are swept from their previous to their
  /// current pose, in substeps of about settings().timeStep / settings().substeps (see
  /// CapeSettings::substeps). Non-finite or non-positive dt is ignored; dt > kMaxStep is kMaxStep. After the
  /// step, the numerical guard (guard()) restores every particle it finds lost.
  void step(float dt, ColliderSpan colliders);
  /// The step of a sleeping cape whose caller knows its colliders to be, bit for bit, those of its last
  /// step (the Bullet adapter, which has checked every body they come from): the clock advances by dt, as
  /// step() with those colliders would do, without comparing them. False, and nothing done, when the cape
  /// is awake, steps a coarse level (Cape::setCoarseLevel) or dt is not a step's: then call step().
  bool stepAsleep(float dt);

  /// What the numerical guard did. After every step it checks every particle: one whose position or
  /// velocity is not finite (or whose speed squared overflows a float), or, in a piece of the fabric a pin
  /// holds (Fabric::components), that is farther from the pins' centroid than the farthest pin target plus
  /// CapeSettings::guardReach times the fabric's rest diameter, is lost. Lost particles are restored to the
  /// reference pose (referencePose(), carried by the pins: the rest shape fitted to the pin targets) with the
  /// pins' mean velocity; a lost pinned particle to its pin's target. So no NaN or runaway particle outlives
  /// the step it appeared in.
  struct GuardReport {
    std::uint32_t lastStep = 0;  ///< particles restored by the last step
    std::uint64_t total = 0;     ///< particles restored since the cape was made
    std::uint64_t steps = 0;     ///< steps that restored at least one
  };
  /// What the numerical guard has done (see GuardReport).
  const GuardReport& guard() const { return guard_; }
  /// Where the rest shape stands (frame coordinates; world = pose * rest): the placement, moved by
  /// teleport() and carry(), and refitted to the pin targets whenever the guard restores a particle.
  const Pose& referencePose() const { return reference_; }

  /// Sleeping (CapeSettings::sleepSpeed): whether the cape is asleep, and how many steps it slept through
  /// (each only a check that its pins and colliders are still where they were when it fell asleep).
  bool isAsleep() const { return asleep_; }
  /// Steps the cape slept through since it was made.
  std::uint64_t sleptSteps() const { return sleptSteps_; }
  /// Wakes the cape (the next step simulates); what every change to the pins, settings or state does.
  void wake();

  /// A particle that touched a collider in this substep's collision pass (index into the step's colliders).
  struct Contact {
    std::uint32_t particle;  ///< The particle's index.
    std::uint32_t collider;  ///< The collider's index in the step's ColliderSpan.
  };

  /// How many times the settings' substeps the next step takes (strain-adaptive substepping), and the max
  /// structural strain measured after the last step.
  int substepRefinement() const { return refinement_; }
  /// The largest structural strain after the last step ((|xi - xj| - L0) / L0, dimensionless).
  float lastMaxStrain() const { return lastMaxStrain_; }

  /// The self-collision thickness in use, m (the setting, or its automatic value).
  float selfCollisionThickness() const;
  /// A predictive self-contact (Lewin 2018): a particle near a triangle it does not belong to, found at the
  /// start of the step, with the side of the triangle it was on then (+1, -1, or 0 while its nearest point
  /// is on the triangle's boundary). The solver keeps it on that side, at least the thickness away.
  struct SelfContact {
    std::uint32_t particle;  ///< The particle's index.
    std::uint32_t triangle;  ///< Triangle t: corners Fabric::triangles()[3t .. 3t + 2].
    float side;              ///< +1, -1 or 0 (see above).
  };
  /// The most self-contacts a search keeps for one particle: the first found, in the search's deterministic
  /// order. A cape's particle meets the few triangles of each layer within reach, well under half of it (a
  /// test holds every canonical scene to that); the bound keeps a mesh whose long triangles make the
  /// automatic thickness as long as the sheet (every particle within reach of every triangle) linear in its
  /// particles, where it was their product.
  static constexpr std::size_t kMaxSelfContactsPerParticle = 128;
  /// Self-contacts found by the last search (diagnostics, benchmarks and tests).
  const std::vector<SelfContact>& selfContacts() const;
  /// The number of self-contacts found by the last search.
  std::size_t selfContactCount() const { return selfContacts().size(); }
  /// Self-contact searches run so far (a search's contacts are kept over the steps its margin covers).
  std::uint64_t selfContactSearches() const;
  /// Of those, the searches that a proof that the cape lay too flat and too little stretched to come within
  /// reach of itself passed over (a grid fabric only; the contacts were none, as the search would have
  /// found).
  std::uint64_t selfContactSearchesProvenApart() const;
  /// Bytes held by the self-contact search's scratch: none until self-collision is first turned on (at
  /// construction or by setSettings), so a crowd of capes without it does not pay for it.
  std::size_t selfCollisionScratchBytes() const;

  /// Sum over particles of kinetic and gravitational potential energy plus spring (Hooke) energy, J.
  double energy() const;

 private:
  /// The substeps of one step: how many, and how long each is (s).
  struct StepPlan {
    int substeps = 1;
    float h = 0.0f;
  };
  StepPlan planSubsteps(float dt) const;
  void beginStep(float dt, ColliderSpan colliders);
  void endStep(float dt);
  void guardParticles(float dt);
  void fitReferenceToPins();
  void markPinnedComponents();
  // The stages of one substep [s0, s1] (fractions of the step) of length h.
  void substepXpbd(float h, float s0, float s1, ColliderSpan colliders);
  void substepExplicit(float h, float s0, float s1, ColliderSpan colliders);
  void predict(float h);
  void movePinsTo(float s, float h);
  void solveConstraints(float h);
  void collideBodies(float h, float s0, float s1, ColliderSpan colliders, bool explicitMode);
  void solveSelfContactsAfterBodies();
  void updateVelocities(float h);
  /// The motion constraints' animated pose of this step (beginStep), and their pass over the particles.
  void animate();
  void applyMotionConstraints(float h, bool explicitMode);
  // Their parts.
  void accumulateExternalAcceleration();
  void accumulateSpringForces();
  void solveSprings(float h);
  /// The explicit integrator's stability with these settings and scales (success for XPBD).
  Status checkExplicitStability(const CapeSettings& settings, const Eigen::VectorXf& massScale,
                                const Eigen::VectorXf& stiffnessScale) const;
  void solveTethers();
  void adaptRefinement(float dt);
  /// Whether nothing the cape feels moves in this step (pins and colliders still, no wind).
  bool surroundingsStill(ColliderSpan colliders) const;
  void updateSleep(float dt, bool still, ColliderSpan colliders);

  /// The coarse level's cape and what carries state between the levels (Cape.cpp).
  struct CoarseLevel;
  bool coarseUsable() const;
  void stepCoarse(float dt, ColliderSpan colliders);
  void restrictToCoarse();
  void rebuildCoarsePins();
  void leaveCoarse();
  /// The coarse level starts again from this cape's state at its next step.
  void markCoarseStale();

  FabricPtr fabric_;
  CapeSettings settings_;
  std::unique_ptr<CoarseLevel> coarse_;  ///< Made by the first setCoarseLevel(true).
  bool coarseOn_ = false;
  bool steppedCoarse_ = false;
  std::array<float, kSpringFamilyCount> familyCompliance_{};  ///< 1 / stiffness per family, m/N (inf: off).
  int substepOverride_ = 0;      ///< Substeps per timeStep in place of the settings' (0: none).
  int refinement_ = 1;           ///< Substep multiplier of the next step (1, 2, 4, ...).
  float halvingDelay_ = 0.0f;    ///< s after a doubling before refinement_ may halve (adaptRefinement).
  float sinceHalving_ = 1e30f;   ///< s since refinement_ last halved.
  float sinceDoubling_ = 1e30f;  ///< s since refinement_ last doubled.
  float lastMaxStrain_ = 0.0f;   ///< Max structural strain after the last step.
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  ///< World position of the cape's frame, m.
  Pose reference_;                                    ///< The rest shape's pose in the frame.
  std::vector<std::uint8_t> pinnedComponent_;         ///< 1 for each fabric component holding a pin.
  GuardReport guard_;
  Eigen::VectorXf massScale_;              ///< Per particle (empty: none).
  Eigen::VectorXf stiffnessScale_;         ///< Per particle (empty: none).
  Eigen::VectorXf springComplianceScale_;  ///< Per spring, every family in turn: 1 / its stiffness scale.
  Eigen::VectorXf hingeStiffnessScale_;    ///< Per hinge: its middle particle's stiffness scale.
  MotionConstraints motion_;
  bool motionActive_ = false;  ///< Some array of motion_ is set.
  bool userAnimated_ = false;  ///< animated_ is the caller's (setAnimatedPositions), not the fit.
  Points animated_;            ///< Animated positions (frame), m.
  Points animatedNormals_;     ///< Their vertex normals.
  bool asleep_ = false;
  float stillTime_ = 0.0f;  ///< s the cape has been slow with its surroundings still
  std::uint64_t sleptSteps_ = 0;
  CapeState state_;
  Status status_ = Status::success();
  std::unique_ptr<detail::CapeScratch> work_;  ///< Sized once; null while the cape is not ok().
};

}  // namespace cape
