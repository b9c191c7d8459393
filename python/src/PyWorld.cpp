#include "PyWorld.h"

#include "cape/bullet/Convert.h"
#include "cape/bullet/ShapeColliders.h"
#include "cape/character/Anchors.h"
#include "cape/character/Urdf.h"
#include "cape/core/FabricPresets.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace capepy {

namespace ch = cape::character;
using cape::bullet::toBt;

namespace {

// Sizes and distances the module accepts, m: a kinematic body or a cape is centimetres to metres; far beyond
// these a float simulation loses its meaning.
constexpr double kMinSize = 1e-3;
constexpr double kMaxSize = 100.0;
constexpr double kMaxCoordinate = 1e5;

[[noreturn]] void fail(const std::string& message) {
  throw std::invalid_argument(message);
}

void checkRange(double value, double lo, double hi, const std::string& what) {
  if (!std::isfinite(value) || value < lo || value > hi)
    fail(what + " must be finite and within [" + std::to_string(lo) + ", " + std::to_string(hi) + "], not " +
         std::to_string(value));
}

void checkPose(const Eigen::Isometry3d& pose, const std::string& what) {
  if (!pose.matrix().allFinite()) fail(what + ": the pose is not finite");
  if (pose.translation().cwiseAbs().maxCoeff() > kMaxCoordinate)
    fail(what + ": the position is more than " + std::to_string(kMaxCoordinate) + " m from the origin");
}

btTransform toBtTransform(const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.rotation());
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                     btVector3(btScalar(pose.translation().x()), btScalar(pose.translation().y()),
                               btScalar(pose.translation().z())));
}

Eigen::Isometry3d toIsometry(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::Quaterniond(double(q.w()), double(q.x()), double(q.y()), double(q.z()))
                      .normalized()
                      .toRotationMatrix();
  pose.translation() =
      Eigen::Vector3d(double(t.getOrigin().x()), double(t.getOrigin().y()), double(t.getOrigin().z()));
  return pose;
}

/// A kinematic body's pose for the next step. Bullet reads the motion state at the start of stepSimulation
/// and derives the velocity from the body's last interpolated pose (btRigidBody::saveKinematicState); the
/// world transform is set too, so queries before the step see the body where it was put. A teleport also
/// resets that last pose: a jump at rest.
void moveKinematic(btRigidBody& body, const btTransform& t, bool teleport) {
  body.getMotionState()->setWorldTransform(t);
  body.setWorldTransform(t);
  if (teleport) {
    body.setInterpolationWorldTransform(t);
    body.setLinearVelocity(btVector3(0, 0, 0));
    body.setAngularVelocity(btVector3(0, 0, 0));
    body.setInterpolationLinearVelocity(btVector3(0, 0, 0));
    body.setInterpolationAngularVelocity(btVector3(0, 0, 0));
  }
}

cape::PinLayout parsePins(const std::string& name) {
  cape::PinLayout layout;
  if (!cape::parsePinLayout(name, layout))
    fail("pins must be \"corners\" or \"collar\", not \"" + name + "\"");
  return layout;
}

/// The fabric preset a spec names, or nullptr for none; ValueError naming the presets for an unknown one.
const cape::FabricMaterial* fabricOf(const CapeSpec& spec) {
  if (spec.fabric.empty()) return nullptr;
  const cape::FabricMaterial* m = cape::findFabric(spec.fabric);
  if (!m) fail("no fabric \"" + spec.fabric + "\"; the presets are " + cape::fabricNames());
  return m;
}

/// makeCapeRig's cape, with the fabric preset's mass per area when one is named.
cape::CapeRig makeRig(const CapeSpec& spec, cape::PinLayout layout, const cape::CapeSize& size) {
  const cape::FabricMaterial* m = fabricOf(spec);
  cape::CapeRig rig = cape::makeCapeRig(spec.resolution, layout, spec.settings.bendStiffness > 0.0f, size, 0,
                                        m ? cape::fabricMass(*m, size.width, size.height) : 0.0f);
  if (!rig.fabric)
    throw std::runtime_error("cannot build a cape of " + std::to_string(spec.resolution) +
                             " particles a side");
  return rig;
}

