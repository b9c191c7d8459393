#include "cape/core/Cape.h"

#include "cape/core/CapeMesh.h"

#include "cape/core/Wind.h"

#include "CapeScratch.h"
#include "CoarseLevel.h"
#include "SpringSolver.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace cape {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kContactPasses = 3;  // extra push-out passes over the substep's contacts
// The strain refinement's halving (Cape::adaptRefinement): a halving followed within kBounceTime by a
// doubling bounced, and the next halving then waits until kFirstBackoff after the last doubling, twice as
// long after each further bounce up to kMaxBackoff, and no longer waits once a halving has held for
// kSettledTime. All of them s of simulated time.
constexpr float kBounceTime = 1.0f;
constexpr float kFirstBackoff = 0.125f;
constexpr float kMaxBackoff = 16.0f;
constexpr float kSettledTime = 20.0f;

float stiffnessOf(const CapeSettings& s, int family) {
  switch (static_cast<SpringFamily>(family)) {
    case SpringFamily::Structural:
      return s.structuralStiffness;
    case SpringFamily::Shear:
      return s.shearStiffness;
    case SpringFamily::Bend:
      return s.bendStiffness;
  }
  return 0.0f;
}

}  // namespace

/// The largest substep the explicit integrator can take without blowing up. Symplectic Euler on a linear
/// spring system is stable while h * omega_max < 2, i.e. h^2 * lambda_max(M^-1 K) < 4; Gershgorin's theorem
/// bounds lambda_max by max over particles i of sum over springs (i, j) of k * (w_i + w_j).
/// With a mass scale and a stiffness scale (Cape::setMassScale, setStiffnessScale; empty: none).
static float explicitStableStep(const Fabric& fabric, const CapeSettings& settings,
                                const Eigen::VectorXf& massScale = Eigen::VectorXf(),
                                const Eigen::VectorXf& stiffnessScale = Eigen::VectorXf()) {
  Eigen::VectorXf bound = Eigen::VectorXf::Zero(static_cast<Eigen::Index>(fabric.particleCount()));
  const Eigen::VectorXf m =
      massScale.size() > 0 ? Eigen::VectorXf(fabric.masses().cwiseProduct(massScale)) : fabric.masses();
  const auto scaleOf = [&](std::uint32_t i) { return stiffnessScale.size() > 0 ? stiffnessScale[i] : 1.0f; };
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const float k0 = stiffnessOf(settings, f);
    if (k0 <= 0.0f) continue;
    const SpringSet& set = fabric.springs(static_cast<SpringFamily>(f));
    for (std::size_t s = 0; s < set.size(); ++s) {
      const float k = k0 * 0.5f * (scaleOf(set.first[s]) + scaleOf(set.second[s]));
      const float w = 1.0f / m[set.first[s]] + 1.0f / m[set.second[s]];
      bound[set.first[s]] += k * w;
      bound[set.second[s]] += k * w;
    }
  }
  if (settings.bendingRigidity > 0.0f) {
    // A hinge's stiffness matrix is k g g^T with g its gradient: Gershgorin's row sums of M^-1 K.
    const HingeSet& h = fabric.hinges();
    for (std::size_t k = 0; k < h.size(); ++k) {
      const float kk = settings.bendingRigidity * h.areaOverLength2[k] * scaleOf(h.middle[k]);
      const float a = h.firstWeight[k], b = h.secondWeight[k], ab = a + b;
      const float sum = a + b + ab;
      bound[h.first[k]] += kk * a * sum / m[h.first[k]];
      bound[h.second[k]] += kk * b * sum / m[h.second[k]];
      bound[h.middle[k]] += kk * ab * sum / m[h.middle[k]];
    }
  }
  const float lambdaMax = bound.maxCoeff();
  return lambdaMax > 0.0f ? 2.0f / std::sqrt(lambdaMax) : kInf;
}

detail::CapeScratch::CapeScratch(const Fabric& fabric) : body(fabric.particleCount()), self(fabric) {
  const Eigen::Index n = static_cast<Eigen::Index>(fabric.particleCount());
  startPositions = Points::Zero(n, 3);
  acceleration = Points::Zero(n, 3);
  airVelocity = Points::Zero(n, 3);
  freeMask = Eigen::VectorXf::Ones(n);
  lambda = Eigen::VectorXf::Zero(static_cast<Eigen::Index>(fabric.springCount()));
  hingeLambda = Eigen::VectorXf::Zero(static_cast<Eigen::Index>(fabric.hinges().size()));
  selfWeight = Eigen::VectorXf::Zero(n);
  lost.reserve(static_cast<std::size_t>(n));
}

Cape::Cape(FabricPtr fabric, const CapeSettings& settings, const Pose& placement)
    : fabric_(std::move(fabric)), settings_(settings) {
  if (!fabric_) {
    status_ = Status::error("Cape: no fabric");
    return;
  }
  if (!placement.isFinite()) {
    status_ = Status::error("Cape: placement pose is not finite");
    return;
  }
  status_ = setSettings(settings);
  if (!status_.ok()) return;
  const Eigen::Index n = static_cast<Eigen::Index>(fabric_->particleCount());
  state_.positions.resize(n, 3);
  const Eigen::Matrix3f r = placement.rotation.toRotationMatrix();
  for (Eigen::Index i = 0; i < n; ++i)
    state_.positions.row(i) =
        (r * fabric_->restPositions().row(i).transpose() + placement.position).transpose();
  state_.velocities = Points::Zero(n, 3);
  state_.inverseMasses = fabric_->masses().cwiseInverse();
  state_.pins.reserve(static_cast<std::size_t>(n));
  reference_ = placement;
  reference_.rotation.normalize();
  pinnedComponent_.assign(fabric_->componentCount(), 0);
  work_ = std::make_unique<detail::CapeScratch>(*fabric_);
  if (settings_.selfCollision) work_->self.allocate();  // stepping never allocates
  work_->startPositions = state_.positions;
  animated_ = state_.positions;
  animatedNormals_ = Points::Zero(n, 3);
}

