// Every collider the adapter finds is resolved by the core inside every substep, swept over it: convex
// shapes as core hulls, triangle meshes and heightfields as core triangle-mesh colliders, with the
// collider's own thickness (Bullet's margin) and friction (combined with the cape's, as Bullet combines).
#include "BulletFixture.h"

#include "cape/bullet/Convert.h"

#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <gtest/gtest.h>

namespace capetest {
namespace {

using cape::bullet::CapeAction;

/// The worst depth of any particle in the shape (Bullet's own surface, margin included), m.
double worstDepth(const CapeAction& action, const btCollisionObject* body) {
  double worst = 0.0;
  for (std::size_t i = 0; i < action.particleCount(); ++i) {
    const btScalar d = cape::bullet::shapeSignedDistance(body->getCollisionShape(), body->getWorldTransform(),
                                                         action.position(std::uint32_t(i)));
    worst = std::max(worst, double(-d));
  }
  return worst;
}

btConvexHullShape* boxAsHull(const btVector3& h) {
  auto* s = new btConvexHullShape();
  for (int i = 0; i < 8; ++i)
    s->addPoint(btVector3(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z()), i == 7);
  return s;
}

btConvexHullShape* wedgeHull() {
  // A tetrahedron-like wedge: faces at angles to every axis.
  auto* s = new btConvexHullShape();
  s->addPoint(btVector3(-0.15f, -0.15f, -0.02f), false);
  s->addPoint(btVector3(0.15f, -0.15f, -0.02f), false);
  s->addPoint(btVector3(0.0f, 0.2f, -0.02f), false);
  s->addPoint(btVector3(0.0f, 0.0f, 0.12f), true);
  return s;
}

class FastConvexHull : public ::testing::TestWithParam<int> {};

TEST_P(FastConvexHull, At20MetresPerSecondThroughAHangingCapeLeavesNoParticleInside) {
  // A kinematic hull flying at 20 m/s along -Z through a cape hanging from a bar: 33 cm per frame, 8 cm per
  // internal step, several times the box's 4 cm thickness. Bullet moves kinematic bodies once per frame; the
  // action spreads the motion over the internal steps and the core sweeps every substep.
  World w;
  btRigidBody* bar = w.addKinematic(new btBoxShape(btVector3(0.4f, 0.02f, 0.02f)),
                                    btTransform(btQuaternion::getIdentity(), btVector3(0, 1.6f, 0.15f)));
  btCollisionShape* shape = GetParam() == 0
                                ? static_cast<btCollisionShape*>(boxAsHull(btVector3(0.25f, 0.25f, 0.02f)))
                                : static_cast<btCollisionShape*>(wedgeHull());
  btTransform pose(btQuaternion::getIdentity(), btVector3(0, 1.15f, 1.0f));
  btRigidBody* hull = w.addKinematic(shape, pose);
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.6f, 0.15f)));
  action.attachRow(0, bar);
  w.world->addAction(&action);
  double worst = 0.0;
  btScalar minZ = 1;
  for (int frame = 0; frame < 12; ++frame) {
    pose.getOrigin() += btVector3(0, 0, btScalar(-20.0 / 60.0));
    World::moveKinematic(hull, pose);
    hull->setLinearVelocity(btVector3(0, 0, -20));
    w.world->stepSimulation(kFrame, 8, kFixed);
    worst = std::max(worst, worstDepth(action, hull));
    minZ = std::min(minZ, btScalar(action.positions().col(2).minCoeff()));
  }
  ASSERT_TRUE(allFinite(action.positions()));
  EXPECT_LT(worst, 1e-3) << (GetParam() == 0 ? "box as hull" : "wedge");
  EXPECT_LT(minZ, 0.0) << "the hull carried the cape along";
  w.world->removeAction(&action);
}

INSTANTIATE_TEST_SUITE_P(CoreCollision, FastConvexHull, ::testing::Values(0, 1));

/// A cape lying flat 0.3 m over the ground, thrown down at 10 m/s onto `ground` (a static body whose top is
/// at y = 0) with the ground's friction; returns the lowest particle over the run and the cape's drift along
/// +X over the last half second.
struct Landing {
  float lowest;
  float lateDrift;
};

