#include "BulletScene.h"

#include "cape/bullet/Convert.h"
#include "cape/scenes/BulletSimpleBody.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace cape::demo {

namespace {

using bullet::toBt;
using bullet::toVec3;

// docs/SCENES.md: the pins lie on the line (+-0.30, 1.56, 0.15) of the character frame, 4 cm above and 15 cm
// behind the shoulder centres (+-0.22, 1.52, 0).
const Vec3 kPinLineCentre(0.0f, 1.56f, 0.15f);
constexpr float kPinLineAbove = 0.04f;       // m above the shoulders' centre
constexpr double kPinLineBehindBack = 0.03;  // m behind the back's surface

Pose poseOf(const Eigen::Isometry3d& t) {
  Pose p;
  p.position = t.translation().cast<float>();
  p.rotation = Quat(t.rotation().cast<float>());
  p.rotation.normalize();
  return p;
}

// docs/SCENES.md's crowd: a square grid 2 m apart, rows of ceil(sqrt(count)) characters side by side along
// X, one row behind another along +Z (they walk towards -Z), centred on the origin. One character stands on
// it, two side by side as they always did.
int crowdColumns(int count) {
  int columns = 1;
  while (columns * columns < count) ++columns;
  return columns;
}

Vec3 crowdOffset(int k, int count) {
  const int columns = crowdColumns(count);
  const int rows = (count + columns - 1) / columns;
  const int column = k % columns, row = k / columns;
  return Vec3(2.0f * (static_cast<float>(column) - 0.5f * static_cast<float>(columns - 1)), 0.0f,
              2.0f * (static_cast<float>(row) - 0.5f * static_cast<float>(rows - 1)));
}

// The core's hull of a character's convex-hull shape (vertices and planes in the shape frame).
std::shared_ptr<const ConvexHull> hullOf(const character::ShapeDesc& shape) {
  std::vector<Vec3> vertices;
  std::vector<Eigen::Vector4f> planes;
  for (const Eigen::Vector3d& v : shape.hull) vertices.push_back(v.cast<float>());
  for (const Eigen::Vector4d& p : shape.hullPlanes) planes.push_back(p.cast<float>());
  return ConvexHull::make(std::move(vertices), std::move(planes));
}

}  // namespace

int squareCellRows(int columns, double width, double height) {
  return std::max(2, static_cast<int>(std::lround(static_cast<double>(columns - 1) * height / width)) + 1);
}

bool BulletScene::makeRig(const CapeSize& fitted, double shoulderSpan, std::string& error) {
  const RunOptions& o = options_;
  // A gathered collar from shoulder to shoulder, its ends 3 cm forward onto them; the cape as wide as a
  // corner-pinned one would be (8 cm beyond each shoulder), so gathered onto the collar by about 0.7.
  collar_.span = static_cast<float>(std::round(std::clamp(shoulderSpan, 0.1, 3.0) * 1000.0) / 1000.0);
  collar_.wrap = 0.03f;
  settings_ = o.settings;
  const bool bend = o.settings.bendStiffness > 0.0f;
  if (!o.capeWidth && !o.capeHeight && !o.fabric) {
    capeSize_ = fitted;
    rig_ = makeCapeRig(o.size, o.pinLayout, bend, fitted, 0, 0.0f, collar_);
  } else {
    // The pins and the canonical mass per area as makeCapeRig gives them for this size (or the fabric's
    // mass), on a grid of `size` particles across and, with a width or a height, as many rows as keep the
    // cells square.
    capeSize_.width = o.capeWidth.value_or(fitted.width);
    capeSize_.height = o.capeHeight.value_or(fitted.height);
    const int rows =
        o.capeWidth || o.capeHeight ? squareCellRows(o.size, capeSize_.width, capeSize_.height) : o.size;
    if (rows > kMaxGridSide) {
      char line[256];
      std::snprintf(line, sizeof line,
                    "a %.3g x %.3g m cape %d particles across needs %d rows for square cells, more than %d: "
                    "give a smaller --size or a wider or shorter cape",
                    capeSize_.width, capeSize_.height, o.size, rows, kMaxGridSide);
      error = line;
      return false;
    }
    rig_ = makeCapeRig(o.size, o.pinLayout, bend, capeSize_, rows,
                       o.fabric ? fabricMass(*o.fabric, capeSize_.width, capeSize_.height) : 0.0f, collar_);
  }
  if (!rig_.fabric) {
    error = "cannot build a " + std::to_string(o.size) + " particle wide cape";
    return false;
  }
  if (o.fabric) {
    // The springs for this grid's spacing (the mean of its structural springs' rest lengths).
    const float spacing = rig_.fabric->meanSpacing();
    if (const Status s = checkFabric(*o.fabric, spacing); !s.ok()) {
      error = "--fabric " + o.fabric->name + ": " + s.message();
      return false;
    }
    // The scene's wind first, so that the fabric's drag and lift apply to it.
    settings_ = applyFabric(*o.fabric, spacing, settingsForScene(o.scene, o.settings));
  }
  return true;
}

