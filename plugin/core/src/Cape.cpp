#include "cape/core/Cape.h"

#include "cape/core/Wind.h"

#include "SpringSolver.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cape {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kContactPasses = 3;  // extra push-out passes over the substep's contacts

float stiffnessOf(const CapeSettings& s, int family) {
  switch (static_cast<SpringFamily>(family)) {
    case SpringFamily::Structural: return s.structuralStiffness;
    case SpringFamily::Shear: return s.shearStiffness;
    case SpringFamily::Bend: return s.bendStiffness;
  }
  return 0.0f;
}

}  // namespace

/// The largest substep the explicit integrator can take without blowing up. Symplectic Euler on a linear
/// spring system is stable while h * omega_max < 2, i.e. h^2 * lambda_max(M^-1 K) < 4; Gershgorin's theorem
/// bounds lambda_max by max over particles i of sum over springs (i, j) of k * (w_i + w_j).
static float explicitStableStep(const Fabric& fabric, const CapeSettings& settings) {
  Eigen::VectorXf bound = Eigen::VectorXf::Zero(static_cast<Eigen::Index>(fabric.particleCount()));
  const Eigen::VectorXf& m = fabric.masses();
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const float k = stiffnessOf(settings, f);
    if (k <= 0.0f) continue;
    const SpringSet& set = fabric.springs(static_cast<SpringFamily>(f));
    for (std::size_t s = 0; s < set.size(); ++s) {
      const float w = 1.0f / m[set.first[s]] + 1.0f / m[set.second[s]];
      bound[set.first[s]] += k * w;
      bound[set.second[s]] += k * w;
    }
  }
  const float lambdaMax = bound.maxCoeff();
  return lambdaMax > 0.0f ? 2.0f / std::sqrt(lambdaMax) : kInf;
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
    state_.positions.row(i) = (r * fabric_->restPositions().row(i).transpose() + placement.position).transpose();
  state_.velocities = Points::Zero(n, 3);
  state_.inverseMasses = fabric_->masses().cwiseInverse();
  startPositions_ = state_.positions;
  acceleration_ = Points::Zero(n, 3);
  freeMask_ = Eigen::VectorXf::Ones(n);
  lambda_ = Eigen::VectorXf::Zero(static_cast<Eigen::Index>(fabric_->springCount()));
  invDenominator_ = Eigen::VectorXf::Zero(static_cast<Eigen::Index>(fabric_->springCount()));
  airVelocity_ = Points::Zero(n, 3);
  // Each particle's share of the cloth's rest area (a third of each triangle it belongs to), m^2: the
  // seed's sine-wave wind pushes on it.
  particleArea_ = Eigen::VectorXf::Zero(n);
  const std::vector<std::uint32_t>& tri = fabric_->triangles();
  const Points& rest = fabric_->restPositions();
  for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
    const Vec3 a = rest.row(tri[t]).transpose(), b = rest.row(tri[t + 1]).transpose(), c = rest.row(tri[t + 2]).transpose();
    const float third = (b - a).cross(c - a).norm() / 6.0f;
    for (int k = 0; k < 3; ++k) particleArea_[tri[t + static_cast<std::size_t>(k)]] += third;
  }
  colliderEnd_.reserve(64);
  // Self-collision scratch: a hash of at least twice as many buckets as particles (a power of two).
  std::uint32_t buckets = 1;
  while (buckets < 2 * static_cast<std::uint32_t>(n)) buckets <<= 1;
  hashStart_.assign(buckets + 1, 0u);
  bucketCluster_.assign(buckets, ~0u);
  hashEntries_.assign(8 * fabric_->triangleCount(), HashEntry{});
  bucketHits_.assign(hashEntries_.size(), 0u);
  triangleMotion_.assign(fabric_->triangleCount(), 0.0f);
  {
    // The far corners across each triangle's edges: sort the edges (as vertex pairs) to meet each one's
    // two triangles. An edge of more than two triangles (a non-manifold mesh) gets no wings.
    struct HalfEdge {
      std::uint64_t key;
      std::uint32_t slot;  // 3 * triangle + edge
      std::uint32_t far;
    };
    std::vector<HalfEdge> edges;
    edges.reserve(tri.size());
    for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
      for (std::size_t k = 0; k < 3; ++k) {
        const std::uint32_t u = tri[t + k], v = tri[t + (k + 1) % 3], far = tri[t + (k + 2) % 3];
        const std::uint64_t key = (static_cast<std::uint64_t>(std::min(u, v)) << 32) | std::max(u, v);
        edges.push_back({key, static_cast<std::uint32_t>(t + k), far});
      }
    }
    std::sort(edges.begin(), edges.end(), [](const HalfEdge& a, const HalfEdge& b) {
      return a.key != b.key ? a.key < b.key : a.slot < b.slot;
    });
    LocalSet none;
    std::fill(std::begin(none.v), std::end(none.v), ~0u);
    triangleLocal_.assign(fabric_->triangleCount(), none);
    for (std::size_t t = 0; t < triangleLocal_.size(); ++t)
      for (std::size_t k = 0; k < 3; ++k) triangleLocal_[t].v[k] = tri[3 * t + k];
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i;
      while (j < edges.size() && edges[j].key == edges[i].key) ++j;
      if (j - i == 2) {  // slot = 3 * triangle + edge: the wing goes to v[3 + edge]
        triangleLocal_[edges[i].slot / 3].v[3 + edges[i].slot % 3] = edges[i + 1].far;
        triangleLocal_[edges[i + 1].slot / 3].v[3 + edges[i + 1].slot % 3] = edges[i].far;
      }
      i = j;
    }
  }
  triangleStamp_.assign(fabric_->triangleCount(), 0u);
  largeTriangles_.reserve(fabric_->triangleCount());
  triangleBuckets_.reserve(8 * fabric_->triangleCount());
  // Clusters: consecutive triangles that share an edge go in pairs (a grid's cells come out as pairs).
  clusterStart_.assign(1, 0u);
  for (std::size_t t = 0; t < fabric_->triangleCount();) {
    std::size_t next = t + 1;
    if (next < fabric_->triangleCount()) {
      int shared = 0;
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j) shared += tri[3 * t + i] == tri[3 * next + j] ? 1 : 0;
      if (shared == 2) ++next;
    }
    clusterStart_.push_back(static_cast<std::uint32_t>(next));
    t = next;
  }
  clusterBoxes_.assign(6 * (clusterStart_.size() - 1), 0.0f);
  // The particles local to every triangle of a cluster (at most four kept): the first triangle's local set,
  // less what the others lack.
  ClusterLocal noLocal;
  std::fill(std::begin(noLocal.v), std::end(noLocal.v), ~0u);
  clusterLocal_.assign(clusterStart_.size() - 1, noLocal);
  for (std::size_t g = 0; g + 1 < clusterStart_.size(); ++g) {
    std::size_t kept = 0;
    for (const std::uint32_t q : triangleLocal_[clusterStart_[g]].v) {
      if (q == ~0u || kept == 4) continue;
      bool inAll = true;
      for (std::uint32_t t = clusterStart_[g] + 1; t < clusterStart_[g + 1]; ++t)
        inAll = inAll && std::find(std::begin(triangleLocal_[t].v), std::end(triangleLocal_[t].v), q) != std::end(triangleLocal_[t].v);
      if (inAll) clusterLocal_[g].v[kept++] = q;
    }
  }
  triangleBucketStart_.assign(clusterStart_.size(), 0u);
  stepMotion_ = Points::Zero(n, 3);
  stepMotionNorm_ = Eigen::VectorXf::Zero(n);
  selfWeight_ = Eigen::VectorXf::Zero(n);
  selfContacts_.reserve(static_cast<std::size_t>(32 * n));
  {
    const SpringSet& structural = fabric_->springs(SpringFamily::Structural);
    double sum = 0.0;
    for (float l : structural.restLength) sum += l;
    meanSpacing_ = structural.size() > 0 ? static_cast<float>(sum / static_cast<double>(structural.size())) : 0.01f;
  }
  contacts_.reserve(static_cast<std::size_t>(4 * n));
  distance2_.resize(n);
  candidates_.reserve(static_cast<std::size_t>(n));
  state_.pins.reserve(static_cast<std::size_t>(n));
}