Status Cape::setMotionConstraints(const MotionConstraints& c) {
  if (!ok()) return status_;
  const Eigen::Index n = state_.positions.rows();
  const auto check = [n](const Eigen::VectorXf& v, const char* name, float lo, float hi,
                         bool infinityAllowed) -> Status {
    if (v.size() == 0) return Status::success();
    if (v.size() != n)
      return Status::error(std::string("MotionConstraints: ") + name + " has " + std::to_string(v.size()) +
                           " values for " + std::to_string(n) + " particles");
    for (Eigen::Index i = 0; i < n; ++i) {
      const float x = v[i];
      const bool inRange = x >= lo && x <= hi && (infinityAllowed || std::isfinite(x));
      if (!inRange)
        return Status::error(std::string("MotionConstraints: ") + name + " of particle " + std::to_string(i) +
                             " is " + std::to_string(x) + ", outside its range");
    }
    return Status::success();
  };
  const float inf = std::numeric_limits<float>::infinity();
  for (const Status& st : {check(c.maxDistance, "maxDistance", 0.0f, inf, true),
                           check(c.backstopRadius, "backstopRadius", 0.0f, inf, false),
                           check(c.backstopDistance, "backstopDistance", 0.0f, inf, false),
                           check(c.drive, "drive", 0.0f, 1.0f, false)})
    if (!st.ok()) return st;
  if (c.backstopDistance.size() != 0 && c.backstopRadius.size() == 0)
    return Status::error("MotionConstraints: backstopDistance without backstopRadius");
  motion_ = c;
  motionActive_ = c.maxDistance.size() != 0 || c.backstopRadius.size() != 0 || c.drive.size() != 0;
  wake();
  return Status::success();
}

Status Cape::setAnimatedPositions(const Points& positions) {
  if (!ok()) return status_;
  if (positions.rows() == 0) {
    userAnimated_ = false;
    wake();
    return Status::success();
  }
  if (positions.rows() != state_.positions.rows())
    return Status::error("Cape::setAnimatedPositions: " + std::to_string(positions.rows()) +
                         " positions for " + std::to_string(state_.positions.rows()) + " particles");
  if (!positions.allFinite()) return Status::error("Cape::setAnimatedPositions: a position is not finite");
  if (userAnimated_ && positions == animated_) return Status::success();
  animated_ = positions;
  userAnimated_ = true;
  wake();
  return Status::success();
}

void Cape::animate() {
  // The rest shape fitted to the pins' targets at the end of this step (unless the caller animates), and
  // the animated surface's normals for the backstops.
  if (!userAnimated_) {
    fitReferenceToPins();
    const Points& rest = fabric_->restPositions();
    const Eigen::Matrix3f r = reference_.rotation.toRotationMatrix();
    for (Eigen::Index i = 0; i < rest.rows(); ++i)
      animated_.row(i) = (r * rest.row(i).transpose() + reference_.position).transpose();
  }
  if (motion_.backstopRadius.size() != 0)
    computeVertexNormals(animated_, fabric_->triangles(), animatedNormals_);
}

void Cape::applyMotionConstraints(float h, bool explicitMode) {
  // Drive, then backstops, then the max distance (last, so that it holds at the end of the step). Plain
  // loops over particles; only free particles move.
  const Eigen::Index n = state_.positions.rows();
  const float* w = state_.inverseMasses.data();
  const bool drive = motion_.drive.size() != 0, backstop = motion_.backstopRadius.size() != 0,
             limit = motion_.maxDistance.size() != 0;
  const float side = motion_.backstopAlongNormal ? 1.0f : -1.0f;
  const float frames = h * 60.0f;  // the drive is given per 1/60 s
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(w[i] > 0.0f)) continue;
    const Vec3 a = animated_.row(i).transpose();
    Vec3 x = state_.positions.row(i).transpose();
    const Vec3 before = x;
    if (drive) {
      const float d = motion_.drive[i];
      const float k = d >= 1.0f ? 1.0f : 1.0f - std::pow(1.0f - d, frames);
      x += k * (a - x);
    }
    if (backstop && motion_.backstopRadius[i] > 0.0f) {
      const float r = motion_.backstopRadius[i];
      const float gap = motion_.backstopDistance.size() != 0 ? motion_.backstopDistance[i] : 0.0f;
      const Vec3 normal = animatedNormals_.row(i).transpose();
      const Vec3 c = a + (side * (gap + r)) * normal;
      const Vec3 u = x - c;
      const float len = u.norm();
      if (len < r) x = c + (len > 1e-9f * r ? (r / len) * u : (-side * r) * normal);
    }
    if (limit) {
      const float reach = motion_.maxDistance[i];
      const Vec3 u = x - a;
      const float len = u.norm();
      if (len > reach) x = a + (reach / len) * u;
    }
    if (x != before) {
      state_.positions.row(i) = x.transpose();
      // The explicit integrator keeps its velocities: give them the move (XPBD derives them afterwards).
      if (explicitMode) state_.velocities.row(i) += ((x - before) / h).transpose();
    }
  }
}

Cape::~Cape() = default;
Cape::Cape(Cape&&) noexcept = default;
Cape& Cape::operator=(Cape&&) noexcept = default;

float Cape::selfCollisionThickness() const {
  return work_ ? work_->self.thickness(settings_) : 0.0f;
}

const std::vector<Cape::SelfContact>& Cape::selfContacts() const {
  static const std::vector<SelfContact> none;
  return work_ ? work_->self.contacts() : none;
}

std::size_t Cape::selfCollisionScratchBytes() const {
  return work_ ? work_->self.scratchBytes() : 0;
}

std::uint64_t Cape::selfContactSearches() const {
  return work_ ? work_->self.searches() : 0;
}

std::uint64_t Cape::selfContactSearchesProvenApart() const {
  return work_ ? work_->self.searchesProvenApart() : 0;
}

Status Cape::setGravity(const Vec3& gravity) {
  if (!gravity.allFinite()) return Status::error("Cape::setGravity: gravity must be finite");
  if (gravity != settings_.gravity) wake();
  settings_.gravity = gravity;
  return Status::success();
}

Status Cape::setSettings(const CapeSettings& settings) {
  Status s = settings.validate();
  if (!s.ok()) return s;
  if (Status stable = checkExplicitStability(settings, massScale_, stiffnessScale_); !stable.ok())
    return stable;
  settings_ = settings;
  // The self-contact search's scratch, the first time self-collision is on (stepping never allocates).
  if (settings_.selfCollision && work_) work_->self.allocate();
  wake();
  // The coarse level keeps the settings it has if it refuses these (only the explicit integrator's
  // stability check can, and its longer springs are the more stable).
  if (coarse_) coarse_->cape.setSettings(settings);
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const float k = stiffnessOf(settings_, f);
    familyCompliance_[static_cast<std::size_t>(f)] = k > 0.0f ? 1.0f / k : kInf;  // inf compliance = off
  }
  return Status::success();
}