cape::CapeSize capeSize(const CapeSpec& spec, double width, double height) {
  checkRange(spec.resolution, 3, 128, "resolution (particles per side)");
  checkRange(width, 0.05, 10.0, "width (m)");
  checkRange(height, 0.05, 10.0, "height (m)");
  const cape::Status s = spec.settings.validate();
  if (!s.ok()) fail("cape settings: " + s.message());
  cape::CapeSize size;
  size.width = static_cast<float>(width);
  size.height = static_cast<float>(height);
  return size;
}

}  // namespace

struct World::UserBody {
  std::string name;
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btDefaultMotionState> motion;
  std::unique_ptr<btRigidBody> body;
};

struct World::CharacterEntry {
  ch::UrdfModelPtr model;
  std::unique_ptr<ch::Character> character;
  std::vector<std::string> warnings;
};

struct World::CapeEntry {
  std::unique_ptr<cape::bullet::CapeAction> action;
  std::string description;
  const btRigidBody* reference = nullptr;  ///< the blow-up metric measures from it
  std::vector<std::string> warnings;
  cape::MetricsRecorder recorder;
  cape::FrameMetrics last;
  cape::SelfIntersectionCounter counter;
  bool countSelfIntersections = false;
  std::uint64_t guardSeen = 0;
  cape::CapeMesh mesh;
};

World::World(const WorldSettings& settings) : settings_(settings) {
  const Eigen::Vector3d up =
      settings.up == ch::UpAxis::Y ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  checkRange(settings.groundHeight, -kMaxCoordinate, kMaxCoordinate, "ground_height (m)");
  Eigen::Vector3d g = settings.gravity.value_or(-9.81 * up);
  if (!g.allFinite() || g.norm() > 1000.0) fail("gravity must be finite and at most 1000 m/s^2");
  configuration_ = std::make_unique<btDefaultCollisionConfiguration>();
  dispatcher_ = std::make_unique<btCollisionDispatcher>(configuration_.get());
  broadphase_ = std::make_unique<btDbvtBroadphase>();
  solver_ = std::make_unique<btSequentialImpulseConstraintSolver>();
  world_ = std::make_unique<btDiscreteDynamicsWorld>(dispatcher_.get(), broadphase_.get(), solver_.get(),
                                                     configuration_.get());
  world_->setGravity(btVector3(btScalar(g.x()), btScalar(g.y()), btScalar(g.z())));
  if (settings.ground) {
    groundShape_ = std::make_unique<btStaticPlaneShape>(
        btVector3(btScalar(up.x()), btScalar(up.y()), btScalar(up.z())), btScalar(settings.groundHeight));
    ground_ = std::make_unique<btRigidBody>(
        btRigidBody::btRigidBodyConstructionInfo(0, nullptr, groundShape_.get()));
    world_->addRigidBody(ground_.get());
  }
}

World::~World() {
  // Bullet's rule: what we added we remove before it is freed; the capes first (they point at bodies).
  for (auto& c : capes_) world_->removeAction(c->action.get());
  capes_.clear();
  characters_.clear();  // CharacterBodies removes its own bodies
  for (auto& b : bodies_) world_->removeRigidBody(b->body.get());
  bodies_.clear();
  if (ground_) world_->removeRigidBody(ground_.get());
}

double World::time() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return time_;
}

Eigen::Vector3d World::gravity() const {
  std::lock_guard<std::mutex> lock(mutex_);
  const btVector3 g = world_->getGravity();
  return Eigen::Vector3d(double(g.x()), double(g.y()), double(g.z()));
}

void World::checkBody(int body) const {
  if (body < 0 || body >= static_cast<int>(bodies_.size()))
    throw std::out_of_range("no body " + std::to_string(body) + " (the world has " +
                            std::to_string(bodies_.size()) + ")");
}
void World::checkCharacter(int character) const {
  if (character < 0 || character >= static_cast<int>(characters_.size()))
    throw std::out_of_range("no character " + std::to_string(character));
}
void World::checkCape(int cape) const {
  if (cape < 0 || cape >= static_cast<int>(capes_.size()))
    throw std::out_of_range("no cape " + std::to_string(cape));
}
void World::checkNotRecording(const char* what) const {
  if (recorder_) throw std::runtime_error(std::string("cannot ") + what + " while recording glTF");
}

