#include "cape/core/CapeSettings.h"

#include <cmath>
#include <string>

namespace cape {

const char* toString(Integrator integrator) {
  switch (integrator) {
    case Integrator::Xpbd:
      return "xpbd";
    case Integrator::ExplicitSpring:
      return "explicit";
  }
  return "?";
}

CapeSettings CapeSettings::unitySeed() {
  CapeSettings s;
  s.integrator = Integrator::ExplicitSpring;
  // The seed's grid has 1 g particles: symplectic Euler at 0.00875 s is only stable for a few N/m
  // (see Cape::explicitStableStep), so the seed's cloth is soft and stretches under its own weight.
  s.structuralStiffness = 3.0f;
  s.shearStiffness = 3.0f;
  s.bendStiffness = 0.0f;
  s.useTethers = false;
  s.damping = 0.5f;
  s.substeps = 4;
  s.iterations = 1;
  s.timeStep = 0.035f;  // one frame = four steps of 0.00875 s
  s.collisionThickness = 0.0f;
  s.friction = 0.0f;
  return s;
}

Status CapeSettings::validate() const {
  auto finiteNonNegative = [](float v) { return std::isfinite(v) && v >= 0.0f; };
  if (integrator != Integrator::Xpbd && integrator != Integrator::ExplicitSpring)
    return Status::error("CapeSettings: unknown integrator");
  if (std::isnan(structuralStiffness) || !(structuralStiffness > 0.0f))
    return Status::error("CapeSettings: structuralStiffness must be > 0 N/m (infinity = inextensible)");
  if (std::isnan(shearStiffness) || shearStiffness < 0.0f)
    return Status::error("CapeSettings: shearStiffness must be >= 0 N/m (0 disables the family)");
  if (std::isnan(bendStiffness) || bendStiffness < 0.0f)
    return Status::error("CapeSettings: bendStiffness must be >= 0 N/m (0 disables the family)");
  if (!finiteNonNegative(bendingRigidity))
    return Status::error("CapeSettings: bendingRigidity must be finite and >= 0 N·m (0 = off)");
  if (integrator == Integrator::ExplicitSpring &&
      (std::isinf(structuralStiffness) || std::isinf(shearStiffness) || std::isinf(bendStiffness)))
    return Status::error("CapeSettings: the explicit integrator needs finite stiffness");
  if (!finiteNonNegative(damping))
    return Status::error("CapeSettings: damping must be finite and >= 0 (1/s)");
  if (!finiteNonNegative(collisionThickness))
    return Status::error("CapeSettings: collisionThickness must be finite and >= 0 (m)");
  if (!finiteNonNegative(friction)) return Status::error("CapeSettings: friction must be finite and >= 0");
  if (!(std::isfinite(selfCollisionThickness) && selfCollisionThickness >= 0.0f))
    return Status::error("CapeSettings: selfCollisionThickness must be finite and >= 0 (m; 0 = automatic)");
  if (substeps < 1 || substeps > 1000) return Status::error("CapeSettings: substeps must be in 1..1000");
  if (!(std::isfinite(strainLimit) && strainLimit >= 0.0f))
    return Status::error("CapeSettings: strainLimit must be finite and >= 0");
  if (maxRefinement < 1 || maxRefinement > 64)
    return Status::error("CapeSettings: maxRefinement must be in 1..64");
  if (!(std::isfinite(strainCeiling) && strainCeiling >= 0.0f && strainCeiling <= 10.0f))
    return Status::error("CapeSettings: strainCeiling must be in 0..10 (a strain; 0 = no strain limiting)");
  if (strainCeilingPasses < 1 || strainCeilingPasses > 64)
    return Status::error("CapeSettings: strainCeilingPasses must be in 1..64");
  if (iterations < 1 || iterations > 1000)
    return Status::error("CapeSettings: iterations must be in 1..1000");
  if (!gravity.allFinite()) return Status::error("CapeSettings: gravity must be finite");
  if (!(timeStep >= 1e-5f && timeStep <= 1.0f))
    return Status::error("CapeSettings: timeStep must be in 1e-5..1 s");
  if (!(std::isfinite(guardReach) && guardReach > 0.0f))
    return Status::error("CapeSettings: guardReach must be finite and > 0 (rest diameters)");
  if (!finiteNonNegative(sleepSpeed) || !finiteNonNegative(sleepDelay))
    return Status::error("CapeSettings: sleepSpeed (m/s) and sleepDelay (s) must be finite and >= 0");
  if (wind.model != WindSettings::Model::None) {
    if (!wind.direction.allFinite() || !(wind.direction.norm() > 0.0f))
      return Status::error("CapeSettings: wind direction must be a finite nonzero vector");
    if (!finiteNonNegative(wind.speed) || !finiteNonNegative(wind.gustAmplitude) ||
        !finiteNonNegative(wind.gustFrequency) ||
        !(std::isfinite(wind.turbulenceScale) && wind.turbulenceScale > 0.0f) ||
        !finiteNonNegative(wind.airDensity) || !finiteNonNegative(wind.dragCoefficient) ||
        !std::isfinite(wind.liftCoefficient))
      return Status::error("CapeSettings: wind parameters must be finite and >= 0 (turbulence scale > 0)");
  }
  return Status::success();
}

}  // namespace cape