Status Cape::setSubstepOverride(int substeps) {
  if (substeps < 0 || substeps > 1000)
    return Status::error("Cape::setSubstepOverride: substeps must be 0 (none) or in 1..1000, not " +
                         std::to_string(substeps));
  substepOverride_ = substeps;
  if (coarse_) coarse_->cape.setSubstepOverride(substeps);
  return Status::success();
}

std::size_t Cape::pin(std::uint32_t particle, const Vec3& target) {
  if (!ok() || particle >= fabric_->particleCount() || !target.allFinite())
    return static_cast<std::size_t>(-1);
  wake();
  for (std::size_t k = 0; k < state_.pins.size(); ++k) {
    if (state_.pins[k].particle == particle) {
      state_.pins[k].previousTarget = state_.pins[k].target = target;
      return k;
    }
  }
  state_.inverseMasses[particle] = 0.0f;
  state_.pins.push_back({particle, target, target});
  markPinnedComponents();
  if (coarse_) coarse_->pinsStale = true;
  return state_.pins.size() - 1;
}

void Cape::unpin(std::uint32_t particle) {
  if (!ok() || particle >= fabric_->particleCount()) return;
  auto it = std::find_if(state_.pins.begin(), state_.pins.end(),
                         [&](const Pin& p) { return p.particle == particle; });
  if (it == state_.pins.end()) return;
  wake();
  state_.pins.erase(it);
  if (coarse_) coarse_->pinsStale = true;
  state_.inverseMasses[particle] =
      1.0f / (fabric_->masses()[particle] * (massScale_.size() > 0 ? massScale_[particle] : 1.0f));
  markPinnedComponents();
}

namespace {

// A per-particle scale's checks (setMassScale, setStiffnessScale): empty, or one finite value in (0, 1e6]
// per particle.
Status checkScale(const char* what, const Eigen::VectorXf& scale, std::size_t particles) {
  if (scale.size() == 0) return Status::success();
  if (static_cast<std::size_t>(scale.size()) != particles)
    return Status::error(std::string("Cape::") + what + ": " + std::to_string(scale.size()) + " values for " +
                         std::to_string(particles) + " particles");
  for (Eigen::Index i = 0; i < scale.size(); ++i)
    if (!(std::isfinite(scale[i]) && scale[i] > 0.0f && scale[i] <= 1e6f))
      return Status::error(std::string("Cape::") + what + ": value " + std::to_string(i) +
                           " is not finite in (0, 1e6]");
  return Status::success();
}

}  // namespace

Status Cape::checkExplicitStability(const CapeSettings& settings, const Eigen::VectorXf& massScale,
                                    const Eigen::VectorXf& stiffnessScale) const {
  if (settings.integrator != Integrator::ExplicitSpring) return Status::success();
  const float hMax = explicitStableStep(*fabric_, settings, massScale, stiffnessScale);
  const float h = settings.timeStep / static_cast<float>(settings.substeps);
  if (h >= hMax)
    return Status::error("CapeSettings: the explicit integrator is unstable for this fabric: substep " +
                         std::to_string(h) + " s >= stability bound " + std::to_string(hMax) +
                         " s; lower the stiffness (or its scale), raise the masses or the substeps");
  return Status::success();
}

Status Cape::setMassScale(const Eigen::VectorXf& scale) {
  if (!ok()) return status_;
  if (Status s = checkScale("setMassScale", scale, fabric_->particleCount()); !s.ok()) return s;
  if (Status s = checkExplicitStability(settings_, scale, stiffnessScale_); !s.ok()) return s;
  wake();
  massScale_ = scale;
  const Eigen::VectorXf& m = fabric_->masses();
  for (Eigen::Index i = 0; i < state_.inverseMasses.size(); ++i)
    state_.inverseMasses[i] = 1.0f / (m[i] * (massScale_.size() > 0 ? massScale_[i] : 1.0f));
  for (const Pin& p : state_.pins) state_.inverseMasses[p.particle] = 0.0f;
  return Status::success();
}

Status Cape::setStiffnessScale(const Eigen::VectorXf& scale) {
  if (!ok()) return status_;
  if (Status s = checkScale("setStiffnessScale", scale, fabric_->particleCount()); !s.ok()) return s;
  if (Status s = checkExplicitStability(settings_, massScale_, scale); !s.ok()) return s;
  wake();
  stiffnessScale_ = scale;
  springComplianceScale_.resize(0);
  hingeStiffnessScale_.resize(0);
  if (scale.size() == 0) return Status::success();
  springComplianceScale_.resize(static_cast<Eigen::Index>(fabric_->springCount()));
  Eigen::Index at = 0;
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const SpringSet& set = fabric_->springs(static_cast<SpringFamily>(f));
    for (std::size_t s = 0; s < set.size(); ++s)
      springComplianceScale_[at++] = 1.0f / (0.5f * (scale[set.first[s]] + scale[set.second[s]]));
  }
  const HingeSet& h = fabric_->hinges();
  hingeStiffnessScale_.resize(static_cast<Eigen::Index>(h.size()));
  for (std::size_t k = 0; k < h.size(); ++k)
    hingeStiffnessScale_[static_cast<Eigen::Index>(k)] = scale[h.middle[k]];
  return Status::success();
}

void Cape::movePin(std::size_t k, const Vec3& target) {
  if (k >= state_.pins.size()) return;
  Pin& p = state_.pins[k];
  p.previousTarget = p.target;
  if (target.allFinite()) p.target = target;  // a non-finite target is ignored: the pin holds still
}

void Cape::markPinnedComponents() {
  std::fill(pinnedComponent_.begin(), pinnedComponent_.end(), std::uint8_t{0});
  for (const Pin& p : state_.pins) pinnedComponent_[fabric_->components()[p.particle]] = 1;
}