void World::addBodyColliders(const btRigidBody* body, const std::string& owner) {
  BodyColliders entry;
  entry.body = body;
  entry.owner = owner;
  const cape::bullet::ShapeConversion conversion = cape::bullet::convertShape(body->getCollisionShape());
  for (const auto& p : conversion.primitives) entry.parts.emplace_back(p.collider, p.local);
  bodyColliders_.push_back(std::move(entry));
}

int World::addBody(BodyShape shape, const Eigen::Vector3d& size, int axis, const Eigen::Isometry3d& pose,
                   const std::string& name) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkNotRecording("add a body");
  checkPose(pose, "body pose");
  auto b = std::make_unique<UserBody>();
  const auto s = [](double v) { return btScalar(v); };
  switch (shape) {
    case BodyShape::Sphere:
      checkRange(size.x(), kMinSize, kMaxSize, "sphere radius (m)");
      b->shape = std::make_unique<btSphereShape>(s(size.x()));
      break;
    case BodyShape::Box:
      for (int k = 0; k < 3; ++k) checkRange(size[k], kMinSize, kMaxSize, "box half extent (m)");
      b->shape = std::make_unique<btBoxShape>(btVector3(s(size.x()), s(size.y()), s(size.z())));
      break;
    case BodyShape::Capsule:
      checkRange(size.x(), kMinSize, kMaxSize, "capsule radius (m)");
      checkRange(size.y(), 0.0, kMaxSize, "capsule half height (m)");
      if (axis == 0) {
        b->shape = std::make_unique<btCapsuleShapeX>(s(size.x()), s(2.0 * size.y()));
      } else if (axis == 1) {
        b->shape = std::make_unique<btCapsuleShape>(s(size.x()), s(2.0 * size.y()));
      } else if (axis == 2) {
        b->shape = std::make_unique<btCapsuleShapeZ>(s(size.x()), s(2.0 * size.y()));
      } else {
        fail("capsule axis must be 0 (x), 1 (y) or 2 (z), not " + std::to_string(axis));
      }
      break;
  }
  b->name = name.empty() ? "body" + std::to_string(bodies_.size()) : name;
  const btTransform t = toBtTransform(pose);
  b->motion = std::make_unique<btDefaultMotionState>(t);
  b->body = std::make_unique<btRigidBody>(
      btRigidBody::btRigidBodyConstructionInfo(0, b->motion.get(), b->shape.get()));
  b->body->setCollisionFlags(b->body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
  b->body->setActivationState(DISABLE_DEACTIVATION);
  world_->addRigidBody(b->body.get());
  addBodyColliders(b->body.get(), b->name);
  bodies_.push_back(std::move(b));
  return static_cast<int>(bodies_.size()) - 1;
}

int World::bodyCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(bodies_.size());
}

std::string World::bodyName(int body) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkBody(body);
  return bodies_[static_cast<std::size_t>(body)]->name;
}

void World::setBodyPose(int body, const Eigen::Isometry3d& pose, bool teleport) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkBody(body);
  checkPose(pose, "body " + std::to_string(body));
  moveKinematic(*bodies_[static_cast<std::size_t>(body)]->body, toBtTransform(pose), teleport);
}

void World::setBodyPoses(const std::vector<Eigen::Isometry3d>& poses, bool teleport) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (poses.size() != bodies_.size())
    fail("expected one pose per body (" + std::to_string(bodies_.size()) + "), got " +
         std::to_string(poses.size()));
  for (std::size_t i = 0; i < poses.size(); ++i) checkPose(poses[i], "body " + std::to_string(i));
  for (std::size_t i = 0; i < poses.size(); ++i)
    moveKinematic(*bodies_[i]->body, toBtTransform(poses[i]), teleport);
}

Eigen::Isometry3d World::bodyPose(int body) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkBody(body);
  return toIsometry(bodies_[static_cast<std::size_t>(body)]->body->getWorldTransform());
}

