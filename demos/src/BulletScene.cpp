#include "BulletScene.h"

#include "cape/bullet/Convert.h"
#include "cape/scenes/BulletSimpleBody.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace cape::demo {

namespace {

using bullet::toBt;
using bullet::toVec3;

// docs/SCENES.md: the pins lie on the line (+-0.30, 1.56, 0.15) of the character frame, 4 cm above and 15 cm
// behind the shoulder centres (+-0.22, 1.52, 0).
const Vec3 kPinLineCentre(0.0f, 1.56f, 0.15f);
const Vec3 kPinLineFromShoulders(0.0f, 0.04f, 0.15f);

Pose poseOf(const Eigen::Isometry3d& t) {
  Pose p;
  p.position = t.translation().cast<float>();
  p.rotation = Quat(t.rotation().cast<float>());
  p.rotation.normalize();
  return p;
}

Vec3 crowdOffset(int k, int count) {
  // Side by side, 2 m apart along X, centred on the origin.
  return Vec3(2.0f * (static_cast<float>(k) - 0.5f * static_cast<float>(count - 1)), 0.0f, 0.0f);
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
  Pose placement;
  std::vector<PinSpec> pins;
};

std::unique_ptr<BulletScene> BulletScene::create(const RunOptions& options, std::string& error,
                                                 WorldKind kind) {
  std::unique_ptr<BulletScene> scene(new BulletScene());
  if (!scene->build(options, kind, error)) return nullptr;
  return scene;
}

BulletScene::~BulletScene() {
  characters_.clear();
  if (world_ && ground_) world_->removeRigidBody(ground_.get());
}

bool BulletScene::build(const RunOptions& o, WorldKind kind, std::string& error) {
  options_ = o;
  motion_ = MotionDesc::forScene(o.scene);
  rig_ = makeCapeRig(o.size, o.pinLayout, o.settings.bendStiffness > 0.0f);
  if (!rig_.fabric) {
    error = "cannot build a " + std::to_string(o.size) + " x " + std::to_string(o.size) + " cape";
    return false;
  }

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
  world_->setGravity(btVector3(0, btScalar(-9.8), 0));
  // Soft bodies (the twins of cape_compare) take gravity and air from the world's soft body info.
  info->m_gravity = world_->getGravity();
  info->air_density = btScalar(1.2);

  groundShape_ = std::make_unique<btStaticPlaneShape>(btVector3(0, 1, 0), btScalar(0));
  ground_ = std::make_unique<btRigidBody>(btScalar(0), nullptr, groundShape_.get());
  ground_->setUserIndex(-1);
  world_->addRigidBody(ground_.get());

  const int count = o.scene == SceneKind::Crowd ? std::max(1, o.characters) : 1;
  character::UrdfModelPtr model;
  if (!o.simpleBody) {
    const character::UrdfLoadResult loaded =
        o.urdf.empty() ? character::UrdfModel::humanoid() : character::UrdfModel::fromFile(o.urdf);
    if (!loaded.ok()) {
      error = (o.urdf.empty() ? std::string("shipped humanoid") : o.urdf) + ": " + loaded.status.message();
      return false;
    }
    model = loaded.model;
    warnings_ = model->warnings();
    // The links the cape pins to: as asked, or every link named like a shoulder.
    attachLinks_ = o.attachLinks.empty() ? model->linksContaining("shoulder") : o.attachLinks;
    if (attachLinks_.empty()) {
      error = "no link named like \"shoulder\" in " +
              (o.urdf.empty() ? std::string("the humanoid") : o.urdf) +
              ": name the links to attach to with --attach LINK[,LINK]";
      return false;
    }
    for (const std::string& name : attachLinks_) {
      if (model->findLink(name) < 0) {
        std::string known;
        for (const auto& l : model->links()) known += (known.empty() ? "" : ", ") + l.name;
        error = "unknown link \"" + name + "\" (the model's links: " + known + ")";
        return false;
      }
    }
    body_ = (o.urdf.empty() ? std::string("the shipped humanoid (character/models/humanoid.urdf)")
                            : "URDF " + o.urdf);
  } else {
    body_ = "the simple body of docs/SCENES.md as kinematic Bullet bodies";
  }

  for (int k = 0; k < count; ++k) {
    auto c = std::make_unique<Character>();
    c->offset = crowdOffset(k, count);
    Vec3 shift = c->offset;  // moves docs/SCENES.md's pin line onto this character's
    std::vector<std::pair<float, btRigidBody*>> anchors;  // attachment bodies by their x at rest
    if (model) {
      character::CharacterSettings cs;
      cs.offset = c->offset.cast<double>();
      character::CharacterResult made =
          character::Character::create(model, *world_, character::Gait::forScene(o.scene), cs);
      if (!made.ok()) {
        error = made.status.message();
        return false;
      }
      c->urdf = std::move(made.character);
      for (const character::WorldShape& w : c->urdf->skeleton().worldShapes())
        c->hulls.push_back(w.shape->type == character::ShapeType::ConvexHull ? hullOf(*w.shape) : nullptr);
      if (k == 0)
        for (const std::string& w : c->urdf->warnings())
          if (std::find(warnings_.begin(), warnings_.end(), w) == warnings_.end()) warnings_.push_back(w);
      const int torso = model->findLink("torso");
      c->torsoLink = torso >= 0 ? torso : 0;
      Vec3 centre = Vec3::Zero();
      for (const std::string& name : attachLinks_) {
        const int link = model->findLink(name);
        const Vec3 at = c->urdf->skeleton().linkPose(link).translation().cast<float>();
        centre += at / static_cast<float>(attachLinks_.size());
        btRigidBody* body = c->urdf->bodies().bodyForLink(link);
        if (!body) {
          error = "link \"" + name + "\" has no collision shape, so no body to attach the cape to";
          return false;
        }
        anchors.emplace_back(at.x(), body);
      }
      shift = centre + kPinLineFromShoulders - kPinLineCentre;
    } else {
      // Torso, shoulders and legs as kinematic bodies, at the scene's starting pose (the world's ground is
      // shared by every character).
      c->simple = std::make_unique<BulletSimpleBody>(*world_, c->offset, motionAt(motion_, 0.0));
      if (o.pinLayout == PinLayout::Collar) {
        anchors.emplace_back(0.0f, c->simple->rigidBody(SimpleBody::kTorso));
      } else {
        anchors.emplace_back(-1.0f, c->simple->rigidBody(SimpleBody::kLeftShoulder));
        anchors.emplace_back(1.0f, c->simple->rigidBody(SimpleBody::kRightShoulder));
      }
    }
    std::sort(anchors.begin(), anchors.end(), [](const auto& a, const auto& b) { return a.first < b.first; });

    // The cape starts as docs/SCENES.md says, moved onto this character's pin line; each pinned particle goes
    // to the attachment body nearest to it along X (left corner to the left shoulder, and so on).
    const Pose start = capeStartPlacement(o.scene);
    c->placement.position = start.position + shift;
    c->placement.rotation = start.rotation;
    for (std::size_t p = 0; p < rig_.pinnedParticles.size(); ++p) {
      const Vec3 point = rig_.pinLocalPoints[p] + shift;
      const auto nearest =
          std::min_element(anchors.begin(), anchors.end(), [&](const auto& a, const auto& b) {
            return std::fabs(a.first - point.x()) < std::fabs(b.first - point.x());
          });
      btRigidBody* body = nearest->second;
      c->pins.push_back({rig_.pinnedParticles[p], body, body->getWorldTransform().inverse() * toBt(point)});
    }
    characters_.push_back(std::move(c));
  }
  if (o.simpleBody && !o.attachLinks.empty()) warnings_.push_back("--attach is ignored with --simple-body");
  return true;
}

void BulletScene::poseAt(double t) {
  for (auto& c : characters_) {
    if (c->urdf) {
      c->urdf->advanceTo(t);
      continue;
    }
    c->simple->moveTo(motionAt(motion_, t));  // the colliders, and the bodies' motion states
  }
}

double BulletScene::stepFrame(double t) {
  poseAt(t);
  const auto t0 = std::chrono::steady_clock::now();
  world_->stepSimulation(btScalar(1.0 / 60.0), 8, btScalar(1.0 / 240.0));
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<Collider> BulletScene::bodyColliders(int k) const {
  const Character& c = *characters_[static_cast<std::size_t>(k)];
  if (c.simple) {
    const ColliderSpan s = c.simple->body().bodyColliders();
    return std::vector<Collider>(s.begin(), s.end());
  }
  std::vector<Collider> out;
  const std::vector<character::WorldShape> shapes = c.urdf->skeleton().worldShapes();
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const character::WorldShape& w = shapes[k];
    const Pose pose = poseOf(w.pose);
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

Vec3 BulletScene::torsoCentre(int k) const {
  const Character& c = *characters_[static_cast<std::size_t>(k)];
  if (c.simple) return c.simple->body().torsoCentre();
  return c.urdf->skeleton().linkPose(c.torsoLink).translation().cast<float>();
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
         "; stepSimulation(1/60, 8, 1/240)";
}

}  // namespace cape::demo