void Cape::setOrigin(const Eigen::Vector3d& origin) {
  if (!ok() || !origin.allFinite()) return;
  if (origin == origin_) return;
  wake();
  // The coarse level's frame is this cape's: it moves the same way (a stale one takes the origin when it
  // starts again).
  if (coarse_ && !coarse_->stale) coarse_->cape.setOrigin(origin);
  // Frame coordinates change by old - new, computed in double and rounded once.
  const Vec3 d = (origin_ - origin).cast<float>();
  origin_ = origin;
  if (d.isZero()) return;
  state_.positions.rowwise() += d.transpose();
  work_->startPositions.rowwise() += d.transpose();
  for (Pin& p : state_.pins) {
    p.previousTarget += d;
    p.target += d;
  }
  reference_.position += d;
}

void Cape::relocate(const Eigen::Vector3d& origin) {
  if (!ok() || !origin.allFinite() || origin == origin_) return;
  wake();  // the colliders it sleeps among are in the old frame's coordinates
  origin_ = origin;
  if (coarse_ && !coarse_->stale) coarse_->cape.relocate(origin);
}

void Cape::teleport(const Pose& delta) {
  if (!ok() || !delta.isFinite()) return;
  wake();
  reference_.position = delta.apply(reference_.position);
  reference_.rotation = (delta.rotation * reference_.rotation).normalized();
  const Eigen::Matrix3f r = delta.rotation.toRotationMatrix();
  for (Eigen::Index i = 0; i < state_.positions.rows(); ++i) {
    state_.positions.row(i) = (r * state_.positions.row(i).transpose() + delta.position).transpose();
    state_.velocities.row(i) = (r * state_.velocities.row(i).transpose()).transpose();
  }
  for (Pin& p : state_.pins) {
    p.previousTarget = delta.apply(p.previousTarget);
    p.target = delta.apply(p.target);
  }
  if (coarse_ && !coarse_->stale) {
    coarse_->cape.teleport(delta);
    coarse_->turnOffset(r);
  }
}

void Cape::resetToReference() {
  if (!ok()) return;
  wake();
  fitReferenceToPins();
  const Points& rest = fabric_->restPositions();
  for (Eigen::Index i = 0; i < state_.positions.rows(); ++i)
    state_.positions.row(i) = reference_.apply(rest.row(i).transpose()).transpose();
  for (Pin& p : state_.pins) {
    p.previousTarget = p.target;
    state_.positions.row(p.particle) = p.target.transpose();
  }
  state_.velocities.setZero();
  work_->startPositions = state_.positions;
  work_->self.forget();
  markCoarseStale();
}

void Cape::carry(const Eigen::Matrix3f& m, const Vec3& centre, const Vec3& shift) {
  if (!ok() || !m.allFinite() || !centre.allFinite() || !shift.allFinite()) return;
  if (m == Eigen::Matrix3f::Identity() && shift.isZero()) return;  // carries nothing
  wake();
  reference_.position = m * (reference_.position - centre) + centre + shift;
  reference_.rotation = (Quat(m) * reference_.rotation).normalized();
  for (Eigen::Index i = 0; i < state_.positions.rows(); ++i) {
    const Vec3 x = state_.positions.row(i).transpose();
    state_.positions.row(i) = (m * (x - centre) + centre + shift).transpose();
    state_.velocities.row(i) = (m * Vec3(state_.velocities.row(i).transpose())).transpose();
  }
  for (Pin& p : state_.pins) p.previousTarget = m * (p.previousTarget - centre) + centre + shift;
  if (coarse_ && !coarse_->stale) {
    coarse_->cape.carry(m, centre, shift);
    coarse_->turnOffset(m);
  }
}

void Cape::step(float dt, ColliderSpan colliders) {
  if (!ok() || !std::isfinite(dt) || !(dt > 0.0f)) return;
  dt = std::min(dt, kMaxStep);
  if (coarseOn_ && coarseUsable()) {
    stepCoarse(dt, colliders);
    return;
  }
  if (steppedCoarse_) leaveCoarse();
  const bool still = surroundingsStill(colliders);
  if (asleep_) {
    if (still && work_->sleep.same(colliders)) {
      state_.time += static_cast<double>(dt);
      ++sleptSteps_;
      return;
    }
    wake();
  }
  const StepPlan plan = planSubsteps(dt);
  beginStep(dt, colliders);
  int searchEvery = 0;  // substeps between self-contact searches inside the loop; 0: none there
  if (settings_.selfCollision && settings_.integrator == Integrator::Xpbd)
    searchEvery = work_->self.schedule(state_, work_->freeMask, settings_, dt, plan.substeps);
  for (int k = 0; k < plan.substeps; ++k) {
    if (searchEvery > 0 && k % searchEvery == 0)
      work_->self.searchFor(state_, work_->freeMask, settings_,
                            plan.h * static_cast<float>(std::min(searchEvery, plan.substeps - k)));
    const float s0 = static_cast<float>(k) / static_cast<float>(plan.substeps);
    const float s1 = static_cast<float>(k + 1) / static_cast<float>(plan.substeps);
    if (settings_.integrator == Integrator::Xpbd)
      substepXpbd(plan.h, s0, s1, colliders);
    else
      substepExplicit(plan.h, s0, s1, colliders);
  }
  endStep(dt);
  updateSleep(dt, still, colliders);
}

bool Cape::stepAsleep(float dt) {
  // As step() with the colliders of the last step: awake, coarse or leaving the coarse level, it simulates.
  if (!ok() || !asleep_ || coarseOn_ || steppedCoarse_ || !std::isfinite(dt) || !(dt > 0.0f)) return false;
  for (const Pin& p : state_.pins)
    if (p.target != p.previousTarget) return false;
  state_.time += static_cast<double>(std::min(dt, kMaxStep));
  ++sleptSteps_;
  return true;
}

void Cape::wake() {
  asleep_ = false;
  stillTime_ = 0.0f;
  if (coarse_) coarse_->cape.wake();
}

bool Cape::surroundingsStill(ColliderSpan colliders) const {
  if (!(settings_.sleepSpeed > 0.0f) || settings_.wind.model != WindSettings::Model::None) return false;
  for (const Pin& p : state_.pins)
    if (p.target != p.previousTarget) return false;
  for (const Collider& c : colliders)
    if (c.previous.position != c.current.position ||
        c.previous.rotation.coeffs() != c.current.rotation.coeffs())
      return false;
  return true;
}