int World::addCharacter(const CharacterSpec& spec) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkNotRecording("add a character");
  checkRange(spec.scale, 1e-3, 1e3, "scale");
  if (!spec.offset.allFinite() || spec.offset.cwiseAbs().maxCoeff() > kMaxCoordinate)
    fail("offset must be finite and within " + std::to_string(kMaxCoordinate) + " m");
  ch::UrdfLoadOptions options;
  options.packagePaths = spec.packagePaths;
  if (spec.modelUp == "auto") {
    options.modelUp = ch::UrdfLoadOptions::Up::Auto;
  } else if (spec.modelUp == "z") {
    options.modelUp = ch::UrdfLoadOptions::Up::Z;
  } else if (spec.modelUp == "y") {
    options.modelUp = ch::UrdfLoadOptions::Up::Y;
  } else {
    fail("model_up must be \"auto\", \"z\" or \"y\", not \"" + spec.modelUp + "\"");
  }
  ch::Gait gait{ch::GaitParams()};
  if (spec.gait != "stand") {
    cape::SceneKind kind;
    if (!cape::parseSceneKind(spec.gait, kind))
      fail("gait must be \"stand\", \"walk\", \"sprint-turn\", \"hang\", \"wind\" or \"crowd\", not \"" +
           spec.gait + "\"");
    gait = ch::Gait::forScene(kind);
  }
  const ch::UrdfLoadResult loaded = !spec.path.empty()   ? ch::UrdfModel::fromFile(spec.path, options)
                                    : !spec.text.empty() ? ch::UrdfModel::fromString(spec.text, options)
                                                         : ch::UrdfModel::humanoid();
  if (!loaded.ok()) {
    std::string message = loaded.status.message();
    if (loaded.status.code() == ch::ErrorCode::FileNotFound) throw FileNotFound(message);
    throw std::invalid_argument(message);
  }
  ch::CharacterSettings settings;
  settings.scale = spec.scale;
  settings.offset = spec.offset;
  settings.up = settings_.up;
  ch::CharacterResult made = ch::Character::create(loaded.model, *world_, gait, settings);
  if (!made.ok()) throw std::invalid_argument(made.status.message());
  auto entry = std::make_unique<CharacterEntry>();
  entry->model = loaded.model;
  entry->character = std::move(made.character);
  entry->warnings = entry->character->warnings();
  const ch::CharacterBodies& bodies = entry->character->bodies();
  const std::string prefix = loaded.model->name() + std::to_string(characters_.size()) + "/";
  for (int link = 0; link < entry->character->skeleton().linkCount(); ++link) {
    if (const btRigidBody* body = bodies.bodyForLink(link))
      addBodyColliders(body, prefix + loaded.model->links()[static_cast<std::size_t>(link)].name);
  }
  characters_.push_back(std::move(entry));
  return static_cast<int>(characters_.size()) - 1;
}

int World::characterCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(characters_.size());
}

std::vector<std::string> World::characterWarnings(int character) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  return characters_[static_cast<std::size_t>(character)]->warnings;
}

std::vector<std::string> World::linkNames(int character) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  std::vector<std::string> names;
  for (const ch::LinkDesc& l : characters_[static_cast<std::size_t>(character)]->model->links())
    names.push_back(l.name);
  return names;
}

std::vector<std::string> World::jointNames(int character) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  std::vector<std::string> names;
  for (const ch::JointDesc& j : characters_[static_cast<std::size_t>(character)]->model->joints())
    if (j.isMovable()) names.push_back(j.name);
  return names;
}

std::vector<std::string> World::sphericalJointNames(int character) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  std::vector<std::string> names;
  for (const ch::JointDesc& j : characters_[static_cast<std::size_t>(character)]->model->joints())
    if (j.isSpherical()) names.push_back(j.name);
  return names;
}

std::vector<Eigen::Isometry3d> World::linkPoses(int character) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  const ch::Skeleton& s = characters_[static_cast<std::size_t>(character)]->character->skeleton();
  std::vector<Eigen::Isometry3d> poses;
  for (int link = 0; link < s.linkCount(); ++link) poses.push_back(s.linkPose(link));
  return poses;
}

double World::rootHeight(int character) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  return characters_[static_cast<std::size_t>(character)]->character->rootHeight();
}

double World::characterTime(int character) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  return characters_[static_cast<std::size_t>(character)]->character->time();
}

