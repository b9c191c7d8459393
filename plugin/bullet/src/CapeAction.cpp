// CapeAction: the cape's side of each internal step of a Bullet world. Order of one update:
//   1. prepare (reads the world): drop bodies that left the world (an index check per followed object, a
//      scan of the world's array only when one fails), discover colliders (the broadphase's aabbTest),
//      advance every followed body's pose by one internal step, teleport and inertia, pin targets, core
//      colliders (and the triangles of meshes near the cape, from Bullet's mesh queries);
//   2. advance (this cape only): Cape::step, which resolves every collider inside its substeps.
#include "cape/bullet/CapeAction.h"

#include <BulletDynamics/Dynamics/btDynamicsWorld.h>

#include "cape/bullet/Convert.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseInterface.h>
#include <BulletCollision/CollisionDispatch/btCollisionWorld.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <LinearMath/btAabbUtil2.h>
#include <LinearMath/btIDebugDraw.h>
#include <LinearMath/btMotionState.h>
#include <LinearMath/btTransformUtil.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>

namespace cape::bullet {

namespace {

bool sameTransform(const btTransform& a, const btTransform& b) {
  return a.getOrigin() == b.getOrigin() && a.getBasis()[0] == b.getBasis()[0] &&
         a.getBasis()[1] == b.getBasis()[1] && a.getBasis()[2] == b.getBasis()[2];
}

/// Angle of the rotation taking a's basis to b's, rad.
btScalar rotationAngle(const btTransform& a, const btTransform& b) {
  const btQuaternion d = b.getRotation() * a.getRotation().inverse();
  return d.getAngleShortestPath();
}

/// Pose a fraction s of the way from a to b: origins linearly, rotations along the shortest arc.
btTransform interpolate(const btTransform& a, const btTransform& b, btScalar s) {
  if (s >= btScalar(1)) return b;
  if (s <= btScalar(0)) return a;
  btQuaternion qa = a.getRotation(), qb = b.getRotation();
  if (qa.dot(qb) < 0) qb = -qb;
  return btTransform(qa.slerp(qb, s), a.getOrigin().lerp(b.getOrigin(), s));
}

/// Discovery's broadphase query: keeps every proxy the rule accepts, with its object's index in the world's
/// collision object array. Bullet calls process() only for proxies in its broadphase, i.e. for objects in
/// the world, so reading the object here is safe.
struct DiscoveryCallback : btBroadphaseAabbCallback {
  const btCollisionObjectArray* objects = nullptr;
  btVector3 lo, hi;
  int group = 0, mask = 0;
  std::vector<std::pair<int, const btCollisionObject*>>* found = nullptr;

  bool process(const btBroadphaseProxy* proxy) override {
    const auto* o = static_cast<const btCollisionObject*>(proxy->m_clientObject);
    // Only the world's own proxies (an object whose handle this is), as the scan of the world's array had.
    if (o == nullptr || o->getBroadphaseHandle() != proxy || !o->hasContactResponse()) return true;
    if (o->getInternalType() == btCollisionObject::CO_SOFT_BODY) return true;
    const bool accepted =
        (proxy->m_collisionFilterGroup & mask) != 0 && (group & proxy->m_collisionFilterMask) != 0;
    // The trees hold grown volumes: the proxy's own AABB decides, as before.
    if (!accepted || !TestAabbAgainstAabb2(lo, hi, proxy->m_aabbMin, proxy->m_aabbMax)) return true;
    int index = o->getWorldArrayIndex();
    if (index < 0 || index >= objects->size() || (*objects)[index] != o) {
      // Bullet keeps the index (btCollisionWorld add/remove); should it not, find the object's slot.
      index = objects->findLinearSearch(const_cast<btCollisionObject*>(o));
      if (index >= objects->size()) return true;  // not in this world's array
    }
    found->emplace_back(index, o);
    return true;
  }
};

Eigen::Vector3d toDouble(const btVector3& v) {
  return Eigen::Vector3d(double(v.x()), double(v.y()), double(v.z()));
}

/// The grid point of `spacing` nearest p (zero for spacing 0 or a point that is not finite).
Eigen::Vector3d nearestGridPoint(const btVector3& p, btScalar spacing) {
  const Eigen::Vector3d x = toDouble(p);
  if (!(spacing > 0) || !std::isfinite(double(spacing)) || !x.allFinite()) return Eigen::Vector3d::Zero();
  const double g = double(spacing);
  return Eigen::Vector3d(g * std::round(x.x() / g), g * std::round(x.y() / g), g * std::round(x.z() / g));
}

/// `world` relative to `origin`, the subtraction in double (the identity for origin zero: same bits).
btTransform relativeTo(const btTransform& world, const Eigen::Vector3d& origin) {
  if (origin.isZero()) return world;
  const Eigen::Vector3d p = toDouble(world.getOrigin()) - origin;
  return btTransform(world.getBasis(), btVector3(btScalar(p.x()), btScalar(p.y()), btScalar(p.z())));
}

Pose framePlacement(const btTransform& placement, btScalar spacing) {
  return toPose(relativeTo(placement, nearestGridPoint(placement.getOrigin(), spacing)));
}

}  // namespace

CapeAction::CapeAction(FabricPtr fabric, const CapeSettings& settings, const btTransform& placement,
                       const CapeActionSettings& actionSettings)
    : cape_(std::move(fabric), settings, framePlacement(placement, actionSettings.frameSpacing)),
      settings_(actionSettings) {
  warn_ = [](const std::string& message) { std::cerr << "cape::bullet: " << message << '\n'; };
  cape_.relocate(nearestGridPoint(placement.getOrigin(), settings_.frameSpacing));
}

btTransform CapeAction::toFrame(const btTransform& world) const {
  return relativeTo(world, cape_.origin());
}

Eigen::Vector3d CapeAction::gridPoint(const btVector3& worldPoint) const {
  return nearestGridPoint(worldPoint, settings_.frameSpacing);
}

const Points& CapeAction::positions() const {
  const Points& x = cape_.state().positions;
  const Eigen::Vector3d& o = cape_.origin();
  if (o.isZero()) return x;
  worldPositions_.resize(x.rows(), 3);
  for (int c = 0; c < 3; ++c)
    worldPositions_.col(c) = (x.col(c).cast<double>().array() + o[c]).cast<float>().matrix();
  return worldPositions_;
}

const CapeMesh& CapeAction::mesh(bool twoSided) const {
  if (!ok()) return mesh_;
  if (!meshAllocated_ || mesh_.twoSided() != twoSided) {
    mesh_.allocate(cape_.fabric(), twoSided);
    meshAllocated_ = true;
  }
  mesh_.update(cape_.fabric(), positions());
  return mesh_;
}

bool CapeAction::renderedPose(const btCollisionWorld& world, const btRigidBody* body,
                              btTransform& framePose) const {
  const auto it = trackedIndex_.find(body);
  if (body == nullptr || it == trackedIndex_.end()) return false;
  // In the world (pointers only: the slot where the action last saw it, else one scan of the array), so
  // that a body removed and deleted since the last step is never read.
  const btCollisionObjectArray& objects = world.getCollisionObjectArray();
  const int hint = tracked_[it->second].worldIndex;
  if (hint < 0 || hint >= objects.size() || objects[hint] != body) {
    if (objects.findLinearSearch(const_cast<btRigidBody*>(body)) >= objects.size()) return false;
  }
  btTransform rendered = body->getWorldTransform();
  if (const btMotionState* m = body->getMotionState()) m->getWorldTransform(rendered);
  const btMatrix3x3& b = rendered.getBasis();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(double(b[r][c]))) return false;
    if (!std::isfinite(double(rendered.getOrigin()[r]))) return false;
  }
  framePose = toFrame(rendered);
  return true;
}