Status Cape::setSettings(const CapeSettings& settings) {
  Status s = settings.validate();
  if (!s.ok()) return s;
  if (settings.integrator == Integrator::ExplicitSpring) {
    const float hMax = explicitStableStep(*fabric_, settings);
    const float h = settings.timeStep / static_cast<float>(settings.substeps);
    if (h >= hMax) {
      return Status::error("CapeSettings: the explicit integrator is unstable for this fabric: substep " +
                           std::to_string(h) + " s >= stability bound " + std::to_string(hMax) +
                           " s; lower the stiffness or raise the substeps");
    }
  }
  settings_ = settings;
  familyCompliance_.assign(kSpringFamilyCount, 0.0f);
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const float k = stiffnessOf(settings_, f);
    familyCompliance_[static_cast<std::size_t>(f)] = k > 0.0f ? 1.0f / k : kInf;  // inf compliance = off
  }
  return Status::success();
}

std::size_t Cape::pin(std::uint32_t particle, const Vec3& target) {
  if (!ok() || particle >= fabric_->particleCount() || !target.allFinite()) return static_cast<std::size_t>(-1);
  for (std::size_t k = 0; k < state_.pins.size(); ++k) {
    if (state_.pins[k].particle == particle) {
      state_.pins[k].previousTarget = state_.pins[k].target = target;
      return k;
    }
  }
  state_.inverseMasses[particle] = 0.0f;
  state_.pins.push_back({particle, target, target});
  return state_.pins.size() - 1;
}