void World::advanceCharacter(int character, double t) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  checkRange(t, -1e7, 1e7, "t (s)");
  characters_[static_cast<std::size_t>(character)]->character->advanceTo(t);
}

void World::setCharacterMotion(int character, double t, const Eigen::Isometry3d& root,
                               const ch::JointPose& joints, const ch::JointRotations& rotations) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  checkPose(root, "root pose");
  const ch::Status s =
      characters_[static_cast<std::size_t>(character)]->character->setMotion(t, root, joints, rotations);
  if (!s.ok()) fail(s.message());
}

void World::setLinkPoses(int character, const std::vector<Eigen::Isometry3d>& poses, bool teleport) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCharacter(character);
  ch::Character& c = *characters_[static_cast<std::size_t>(character)]->character;
  const int links = c.skeleton().linkCount();
  if (static_cast<int>(poses.size()) != links)
    fail("expected one pose per link (" + std::to_string(links) + "), got " + std::to_string(poses.size()));
  for (int link = 0; link < links; ++link)
    checkPose(poses[static_cast<std::size_t>(link)], "link " + std::to_string(link));
  for (int link = 0; link < links; ++link) {
    if (btRigidBody* body = c.bodies().bodyForLink(link))
      moveKinematic(*body, toBtTransform(poses[static_cast<std::size_t>(link)]), teleport);
  }
}

int World::addCape(const cape::CapeRig& rig, const CapeSpec& spec, const btTransform& placement,
                   const std::vector<std::pair<std::uint32_t, std::pair<btRigidBody*, btVector3>>>& pins,
                   const btRigidBody* reference, std::string description) {
  cape::CapeSettings settings = spec.settings;
  if (const cape::FabricMaterial* m = fabricOf(spec)) {
    const float spacing = rig.fabric->meanSpacing();  // the springs for this grid's spacing
    const cape::Status s = cape::checkFabric(*m, spacing);
    if (!s.ok()) fail("fabric " + m->name + ": " + s.message());
    settings = cape::applyFabric(*m, spacing, settings);
    description += " of " + m->name;
  }
  auto entry = std::make_unique<CapeEntry>();
  entry->action = std::make_unique<cape::bullet::CapeAction>(rig.fabric, settings, placement);
  if (!entry->action->ok()) throw std::runtime_error("the cape: " + entry->action->cape().status().message());
  CapeEntry* raw = entry.get();
  entry->action->setWarningHandler([raw](const std::string& w) { raw->warnings.push_back(w); });
  for (const auto& [particle, at] : pins) {
    if (!entry->action->attach(particle, at.first, at.first->getWorldTransform().inverse() * at.second))
      throw std::runtime_error("could not pin particle " + std::to_string(particle));
  }
  entry->reference = reference;
  entry->description = std::move(description);
  entry->mesh.allocate(entry->action->cape().fabric(), false);
  world_->addAction(entry->action.get());
  capes_.push_back(std::move(entry));
  return static_cast<int>(capes_.size()) - 1;
}

int World::addCapeOnBodies(const CapeSpec& spec, const Eigen::Isometry3d& frame,
                           const std::vector<int>& bodies) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkNotRecording("add a cape");
  checkPose(frame, "frame");
  if (bodies.empty()) fail("a cape needs at least one body to hang from");
  for (int b : bodies) checkBody(b);
  const cape::CapeSize size = capeSize(spec, spec.width.value_or(0.6), spec.height.value_or(1.0));
  const cape::CapeRig rig = makeRig(spec, parsePins(spec.pins), size);
  const Eigen::Isometry3f f = frame.cast<float>();
  const cape::Pose start = cape::capeStartPlacement(cape::SceneKind::Walk, size);
  cape::Pose placement;
  placement.position = f * start.position;
  placement.rotation = (Eigen::Quaternionf(f.rotation()) * start.rotation).normalized();
  std::vector<std::pair<std::uint32_t, std::pair<btRigidBody*, btVector3>>> pins;
  for (std::size_t p = 0; p < rig.pinnedParticles.size(); ++p) {
    const btVector3 at = toBt(f * rig.pinLocalPoints[p]);
    btRigidBody* nearest = nullptr;
    btScalar best = std::numeric_limits<btScalar>::infinity();
    for (int b : bodies) {
      btRigidBody* body = bodies_[static_cast<std::size_t>(b)]->body.get();
      const btScalar d = (body->getWorldTransform().getOrigin() - at).length2();
      if (d < best) best = d, nearest = body;
    }
    pins.push_back({rig.pinnedParticles[p], {nearest, at}});
  }
  std::string description = "a " + std::to_string(spec.resolution) + "x" + std::to_string(spec.resolution) +
                            " cape on " + std::to_string(bodies.size()) + " bodies";
  return addCape(rig, spec, toBt(placement), pins, pins.front().second.first, std::move(description));
}

