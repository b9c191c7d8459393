/// \file
/// CapeSettings: per-cape parameters, plain data with units. Checked by validate() before every run.
#pragma once

#include "cape/core/Export.h"
#include "cape/core/Types.h"

namespace cape {

/// How the cape's equations of motion are integrated.
enum class Integrator : int {
  /// Extended position-based dynamics (Macklin, Müller and Chentanez 2016, "XPBD"), with small substeps
  /// (Macklin et al. 2019, "Small Steps in Physics Simulation") and long-range attachments. The default:
  /// stiff cloth stays stable at a 1/60 s frame with 3-4 substeps; see the README for why it was chosen.
  Xpbd = 0,
  /// The seed's explicit Hooke mass-spring with symplectic Euler. A reference: only stable for soft springs
  /// and short steps (the seed used 0.00875 s, four per 0.035 s frame); validate() rejects set-ups beyond its
  /// stability bound.
  ExplicitSpring = 1,
};
/// The integrator's name: "xpbd" or "explicit" ("?" for a value outside the enum).
CAPE_CORE_API const char* toString(Integrator integrator);

/// Wind acting on the cape (the aerodynamic model lives with the solver; this is its data).
struct WindSettings {
  /// The wind models (cape/core/Wind.h gives their equations).
  enum class Model : int {
    None = 0,         ///< No wind.
    SineWave = 1,     ///< Uniform air with a sine gust, quadratic drag per particle (the seed's model).
    Aerodynamic = 2,  ///< Drag and lift per triangle in a gusty, turbulent field.
  };
  Model model = Model::None;       ///< Which model acts; None: no wind.
  Vec3 direction = Vec3::UnitX();  ///< Unit direction of the mean wind.
  float speed = 0.0f;              ///< Mean wind speed, m/s.
  float gustAmplitude = 0.0f;      ///< Relative gust strength (0.5 = +-50 %).
  float gustFrequency = 0.5f;      ///< Hz.
  float turbulenceScale = 1.0f;    ///< m: spatial scale of the turbulence.
  float airDensity = 1.2f;         ///< kg/m^3.
  float dragCoefficient = 1.0f;    ///< Normal (pressure) drag coefficient per triangle.
  float liftCoefficient = 0.2f;    ///< Lift coefficient per triangle.
  unsigned seed = 1;               ///< Seeds the deterministic gust field.
};

/// Per-cape parameters, plain data with units; validate() checks them (Cape checks them when it is made and
/// on setSettings()).
struct CAPE_CORE_API CapeSettings {
  Integrator integrator = Integrator::Xpbd;  ///< How the equations of motion are integrated.

  /// Spring stiffness per family, N/m per spring (Hooke's k). XPBD uses the compliance 1/k; infinity means
  /// inextensible. Families: structural, shear, bend.
  float structuralStiffness = 2.0e4f;
  float shearStiffness = 2.0e3f;  ///< N/m per shear spring (see structuralStiffness).
  float bendStiffness = 20.0f;    ///< N/m per bend spring (see structuralStiffness).
  bool useTethers = true;         ///< Long-range attachments to pinned anchors (XPBD only).
  /// Linear bending, N·m: the fabric's flexural rigidity per unit width (bending moment per width per unit
  /// curvature, KES-F's B), resisted at every hinge of Fabric::hinges() with a moment linear in its angle,
  /// so a coarse and a fine grid bend alike (applyFabric sets it from a FabricMaterial). 0, the default, is
  /// off: the bend springs are the seed's bending.
  float bendingRigidity = 0.0f;