void Cape::updateSleep(float dt, bool still, ColliderSpan colliders) {
  // Asleep once every particle has been slow for sleepDelay with nothing around it moving. The test reads
  // the velocities once per step (the speed of a pinned particle is its still pin's: zero).
  if (!still) {
    stillTime_ = 0.0f;
    return;
  }
  const float limit2 = settings_.sleepSpeed * settings_.sleepSpeed;
  const float *vx = state_.velocities.col(0).data(), *vy = state_.velocities.col(1).data(),
              *vz = state_.velocities.col(2).data();
  float fastest2 = 0.0f;
  for (Eigen::Index i = 0, n = state_.velocities.rows(); i < n; ++i)
    fastest2 = std::max(fastest2, vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i]);
  if (!(fastest2 < limit2)) {
    stillTime_ = 0.0f;
    return;
  }
  stillTime_ += dt;
  if (stillTime_ < settings_.sleepDelay) return;
  asleep_ = true;
  state_.velocities.setZero();
  work_->sleep.remember(colliders);
}

Cape::StepPlan Cape::planSubsteps(float dt) const {
  // settings.substeps are per settings.timeStep: a step of another length keeps the substep length, so a
  // world stepping at 1/240 s takes one substep where a 1/60 s frame takes three (the 1e-3 keeps dt =
  // timeStep at exactly `substeps` despite rounding).
  // Counts are bounded before they become ints (dt <= kMaxStep, timeStep >= 1e-5 s: at most 1e8 substeps
  // before refinement; the cap keeps a pathological explicit bound from overflowing).
  constexpr double kMaxSubsteps = 1e6;
  const int perTimeStep = substepOverride_ > 0 ? substepOverride_ : settings_.substeps;
  const float targetSubstep = settings_.timeStep / static_cast<float>(perTimeStep);
  int substeps = static_cast<int>(
      std::clamp(std::ceil(static_cast<double>(dt / targetSubstep - 1e-3f)), 1.0, kMaxSubsteps));
  if (settings_.integrator == Integrator::Xpbd) substeps *= refinement_;
  if (settings_.integrator == Integrator::ExplicitSpring) {
    // A longer step than the settings were checked for: split it further rather than blow up.
    const float hMax = explicitStableStep(*fabric_, settings_);
    const double needed = std::ceil(static_cast<double>(dt) / (0.9 * static_cast<double>(hMax)));
    substeps = std::max(substeps, static_cast<int>(std::clamp(needed, 1.0, kMaxSubsteps)));
  }
  return {substeps, dt / static_cast<float>(substeps)};
}

void Cape::beginStep(float dt, ColliderSpan colliders) {
  // 1 for free particles, 0 for pinned ones (same size every step: no allocation).
  work_->freeMask = (state_.inverseMasses.array() > 0.0f).cast<float>();
  // The air's velocity at each particle, once per step at its middle: gusts change over tenths of a second,
  // far slower than a frame.
  if (settings_.wind.model != WindSettings::Model::None)
    windVelocities(settings_.wind, state_.positions, state_.time + 0.5 * static_cast<double>(dt),
                   work_->airVelocity, origin_);
  // Triangle meshes: each particle's candidate triangles for the whole step, found once. The slack, a
  // quarter of the spacing, is the self-collision search's for the same reason.
  work_->body.beginStep(state_, colliders, settings_, dt, 0.25f * fabric_->meanSpacing());
  if (motionActive_) animate();
}

void Cape::endStep(float dt) {
  guardParticles(dt);
  for (Pin& p : state_.pins) p.previousTarget = p.target;
  state_.time += static_cast<double>(dt);
  adaptRefinement(dt);
}

void Cape::guardParticles(float dt) {
  // One pass over the particles (no allocation: `lost` has its capacity), whose result is almost always
  // "none": the comparisons are written so that NaN fails them.
  const Eigen::Index n = state_.positions.rows();
  Vec3 centre = Vec3::Zero();
  float bound2 = std::numeric_limits<float>::infinity();
  if (!state_.pins.empty()) {
    for (const Pin& p : state_.pins) centre += p.target;
    centre /= static_cast<float>(state_.pins.size());
    float reach = 0.0f;
    for (const Pin& p : state_.pins) reach = std::max(reach, (p.target - centre).norm());
    reach += settings_.guardReach * fabric_->restDiameter();
    bound2 = reach * reach;
  }
  const float *px = state_.positions.col(0).data(), *py = state_.positions.col(1).data(),
              *pz = state_.positions.col(2).data();
  const float *vx = state_.velocities.col(0).data(), *vy = state_.velocities.col(1).data(),
              *vz = state_.velocities.col(2).data();
  const std::uint32_t* component = fabric_->components().data();
  const std::uint8_t* pinned = pinnedComponent_.data();
  std::vector<std::uint32_t>& lost = work_->lost;
  lost.clear();
  for (Eigen::Index i = 0; i < n; ++i) {
    const float dx = px[i] - centre.x(), dy = py[i] - centre.y(), dz = pz[i] - centre.z();
    // A piece no pin holds may go anywhere: only finiteness is asked of it (0 * x is NaN for x inf or NaN).
    const float d2 = pinned[component[i]] != 0 ? dx * dx + dy * dy + dz * dz : 0.0f * (px[i] + py[i] + pz[i]);
    const float v2 = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
    if (!(d2 <= bound2) || !(v2 <= std::numeric_limits<float>::max()))
      lost.push_back(static_cast<std::uint32_t>(i));
  }
  guard_.lastStep = static_cast<std::uint32_t>(lost.size());
  if (lost.empty()) return;
  guard_.total += lost.size();
  ++guard_.steps;
  fitReferenceToPins();
  Vec3 pinVelocity = Vec3::Zero();
  for (const Pin& p : state_.pins) pinVelocity += (p.target - p.previousTarget) / dt;
  if (!state_.pins.empty()) pinVelocity /= static_cast<float>(state_.pins.size());
  if (!pinVelocity.allFinite()) pinVelocity.setZero();
  const Points& rest = fabric_->restPositions();
  for (const std::uint32_t i : lost) {
    Vec3 x = reference_.apply(rest.row(i).transpose());
    if (state_.inverseMasses[i] == 0.0f)
      for (const Pin& p : state_.pins)
        if (p.particle == i) x = p.target;
    state_.positions.row(i) = x.transpose();
    state_.velocities.row(i) = pinVelocity.transpose();
  }
}