int World::addCapeOnCharacter(const CapeSpec& spec, int character) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkNotRecording("add a cape");
  checkCharacter(character);
  const ch::Character& c = *characters_[static_cast<std::size_t>(character)]->character;
  const ch::ShoulderAnchors a = ch::findShoulderAnchors(c);
  if (!a.status.ok()) throw std::runtime_error(a.status.message());
  // The pin line of docs/SCENES.md moved onto this character: its centre 4 cm above the shoulders' centre
  // and 3 cm behind the back's surface, all in the Y-up scene frame. Unless the size is given: 8 cm of cape
  // beyond each shoulder, and long enough to end 45 cm above the ground (at most 1 m).
  constexpr double kAbove = 0.04, kBehind = 0.03, kBeyond = 0.08, kHem = 0.45;
  const Eigen::Vector3d centre = 0.5 * (a.left + a.right) + Eigen::Vector3d(0.0, kAbove, a.back + kBehind);
  const double width =
      spec.width.value_or(std::clamp(std::fabs(a.right.x() - a.left.x()) + 2 * kBeyond, 0.2, 3.0));
  const double height = spec.height.value_or(std::clamp(centre.y() - kHem, 0.2, 1.0));
  const cape::CapeSize size = capeSize(spec, width, height);
  const cape::PinLayout layout = parsePins(spec.pins);
  const cape::CapeRig rig = makeRig(spec, layout, size);
  // The rig's pins lie on the canonical line (+-w/2, 1.56, 0.15) of the scene frame: moved onto this one.
  const Eigen::Vector3f shift = centre.cast<float>() - Eigen::Vector3f(0.0f, 1.56f, 0.15f);
  const Eigen::Matrix3f toWorld = ch::Skeleton::sceneToWorld(settings_.up).cast<float>();
  const cape::Pose start = cape::capeStartPlacement(cape::SceneKind::Walk, size);
  cape::Pose placement;
  placement.position = toWorld * (start.position + shift);
  placement.rotation = (Eigen::Quaternionf(toWorld) * start.rotation).normalized();
  btRigidBody* left = c.bodies().bodyForLink(a.leftLink);
  btRigidBody* right = c.bodies().bodyForLink(a.rightLink);
  btRigidBody* torso = c.bodies().bodyForLink(a.upperTorsoLink);
  if (!left || !right || !torso) throw std::runtime_error("the shoulders' links have no bodies to pin to");
  std::vector<std::pair<std::uint32_t, std::pair<btRigidBody*, btVector3>>> pins;
  for (std::size_t p = 0; p < rig.pinnedParticles.size(); ++p) {
    const Eigen::Vector3f scene = rig.pinLocalPoints[p] + shift;
    btRigidBody* body = layout == cape::PinLayout::Collar                                         ? torso
                        : std::fabs(scene.x() - a.left.x()) <= std::fabs(scene.x() - a.right.x()) ? left
                                                                                                  : right;
    pins.push_back({rig.pinnedParticles[p], {body, toBt(Eigen::Vector3f(toWorld * scene))}});
  }
  char line[128];
  std::snprintf(line, sizeof line, "; a %.2f x %.2f m cape, its top %.0f cm behind the shoulders", width,
                height, 100.0 * (a.back + kBehind));
  std::string description = a.description + line;
  if (layout == cape::PinLayout::Collar)
    description += "; its top row pinned to the upper torso '" +
                   c.skeleton().model().links()[static_cast<std::size_t>(a.upperTorsoLink)].name + "'";
  return addCape(rig, spec, toBt(placement), pins, torso, std::move(description));
}

int World::capeCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(capes_.size());
}