const Points& CapeAction::renderPositions(const btCollisionWorld& world) const {
  const Points& x = cape_.state().positions;
  renderPositions_.resize(x.rows(), 3);
  // The reference body's motion from its pose at the end of the last step to its rendered pose, in the
  // cape's frame (both poses relative to its origin), applied in double.
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  const btRigidBody* reference = ok() ? referenceBody() : nullptr;
  btTransform rendered;
  if (reference != nullptr && renderedPose(world, reference, rendered)) {
    const btTransform delta = rendered * tracked_[trackedIndex_.at(reference)].stepEnd.inverse();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation(r, c) = double(delta.getBasis()[r][c]);
      shift[r] = double(delta.getOrigin()[r]);
    }
  }
  const Eigen::Vector3d origin = cape_.origin() + shift;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    renderPositions_.row(i) =
        (rotation * x.row(i).transpose().cast<double>() + origin).transpose().cast<float>();
  // Every attached particle exactly on its attachment point at its body's rendered pose.
  for (const Attachment& a : attachments_) {
    if (a.particle >= particleCount() || !renderedPose(world, a.body, rendered)) continue;
    const btVector3 p = rendered * a.localPivot;
    renderPositions_.row(a.particle) =
        (Eigen::Vector3d(double(p.x()), double(p.y()), double(p.z())) + cape_.origin())
            .transpose()
            .cast<float>();
  }
  return renderPositions_;
}

const CapeMesh& CapeAction::renderMesh(const btCollisionWorld& world, bool twoSided) const {
  if (!ok()) return mesh_;
  if (!meshAllocated_ || mesh_.twoSided() != twoSided) {
    mesh_.allocate(cape_.fabric(), twoSided);
    meshAllocated_ = true;
  }
  mesh_.update(cape_.fabric(), renderPositions(world));
  return mesh_;
}

CapeAction::~CapeAction() = default;

void CapeAction::warnOnce(const std::string& key, const std::string& message) {
  if (!warned_.insert(key).second) return;
  if (deferWarnings_)
    deferredWarnings_.push_back(message);
  else if (warn_)
    warn_(message);
}

void CapeAction::sayDeferredWarnings() {
  for (const std::string& message : deferredWarnings_)
    if (warn_) warn_(message);
  deferredWarnings_.clear();
}

btVector3 CapeAction::toWorld(const Vec3& framePoint) const {
  const Eigen::Vector3d x = framePoint.cast<double>() + cape_.origin();
  return btVector3(btScalar(x.x()), btScalar(x.y()), btScalar(x.z()));
}

btVector3 CapeAction::position(std::uint32_t particle) const {
  if (particle >= particleCount()) return btVector3(0, 0, 0);
  return toWorld(cape_.state().positions.row(particle).transpose());
}

btScalar CapeAction::maxPinError() const {
  // In the cape's frame, where both the particle and the body's pose are precise.
  btScalar worst = 0;
  const Points& x = cape_.state().positions;
  for (const Attachment& a : attachments_) {
    auto it = trackedIndex_.find(a.body);
    if (it == trackedIndex_.end() || a.particle >= particleCount()) continue;
    const btVector3 target = tracked_[it->second].stepEnd * a.localPivot;
    worst = std::max(worst, (toBt(Vec3(x.row(a.particle).transpose())) - target).length());
  }
  return worst;
}

