// Shared set-up for the adapter's tests and the comparison's (tests/compare): a real Bullet world (discrete,
// or soft-rigid or deformable for the twins), bodies made the usual way, and the canonical cape.
#pragma once

#include "cape/bullet/CapeAction.h"
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <BulletSoftBody/btDeformableBodySolver.h>
#include <BulletSoftBody/btDeformableMultiBodyConstraintSolver.h>
#include <BulletSoftBody/btDeformableMultiBodyDynamicsWorld.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include "cape/bullet/Convert.h"

#include <memory>
#include <utility>
#include <vector>

namespace capetest {

constexpr btScalar kFrame = btScalar(1.0 / 60.0);
constexpr btScalar kFixed = btScalar(1.0 / 240.0);
constexpr btScalar kSeedStep = btScalar(0.00875);

/// Selects Bullet's deformable world (explicit steps, as its cloth demos) in World's constructor.
struct DeformableWorldTag {};

/// A Bullet world and the bodies the test made (removed and deleted in order at the end).
struct World {
  explicit World(DeformableWorldTag) {
    config = std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>();
    dispatcher = std::make_unique<btCollisionDispatcher>(config.get());
    broadphase = std::make_unique<btDbvtBroadphase>();
    deformableSolver = std::make_unique<btDeformableBodySolver>();
    auto* s = new btDeformableMultiBodyConstraintSolver();
    s->setDeformableSolver(deformableSolver.get());
    solver.reset(s);
    auto* w = new btDeformableMultiBodyDynamicsWorld(dispatcher.get(), broadphase.get(), s, config.get(),
                                                     deformableSolver.get());
    w->getWorldInfo().m_sparsesdf.setDefaultVoxelsz(btScalar(0.25));
    w->getWorldInfo().m_sparsesdf.Reset();
    w->getWorldInfo().m_gravity = btVector3(0, btScalar(-9.8), 0);
    world.reset(w);
    world->setGravity(btVector3(0, btScalar(-9.8), 0));
  }
  explicit World(bool soft = false) {
    if (soft)
      config = std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>();
    else
      config = std::make_unique<btDefaultCollisionConfiguration>();
    dispatcher = std::make_unique<btCollisionDispatcher>(config.get());
    broadphase = std::make_unique<btDbvtBroadphase>();
    solver = std::make_unique<btSequentialImpulseConstraintSolver>();
    if (soft) {
      auto* w = new btSoftRigidDynamicsWorld(dispatcher.get(), broadphase.get(), solver.get(), config.get());
      w->getWorldInfo().m_gravity = btVector3(0, btScalar(-9.8), 0);
      w->getWorldInfo().m_sparsesdf.Initialize();
      w->getWorldInfo().m_broadphase = broadphase.get();
      w->getWorldInfo().m_dispatcher = dispatcher.get();
      world.reset(w);
    } else {
      world = std::make_unique<btDiscreteDynamicsWorld>(dispatcher.get(), broadphase.get(), solver.get(),
                                                        config.get());
    }
    world->setGravity(btVector3(0, btScalar(-9.8), 0));
  }
  ~World() {
    for (int i = world->getNumCollisionObjects() - 1; i >= 0; --i) {
      btCollisionObject* o = world->getCollisionObjectArray()[i];
      if (btRigidBody* b = btRigidBody::upcast(o))
        world->removeRigidBody(b);
      else
        world->removeCollisionObject(o);
    }
    // Compounds made by the tests own their children here (Bullet's compounds do not delete them).
    for (auto& shape : shapes) deleteChildren(shape.get());
  }
  static void deleteChildren(btCollisionShape* shape) {
    if (shape == nullptr || shape->getShapeType() != COMPOUND_SHAPE_PROXYTYPE) return;
    auto* compound = static_cast<btCompoundShape*>(shape);
    for (int i = compound->getNumChildShapes() - 1; i >= 0; --i) {
      btCollisionShape* child = compound->getChildShape(i);
      compound->removeChildShapeByIndex(i);
      deleteChildren(child);
      delete child;
    }
  }
  btSoftRigidDynamicsWorld* soft() { return static_cast<btSoftRigidDynamicsWorld*>(world.get()); }
  btDeformableMultiBodyDynamicsWorld* deformable() {
    return static_cast<btDeformableMultiBodyDynamicsWorld*>(world.get());
  }