void Cape::unpin(std::uint32_t particle) {
  if (!ok() || particle >= fabric_->particleCount()) return;
  auto it = std::find_if(state_.pins.begin(), state_.pins.end(), [&](const Pin& p) { return p.particle == particle; });
  if (it == state_.pins.end()) return;
  state_.pins.erase(it);
  state_.inverseMasses[particle] = 1.0f / fabric_->masses()[particle];
}

void Cape::movePin(std::size_t k, const Vec3& target) {
  if (k >= state_.pins.size()) return;
  Pin& p = state_.pins[k];
  p.previousTarget = p.target;
  if (target.allFinite()) p.target = target;  // a non-finite target is ignored: the pin holds still
}

void Cape::teleport(const Pose& delta) {
  if (!ok() || !delta.isFinite()) return;
  const Eigen::Matrix3f r = delta.rotation.toRotationMatrix();
  for (Eigen::Index i = 0; i < state_.positions.rows(); ++i) {
    state_.positions.row(i) = (r * state_.positions.row(i).transpose() + delta.position).transpose();
    state_.velocities.row(i) = (r * state_.velocities.row(i).transpose()).transpose();
  }
  for (Pin& p : state_.pins) {
    p.previousTarget = delta.apply(p.previousTarget);
    p.target = delta.apply(p.target);
  }
}