double CapeAction::takeAccumulatedMicroseconds() {
  const double t = accumulatedMicroseconds_;
  accumulatedMicroseconds_ = 0.0;
  return t;
}

// --- Tracking -----------------------------------------------------------------------------------------

CapeAction::Tracked* CapeAction::find(const btCollisionObject* object) {
  auto it = trackedIndex_.find(object);
  return it == trackedIndex_.end() ? nullptr : &tracked_[it->second];
}

CapeAction::Tracked& CapeAction::track(const btCollisionObject* object) {
  if (Tracked* t = find(object)) return *t;
  // First sight: the body is where it is now, and has not moved (no sweep from the origin).
  Tracked t;
  t.object = object;
  const btTransform& w = object->getWorldTransform();
  t.lastSeen = w;
  t.segmentStart = t.segmentEnd = t.stepStart = t.stepEnd = toFrame(w);
  t.worldIndex = object->getWorldArrayIndex();  // a hint for dropMissing (checked before it is trusted)
  trackedIndex_[object] = tracked_.size();
  tracked_.push_back(std::move(t));
  return tracked_.back();
}

void CapeAction::refreshPinIndices() {
  pinIndex_.assign(attachments_.size(), static_cast<std::size_t>(-1));
  const std::vector<Pin>& pins = cape_.state().pins;
  for (std::size_t a = 0; a < attachments_.size(); ++a)
    for (std::size_t k = 0; k < pins.size(); ++k)
      if (pins[k].particle == attachments_[a].particle) pinIndex_[a] = k;
}

// --- Attachments --------------------------------------------------------------------------------------

bool CapeAction::attach(std::uint32_t particle, const btRigidBody* body, const btVector3& localPivot) {
  if (!ok() || body == nullptr || particle >= particleCount()) return false;
  const btVector3 target = body->getWorldTransform() * localPivot;
  if (!std::isfinite(target.x()) || !std::isfinite(target.y()) || !std::isfinite(target.z())) return false;
  auto it = std::find_if(attachments_.begin(), attachments_.end(),
                         [&](const Attachment& a) { return a.particle == particle; });
  if (it != attachments_.end()) {
    it->body = body;
    it->localPivot = localPivot;
  } else {
    attachments_.push_back({particle, body, localPivot});
  }
  track(body);
  // Pin at the body's pose as this action last saw it, so that the next step sweeps the pin along with it.
  cape_.pin(particle, toVec3(find(body)->stepEnd * localPivot));
  refreshPinIndices();
  return true;
}

bool CapeAction::attach(std::uint32_t particle, const btRigidBody* body) {
  if (!ok() || body == nullptr || particle >= particleCount()) return false;
  // The pivot from the body's pose and the particle in the cape's frame: precise however far from the
  // world's origin.
  const btVector3 here = toBt(Vec3(cape_.state().positions.row(particle).transpose()));
  return attach(particle, body, track(body).stepEnd.invXform(here));
}

std::uint32_t CapeAction::attachNearest(const btRigidBody* body, const btVector3& worldPoint) {
  if (!ok() || body == nullptr) return kNoParticle;
  const Vec3 p = toVec3(toFrame(btTransform(btMatrix3x3::getIdentity(), worldPoint)).getOrigin());
  Eigen::Index best = 0;
  (cape_.state().positions.rowwise() - p.transpose()).rowwise().squaredNorm().minCoeff(&best);
  const auto particle = static_cast<std::uint32_t>(best);
  return attach(particle, body, body->getWorldTransform().invXform(worldPoint)) ? particle : kNoParticle;
}

std::size_t CapeAction::attachRow(int row, const btRigidBody* body) {
  if (!ok()) return 0;
  const int columns = cape_.fabric().gridColumns(), rows = cape_.fabric().gridRows();
  if (columns <= 0 || row < 0 || row >= rows) return 0;
  std::size_t n = 0;
  for (int c = 0; c < columns; ++c) n += attach(static_cast<std::uint32_t>(row * columns + c), body) ? 1 : 0;
  return n;
}

void CapeAction::detach(std::uint32_t particle) {
  auto it = std::find_if(attachments_.begin(), attachments_.end(),
                         [&](const Attachment& a) { return a.particle == particle; });
  if (it == attachments_.end()) return;
  attachments_.erase(it);
  cape_.unpin(particle);
  refreshPinIndices();
}

void CapeAction::detach(const btCollisionObject* body) {
  std::vector<std::uint32_t> released;
  for (const Attachment& a : attachments_)
    if (a.body == body) released.push_back(a.particle);
  for (std::uint32_t p : released) detach(p);
  if (referenceBody_ == body) referenceBody_ = nullptr;
}

void CapeAction::detachAll() {
  for (const Attachment& a : attachments_) cape_.unpin(a.particle);
  attachments_.clear();
  pinIndex_.clear();
}

const btRigidBody* CapeAction::referenceBody() const {
  if (referenceBody_ != nullptr) return referenceBody_;
  return attachments_.empty() ? nullptr : attachments_.front().body;
}

void CapeAction::addCollider(const btCollisionObject* object) {
  if (object == nullptr) return;
  track(object).explicitCollider = true;
  changed_ = true;
}