/// One character: its bodies (from the character library, or the simple body's five), and its cape's pins.
/// Each removes its bodies from the world when destroyed.
struct BulletScene::Character {
  // URDF character.
  std::unique_ptr<character::Character> urdf;
  int torsoLink = 0;
  std::vector<std::shared_ptr<const ConvexHull>> hulls;  ///< per Skeleton::worldShapes() entry; null: none
  // The simple body.
  std::unique_ptr<BulletSimpleBody> simple;

  Vec3 offset = Vec3::Zero();
  Vec3 shift = Vec3::Zero();  ///< moves docs/SCENES.md's pin line onto this character's (character frame)
  std::vector<std::pair<float, btRigidBody*>> anchors;  ///< attachment bodies by their x at rest
  Pose placement;
  std::vector<PinSpec> pins;
  /// A motion clip's first pose from the standing pose the cape was fitted to (the upper torso's rigid move,
  /// relative to the scene's origin): placeCape carries the cape with it. The identity for the gait.
  Eigen::Isometry3d carry = Eigen::Isometry3d::Identity();
};

std::unique_ptr<BulletScene> BulletScene::create(const RunOptions& options, std::string& error,
                                                 WorldKind kind, std::vector<std::string>* warnings) {
  std::unique_ptr<BulletScene> scene(new BulletScene());
  const bool built = scene->build(options, kind, error);
  if (warnings) *warnings = scene->warnings_;
  if (!built) return nullptr;
  return scene;
}

BulletScene::~BulletScene() {
  characters_.clear();
  if (world_ && ground_) world_->removeRigidBody(ground_.get());
}

bool BulletScene::build(const RunOptions& o, WorldKind kind, std::string& error) {
  options_ = o;
  motion_ = MotionDesc::forScene(o.scene);
  if (o.simpleBody && o.up != character::UpAxis::Y) {
    error = "--up z needs a URDF character (the simple body is built in the Y-up frame of docs/SCENES.md)";
    return false;
  }
  if (o.simpleBody && !o.origin.isZero()) {
    error = "--origin needs a URDF character (the simple body is built in float world coordinates)";
    return false;
  }
  toWorld_ = character::Skeleton::sceneToWorld(o.up).cast<float>();
  makeWorld(kind);

  const int count = o.scene == SceneKind::Crowd ? std::max(1, o.characters) : 1;
  if (o.simpleBody) {
    body_ = "the simple body of docs/SCENES.md as kinematic Bullet bodies";
    // docs/SCENES.md's shoulder spheres are 0.44 m apart.
    if (!makeRig(CapeSize(), 0.44, error)) return false;
    for (int k = 0; k < count; ++k) addSimpleCharacter(crowdOffset(k, count));
    if (!o.attachLinks.empty()) warnings_.push_back("--attach is ignored with --simple-body");
  } else {
    if (!loadModel(o, error)) return false;
    for (int k = 0; k < count; ++k)
      if (!addUrdfCharacter(crowdOffset(k, count), k == 0, error)) return false;
  }
  for (auto& c : characters_) placeCape(*c);
  return true;
}