void Cape::step(float dt, ColliderSpan colliders) {
  if (!ok() || !std::isfinite(dt) || !(dt > 0.0f)) return;
  // settings.substeps are per settings.timeStep: a step of another length keeps the substep length, so a
  // world stepping at 1/240 s takes one substep where a 1/60 s frame takes three (the 1e-3 keeps dt =
  // timeStep at exactly `substeps` despite rounding).
  const float targetSubstep = settings_.timeStep / static_cast<float>(settings_.substeps);
  int substeps = std::max(1, static_cast<int>(std::ceil(dt / targetSubstep - 1e-3f)));
  if (settings_.integrator == Integrator::Xpbd) substeps *= refinement_;
  if (settings_.integrator == Integrator::ExplicitSpring) {
    // A longer step than the settings were checked for: split it further rather than blow up.
    const float hMax = explicitStableStep(*fabric_, settings_);
    substeps = std::max(substeps, static_cast<int>(std::ceil(dt / (0.9f * hMax))));
  }
  const float h = dt / static_cast<float>(substeps);
  // 1 for free particles, 0 for pinned ones (same size every step: no allocation).
  freeMask_ = (state_.inverseMasses.array() > 0.0f).cast<float>();
  if (settings_.integrator == Integrator::Xpbd) prepareSpringDenominators(h);
  // The air's velocity at each particle, once per step at its middle: gusts change over tenths of a second,
  // far slower than a frame.
  if (settings_.wind.model != WindSettings::Model::None)
    windVelocities(settings_.wind, state_.positions, state_.time + 0.5 * static_cast<double>(dt), airVelocity_);
  // Self-contacts are found from where the cape is now and kept through the substeps. One search covers at
  // most a spacing of motion (relative to the cape's rigid motion) and at most one settings.timeStep. A
  // calm cape (no particle faster than a spacing per timeStep) searches once per timeStep: a world stepping
  // at 1/240 s then searches once per 1/60 s, with that 1/60 s's motion bound. A faster one searches again
  // every few substeps: a search over a whole fast frame would pair every particle with every triangle it
  // might sweep past, and the substeps would carry thousands of contacts.
  int searchEvery = 0;  // substeps between searches; 0: the contacts found earlier still cover this step
  if (settings_.selfCollision && settings_.integrator == Integrator::Xpbd &&
      state_.time + static_cast<double>(dt) > selfContactsValidUntil_ + 1e-9) {
    // The fastest particle relative to the cape's rigid motion (predictSelfMotion), m/s.
    const float fastest = predictSelfMotion(dt) / dt;
    constexpr float kSearchMotion = 1.0f;  // spacings of motion one search may cover
    if (std::isfinite(fastest) && fastest * settings_.timeStep < kSearchMotion * meanSpacing_) {
      const float window = std::max(dt, settings_.timeStep);
      if (window != dt) predictSelfMotion(window);
      findSelfContacts();
      ++selfSearches_;
      selfContactsValidUntil_ = state_.time + static_cast<double>(window);
    } else {
      // Enough searches that none covers more than kSearchMotion spacings; every substep at most (and for a
      // non-finite motion, whose search finds nothing: findSelfContacts leaves a blown-up cape alone).
      const float wanted = fastest * dt / (kSearchMotion * meanSpacing_);
      const int searches = std::isfinite(wanted) ? static_cast<int>(std::clamp(std::ceil(wanted), 1.0f, static_cast<float>(substeps))) : substeps;
      searchEvery = (substeps + searches - 1) / searches;
      selfContactsValidUntil_ = state_.time + static_cast<double>(dt);
    }
  }
  for (int k = 0; k < substeps; ++k) {
    if (searchEvery > 0 && k % searchEvery == 0) {
      predictSelfMotion(h * static_cast<float>(std::min(searchEvery, substeps - k)));
      findSelfContacts();
      ++selfSearches_;
    }
    const float s0 = static_cast<float>(k) / static_cast<float>(substeps);
    const float s1 = static_cast<float>(k + 1) / static_cast<float>(substeps);
    if (settings_.integrator == Integrator::Xpbd)
      stepXpbd(h, s0, s1, colliders);
    else
      stepExplicit(h, s0, s1, colliders);
  }
  for (Pin& p : state_.pins) p.previousTarget = p.target;
  state_.time += static_cast<double>(dt);
  adaptRefinement();
}

void Cape::adaptRefinement() {
  // Strain-adaptive substepping: one Gauss-Seidel pass per substep carries a sudden load (a 180-degree turn
  // at a run) through a 20-row cape too slowly, and the cape stretches. When the structural strain after a
  // step exceeds the limit, the next step takes twice the substeps (up to maxRefinement times); once it is
  // below half the limit, half as many again. Decided from the state alone: deterministic.
  const int maxRefinement = settings_.maxRefinement;
  if (settings_.integrator != Integrator::Xpbd || !(settings_.strainLimit > 0.0f) || maxRefinement <= 1) {
    refinement_ = 1;
    return;
  }
  const SpringSet& set = fabric_->springs(SpringFamily::Structural);
  const float* px = state_.positions.col(0).data();
  const float* py = state_.positions.col(1).data();
  const float* pz = state_.positions.col(2).data();
  float worst = 0.0f;  // max over springs of |x_i - x_j|^2 / L0^2
  for (std::size_t s = 0; s < set.size(); ++s) {
    const std::uint32_t i = set.first[s], j = set.second[s];
    const float dx = px[j] - px[i], dy = py[j] - py[i], dz = pz[j] - pz[i];
    const float rest = set.restLength[s];
    worst = std::max(worst, (dx * dx + dy * dy + dz * dz) / (rest * rest));
  }
  lastMaxStrain_ = std::sqrt(worst) - 1.0f;
  if (lastMaxStrain_ > settings_.strainLimit)
    refinement_ = std::min(2 * refinement_, maxRefinement);
  else if (lastMaxStrain_ < 0.5f * settings_.strainLimit)
    refinement_ = std::max(refinement_ / 2, 1);
}