void Cape::fitReferenceToPins() {
  // The rotation R and shift t minimising sum |R r_k + t - x_k|^2 over the pins (rest point r_k, target
  // x_k): Kabsch's, from the SVD of M = sum (r_k - r)(x_k - x)^T. With fewer than three pins, or pins on a
  // line, some rotations are not fixed by them: a small multiple of the current rotation added to M takes
  // those from the pose the reference had, so the fit turns it as little as the pins allow. No pins: the
  // reference follows the mean displacement of the particles still finite.
  const Points& rest = fabric_->restPositions();
  if (state_.pins.empty()) {
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();
    std::size_t count = 0;
    for (Eigen::Index i = 0; i < state_.positions.rows(); ++i) {
      const Vec3 x = state_.positions.row(i).transpose();
      if (!x.allFinite() || x.cwiseAbs().maxCoeff() > 1e30f) continue;
      shift += (x - reference_.apply(rest.row(i).transpose())).cast<double>();
      ++count;
    }
    if (count > 0) reference_.position += (shift / static_cast<double>(count)).cast<float>();
    return;
  }
  Eigen::Vector3d r = Eigen::Vector3d::Zero(), x = Eigen::Vector3d::Zero();
  for (const Pin& p : state_.pins) {
    r += rest.row(p.particle).transpose().cast<double>();
    x += p.target.cast<double>();
  }
  const double count = static_cast<double>(state_.pins.size());
  r /= count;
  x /= count;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  double spread = 0.0;
  for (const Pin& p : state_.pins) {
    const Eigen::Vector3d a = rest.row(p.particle).transpose().cast<double>() - r;
    m += a * (p.target.cast<double>() - x).transpose();
    spread += a.squaredNorm();
  }
  const Eigen::Matrix3d previous = reference_.rotation.toRotationMatrix().cast<double>();
  m += 1e-3 * std::max(spread, 1e-12) * previous.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  const Eigen::Matrix3d rotation = svd.matrixV() * d * svd.matrixU().transpose();
  if (!rotation.allFinite()) return;
  reference_.rotation = Quat(rotation.cast<float>()).normalized();
  reference_.position = (x - rotation * r).cast<float>();
}

void Cape::adaptRefinement(float dt) {
  // Strain-adaptive substepping: one Gauss-Seidel pass per substep carries a sudden load (a 180-degree turn
  // at a run) through a 20-row cape too slowly, and the cape stretches. When the structural strain after a
  // step exceeds the limit, the next step takes twice the substeps (up to maxRefinement times); once it is
  // below half the limit, half as many again. A halving can bounce: a 64 x 64 cape hanging from its corners
  // rests at 8.4 % strain on the settings' substeps and at 1.9 % on twice as many, so the rule alone
  // switched between the two for ever, and every switch shook it (particles at 0.2 to 0.9 m/s after 30 s;
  // it never fell asleep). So a halving that bounced makes the next one wait at least kFirstBackoff after
  // the last doubling, twice as long after every further bounce, up to kMaxBackoff. Decided from the state
  // and the time alone: deterministic.
  const int maxRefinement = settings_.maxRefinement;
  if (settings_.integrator != Integrator::Xpbd || !(settings_.strainLimit > 0.0f) || maxRefinement <= 1) {
    refinement_ = 1;
    return;
  }
  // max over the structural springs of |x_i - x_j|^2 / L0^2
  const float worst =
      detail::maxSquaredStretch(state_.positions.col(0).data(), state_.positions.col(1).data(),
                                state_.positions.col(2).data(), fabric_->springs(SpringFamily::Structural));
  lastMaxStrain_ = std::sqrt(worst) - 1.0f;
  sinceHalving_ += dt;
  sinceDoubling_ += dt;
  if (sinceHalving_ >= kSettledTime) halvingDelay_ = 0.0f;  // the last halving held
  if (lastMaxStrain_ > settings_.strainLimit) {
    if (refinement_ < maxRefinement && sinceHalving_ < kBounceTime)
      halvingDelay_ = std::min(std::max(2.0f * halvingDelay_, kFirstBackoff), kMaxBackoff);
    refinement_ = std::min(2 * refinement_, maxRefinement);
    sinceDoubling_ = 0.0f;
  } else if (refinement_ > 1 && lastMaxStrain_ < 0.5f * settings_.strainLimit &&
             sinceDoubling_ >= halvingDelay_) {
    refinement_ /= 2;
    sinceHalving_ = 0.0f;
  }
}

void Cape::movePinsTo(float s, float h) {
  // A pinned particle's velocity is its move over the substep, from where the substep started
  // (startPositions) to the target: the prediction has already carried it by h v, and the move left after
  // that would alternate between u and 0 for a pin moving at a constant u.
  const float invH = 1.0f / h;
  for (const Pin& p : state_.pins) {
    const Vec3 target = p.previousTarget + s * (p.target - p.previousTarget);
    const Eigen::Index i = p.particle;
    state_.velocities.row(i) = (target.transpose() - work_->startPositions.row(i)) * invH;
    state_.positions.row(i) = target.transpose();
  }
}