std::string World::capeDescription(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->description;
}

cape::CapeSettings World::capeSettings(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->action->cape().settings();
}

void World::setCapeSettings(int cape, const cape::CapeSettings& settings) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  const cape::Status s = capes_[static_cast<std::size_t>(cape)]->action->cape().setSettings(settings);
  if (!s.ok()) fail("cape settings: " + s.message());
}

void World::setMotionConstraints(int cape, const cape::MotionConstraints& constraints) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  const cape::Status s =
      capes_[static_cast<std::size_t>(cape)]->action->cape().setMotionConstraints(constraints);
  if (!s.ok()) fail(s.message());
}

void World::setWeightScale(int cape, bool mass, const Eigen::VectorXf& scale) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  cape::Cape& c = capes_[static_cast<std::size_t>(cape)]->action->cape();
  const cape::Status s = mass ? c.setMassScale(scale) : c.setStiffnessScale(scale);
  if (!s.ok()) fail(s.message());
}

void World::setDetailLevel(int cape, int stepInterval, int substeps, bool coarseFabric) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  const cape::Status s =
      capes_[static_cast<std::size_t>(cape)]->action->setDetailLevel({stepInterval, substeps, coarseFabric});
  if (!s.ok()) fail(s.message());
}

std::tuple<int, int, bool> World::detailLevel(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  const cape::bullet::DetailLevel& d = capes_[static_cast<std::size_t>(cape)]->action->detailLevel();
  return {d.stepInterval, d.substeps, d.coarseFabric};
}

cape::Points World::capeAnimatedPositions(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  const cape::Cape& c = capes_[static_cast<std::size_t>(cape)]->action->cape();
  cape::Points x = c.animatedPositions();
  const Eigen::Vector3d& o = c.origin();
  for (int k = 0; k < 3; ++k) x.col(k) = (x.col(k).cast<double>().array() + o[k]).cast<float>().matrix();
  return x;
}

void World::setCountSelfIntersections(int cape, bool on) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  capes_[static_cast<std::size_t>(cape)]->countSelfIntersections = on;
}

bool World::countSelfIntersections(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->countSelfIntersections;
}

cape::Points World::capePositions(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->action->positions();
}

cape::Points World::capeNormals(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  CapeEntry& c = *capes_[static_cast<std::size_t>(cape)];
  c.mesh.update(c.action->cape().fabric(), c.action->positions());
  return c.mesh.normals;
}

cape::Points World::capeVelocities(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->action->cape().state().velocities;
}

std::vector<std::uint32_t> World::capeTriangles(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->action->cape().fabric().triangles();
}

std::vector<Eigen::Vector2f> World::capeUvs(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->action->cape().fabric().uvs();
}

std::vector<std::uint32_t> World::capePinnedParticles(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  std::vector<std::uint32_t> out;
  for (const auto& a : capes_[static_cast<std::size_t>(cape)]->action->attachments())
    out.push_back(a.particle);
  return out;
}

std::vector<std::string> World::capeWarnings(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->warnings;
}

cape::FrameMetrics World::capeMetrics(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->last;
}

cape::RunSummary World::capeSummary(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->recorder.summary();
}

bool World::capeAsleep(int cape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  checkCape(cape);
  return capes_[static_cast<std::size_t>(cape)]->action->cape().isAsleep();
}

std::vector<cape::Collider> World::currentColliders(const Eigen::Vector3d& origin) const {
  std::vector<cape::Collider> out;
  for (const BodyColliders& b : bodyColliders_) {
    btTransform body = b.body->getWorldTransform();
    const Eigen::Vector3d at = Eigen::Vector3d(double(body.getOrigin().x()), double(body.getOrigin().y()),
                                               double(body.getOrigin().z())) -
                               origin;
    body.setOrigin(btVector3(btScalar(at.x()), btScalar(at.y()), btScalar(at.z())));
    for (const auto& [collider, local] : b.parts) {
      cape::Collider c = collider;
      c.name = b.owner;
      c.teleportTo(cape::bullet::toPose(body * local));
      out.push_back(std::move(c));
    }
  }
  return out;
}