Landing dropOn(btCollisionShape* ground, const btTransform& groundPose, btScalar friction) {
  World w;
  btRigidBody* body = w.addStatic(ground, groundPose);
  body->setFriction(friction);
  cape::CapeSettings settings;
  settings.gravity = cape::bullet::toVec3(w.world->getGravity());
  CapeAction action(cornerFabric(), settings, horizontalAt(btScalar(0.3)));
  action.cape().mutableState().velocities.col(1).setConstant(-10.0f);
  w.world->addAction(&action);
  Landing r{1e9f, 0.0f};
  float xHalf = 0.0f;
  for (int frame = 0; frame < 60; ++frame) {
    if (frame == 30) xHalf = action.positions().col(0).mean();
    w.world->stepSimulation(kFrame, 8, kFixed);
    EXPECT_TRUE(allFinite(action.positions()));
    r.lowest = std::min(r.lowest, float(action.positions().col(1).minCoeff()));
  }
  r.lateDrift = action.positions().col(0).mean() - xHalf;
  EXPECT_EQ(action.meshShapeCount(), 1u);
  w.world->removeAction(&action);
  return r;
}

btCollisionShape* meshFloor() {
  auto* mesh = new btTriangleMesh();  // the caller deletes it (getMeshInterface) after the world
  mesh->addTriangle(btVector3(-3, 0, -3), btVector3(-3, 0, 3), btVector3(3, 0, 3));
  mesh->addTriangle(btVector3(-3, 0, -3), btVector3(3, 0, 3), btVector3(3, 0, -3));
  return new btBvhTriangleMeshShape(mesh, true);
}

TEST(CoreCollision, AMeshFloorHoldsACapeDroppedAt10MetresPerSecond) {
  btCollisionShape* floor = meshFloor();
  btStridingMeshInterface* mesh = static_cast<btBvhTriangleMeshShape*>(floor)->getMeshInterface();
  const btScalar margin = floor->getMargin();
  const Landing r = dropOn(floor, btTransform::getIdentity(), btScalar(0.5));
  EXPECT_GT(r.lowest, float(margin) - 1e-3f) << "into or through the mesh floor";
  delete mesh;
}

TEST(CoreCollision, AHeightfieldHoldsACapeDroppedAt10MetresPerSecond) {
  static float heights[9 * 9];
  for (int i = 0; i < 81; ++i) heights[i] = 0.0f;
  auto* terrain =
      new btHeightfieldTerrainShape(9, 9, static_cast<const float*>(heights), -1.0f, 1.0f, 1, false);
  terrain->setLocalScaling(btVector3(0.5f, 1.0f, 0.5f));
  const btScalar margin = terrain->getMargin();  // the world dropOn makes owns the shape, and deletes it
  const Landing r = dropOn(terrain, btTransform::getIdentity(), btScalar(0.5));
  EXPECT_GT(r.lowest, float(margin) - 1e-3f) << "into or through the heightfield";
}

TEST(CoreCollision, TheMeshsOwnFrictionHoldsTheCapeOnASlopeOrLetsItSlide) {
  // Gravity tilted by 20 degrees (tan 20 = 0.36). The cape's own friction is 1; combined with the floor's
  // (the product), a floor of friction 1 holds the landed cape still, and a floor of friction 0 lets it
  // slide.
  for (btScalar friction : {btScalar(1), btScalar(0)}) {
    btCollisionShape* floor = meshFloor();
    btStridingMeshInterface* mesh = static_cast<btBvhTriangleMeshShape*>(floor)->getMeshInterface();
    const btScalar margin = floor->getMargin();
    {
      World w;
      const btScalar tilt = btScalar(0.349);
      w.world->setGravity(btVector3(btScalar(9.8) * std::sin(tilt), btScalar(-9.8) * std::cos(tilt), 0));
      btRigidBody* body = w.addStatic(floor, btTransform::getIdentity());
      body->setFriction(friction);
      cape::CapeSettings settings;
      settings.gravity = cape::bullet::toVec3(w.world->getGravity());
      settings.friction = 1.0f;
      CapeAction action(cornerFabric(), settings, horizontalAt(btScalar(0.2)));
      action.cape().mutableState().velocities.col(1).setConstant(-10.0f);
      w.world->addAction(&action);
      float xHalf = 0.0f;
      for (int frame = 0; frame < 60; ++frame) {
        if (frame == 30) xHalf = action.positions().col(0).mean();
        w.world->stepSimulation(kFrame, 8, kFixed);
      }
      const float drift = action.positions().col(0).mean() - xHalf;
      EXPECT_GT(action.positions().col(1).minCoeff(), float(margin) - 1e-3f);
      if (friction > 0)
        EXPECT_LT(std::abs(drift), 0.002f) << "static friction should hold it";
      else
        EXPECT_GT(drift, 0.4f) << "frictionless: g sin 20 = 3.35 m/s^2 slides it over 0.4 m in half a second";
      w.world->removeAction(&action);
    }  // the world deletes the floor shape; then its mesh
    delete mesh;
  }
}

}  // namespace
}  // namespace capetest