void BulletScene::makeWorld(WorldKind kind) {
  configuration_ = std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>();
  dispatcher_ = std::make_unique<btCollisionDispatcher>(configuration_.get());
  broadphase_ = std::make_unique<btDbvtBroadphase>();
  btSoftBodyWorldInfo* info = nullptr;
  if (kind == WorldKind::Deformable) {
    deformableSolver_ = std::make_unique<btDeformableBodySolver>();
    auto solver = std::make_unique<btDeformableMultiBodyConstraintSolver>();
    solver->setDeformableSolver(deformableSolver_.get());
    auto world = std::make_unique<btDeformableMultiBodyDynamicsWorld>(
        dispatcher_.get(), broadphase_.get(), solver.get(), configuration_.get(), deformableSolver_.get());
    // Explicit steps, as Bullet's own cloth demos: on this cape the implicit mode either leaves the nodes
    // where they are (its default Lagrange multipliers) or blows up (with projection), measured. Contacts
    // read the world's sparse signed-distance field, set up as those demos do.
    world->getWorldInfo().m_sparsesdf.setDefaultVoxelsz(btScalar(0.25));
    world->getWorldInfo().m_sparsesdf.Reset();
    deformableWorld_ = world.get();
    info = &world->getWorldInfo();
    solver_ = std::move(solver);
    world_ = std::move(world);
  } else {
    solver_ = std::make_unique<btSequentialImpulseConstraintSolver>();
    auto world = std::make_unique<btSoftRigidDynamicsWorld>(dispatcher_.get(), broadphase_.get(),
                                                            solver_.get(), configuration_.get());
    softRigidWorld_ = world.get();
    info = &world->getWorldInfo();
    world_ = std::move(world);
  }
  // Gravity and the ground in the world's own axes (Y or Z up); the caps read the world's gravity.
  world_->setGravity(toBt(toWorld(Vec3(0.0f, -9.8f, 0.0f))));
  // Soft bodies (the twins of cape_compare) take gravity and air from the world's soft body info.
  info->m_gravity = world_->getGravity();
  info->air_density = btScalar(1.2);

  // Through the scene's origin (--origin), where the characters stand.
  const Vec3 up = toWorld(Vec3::UnitY());
  groundShape_ =
      std::make_unique<btStaticPlaneShape>(toBt(up), btScalar(up.cast<double>().dot(options_.origin)));
  ground_ = std::make_unique<btRigidBody>(btScalar(0), nullptr, groundShape_.get());
  ground_->setUserIndex(-1);
  world_->addRigidBody(ground_.get());
}

bool BulletScene::loadModel(const RunOptions& o, std::string& error) {
  character::UrdfLoadOptions load;
  load.packagePaths = o.packagePaths;
  load.modelUp = o.modelUp;
  const character::UrdfLoadResult loaded =
      o.urdf.empty() ? character::UrdfModel::humanoid() : character::UrdfModel::fromFile(o.urdf, load);
  warnings_ = loaded.warnings;  // also when the load failed: they may say why
  if (!loaded.ok()) {
    // fromFile's messages already begin with the file's path.
    const std::string& m = loaded.status.message();
    const bool named = !o.urdf.empty() && m.rfind(o.urdf, 0) == 0;
    error = named ? m : (o.urdf.empty() ? std::string("shipped humanoid") : o.urdf) + ": " + m;
    return false;
  }
  model_ = loaded.model;
  if (!o.motion.empty()) {
    character::MotionClipResult clip =
        character::loadMotion(o.motion, model_, o.motionLoad, nullptr, o.scale);
    warnings_.insert(warnings_.end(), clip.warnings.begin(), clip.warnings.end());
    if (!clip.ok()) {
      error = clip.status.message();
      return false;
    }
    clip_ = std::move(clip.clip);
  }
  body_ = (o.urdf.empty() ? std::string("the shipped humanoid (character/models/humanoid.urdf)")
                          : "URDF " + o.urdf);
  return true;
}