void Cape::accumulateExternalAcceleration() {
  // Gravity on free particles only: pinned particles (inverse mass 0) feel nothing.
  for (int c = 0; c < 3; ++c) work_->acceleration.col(c) = work_->freeMask * settings_.gravity[c];
  const WindSettings& wind = settings_.wind;
  if (wind.model == WindSettings::Model::SineWave) {
    // The seed's wind: quadratic drag of each particle's area share, whatever the cloth's orientation.
    const float q = 0.5f * wind.airDensity * wind.dragCoefficient;
    const Eigen::VectorXf& areas = fabric_->particleAreas();
    for (Eigen::Index i = 0; i < state_.positions.rows(); ++i) {
      const Vec3 u = (work_->airVelocity.row(i) - state_.velocities.row(i)).transpose();
      work_->acceleration.row(i) += (state_.inverseMasses[i] * q * areas[i] * u.norm()) * u.transpose();
    }
  } else if (wind.model == WindSettings::Model::Aerodynamic) {
    // Per triangle, from the air's velocity relative to the triangle (averages of its corners); a third of
    // the force goes to each corner. Flat arrays: this loop runs once per substep over every triangle.
    const std::vector<std::uint32_t>& tri = fabric_->triangles();
    const float *px = state_.positions.col(0).data(), *py = state_.positions.col(1).data(),
                *pz = state_.positions.col(2).data();
    const float *vx = state_.velocities.col(0).data(), *vy = state_.velocities.col(1).data(),
                *vz = state_.velocities.col(2).data();
    const float *ux = work_->airVelocity.col(0).data(), *uy = work_->airVelocity.col(1).data(),
                *uz = work_->airVelocity.col(2).data();
    float *ax = work_->acceleration.col(0).data(), *ay = work_->acceleration.col(1).data(),
          *az = work_->acceleration.col(2).data();
    const float* w = state_.inverseMasses.data();
    const float rho = wind.airDensity, cd = wind.dragCoefficient, cl = wind.liftCoefficient;
    for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
      const std::uint32_t i = tri[t], j = tri[t + 1], k = tri[t + 2];
      const Vec3 e1(px[j] - px[i], py[j] - py[i], pz[j] - pz[i]);
      const Vec3 e2(px[k] - px[i], py[k] - py[i], pz[k] - pz[i]);
      const Vec3 areaNormal = 0.5f * e1.cross(e2);
      const Vec3 u((ux[i] + ux[j] + ux[k] - vx[i] - vx[j] - vx[k]) * (1.0f / 3.0f),
                   (uy[i] + uy[j] + uy[k] - vy[i] - vy[j] - vy[k]) * (1.0f / 3.0f),
                   (uz[i] + uz[j] + uz[k] - vz[i] - vz[j] - vz[k]) * (1.0f / 3.0f));
      const Vec3 third = aerodynamicForce(u, areaNormal, rho, cd, cl) * (1.0f / 3.0f);
      for (const std::uint32_t c : {i, j, k}) {
        ax[c] += w[c] * third.x();
        ay[c] += w[c] * third.y();
        az[c] += w[c] * third.z();
      }
    }
  }
}

void Cape::substepXpbd(float h, float s0, float s1, ColliderSpan colliders) {
  work_->startPositions = state_.positions;
  predict(h);
  movePinsTo(s1, h);
  solveConstraints(h);
  collideBodies(h, s0, s1, colliders, false);
  if (settings_.selfCollision) solveSelfContactsAfterBodies();
  if (motionActive_) applyMotionConstraints(h, false);
  updateVelocities(h);
}

void Cape::predict(float h) {
  // x* = x + h v + h^2 a: symplectic Euler on the external forces.
  if (settings_.wind.model == WindSettings::Model::None) {
    // Gravity alone: the same operations, v + h (free g), without the acceleration array and its traffic.
    for (int c = 0; c < 3; ++c) {
      const float g = settings_.gravity[c];
      float* __restrict v = state_.velocities.col(c).data();
      float* __restrict x = state_.positions.col(c).data();
      const float* __restrict free = work_->freeMask.data();
      for (Eigen::Index i = 0, n = state_.positions.rows(); i < n; ++i) {
        v[i] += h * (free[i] * g);
        x[i] += h * v[i];
      }
    }
    return;
  }
  accumulateExternalAcceleration();
  state_.velocities += h * work_->acceleration;
  state_.positions += h * state_.velocities;
}

void Cape::solveConstraints(float h) {
  // Tethers first (they fix the global stretch in one pass), then the springs, which are left with only
  // local corrections, then the strain ceiling over those still stretched beyond it, then the hinges and the
  // self-contacts. Collisions come after, so the cape ends every substep outside the colliders.
  // The multipliers start every substep at zero; with one iteration they are never read again, so none is
  // kept (SpringSolveArrays::lambda null).
  const bool bending = settings_.bendingRigidity > 0.0f && fabric_->hinges().size() > 0;
  if (settings_.iterations > 1) {
    work_->lambda.setZero();
    if (bending) work_->hingeLambda.setZero();
  }
  for (int it = 0; it < settings_.iterations; ++it) {
    if (settings_.useTethers) solveTethers();
    solveSprings(h);
    if (settings_.strainCeiling > 0.0f) {
      for (int pass = 0; pass < settings_.strainCeilingPasses; ++pass)
        detail::limitStretch(state_.positions.col(0).data(), state_.positions.col(1).data(),
                             state_.positions.col(2).data(), state_.inverseMasses.data(),
                             fabric_->springs(SpringFamily::Structural), 1.0f + settings_.strainCeiling);
    }
    if (bending) {
      detail::solveHinges(state_.positions.col(0).data(), state_.positions.col(1).data(),
                          state_.positions.col(2).data(), state_.inverseMasses.data(), fabric_->hinges(),
                          settings_.bendingRigidity, 1.0f / (h * h),
                          settings_.iterations > 1 ? work_->hingeLambda.data() : nullptr,
                          hingeStiffnessScale_.size() > 0 ? hingeStiffnessScale_.data() : nullptr);
    }
    if (settings_.selfCollision)
      work_->self.solve(state_.positions, state_.inverseMasses.data(), work_->self.thickness(settings_));
  }
}

void Cape::collideBodies(float h, float s0, float s1, ColliderSpan colliders, bool explicitMode) {
  const detail::CollisionArrays p{state_.positions.col(0).data(),
                                  state_.positions.col(1).data(),
                                  state_.positions.col(2).data(),
                                  work_->startPositions.col(0).data(),
                                  work_->startPositions.col(1).data(),
                                  work_->startPositions.col(2).data(),
                                  state_.inverseMasses.data(),
                                  state_.velocities.col(0).data(),
                                  state_.velocities.col(1).data(),
                                  state_.velocities.col(2).data(),
                                  state_.positions.rows()};
  work_->body.collide(p, settings_, h, s0, s1, colliders, explicitMode);
  // A particle wedged where two colliders meet (a shoulder sphere poking out of the torso box) is pushed out
  // of one into the other; a few Gauss-Seidel passes over the contacts settle it outside both.
  for (int pass = 0; pass < kContactPasses; ++pass) work_->body.reproject(p, settings_, colliders);
}

void Cape::solveSelfContactsAfterBodies() {
  // Cloth pressed between a body and another layer of itself: the layer on the body cannot give way, so
  // the outer layer takes the whole correction (mass scaling by contact).
  work_->selfWeight = state_.inverseMasses;
  for (const Contact& k : work_->body.contacts()) work_->selfWeight[k.particle] = 0.0f;
  work_->self.solve(state_.positions, work_->selfWeight.data(), work_->self.thickness(settings_));
}