std::vector<ColliderInfo> World::colliders() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<ColliderInfo> out;
  for (const cape::Collider& c : currentColliders(Eigen::Vector3d::Zero())) {
    ColliderInfo info;
    info.owner = c.name;
    info.shape = c.shape;
    info.radius = c.shape == cape::ColliderShape::ConvexHull && c.hull ? c.hull->radius : c.radius;
    info.halfHeight = c.halfHeight;
    info.axis = c.axis;
    info.halfExtents = c.halfExtents.cast<double>();
    info.pose.linear() = c.current.rotation.cast<double>().normalized().toRotationMatrix();
    info.pose.translation() = c.current.position.cast<double>();
    out.push_back(std::move(info));
  }
  return out;
}

void World::step(double dt, int frames, int maxSubsteps, double fixedStep) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkRange(dt, 1e-5, 1.0, "dt (s)");
  checkRange(frames, 1, 1000000, "frames");
  checkRange(maxSubsteps, 1, 1000, "max_substeps");
  checkRange(fixedStep, 1e-5, 1.0, "fixed_step (s)");
  if (dt > maxSubsteps * fixedStep * (1.0 + 1e-6))
    fail("dt " + std::to_string(dt) + " s needs more than max_substeps = " + std::to_string(maxSubsteps) +
         " internal steps of " + std::to_string(fixedStep) + " s: Bullet would drop the rest of the time");
  for (int f = 0; f < frames; ++f) {
    world_->stepSimulation(btScalar(dt), maxSubsteps, btScalar(fixedStep));
    time_ += dt;
    measureCapes();
    if (recorder_) recordFrame();
  }
}

void World::measureCapes() {
  for (auto& c : capes_) {
    const cape::Cape& cape = c->action->cape();
    const Eigen::Vector3d& origin = cape.origin();
    const std::vector<cape::Collider> colliders = currentColliders(origin);
    const btVector3 r = c->reference->getWorldTransform().getOrigin();
    const Eigen::Vector3d torso = Eigen::Vector3d(double(r.x()), double(r.y()), double(r.z())) - origin;
    c->last = cape::measureFrame(cape, colliders, torso.cast<float>(),
                                 c->countSelfIntersections ? &c->counter : nullptr);
    c->last.guardRestored = static_cast<std::uint32_t>(cape.guard().total - c->guardSeen);
    if (c->last.guardRestored > 0) c->last.blowUp = true;
    c->guardSeen = cape.guard().total;
    c->recorder.add(c->last);
  }
}

void World::startRecording() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (recorder_) throw std::runtime_error("already recording");
  if (capes_.empty()) throw std::runtime_error("nothing to record: add a cape first");
  recorder_ = std::make_unique<cape::demo::GltfRecorder>(static_cast<int>(capes_.size()));
  recordFrame();
}

bool World::recording() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return recorder_ != nullptr;
}

int World::recordedFrames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return recorder_ ? recorder_->frames() : 0;
}

void World::recordFrame() {
  // glTF is Y-up: a Z-up world is turned back into the scenes' frame.
  const Eigen::Matrix3f toGltf = ch::Skeleton::sceneToWorld(settings_.up).transpose().cast<float>();
  const Eigen::Quaternionf turn(toGltf);
  std::vector<cape::Collider> colliders = currentColliders(Eigen::Vector3d::Zero());
  for (cape::Collider& c : colliders) {
    cape::Pose p = c.current;
    p.position = toGltf * p.position;
    p.rotation = (turn * p.rotation).normalized();
    c.teleportTo(p);
  }
  const std::vector<cape::Collider> none;
  for (std::size_t k = 0; k < capes_.size(); ++k) {
    const cape::bullet::CapeAction& action = *capes_[k]->action;
    const cape::Points positions = action.positions() * toGltf.transpose();
    recorder_->record(static_cast<int>(k), action.cape().fabric(), positions, k == 0 ? colliders : none);
  }
}

int World::writeRecording(const std::string& path) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!recorder_) throw std::runtime_error("not recording: call start_recording() first");
  if (path.empty()) fail("an empty path");
  const int frames = recorder_->frames();
  std::string error;
  const bool written = recorder_->write(path, error);
  recorder_.reset();
  if (!written) throw std::runtime_error(error);
  return frames;
}

}  // namespace capepy