void CapeAction::removeCollider(const btCollisionObject* object) {
  if (Tracked* t = find(object)) t->explicitCollider = false;
  changed_ = true;
}

// --- One step -----------------------------------------------------------------------------------------

void CapeAction::updateAction(btCollisionWorld* world, btScalar dt) {
  prepare(world, dt);
  advance(dt);
}

void CapeAction::dropMissing(btCollisionWorld* world) {
  // Pointers only: a body removed from the world may already be deleted. Each followed object should still
  // be where it was last seen in the world's array; if all are, none left the world (O(followed objects)).
  const btCollisionObjectArray& objects = world->getCollisionObjectArray();
  const auto inPlace = [&](const Tracked& t) {
    return t.worldIndex >= 0 && t.worldIndex < objects.size() && objects[t.worldIndex] == t.object;
  };
  if (std::all_of(tracked_.begin(), tracked_.end(), inPlace)) return;
  // Something left the world or was moved by Bullet's swap-and-pop removal: one pass over the world's array
  // marks the followed objects still in it and refreshes their indices (a lookup in the small map of
  // followed objects, no allocation).
  for (Tracked& t : tracked_) t.present = false;
  for (int i = 0; i < objects.size(); ++i) {
    auto it = trackedIndex_.find(objects[i]);
    if (it == trackedIndex_.end()) continue;
    tracked_[it->second].present = true;
    tracked_[it->second].worldIndex = i;
  }
  bool dropped = false;
  for (const Tracked& t : tracked_) {
    if (t.present) continue;
    dropped = true;
    std::size_t released = 0;
    for (const Attachment& a : attachments_) released += a.body == t.object ? 1 : 0;
    if (released > 0) {
      warnOnce("removed:" + std::to_string(reinterpret_cast<std::uintptr_t>(t.object)) + ":" +
                   std::to_string(stepCount_),
               "a body was removed from the world while " + std::to_string(released) +
                   " cape particle(s) were attached to it; they were released (call detach(body) first)");
    }
    detach(t.object);
  }
  if (!dropped) return;
  std::vector<Tracked> kept;
  kept.reserve(tracked_.size());
  for (Tracked& t : tracked_)
    if (t.present) kept.push_back(std::move(t));
  tracked_ = std::move(kept);
  trackedIndex_.clear();
  for (std::size_t i = 0; i < tracked_.size(); ++i) trackedIndex_[tracked_[i].object] = i;
}