void Cape::movePinsTo(float s, float h) {
  const float invH = 1.0f / h;
  for (const Pin& p : state_.pins) {
    const Vec3 target = p.previousTarget + s * (p.target - p.previousTarget);
    const Eigen::Index i = p.particle;
    state_.velocities.row(i) = (target.transpose() - state_.positions.row(i)) * invH;
    state_.positions.row(i) = target.transpose();
  }
}

void Cape::accumulateExternalAcceleration() {
  // Gravity on free particles only: pinned particles (inverse mass 0) feel nothing.
  for (int c = 0; c < 3; ++c) acceleration_.col(c) = freeMask_ * settings_.gravity[c];
  const WindSettings& wind = settings_.wind;
  if (wind.model == WindSettings::Model::SineWave) {
    // The seed's wind: quadratic drag of each particle's area share, whatever the cloth's orientation.
    const float q = 0.5f * wind.airDensity * wind.dragCoefficient;
    for (Eigen::Index i = 0; i < state_.positions.rows(); ++i) {
      const Vec3 u = (airVelocity_.row(i) - state_.velocities.row(i)).transpose();
      acceleration_.row(i) += (state_.inverseMasses[i] * q * particleArea_[i] * u.norm()) * u.transpose();
    }
  } else if (wind.model == WindSettings::Model::Aerodynamic) {
    // Per triangle, from the air's velocity relative to the triangle (averages of its corners); a third of
    // the force goes to each corner. Flat arrays: this loop runs once per substep over every triangle.
    const std::vector<std::uint32_t>& tri = fabric_->triangles();
    const float *px = state_.positions.col(0).data(), *py = state_.positions.col(1).data(), *pz = state_.positions.col(2).data();
    const float *vx = state_.velocities.col(0).data(), *vy = state_.velocities.col(1).data(), *vz = state_.velocities.col(2).data();
    const float *ux = airVelocity_.col(0).data(), *uy = airVelocity_.col(1).data(), *uz = airVelocity_.col(2).data();
    float *ax = acceleration_.col(0).data(), *ay = acceleration_.col(1).data(), *az = acceleration_.col(2).data();
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

void Cape::stepXpbd(float h, float s0, float s1, ColliderSpan colliders) {
  startPositions_ = state_.positions;
  accumulateExternalAcceleration();
  // Predict: x* = x + h v + h^2 a (symplectic Euler on the external forces).
  state_.velocities += h * acceleration_;
  state_.positions += h * state_.velocities;
  movePinsTo(s1, h);
  // Constraints: tethers first (they fix the global stretch in one pass), then the springs, which are left
  // with only local corrections. Collisions come last, so the cape ends every substep outside the colliders.
  lambda_.setZero();
  for (int it = 0; it < settings_.iterations; ++it) {
    if (settings_.useTethers) solveTethers();
    solveSprings(h);
    if (settings_.selfCollision) solveSelfContacts(state_.inverseMasses.data());
  }
  collide(h, s0, s1, colliders, false);
  // A particle wedged where two colliders meet (a shoulder sphere poking out of the torso box) is pushed out
  // of one into the other; a few Gauss-Seidel passes over the contacts settle it outside both.
  for (int pass = 0; pass < kContactPasses; ++pass) reprojectContacts(colliders);
  if (settings_.selfCollision) {
    // Cloth pressed between a body and another layer of itself: the layer on the body cannot give way, so
    // the outer layer takes the whole correction (mass scaling by contact).
    selfWeight_ = state_.inverseMasses;
    for (const Contact& k : contacts_) selfWeight_[k.particle] = 0.0f;
    solveSelfContacts(selfWeight_.data());
  }
  // New velocities from the position change, then damping: dv/dt = -c v integrated implicitly
  // (v <- v / (1 + c h), the Padé approximation of exp(-c h), unconditionally stable).
  const float scale = 1.0f / (h * (1.0f + settings_.damping * h));
  for (int c = 0; c < 3; ++c) {
    state_.velocities.col(c) = freeMask_.cwiseProduct(state_.positions.col(c) - startPositions_.col(c)) * scale +
                               (1.0f - freeMask_.array()).matrix().cwiseProduct(state_.velocities.col(c));
  }
}

void Cape::prepareSpringDenominators(float h) {
  // 1 / (w_i + w_j + alpha / h^2) of every spring: constant over the step's substeps, so the solver loop
  // multiplies instead of dividing. 0 when both ends are pinned (no correction).
  const float invH2 = 1.0f / (h * h);
  const float* w = state_.inverseMasses.data();
  float* out = invDenominator_.data();
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const SpringSet& set = fabric_->springs(static_cast<SpringFamily>(f));
    const float compliance = familyCompliance_[static_cast<std::size_t>(f)];
    const float alpha = std::isinf(compliance) ? 0.0f : compliance * invH2;
    for (std::size_t s = 0; s < set.size(); ++s) {
      const float wsum = w[set.first[s]] + w[set.second[s]];
      out[s] = wsum > 0.0f ? 1.0f / (wsum + alpha) : 0.0f;
    }
    out += set.size();
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
  arrays.lambda = lambda_.data();
  arrays.invDenominator = invDenominator_.data();
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
    arrays.lambda += set.size();
    arrays.invDenominator += set.size();
  }
}

void Cape::solveTethers() {
  // Long-range attachments (Fabric.h's TetherSet); the kernel is in SpringSolver.h.
  detail::solveTethers(state_.positions.col(0).data(), state_.positions.col(1).data(), state_.positions.col(2).data(),
                       state_.inverseMasses.data(), fabric_->tethers());
}

void Cape::stepExplicit(float h, float s0, float s1, ColliderSpan colliders) {
  // The seed: F = m g - m c v + sum of Hooke forces k (|d| - L) d / |d|; v += h F / m; x += h v.
  accumulateExternalAcceleration();
  const float* px = state_.positions.col(0).data();
  const float* py = state_.positions.col(1).data();
  const float* pz = state_.positions.col(2).data();
  float* ax = acceleration_.col(0).data();
  float* ay = acceleration_.col(1).data();
  float* az = acceleration_.col(2).data();
  const float* w = state_.inverseMasses.data();
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const float k = stiffnessOf(settings_, f);
    if (k <= 0.0f) continue;
    const SpringSet& set = fabric_->springs(static_cast<SpringFamily>(f));
    for (std::size_t s = 0; s < set.size(); ++s) {
      const std::uint32_t i = set.first[s], j = set.second[s];
      const float dx = px[j] - px[i], dy = py[j] - py[i], dz = pz[j] - pz[i];
      const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (len < 1e-9f) continue;
      const float fs = k * (len - set.restLength[s]) / len;  // force on i along d, N/m * m / m
      ax[i] += w[i] * fs * dx;
      ay[i] += w[i] * fs * dy;
      az[i] += w[i] * fs * dz;
      ax[j] -= w[j] * fs * dx;
      ay[j] -= w[j] * fs * dy;
      az[j] -= w[j] * fs * dz;
    }
  }
  for (int c = 0; c < 3; ++c) {
    acceleration_.col(c) -= settings_.damping * freeMask_.cwiseProduct(state_.velocities.col(c));
  }
  state_.velocities += h * acceleration_;
  startPositions_ = state_.positions;
  state_.positions += h * state_.velocities;
  movePinsTo(s1, h);
  collide(h, s0, s1, colliders, true);
  for (int pass = 0; pass < kContactPasses; ++pass) reprojectContacts(colliders);
}

double Cape::energy() const {
  if (!ok()) return 0.0;
  double e = 0.0;
  const Eigen::VectorXf& m = fabric_->masses();
  for (Eigen::Index i = 0; i < state_.positions.rows(); ++i) {
    const double mi = m[i];
    e += 0.5 * mi * static_cast<double>(state_.velocities.row(i).squaredNorm());
    e -= mi * static_cast<double>(settings_.gravity.dot(state_.positions.row(i).transpose()));
  }
  for (int f = 0; f < kSpringFamilyCount; ++f) {
    const double k = stiffnessOf(settings_, f);
    if (!(k > 0.0) || std::isinf(k)) continue;
    const SpringSet& set = fabric_->springs(static_cast<SpringFamily>(f));
    for (std::size_t s = 0; s < set.size(); ++s) {
      const double len = (state_.positions.row(set.first[s]) - state_.positions.row(set.second[s])).norm();
      const double ext = len - set.restLength[s];
      e += 0.5 * k * ext * ext;
    }
  }
  return e;
}

}  // namespace cape