  /// A static body (mass 0) with the shape at the transform; group/mask < 0: Bullet's defaults.
  btRigidBody* addStatic(btCollisionShape* shape, const btTransform& t, int group = -1, int mask = -1) {
    shapes.emplace_back(shape);
    auto state = std::make_unique<btDefaultMotionState>(t);
    btRigidBody::btRigidBodyConstructionInfo info(0, state.get(), shape);
    auto body = std::make_unique<btRigidBody>(info);
    if (group >= 0)
      world->addRigidBody(body.get(), group, mask);
    else
      world->addRigidBody(body.get());
    states.push_back(std::move(state));
    bodies.push_back(std::move(body));
    return bodies.back().get();
  }
  /// A kinematic body (moved through its motion state, once per stepSimulation).
  btRigidBody* addKinematic(btCollisionShape* shape, const btTransform& t) {
    btRigidBody* b = addStatic(shape, t);
    b->setCollisionFlags(b->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    b->setActivationState(DISABLE_DEACTIVATION);
    return b;
  }
  static void moveKinematic(btRigidBody* b, const btTransform& t) {
    b->getMotionState()->setWorldTransform(t);
  }

  std::unique_ptr<btCollisionConfiguration> config;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btBroadphaseInterface> broadphase;
  std::unique_ptr<btDeformableBodySolver> deformableSolver;  ///< Deformable worlds only.
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
};

/// The canonical 20 x 20 cape (0.6 m x 1.0 m, 0.4 kg), tethered to its top corners.
inline cape::FabricPtr cornerFabric(int n = 20) {
  return cape::makeCapeRig(n, cape::PinLayout::Corners).fabric;
}

/// Lying flat and horizontal (rotated +90 degrees about X: the grid spans x in [-0.3, 0.3], z in [-0.5,
/// 0.5]), centred on (0, y, 0).
inline btTransform horizontalAt(btScalar y) {
  btTransform t(btQuaternion(btVector3(1, 0, 0), SIMD_HALF_PI), btVector3(btScalar(-0.3), y, btScalar(0.5)));
  return t;
}

/// docs/SCENES.md's walk on kinematic Bullet bodies in `world`: a torso box, shoulder spheres and leg
/// capsules moved rigidly with the character frame, the canonical cape pinned by its corners to the
/// shoulders, the whole scene moved by `offset` (and, with `ground`, a static ground plane through it);
/// advance() is one 1/60 s frame, stepSimulation(1/60, 8, 1/240).
struct SimpleWalk {
  SimpleWalk(World& w, const btVector3& offset = btVector3(0, 0, 0),
             const cape::bullet::CapeActionSettings& settings = cape::bullet::CapeActionSettings(),
             bool ground = false)
      : world(w),
        shift(btQuaternion::getIdentity(), offset),
        motion(cape::MotionDesc::forScene(cape::SceneKind::Walk)) {
    const auto part = [&](btCollisionShape* s, const btVector3& at) {
      const btTransform local(btQuaternion::getIdentity(), at);
      parts.push_back({w.addKinematic(s, shift * local), local});
      return parts.back().first;
    };
    part(new btBoxShape(btVector3(0.2f, 0.3f, 0.12f)), btVector3(0, 1.25f, 0));
    btRigidBody* left = part(new btSphereShape(0.08f), btVector3(-0.22f, 1.52f, 0));
    btRigidBody* right = part(new btSphereShape(0.08f), btVector3(0.22f, 1.52f, 0));
    part(new btCapsuleShape(0.07f, 0.66f), btVector3(-0.1f, 0.55f, 0));
    part(new btCapsuleShape(0.07f, 0.66f), btVector3(0.1f, 0.55f, 0));
    if (ground)
      w.addStatic(new btStaticPlaneShape(btVector3(0, 1, 0), offset.y()), btTransform::getIdentity());
    const cape::CapeRig rig = cape::makeCapeRig(20, cape::PinLayout::Corners);
    action = std::make_unique<cape::bullet::CapeAction>(
        rig.fabric, cape::CapeSettings(),
        shift * cape::bullet::toBt(cape::capeStartPlacement(cape::SceneKind::Walk)), settings);
    const btRigidBody* shoulders[2] = {left, right};
    for (int k = 0; k < 2; ++k) {
      const btVector3 at = shift * cape::bullet::toBt(rig.pinLocalPoints[std::size_t(k)]);
      action->attach(rig.pinnedParticles[std::size_t(k)], shoulders[k],
                     shoulders[k]->getWorldTransform().invXform(at));
    }
    w.world->addAction(action.get());
  }
  ~SimpleWalk() { world.world->removeAction(action.get()); }
  SimpleWalk(const SimpleWalk&) = delete;
  SimpleWalk& operator=(const SimpleWalk&) = delete;

  void advance() {
    ++frame;
    const btTransform f = shift * cape::bullet::toBt(cape::motionAt(motion, frame / 60.0).frame());
    for (auto& p : parts) World::moveKinematic(p.first, f * p.second);
    world.world->stepSimulation(kFrame, 8, kFixed);
  }

  World& world;
  btTransform shift;
  cape::MotionDesc motion;
  std::vector<std::pair<btRigidBody*, btTransform>> parts;  ///< body, pose in the character frame
  std::unique_ptr<cape::bullet::CapeAction> action;
  int frame = 0;
};

inline bool allFinite(const cape::Points& x) {
  return x.allFinite();
}

/// Largest structural strain (|xi - xj| - L0) / L0 of the cape, by the metrics' own structuralStrain: signed,
/// as docs/SCENES.md defines it (a compressed spring's strain is negative).
inline float maxStructuralStrain(const cape::Cape& c) {
  return cape::structuralStrain(c.fabric(), c.state().positions).max;
}

}  // namespace capetest