void Cape::updateVelocities(float h) {
  // New velocities from the position change, then damping: dv/dt = -c v integrated implicitly
  // (v <- v / (1 + c h), the Pade approximation of exp(-c h), unconditionally stable). Pinned particles keep
  // the velocity their pin gave them.
  const float scale = 1.0f / (h * (1.0f + settings_.damping * h));
  const Eigen::VectorXf& free = work_->freeMask;
  for (int c = 0; c < 3; ++c) {
    state_.velocities.col(c) =
        free.cwiseProduct(state_.positions.col(c) - work_->startPositions.col(c)) * scale +
        (1.0f - free.array()).matrix().cwiseProduct(state_.velocities.col(c));
  }
}

void Cape::solveSprings(float h) {
  // XPBD distance constraints, family after family, each family's springs in its fabric order (colour after
  // colour); the kernel and its equations are in SpringSolver.h.
  detail::SpringSolveArrays arrays;
  arrays.px = state_.positions.col(0).data();
  arrays.py = state_.positions.col(1).data();
  arrays.pz = state_.positions.col(2).data();
  arrays.inverseMass = state_.inverseMasses.data();
  arrays.lambda = settings_.iterations > 1 ? work_->lambda.data() : nullptr;
  arrays.complianceScale = springComplianceScale_.size() > 0 ? springComplianceScale_.data() : nullptr;
  const float invH2 = 1.0f / (h * h);
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const SpringSet& set = fabric_->springs(static_cast<SpringFamily>(f));
    const float compliance = familyCompliance_[static_cast<std::size_t>(f)];
    if (!std::isinf(compliance)) {
      arrays.first = set.first.data();
      arrays.second = set.second.data();
      arrays.restLength = set.restLength.data();
      for (const SpringRun& run : set.runs) detail::solveSpringRun(arrays, run, compliance * invH2);
    }
    if (arrays.lambda != nullptr) arrays.lambda += set.size();
    if (arrays.complianceScale != nullptr) arrays.complianceScale += set.size();
  }
}

void Cape::solveTethers() {
  // Long-range attachments (Fabric.h's TetherSet); the kernel is in SpringSolver.h.
  detail::solveTethers(state_.positions.col(0).data(), state_.positions.col(1).data(),
                       state_.positions.col(2).data(), state_.inverseMasses.data(), fabric_->tethers());
}

void Cape::substepExplicit(float h, float s0, float s1, ColliderSpan colliders) {
  // The seed: F = m g - m c v + sum of Hooke forces k (|d| - L) d / |d|; v += h F / m; x += h v.
  accumulateExternalAcceleration();
  accumulateSpringForces();
  for (int c = 0; c < 3; ++c)
    work_->acceleration.col(c) -= settings_.damping * work_->freeMask.cwiseProduct(state_.velocities.col(c));
  state_.velocities += h * work_->acceleration;
  work_->startPositions = state_.positions;
  state_.positions += h * state_.velocities;
  movePinsTo(s1, h);
  collideBodies(h, s0, s1, colliders, true);
  if (motionActive_) applyMotionConstraints(h, true);
}

void Cape::accumulateSpringForces() {
  const float* px = state_.positions.col(0).data();
  const float* py = state_.positions.col(1).data();
  const float* pz = state_.positions.col(2).data();
  float* ax = work_->acceleration.col(0).data();
  float* ay = work_->acceleration.col(1).data();
  float* az = work_->acceleration.col(2).data();
  const float* w = state_.inverseMasses.data();
  if (settings_.bendingRigidity > 0.0f)
    detail::addHingeForces(px, py, pz, w, fabric_->hinges(), settings_.bendingRigidity, ax, ay, az,
                           hingeStiffnessScale_.size() > 0 ? hingeStiffnessScale_.data() : nullptr);
  const float* springScale = springComplianceScale_.size() > 0 ? springComplianceScale_.data() : nullptr;
  std::size_t offset = 0;  // of the family's first spring in springComplianceScale_
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const SpringSet& set = fabric_->springs(static_cast<SpringFamily>(f));
    const std::size_t base = offset;
    offset += set.size();
    const float k0 = stiffnessOf(settings_, f);
    if (k0 <= 0.0f) continue;
    for (std::size_t s = 0; s < set.size(); ++s) {
      const std::uint32_t i = set.first[s], j = set.second[s];
      const float dx = px[j] - px[i], dy = py[j] - py[i], dz = pz[j] - pz[i];
      const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (len < 1e-9f) continue;
      const float k = springScale != nullptr ? k0 / springScale[base + s] : k0;
      const float fs = k * (len - set.restLength[s]) / len;  // force on i along d, N/m * m / m
      ax[i] += w[i] * fs * dx;
      ay[i] += w[i] * fs * dy;
      az[i] += w[i] * fs * dz;
      ax[j] -= w[j] * fs * dx;
      ay[j] -= w[j] * fs * dy;
      az[j] -= w[j] * fs * dz;
    }
  }
}

double Cape::energy() const {
  if (!ok()) return 0.0;
  double e = 0.0;
  const Eigen::VectorXf& m = fabric_->masses();
  for (Eigen::Index i = 0; i < state_.positions.rows(); ++i) {
    const double mi = static_cast<double>(m[i]) * (massScale_.size() > 0 ? massScale_[i] : 1.0f);
    e += 0.5 * mi * static_cast<double>(state_.velocities.row(i).squaredNorm());
    e -= mi * static_cast<double>(settings_.gravity.dot(state_.positions.row(i).transpose()));
  }
  std::size_t offset = 0;
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const SpringSet& set = fabric_->springs(static_cast<SpringFamily>(f));
    const std::size_t base = offset;
    offset += set.size();
    const double k0 = stiffnessOf(settings_, f);
    if (!(k0 > 0.0) || std::isinf(k0)) continue;
    for (std::size_t s = 0; s < set.size(); ++s) {
      const double len = (state_.positions.row(set.first[s]) - state_.positions.row(set.second[s])).norm();
      const double ext = len - set.restLength[s];
      const double k = springComplianceScale_.size() > 0
                           ? k0 / springComplianceScale_[static_cast<Eigen::Index>(base + s)]
                           : k0;
      e += 0.5 * k * ext * ext;
    }
  }
  if (settings_.bendingRigidity > 0.0f)
    e += detail::hingeEnergy(state_.positions, fabric_->hinges(), settings_.bendingRigidity,
                             hingeStiffnessScale_.size() > 0 ? hingeStiffnessScale_.data() : nullptr);
  return e;
}

}  // namespace cape