void BulletScene::addSimpleCharacter(const Vec3& offset) {
  // Torso, shoulders and legs as kinematic bodies, at the scene's starting pose (the world's ground is shared
  // by every character).
  auto c = std::make_unique<Character>();
  c->offset = offset;
  c->simple = std::make_unique<BulletSimpleBody>(*world_, offset, motionAt(motion_, 0.0));
  if (options_.pinLayout != PinLayout::Corners) {
    c->anchors.emplace_back(0.0f, c->simple->rigidBody(SimpleBody::kTorso));
  } else {
    c->anchors.emplace_back(-1.0f, c->simple->rigidBody(SimpleBody::kLeftShoulder));
    c->anchors.emplace_back(1.0f, c->simple->rigidBody(SimpleBody::kRightShoulder));
  }
  c->shift = offset;  // docs/SCENES.md's pin line, moved onto this character
  characters_.push_back(std::move(c));
}

bool BulletScene::addUrdfCharacter(const Vec3& offset, bool first, std::string& error) {
  auto c = std::make_unique<Character>();
  c->offset = offset;
  character::CharacterSettings cs;
  cs.offset = offset.cast<double>() + options_.origin;
  cs.up = options_.up;
  cs.rootHeight = options_.rootHeight;
  cs.pose = options_.pose;
  cs.scale = options_.scale;
  character::CharacterResult made =
      character::Character::create(model_, *world_, character::Gait::forScene(options_.scene), cs);
  if (!made.ok()) {
    error = made.status.message();
    return false;
  }
  c->urdf = std::move(made.character);
  if (!options_.motion.empty()) {
    // One player serves every character (they share the model); each starts in the clip's first pose.
    if (!player_) {
      player_ = std::make_unique<character::MotionPlayer>();
      character::PlaybackSettings playback = options_.playback;
      playback.loop = playback.loop && clip_.loop;  // --motion-once, or the file (DeepMimic's "Loop")
      const character::LoopGap gap = character::loopGap(clip_);
      if (playback.loop && gap.value > 0.35) {  // 20 degrees
        char line[300];
        std::snprintf(
            line, sizeof line,
            "motion %s: its last frame is %.2f %s from its first at '%s', so every loop jumps there "
            "(a clip that is not a cycle); --motion-once plays it once and holds the end",
            clip_.name.c_str(), gap.value,
            model_->findJoint(gap.where) >= 0 &&
                    model_->joints()[static_cast<std::size_t>(model_->findJoint(gap.where))].type ==
                        character::JointType::Prismatic
                ? "m"
                : "rad",
            gap.where.c_str());
        warnings_.push_back(line);
      }
      const character::Status bound =
          character::MotionPlayer::create(clip_, c->urdf->skeleton(), playback, *player_);
      if (!bound.ok()) {
        error = bound.message();  // names the clip
        return false;
      }
      char line[200];
      std::snprintf(line, sizeof line,
                    "motion %s: %d samples, %.2f s%s, %zu joints and %zu ball joints played",
                    clip_.name.c_str(), clip_.sampleCount(), clip_.duration(),
                    playback.loop ? " looped" : ", its ends held", clip_.joints.size(), clip_.balls.size());
      notes_.push_back(line);
    }
  }
  // Every character is the same model at the same scale: the first one's hulls serve the crowd.
  const std::vector<character::WorldShape> shapes = c->urdf->skeleton().worldShapes();
  if (!first && characters_.front()->hulls.size() == shapes.size()) {
    c->hulls = characters_.front()->hulls;
  } else {
    for (const character::WorldShape& w : shapes)
      c->hulls.push_back(w.shape->type == character::ShapeType::ConvexHull ? hullOf(*w.shape) : nullptr);
  }
  if (first) {
    for (const std::string& w : c->urdf->warnings())
      if (std::find(warnings_.begin(), warnings_.end(), w) == warnings_.end()) warnings_.push_back(w);
    // A humanoid far taller or shorter than people and robots are may not be in metres.
    const Eigen::AlignedBox3d box = character::skeletonBounds(
        c->urdf->skeleton(), character::Skeleton::sceneToWorld(options_.up).transpose());
    if (!box.isEmpty() && (box.max().y() > 3.0 || box.max().y() < 0.3)) {
      char line[160];
      std::snprintf(line, sizeof line,
                    "the character is %.2f m tall: if its file is not in metres, scale it (--scale)",
                    box.max().y());
      warnings_.push_back(line);
    }
  }

  // Where the cape hangs: on the links asked for, or on the shoulders the joint mapping found.
  const character::ShoulderAnchors a =
      options_.attachLinks.empty() ? character::findShoulderAnchors(*c->urdf)
                                   : character::shoulderAnchorsOnLinks(*c->urdf, options_.attachLinks);
  if (!a.status.ok()) {
    error =
        a.status.message() + (options_.attachLinks.empty() ? "; name the links to pin to with --attach" : "");
    return false;
  }
  c->torsoLink = a.upperTorsoLink;
  std::vector<int> links;
  if (!options_.attachLinks.empty()) {
    // The links asked for, whatever the layout: each pin goes to the nearest of them along X.
    for (const std::string& name : options_.attachLinks) links.push_back(model_->findLink(name));
  } else if (options_.pinLayout != PinLayout::Corners) {
    links = {a.upperTorsoLink};
  } else {
    links = {a.leftLink, a.rightLink};
  }
  const Eigen::Matrix3d toScene = character::Skeleton::sceneToWorld(options_.up).transpose();
  for (int link : links) {
    btRigidBody* body = c->urdf->bodies().bodyForLink(link);
    if (!body) {
      error = "link \"" + model_->links()[static_cast<std::size_t>(link)].name +
              "\" has no collision shape, so no body to attach the cape to";
      return false;
    }
    const Eigen::Vector3d at = toScene * c->urdf->skeleton().linkPose(link).translation();
    c->anchors.emplace_back(static_cast<float>(at.x()), body);
  }
  // The pin line: 4 cm above the shoulders' centre and 3 cm behind the back (docs/SCENES.md: 15 cm behind
  // the shipped humanoid's shoulders, whose back is 12 cm behind them). In float as it always was, so the
  // shipped humanoid's cape starts where it did to the bit.
  // Relative to the scene's origin (subtracted in double: the same bits when it is zero).
  const Eigen::Vector3d o = toScene * options_.origin;
  const Vec3 centre = (a.left - o).cast<float>() / 2.0f + (a.right - o).cast<float>() / 2.0f;
  const Vec3 above(0.0f, kPinLineAbove, static_cast<float>(a.back + kPinLineBehindBack));
  c->shift = centre + above - kPinLineCentre;
  if (first) {
    // The cape's width follows the shoulders (8 cm beyond each), its length the height of the pins (it ends
    // 45 cm above the ground at most, 1 m long at most), both to the millimetre.
    const double span = std::fabs(a.right.x() - a.left.x());
    CapeSize size;
    size.width = static_cast<float>(std::round(std::clamp(span + 2.0 * 0.08, 0.2, 3.0) * 1000.0) / 1000.0);
    const double pinHeight = 0.5 * (a.left.y() + a.right.y()) + kPinLineAbove;
    size.height = static_cast<float>(std::round(std::clamp(pinHeight - 0.45, 0.2, 1.0) * 1000.0) / 1000.0);
    if (!makeRig(size, span, error)) return false;
    size = capeSize_;
    attachDescription_ = a.description;
    char line[160];
    std::snprintf(line, sizeof line, "; a %.2f x %.2f m cape, its top %.0f cm behind the shoulders",
                  size.width, size.height, 100.0 * (a.back + kPinLineBehindBack));
    notes_.push_back(a.description + line);
    std::snprintf(line, sizeof line, "the root link '%s' %.3f m above the ground (%s)",
                  model_->links()[0].name.c_str(), c->urdf->rootHeight(),
                  options_.rootHeight ? "--root-height" : "its lowest collision point on the ground");
    notes_.push_back(line);
    for (int link : links) attachLinks_.push_back(model_->links()[static_cast<std::size_t>(link)].name);
  }
  if (player_) {
    // The cape was fitted to the standing character (the shoulders, the back, the pin line: as for the gait,
    // whatever pose the clip starts in). Now the clip's first pose, and the cape carried there with the
    // upper torso (placeCape), relative to the scene's origin as every placement is.
    // The skeleton's link poses, in double: the bodies' float transforms are a millimetre apart 10 km out.
    const auto relative = [&]() {
      Eigen::Isometry3d pose = c->urdf->skeleton().linkPose(c->torsoLink);
      pose.translation() -= options_.origin;
      return pose;
    };
    const Eigen::Isometry3d standing = relative();
    const character::Status played = c->urdf->play(*player_, 0.0);
    if (!played.ok()) {
      error = played.message();
      return false;
    }
    c->carry = relative() * standing.inverse();
  }
  characters_.push_back(std::move(c));
  return true;
}