void CapeAction::discover(btCollisionWorld* world) {
  discoveryChanged_ = false;
  if (!settings_.discoverColliders) {
    for (Tracked& t : tracked_) t.discovered = false;
    lastFound_.clear();
    lastReported_.clear();
    return;
  }
  // The cape's bounds at the start of the step, grown by its thickness and the discovery margin, in the
  // world (the frame's origin added in double).
  const btScalar grow = btScalar(cape_.settings().collisionThickness) + discoveryReach();
  const Eigen::Vector3d& o = cape_.origin();
  const Eigen::Vector3d lo = particleBounds(true).cast<double>() + o;
  const Eigen::Vector3d hi = particleBounds(false).cast<double>() + o;
  DiscoveryCallback query;
  query.objects = &world->getCollisionObjectArray();
  query.lo = btVector3(btScalar(lo.x()), btScalar(lo.y()), btScalar(lo.z())) - btVector3(grow, grow, grow);
  query.hi = btVector3(btScalar(hi.x()), btScalar(hi.y()), btScalar(hi.z())) + btVector3(grow, grow, grow);
  query.group = settings_.collisionGroup;
  query.mask = settings_.collisionMask;
  found_.clear();
  query.found = &found_;
  world->getBroadphase()->aabbTest(query.lo, query.hi, query);
  // The same report as the last step's (the trees unchanged, as around a cape at rest) finds the same
  // objects at the same indices: every followed object's flag and index stand as the last step set them
  // (an object that left the world since would be missing from the report).
  if (found_ == lastReported_) return;
  lastReported_ = found_;  // keeps its capacity
  // The broadphase reports in its trees' order: the world's array order makes the objects first seen in
  // this step follow (and collide) in the same order whatever the trees look like.
  std::sort(found_.begin(), found_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  found_.erase(std::unique(found_.begin(), found_.end(),
                           [](const auto& a, const auto& b) { return a.first == b.first; }),
               found_.end());
  // The same objects at the same indices in another order (the trees rebalanced): as above.
  if (found_ == lastFound_) return;
  discoveryChanged_ = true;
  lastFound_ = found_;  // keeps its capacity
  for (Tracked& t : tracked_) t.discovered = false;
  for (const auto& [index, object] : found_) {
    Tracked& t = track(object);
    t.discovered = true;
    t.worldIndex = index;
  }
}

Vec3 CapeAction::particleBounds(bool low) {
  // A sleeping cape's particles stay where they are until something wakes it (every change to its state
  // does), so its bounds are taken once when it is found asleep and kept while it sleeps.
  if (!boundsKept_ || !cape_.isAsleep()) {
    const Points& x = cape_.state().positions;
    boundsLow_ = x.colwise().minCoeff().transpose();
    boundsHigh_ = x.colwise().maxCoeff().transpose();
    boundsKept_ = cape_.isAsleep();
  }
  return low ? boundsLow_ : boundsHigh_;
}

bool CapeAction::resting() const {
  if (!cape_.isAsleep() || discoveryChanged_ || changed_) return false;
  for (const Tracked& t : tracked_) {
    // Where Bullet has it now is where the action last read it, and the motion read then is spent.
    if (!t.settled || !sameTransform(t.object->getWorldTransform(), t.lastSeen)) return false;
  }
  return true;
}

void CapeAction::advancePoses(btScalar dt) {
  for (Tracked& t : tracked_) {
    const btTransform& w = t.object->getWorldTransform();
    t.jumped = false;
    if (!sameTransform(w, t.lastSeen)) {
      // A new pose: Bullet moves kinematic bodies once per stepSimulation (saveKinematicState), so the motion
      // may be meant to cover several internal steps. Its duration is the displacement over the velocity
      // Bullet derived for it (a dynamic body moves by v dt each step, so this gives one step); a body moved
      // without velocity jumps at once.
      t.segmentStart = t.stepEnd;
      t.segmentEnd = toFrame(w);
      t.lastSeen = w;
      t.segmentElapsed = 0;
      t.segmentDuration = 0;
      const btScalar distance = (t.segmentEnd.getOrigin() - t.segmentStart.getOrigin()).length();
      const btScalar angle = rotationAngle(t.segmentStart, t.segmentEnd);
      if (const btRigidBody* body = btRigidBody::upcast(t.object)) {
        const btScalar v = body->getLinearVelocity().length(), omega = body->getAngularVelocity().length();
        if (distance > btScalar(1e-6) && v > btScalar(1e-9))
          t.segmentDuration = distance / v;
        else if (angle > btScalar(1e-6) && omega > btScalar(1e-9))
          t.segmentDuration = angle / omega;
        if (!std::isfinite(t.segmentDuration)) t.segmentDuration = 0;
      }
      if (distance > settings_.teleportDistance || angle > settings_.teleportAngle) {
        t.jumped = true;
        t.segmentDuration = 0;
      }
    }
    t.stepStart = t.stepEnd;
    t.segmentElapsed += dt;
    // Within a quarter step of the end counts as the end: rounding must not leave a sliver behind.
    const btScalar s = t.segmentDuration > 0 && t.segmentElapsed < t.segmentDuration - btScalar(0.25) * dt
                           ? t.segmentElapsed / t.segmentDuration
                           : btScalar(1);
    t.stepEnd = interpolate(t.segmentStart, t.segmentEnd, s);
    if (t.jumped) t.stepStart = t.stepEnd;
  }
}

void CapeAction::moveFrame(const Eigen::Vector3d& origin, bool carry) {
  const Eigen::Vector3d shift = cape_.origin() - origin;
  if (carry)
    cape_.relocate(origin);
  else
    cape_.setOrigin(origin);
  // Every followed pose in the new frame: where the body is now exactly (from Bullet's world pose), the
  // poses it is swept from shifted in double.
  const auto shifted = [&](btTransform& t) { t = relativeTo(t, -shift); };
  for (Tracked& t : tracked_) {
    shifted(t.segmentStart);
    shifted(t.stepStart);
    shifted(t.stepEnd);
    t.segmentEnd = toFrame(t.lastSeen);
    if (t.jumped) t.stepStart = t.stepEnd = t.segmentEnd;
  }
}

void CapeAction::relocate(const Eigen::Vector3d& origin) {
  if (ok() && origin.allFinite()) moveFrame(origin, true);
}

void CapeAction::applyTeleport() {
  teleported_ = false;
  const btRigidBody* ref = referenceBody();
  Tracked* t = ref != nullptr ? find(ref) : nullptr;
  if (t == nullptr || !t->jumped) return;
  // The character jumped: carry the cape rigidly (positions, velocities, pin targets), no stretching. The
  // jump is measured from where the action had the body (in the cape's frame) to where it is now (in the
  // world, in double): x -> R (x - c0) + c1. The frame goes with it to the grid point nearest c1, so the
  // cape's coordinates stay small however far the jump (a body moved by 1e20 m and back brings its cape
  // back intact).
  const btQuaternion q0 = t->segmentStart.getRotation(), q1 = t->lastSeen.getRotation();
  const btQuaternion dq = q1 * q0.inverse();
  const Quat r(float(dq.w()), float(dq.x()), float(dq.y()), float(dq.z()));
  const Eigen::Vector3d c0 = toDouble(t->segmentStart.getOrigin());
  const Eigen::Vector3d c1 = toDouble(t->lastSeen.getOrigin()) - cape_.origin();  // old frame
  const Eigen::Vector3d origin = gridPoint(t->lastSeen.getOrigin());
  const Eigen::Vector3d shift = cape_.origin() - origin;  // old frame to new
  Pose delta;
  delta.rotation = r.normalized();
  const Eigen::Vector3d turned = delta.rotation.cast<double>() * c0;
  delta.position = (c1 - turned + shift).cast<float>();
  if (!delta.isFinite() || !origin.allFinite()) return;
  cape_.teleport(delta);
  moveFrame(origin, true);
  if (settings_.teleportMode == TeleportMode::Reset) cape_.resetToReference();
  teleported_ = true;
}

void CapeAction::followReference() {
  // The frame follows the reference body once it is more than a spacing away.
  const btRigidBody* ref = referenceBody();
  const Tracked* t = ref != nullptr ? find(ref) : nullptr;
  if (t == nullptr || t->jumped || !(settings_.frameSpacing > 0)) return;
  const btVector3 c = t->stepEnd.getOrigin();
  const bool away = std::abs(c.x()) > settings_.frameSpacing || std::abs(c.y()) > settings_.frameSpacing ||
                    std::abs(c.z()) > settings_.frameSpacing;
  if (!away) return;
  const Eigen::Vector3d origin = gridPoint(t->lastSeen.getOrigin());
  if (origin.allFinite() && origin != cape_.origin()) moveFrame(origin, false);
}

void CapeAction::reportGuard() {
  // The guard runs in advance() (perhaps on a worker thread of CapeGroup): its warning is said here.
  const Cape::GuardReport& g = cape_.guard();
  if (g.total == guardReported_) return;
  guardReported_ = g.total;
  warnOnce("guard", "the cape's numerical guard restored " + std::to_string(g.total) +
                        " particle(s) (not finite, or runaway) by step " + std::to_string(stepCount_) +
                        "; Cape::guard() counts them (said once)");
}

void CapeAction::applyInertia(btScalar dt) {
  const btRigidBody* ref = referenceBody();
  Tracked* t = ref != nullptr ? find(ref) : nullptr;
  if (t == nullptr || t->jumped) return;
  const btScalar li = btClamped(settings_.linearInertia, btScalar(0), btScalar(1));
  const btScalar ai = btClamped(settings_.angularInertia, btScalar(0), btScalar(1));
  const auto limit = [](btScalar v) { return std::isfinite(v) && v > btScalar(0); };
  const bool linearLimit = limit(settings_.maxLinearSpeed), angularLimit = limit(settings_.maxAngularSpeed);
  if (li >= btScalar(1) && ai >= btScalar(1) && !linearLimit && !angularLimit) return;
  // Shift the free particles by the part of the body's motion they should not feel: its rotation about its
  // origin by (1 - angular inertia) of the step's angle, and (1 - linear inertia) of its displacement; and
  // of what they would feel, whatever is beyond the speed limits.
  const btVector3 c0 = t->stepStart.getOrigin(), c1 = t->stepEnd.getOrigin();
  btQuaternion dq = t->stepEnd.getRotation() * t->stepStart.getRotation().inverse();
  if (dq.w() < 0) dq = -dq;
  btScalar carriedTurn = btScalar(1) - ai;  // the fraction of the step's rotation carried
  if (angularLimit) {
    const btScalar angle = dq.getAngle(), felt = ai * angle, most = settings_.maxAngularSpeed * dt;
    if (felt > most && angle > btScalar(0)) carriedTurn = (angle - most) / angle;
  }
  btVector3 shiftBt = (btScalar(1) - li) * (c1 - c0);
  if (linearLimit) {
    const btVector3 felt = li * (c1 - c0);
    const btScalar length = felt.length(), most = settings_.maxLinearSpeed * dt;
    if (length > most) shiftBt = (c1 - c0) - felt * (most / length);
  }
  const btQuaternion partial = btQuaternion::getIdentity().slerp(dq, carriedTurn);
  const Quat r(static_cast<float>(partial.w()), static_cast<float>(partial.x()),
               static_cast<float>(partial.y()), static_cast<float>(partial.z()));
  const Eigen::Matrix3f m = r.normalized().toRotationMatrix();
  const Vec3 centre = toVec3(c0);
  const Vec3 shift = toVec3(shiftBt);
  // Every particle, and where every pin starts this step, moves alike: otherwise the pins would sweep from
  // their old place while the free particles already stand in the new one, and the springs between them
  // would turn the difference into motion.
  cape_.carry(m, centre, shift);
}

void CapeAction::updatePins() {
  for (std::size_t a = 0; a < attachments_.size(); ++a) {
    const Attachment& att = attachments_[a];
    const Tracked* t = find(att.body);
    if (t == nullptr) continue;
    const Vec3 target = toVec3(t->stepEnd * att.localPivot);
    if (t->jumped || pinIndex_[a] == static_cast<std::size_t>(-1)) {
      cape_.pin(att.particle, target);  // retargets without a sweep
    } else {
      cape_.movePin(pinIndex_[a], target);
    }
  }
  refreshPinIndices();
}

void CapeAction::buildColliders() {
  colliders_.clear();
  activeObjects_.clear();
  meshCount_ = 0;
  for (Tracked& t : tracked_) {
    if (!t.explicitCollider && !t.discovered) continue;
    if (!t.converted) {
      t.shape = convertShape(t.object->getCollisionShape());
      t.converted = true;
      for (const std::string& name : t.shape.unsupported)
        warnOnce("shape:" + name, "unsupported collision shape '" + name + "' ignored by the cape");
      t.soups.clear();
      for (std::size_t k = 0; k < t.shape.meshes.size(); ++k)
        t.soups.push_back(std::make_shared<TriangleSoup>());
    }
    if (t.shape.empty()) continue;
    activeObjects_.push_back(t.object);
    // The collider's own friction, combined with the cape's as Bullet combines two materials (and as
    // btSoftBody does with its kDF): the product.
    const float friction = cape_.settings().friction * float(t.object->getFriction());
    for (const ShapeConversion::Primitive& p : t.shape.primitives) {
      Collider c = p.collider;
      c.previous = toPose(t.stepStart * p.local);
      c.current = toPose(t.stepEnd * p.local);
      c.friction = friction;
      if (c.shape == ColliderShape::Plane) {
        // Planes are static half-spaces: the core reads their normal and constant in the collider frame.
        c.previous = c.current;
      }
      colliders_.push_back(std::move(c));
    }
    for (std::size_t k = 0; k < t.shape.meshes.size(); ++k) {
      const ShapeConversion::Mesh& m = t.shape.meshes[k];
      const btTransform start = t.stepStart * m.local, end = t.stepEnd * m.local;
      gatherTriangles(m.shape, start, end, *t.soups[k]);
      Collider c = Collider::triangleMesh(t.soups[k], toPose(end));
      c.previous = toPose(start);
      c.thickness = float(m.shape->getMargin());  // Bullet's skin over the triangles
      c.friction = friction;
      c.name = m.shape->getName();
      colliders_.push_back(std::move(c));
      ++meshCount_;
    }
  }
}

void CapeAction::gatherTriangles(const btConcaveShape* shape, const btTransform& start,
                                 const btTransform& end, TriangleSoup& soup) const {
  // Bullet's mesh query, once per step: the triangles in the box of the cape's bounds grown by the reach of
  // one step (the discovery margin) and the skins, in the shape's frame at the step's start and its end.
  struct Collect : btTriangleCallback {
    TriangleSoup* soup;
    void processTriangle(btVector3* t, int, int) override {
      for (int k = 0; k < 3; ++k) soup->corners.push_back(toVec3(t[k]));
    }
  } collect;
  collect.soup = &soup;
  soup.corners.clear();  // keeps its capacity: no allocation once the cape has met the mesh
  const Points& x = cape_.state().positions;  // the poses are in the cape's frame too
  const btScalar grow = btScalar(cape_.settings().collisionThickness) + shape->getMargin() + discoveryReach();
  const btVector3 lo = toBt(Vec3(x.colwise().minCoeff().transpose())) - btVector3(grow, grow, grow);
  const btVector3 hi = toBt(Vec3(x.colwise().maxCoeff().transpose())) + btVector3(grow, grow, grow);
  btVector3 qlo(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT), qhi = -qlo;
  for (const btTransform* pose : {&start, &end})
    for (int corner = 0; corner < 8; ++corner) {
      const btVector3 p = pose->invXform(btVector3(corner & 1 ? hi.x() : lo.x(), corner & 2 ? hi.y() : lo.y(),
                                                   corner & 4 ? hi.z() : lo.z()));
      qlo.setMin(p);
      qhi.setMax(p);
    }
  shape->processAllTriangles(&collect, qlo, qhi);
}

void CapeAction::followGravity(btCollisionWorld* world) {
  // Only a dynamics world has a gravity; a bare collision world leaves CapeSettings::gravity in force.
  const auto* dynamics = dynamic_cast<const btDynamicsWorld*>(world);
  if (dynamics == nullptr) return;
  const Vec3 g = toVec3(dynamics->getGravity());
  if (g == cape_.settings().gravity) return;
  if (!cape_.setGravity(g).ok())
    warnOnce("gravity", "the world's gravity is not finite; the cape keeps its own");
}

Status DetailLevel::validate() const {
  if (stepInterval < 1 || stepInterval > kMaxStepInterval)
    return Status::error("DetailLevel: stepInterval must be in 1.." + std::to_string(kMaxStepInterval) +
                         ", not " + std::to_string(stepInterval));
  if (substeps < 0 || substeps > 1000)
    return Status::error("DetailLevel: substeps must be 0 (the settings' own) or in 1..1000, not " +
                         std::to_string(substeps));
  return Status::success();
}

Status CapeAction::setDetailLevel(const DetailLevel& level) {
  if (Status s = level.validate(); !s.ok()) return s;
  if (!ok()) return Status::error("CapeAction::setDetailLevel: the cape was not made");
  if (level.coarseFabric && !cape_.fabric().coarseLevel())
    return Status::error(
        "CapeAction::setDetailLevel: coarseFabric needs a grid fabric of at least 3 x 3 particles "
        "(Fabric::coarseLevel); this cape's has no coarse level");
  if (Status s = cape_.setSubstepOverride(level.substeps); !s.ok()) return s;
  if (Status s = cape_.setCoarseLevel(level.coarseFabric); !s.ok()) return s;
  detail_ = level;
  return Status::success();
}

btVector3 CapeAction::detailPoint() const {
  if (!ok()) return btVector3(0, 0, 0);
  const CapeState& st = cape_.state();
  Vec3 sum = Vec3::Zero();
  for (const Pin& p : st.pins) sum += p.target;
  const Vec3 at = st.pins.empty() ? Vec3(st.positions.row(0).transpose())
                                  : Vec3(sum / static_cast<float>(st.pins.size()));
  return toWorld(at);
}

btScalar CapeAction::discoveryReach() const {
  // The margin covers a step's motion of the bodies around; a step over several internal steps is longer.
  return settings_.discoveryMargin * btScalar(detail_.stepInterval);
}

void CapeAction::prepare(btCollisionWorld* world, btScalar dt) {
  due_ = false;
  resting_ = false;
  if (!ok() || world == nullptr || !(dt > 0)) return;
  // At a coarser level of detail the internal steps between the cape's own steps only add up their time.
  skippedTime_ += dt;
  if (++skippedSteps_ < detail_.stepInterval) return;
  dt = skippedTime_;  // exactly dt at full detail (0 + dt)
  skippedTime_ = 0;
  skippedSteps_ = 0;
  stepTime_ = dt;
  due_ = true;
  const auto start = std::chrono::steady_clock::now();
  if (settings_.useWorldGravity) followGravity(world);
  reportGuard();
  dropMissing(world);
  discover(world);
  resting_ = resting();
  if (resting_) {
    // Asleep, and nothing it follows has moved or come or gone: the pins and colliders of the last step
    // stand, and the cape only counts the step (Cape::stepAsleep).
    prepareMicroseconds_ =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    return;
  }
  advancePoses(dt);
  applyTeleport();
  followReference();
  updatePins();
  applyInertia(dt);  // after the pins have their new targets: it shifts where they start
  buildColliders();
  // What resting() needs of each followed pose besides where Bullet has it: whether its motion is spent
  // (these only change in a full prepare like this one).
  for (Tracked& t : tracked_)
    t.settled = !t.jumped && sameTransform(t.stepStart, t.stepEnd) && sameTransform(t.stepEnd, t.segmentEnd);
  changed_ = false;
  prepareMicroseconds_ =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
}

void CapeAction::advance(btScalar) {
  if (!ok() || !due_) return;
  due_ = false;
  // A resting cape's colliders are those of its last step, bit for bit (every body they come from checked
  // by resting()), and that step left it asleep among them: its step only counts itself, a few
  // nanoseconds, not timed (two reads of the clock would cost more than the step).
  const bool slept = resting_ && cape_.stepAsleep(static_cast<float>(stepTime_));
  resting_ = false;
  double microseconds = 0.0;
  if (!slept) {
    const auto start = std::chrono::steady_clock::now();
    cape_.step(static_cast<float>(stepTime_), ColliderSpan(colliders_));
    microseconds =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  }
  ++stepCount_;
  lastStepMicroseconds_ = prepareMicroseconds_ + microseconds;
  prepareMicroseconds_ = 0.0;
  accumulatedMicroseconds_ += lastStepMicroseconds_;
}

void CapeAction::debugDraw(btIDebugDraw* drawer) {
  if (drawer == nullptr || !ok()) return;
  const int mode = drawer->getDebugMode();
  const CapeState& state = cape_.state();
  // Everything is computed in the cape's frame (where the particles and colliders are precise) and drawn in
  // the world's (toWorld; directions need no shift: toBt).
  // The faces, filled (drawTriangle with the face's normal at its three corners: the counter-clockwise side
  // is the front); their edges with DBG_DrawWireframe, their normals (5 cm) with DBG_DrawNormals.
  const btVector3 edgeColor = debugColor_ * btScalar(0.5);
  const btVector3 normalColor = drawer->getDefaultColors().m_activeObject;
  const std::vector<std::uint32_t>& tri = cape_.fabric().triangles();
  for (std::size_t k = 0; k + 2 < tri.size(); k += 3) {
    const Vec3 pa = state.positions.row(tri[k]).transpose(), pb = state.positions.row(tri[k + 1]).transpose(),
               pc = state.positions.row(tri[k + 2]).transpose();
    const Vec3 cross = (pb - pa).cross(pc - pa);
    const float length = cross.norm();
    const Vec3 n = length > 0.0f && std::isfinite(length) ? Vec3(cross / length) : Vec3::Zero();
    const btVector3 a = toWorld(pa), b = toWorld(pb), c = toWorld(pc), bn = toBt(n);
    drawer->drawTriangle(a, b, c, bn, bn, bn, debugColor_, btScalar(1));
    if (mode & btIDebugDraw::DBG_DrawWireframe) {
      drawer->drawLine(a, b, edgeColor);
      drawer->drawLine(b, c, edgeColor);
      drawer->drawLine(c, a, edgeColor);
    }
    if (mode & btIDebugDraw::DBG_DrawNormals) {
      const Vec3 centre = (pa + pb + pc) / 3.0f;
      drawer->drawLine(toWorld(centre), toWorld(centre + 0.05f * n), normalColor);
    }
  }
  // The pins: a 1 cm sphere at each pin's target, in the colour of Bullet's constraints.
  const btVector3 pinColor = drawer->getDefaultColors().m_disabledSimulationObject;
  for (const Pin& pin : state.pins) drawer->drawSphere(toWorld(pin.target), btScalar(0.01), pinColor);
  // The contacts, when the drawer asks for contact points: each particle within the cape's thickness (and
  // the collider's) of a collider of the last step, at the collider's nearest surface point, with the
  // normal towards the particle and the signed distance (negative: inside), as Bullet draws its own.
  if (mode & btIDebugDraw::DBG_DrawContactPoints) {
    const float reach = cape_.settings().collisionThickness;
    const btVector3 contactColor = drawer->getDefaultColors().m_contactPoint;
    for (const Collider& collider : colliders_) {
      const float within = reach + collider.thickness + 1e-3f;
      for (Eigen::Index i = 0; i < state.positions.rows(); ++i) {
        const Vec3 p = state.positions.row(i).transpose();
        const float d = signedDistance(collider, p);
        if (!(d < within)) continue;
        const Vec3 q = closestSurfacePoint(collider, p);
        const Vec3 towards = p - q;
        const float length = towards.norm();
        const Vec3 n = length > 0.0f && std::isfinite(length) ? Vec3(towards / length) : Vec3::UnitY();
        drawer->drawContactPoint(toWorld(q), toBt(d < 0.0f ? Vec3(-n) : n), btScalar(d), 0, contactColor);
      }
    }
  }
  if (mode & btIDebugDraw::DBG_DrawAabb) {
    const Vec3 lo = state.positions.colwise().minCoeff().transpose();
    const Vec3 hi = state.positions.colwise().maxCoeff().transpose();
    drawer->drawAabb(toWorld(lo), toWorld(hi), drawer->getDefaultColors().m_aabb);
  }
}

}  // namespace cape::bullet