  /// Linear velocity damping, 1/s: dv/dt = -damping * v (applied as v /= 1 + damping * h). Stands in for
  /// the air's drag when no aerodynamic wind model is on: a 0.4 kg, 0.6 m^2 cape moving at 1 m/s through
  /// still air feels about 0.5 rho Cd A v = 0.36 N, i.e. ~1 /s. The default 2 /s was chosen by measurement:
  /// with much less the walking cape swings around the torso and wraps its edges, and its strain climbs
  /// (the sweep is in docs/SOLVER.md, "Choosing the integrator").
  float damping = 2.0f;
  /// Cape half-thickness kept between particles and collider surfaces, m.
  float collisionThickness = 0.01f;
  /// Coulomb friction coefficient against colliders (dimensionless, >= 0).
  float friction = 0.3f;
  /// Substeps per `timeStep`, >= 1: step(dt) takes ceil(dt / (timeStep / substeps)) substeps of equal
  /// length, so a Bullet world stepping at 1/240 s takes one per internal step where a 1/60 s frame takes
  /// three. Three per 1/60 s meet the walk scene's strain bounds (docs/SOLVER.md, "Choosing the integrator").
  int substeps = 3;
  /// Strain-adaptive substepping: when the max structural strain after a step exceeds this (0 = off), the
  /// next steps take 2x, 4x ... up to maxRefinement times the substeps until it falls below half of it. A
  /// halving that has to be undone within a second (the fewer substeps stretch the cape past the limit
  /// again, as a large cape at rest does) makes the next halving wait until 1/8 s after the last doubling,
  /// twice as long after each such bounce up to 16 s, so the substeps do not swing between two levels for
  /// ever (docs/SOLVER.md, "One step").
  /// Meant for stiff cloth under violent motion: it keeps a sprint's 180-degree turn from overstretching the
  /// cape for a few times the cost and leaves walking unchanged (cost in docs/PERFORMANCE.md, strain in
  /// docs/COMPARISON.md); a deliberately stretchy cloth whose working strain is above the limit would pay the
  /// full refinement for nothing: raise the limit or set 0.
  float strainLimit = 0.05f;
  int maxRefinement = 4;  ///< >= 1
  /// Strain limiting (Provot 1995, "Deformation Constraints in a Mass-Spring Model to Describe Rigid Cloth
  /// Behavior"): the most a structural spring may stretch, as a strain (0.1: 10 % beyond its rest length);
  /// 0, the default, is off. In every constraint iteration, after the springs, strainCeilingPasses
  /// Gauss-Seidel passes over the structural springs pull each one stretched beyond the ceiling back to it,
  /// its ends moved in proportion to their inverse masses: a hard, one-sided constraint, so a spring under
  /// the ceiling, compression, folds and gathers are untouched. One XPBD iteration per substep carries a
  /// sudden load through a long cape too slowly, and a sprint's turn stretches single springs far beyond
  /// the cloth's working strain; the ceiling stops them there, and the adaptive substepping above is needed
  /// less often. The collisions and the self-contacts come after it in a substep and win where they
  /// disagree. Off by default: the canonical cape of docs/SCENES.md, hung by its two corners, rests beyond a
  /// few percent beside them and is measured without it; and a ceiling under the strain that a fold held by
  /// self-contacts needs makes the two fight (docs/SOLVER.md, "Strain limiting", has the measurements).
  /// Finite, 0..10. XPBD only.
  float strainCeiling = 0.0f;
  int strainCeilingPasses = 1;  ///< 1..64: passes over the structural springs per iteration.
  /// The numerical guard's reach (Cape::guard()), in rest diameters of the fabric beyond the farthest pin:
  /// a particle farther from the pins is lost and restored. > 0; the default is far beyond any stretch the
  /// springs allow, so only a runaway trips it.
  float guardReach = 2.0f;
  /// Sleeping: a cape whose every particle has been slower than sleepSpeed (m/s) for sleepDelay (s) of
  /// simulated time, with its pins and colliders still and no wind, falls asleep: its velocities become zero
  /// and step() only checks that nothing changed (no solve, no collision, no guard) until it wakes. It wakes,
  /// and simulates that very step, when a pin or a collider moves, a collider comes, goes or changes, or the
  /// settings, the gravity or the state are changed (Cape::isAsleep). 0 never sleeps. The defaults are far
  /// below any motion an eye can see (1 cm/s for a second: a particle drifting less than 1 cm).
  float sleepSpeed = 0.01f;
  float sleepDelay = 1.0f;  ///< s, >= 0
  /// Constraint iterations per substep, >= 1.
  int iterations = 1;
  /// Gravity, m/s^2.
  Vec3 gravity = Vec3(0.0f, -9.8f, 0.0f);
  /// The frame time the settings are tuned for, s, 1e-5..1: `substeps` are per this long, and validate()
  /// checks the explicit mode's stability bound at timeStep / substeps.
  float timeStep = 1.0f / 60.0f;

  WindSettings wind;  ///< The wind acting on the cape (none by default).
  /// Keep the cape from passing through itself: particle-triangle contacts found through a spatial hash at
  /// the start of every step and kept on their side through its substeps (predictive contacts, Lewin 2018).
  bool selfCollision = false;
  /// Distance kept between a particle and any triangle it does not belong to, m; 0 (the default) chooses 0.35
  /// of the mean particle spacing. Measured on the canonical cape: much thinner, the sprint-turn still has
  /// intersecting triangle pairs (two layers crossing edge through edge between their particles); from about
  /// a third of the spacing none, in every scene (docs/SOLVER.md, "Self-collision"). Keep it well under the
  /// spacing, or neighbours of the same layer push each other.
  float selfCollisionThickness = 0.0f;

  /// The Unity seed's explicit solver reproduced: explicit springs, soft, 4 substeps of 0.00875 s per 0.035 s
  /// frame. (Nothing to do with the wind's random `WindSettings::seed`.)
  static CapeSettings unitySeed();

  /// Checks every field against its range (finite, positive where a unit needs it, the explicit mode's
  /// stability bound); the error names the field.
  Status validate() const;
};

}  // namespace cape