void BulletScene::placeCape(Character& c) {
  // The cape starts as docs/SCENES.md says, moved onto this character's pin line and turned into the world;
  // each pinned particle goes to the attachment body nearest to it along the character's X (left corner to
  // the left shoulder, and so on).
  std::sort(c.anchors.begin(), c.anchors.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  const Pose start = capeStartPlacement(options_.scene, capeSize_);
  c.placement.position = toWorld(start.position + c.shift);
  c.placement.rotation = Quat(toWorld_) * start.rotation;
  if (options_.up == character::UpAxis::Y) c.placement.rotation = start.rotation;  // the same bits as ever
  const bool carried = c.carry.matrix() != Eigen::Matrix4d::Identity();
  if (carried) {
    c.placement.position = (c.carry * c.placement.position.cast<double>()).cast<float>();
    c.placement.rotation = (Eigen::Quaterniond(c.carry.linear()) * c.placement.rotation.cast<double>())
                               .normalized()
                               .cast<float>();
  }
  for (std::size_t p = 0; p < rig_.pinnedParticles.size(); ++p) {
    const Vec3 point = rig_.pinLocalPoints[p] + c.shift;
    const auto nearest =
        std::min_element(c.anchors.begin(), c.anchors.end(), [&](const auto& a, const auto& b) {
          return std::fabs(a.first - point.x()) < std::fabs(b.first - point.x());
        });
    btRigidBody* body = nearest->second;
    // The pivot from the body's pose relative to the scene's origin (in double), so it keeps its precision
    // however far away the scene is; the identity of old at the origin.
    const btTransform& w = body->getWorldTransform();
    btTransform relative = w;
    if (!options_.origin.isZero()) {
      const Eigen::Vector3d p0 =
          Eigen::Vector3d(double(w.getOrigin().x()), double(w.getOrigin().y()), double(w.getOrigin().z())) -
          options_.origin;
      relative.setOrigin(btVector3(btScalar(p0.x()), btScalar(p0.y()), btScalar(p0.z())));
    }
    const Vec3 at = carried ? (c.carry * toWorld(point).cast<double>()).cast<float>() : toWorld(point);
    c.pins.push_back({rig_.pinnedParticles[p], body, relative.inverse() * toBt(at)});
  }
}

void BulletScene::startCape(int character, bullet::CapeAction& action) const {
  if (options_.pinLayout != PinLayout::Gathered) return;
  // The grid's rest points gathered onto the collar (gatheredStartPoint, in the grid's frame), placed as the
  // cape is (relative to the scene's origin), and written in the cape's frame (in double: the frame may be
  // far from the world's origin).
  const Pose& placement = characters_[static_cast<std::size_t>(character)]->placement;
  const Eigen::Vector3d shift = options_.origin - action.cape().origin();
  Cape& cape = action.cape();
  const Points& rest = cape.fabric().restPositions();
  Points& x = cape.mutableState().positions;
  for (Eigen::Index i = 0; i < rest.rows(); ++i) {
    const Vec3 at =
        placement.apply(gatheredStartPoint(options_.scene, rest.row(i).transpose(), capeSize_, collar_));
    x.row(i) = (at.cast<double>() + shift).cast<float>().transpose();
  }
}

Vec3 BulletScene::toWorld(const Vec3& scene) const {
  if (options_.up == character::UpAxis::Y) return scene;
  return toWorld_ * scene;
}

void BulletScene::poseAt(double t) {
  for (auto& c : characters_) {
    if (c->urdf) {
      if (player_) {
        (void)c->urdf->play(*player_, t);  // bound to this model at build: cannot fail
      } else {
        c->urdf->advanceTo(t);
      }
      continue;
    }
    c->simple->moveTo(motionAt(motion_, t));  // the colliders, and the bodies' motion states
  }
}

double BulletScene::stepFrame(double t) {
  const auto start = std::chrono::steady_clock::now();
  poseAt(t);
  const auto t0 = std::chrono::steady_clock::now();
  motionUs_ = std::chrono::duration<double, std::micro>(t0 - start).count();
  world_->stepSimulation(btScalar(1.0 / 60.0), 8, btScalar(1.0 / 240.0));
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<Collider> BulletScene::bodyColliders(int k, const Eigen::Vector3d& frame) const {
  const Character& c = *characters_[static_cast<std::size_t>(k)];
  if (c.simple) {
    const ColliderSpan s = c.simple->body().bodyColliders();
    std::vector<Collider> out(s.begin(), s.end());
    if (!frame.isZero())
      for (Collider& col : out) {
        col.previous.position = (col.previous.position.cast<double>() - frame).cast<float>();
        col.current.position = (col.current.position.cast<double>() - frame).cast<float>();
      }
    return out;
  }
  std::vector<Collider> out;
  const std::vector<character::WorldShape> shapes = c.urdf->skeleton().worldShapes();
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const character::WorldShape& w = shapes[k];
    Eigen::Isometry3d relative = w.pose;
    relative.translation() -= frame;
    const Pose pose = poseOf(relative);
    Collider col;
    switch (w.shape->type) {
      case character::ShapeType::Sphere:
        col = Collider::sphere(static_cast<float>(w.shape->radius), pose);
        break;
      case character::ShapeType::Box:
        col = Collider::box(w.shape->halfExtents.cast<float>(), pose);
        break;
      case character::ShapeType::Cylinder:
        col = Collider::cylinder(static_cast<float>(w.shape->radius), static_cast<float>(w.shape->halfLength),
                                 2, pose);
        break;
      case character::ShapeType::Capsule:
        col = Collider::capsule(static_cast<float>(w.shape->radius), static_cast<float>(w.shape->halfLength),
                                2, pose);
        break;
      case character::ShapeType::ConvexHull:
        col = Collider::convexHull(c.hulls[k], pose);
        col.thickness = static_cast<float>(w.shape->radius);  // the hull's rounding
        break;
    }
    col.name = w.shape->name.empty() ? *w.linkName : w.shape->name;
    out.push_back(std::move(col));
  }
  return out;
}

Vec3 BulletScene::torsoCentre(int k, const Eigen::Vector3d& frame) const {
  const Character& c = *characters_[static_cast<std::size_t>(k)];
  if (c.simple) return (c.simple->body().torsoCentre().cast<double>() - frame).cast<float>();
  return (c.urdf->skeleton().linkPose(c.torsoLink).translation() - frame).cast<float>();
}

Pose BulletScene::capePlacement(int k) const {
  return characters_[static_cast<std::size_t>(k)]->placement;
}

const std::vector<PinSpec>& BulletScene::pins(int k) const {
  return characters_[static_cast<std::size_t>(k)]->pins;
}

std::string BulletScene::describe() const {
  std::string links;
  for (const std::string& l : attachLinks_) links += (links.empty() ? "" : ", ") + l;
  return body_ + (links.empty() ? std::string() : ", cape attached to " + links) +
         (options_.motion.empty() ? std::string() : ", playing " + options_.motion) +
         "; stepSimulation(1/60, 8, 1/240)";
}

}  // namespace cape::demo
