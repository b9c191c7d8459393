// CapeAction in real Bullet worlds: pins follow kinematic bodies at every internal step, colliders come from
// Bullet shapes (found by discovery, filtered by group and mask), both reference steppings work.
#include "BulletFixture.h"

#include "cape/bullet/Convert.h"

#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btTriangleMesh.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

using namespace capetest;
using cape::bullet::CapeAction;

namespace {

/// The attachment body's pose at time t: constant linear velocity and constant rotation rate about an
/// oblique axis (so lerp/slerp between two frame poses is the exact pose in between).
btTransform movingPose(double t) {
  const btVector3 axis = btVector3(btScalar(0.3), 1, btScalar(0.2)).normalized();
  return btTransform(btQuaternion(axis, btScalar(1.5 * t)),
                     btVector3(btScalar(0.8 * t), btScalar(1.5 + 0.2 * t), btScalar(-0.5 * t)));
}

struct PinProbe {
  CapeAction* action = nullptr;
  std::vector<std::vector<btVector3>> recorded;  ///< Pinned particle positions after each internal step.
  static void tick(btDynamicsWorld* world, btScalar) {
    auto* self = static_cast<PinProbe*>(world->getWorldUserInfo());
    std::vector<btVector3> row;
    for (const cape::bullet::Attachment& a : self->action->attachments())
      row.push_back(self->action->position(a.particle));
    self->recorded.push_back(row);
  }
};

}  // namespace

class PinStepping : public ::testing::TestWithParam<double> {};

TEST_P(PinStepping, PinsFollowATranslatingRotatingKinematicBodyAtEveryInternalStep) {
  const btScalar fixed = btScalar(GetParam());
  World w;
  btRigidBody* body =
      w.addKinematic(new btBoxShape(btVector3(btScalar(0.2), btScalar(0.3), btScalar(0.1))), movingPose(0));
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)));
  ASSERT_TRUE(action.ok());
  const btVector3 left(btScalar(-0.3), 0, btScalar(0.15)), right(btScalar(0.3), 0, btScalar(0.15));
  ASSERT_TRUE(action.attach(0, body, left));
  ASSERT_TRUE(action.attach(19, body, right));
  w.world->addAction(&action);
  PinProbe probe;
  probe.action = &action;
  w.world->setInternalTickCallback(&PinProbe::tick, &probe);

  double tPrev = 0.0;  // time of the last frame whose pose the world has taken
  double worst = 0.0;
  int steps = 0;
  for (int frame = 1; frame <= 120; ++frame) {
    const double t = frame / 60.0;
    World::moveKinematic(body, movingPose(t));
    probe.recorded.clear();
    const int n = w.world->stepSimulation(kFrame, 8, fixed);
    ASSERT_EQ(static_cast<int>(probe.recorded.size()), std::min(n, 8));
    if (n == 0) continue;
    // Bullet gives the kinematic body its new pose at the first internal step; the action spreads the
    // motion over the n internal steps of this call, so after step j the pin sits at the pose (j+1)/n of
    // the way from the last pose to the new one.
    for (int j = 0; j < n; ++j) {
      const btTransform expected = movingPose(tPrev + (t - tPrev) * (j + 1) / n);
      worst = std::max(worst, double((probe.recorded[j][0] - expected * left).length()));
      worst = std::max(worst, double((probe.recorded[j][1] - expected * right).length()));
      ++steps;
    }
    EXPECT_LT(action.maxPinError(), 1e-5f);
    tPrev = t;
  }
  EXPECT_GT(steps, 100);
  EXPECT_LT(worst, 1e-5) << "worst pin error over " << steps << " internal steps";
  EXPECT_TRUE(allFinite(action.positions()));
  EXPECT_LT(maxStructuralStrain(action.cape()), 0.2f);
  w.world->removeAction(&action);
}

INSTANTIATE_TEST_SUITE_P(Steppings, PinStepping, ::testing::Values(1.0 / 240.0, 0.00875));

// --- Dropped on shapes found by discovery ---------------------------------------------------------------

struct DropCase {
  std::string name;
  std::function<btCollisionShape*()> make;
  double fixed;
};

class DropOnShape : public ::testing::TestWithParam<DropCase> {};

TEST_P(DropOnShape, ComesToRestOnItWithNoParticleDeeperThanOneMillimetre) {
  const DropCase& c = GetParam();
  World w;
  btCollisionShape* shape = c.make();
  btRigidBody* body = w.addStatic(shape, btTransform::getIdentity());
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)));
  w.world->addAction(&action);
  double worstDepth = 0.0;
  for (int frame = 0; frame < 80; ++frame) {
    w.world->stepSimulation(kFrame, 8, btScalar(c.fixed));
    for (std::size_t i = 0; i < action.particleCount(); ++i) {
      const btScalar d = cape::bullet::shapeSignedDistance(shape, body->getWorldTransform(),
                                                           action.position(std::uint32_t(i)));
      worstDepth = std::max(worstDepth, double(-d));
    }
  }
  ASSERT_TRUE(allFinite(action.positions()));
  EXPECT_LT(worstDepth, 1e-3) << c.name;
  ASSERT_EQ(action.activeObjects().size(), 1u) << c.name;
  // It rests on the shape: the middle of the cape is on the top of the shape, within a few centimetres.
  const std::uint32_t middle = 10 * 20 + 10;
  const btScalar d =
      cape::bullet::shapeSignedDistance(shape, body->getWorldTransform(), action.position(middle));
  EXPECT_LT(d, 0.03) << c.name;
  EXPECT_GT(action.position(middle).y(), 0.0) << c.name;
  w.world->removeAction(&action);
}

namespace {
btCollisionShape* makeCompound() {
  // Nested: a compound holding a box and a compound (a sphere offset and rotated).
  auto* inner = new btCompoundShape();
  inner->addChildShape(btTransform(btQuaternion(btVector3(0, 0, 1), 0.3f), btVector3(0.2f, 0.0f, 0.0f)),
                       new btSphereShape(0.2f));
  auto* outer = new btCompoundShape();
  outer->addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(-0.15f, 0.1f, 0.0f)),
                       new btBoxShape(btVector3(0.15f, 0.2f, 0.2f)));
  outer->addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(0.1f, 0.1f, 0.0f)), inner);
  return outer;
}
btCollisionShape* makeScaledCylinder() {
  auto* s = new btCylinderShape(btVector3(0.2f, 0.2f, 0.2f));
  s->setLocalScaling(btVector3(1.5f, 1.0f, 1.5f));  // radius 0.3, half height 0.2
  return s;
}
btCollisionShape* makeHull() {
  // A hexagonal prism (flat top, 0.3 m across the corners, 0.4 m tall): not a primitive the core knows, so
  // Bullet's GJK handles it.
  auto* h = new btConvexHullShape();
  for (int k = 0; k < 6; ++k) {
    const float a = float(k) * SIMD_PI / 3.0f;
    h->addPoint(btVector3(0.3f * std::cos(a), 0.2f, 0.3f * std::sin(a)), false);
    h->addPoint(btVector3(0.3f * std::cos(a), -0.2f, 0.3f * std::sin(a)), k == 5);
  }
  return h;
}
}  // namespace

INSTANTIATE_TEST_SUITE_P(
    Shapes, DropOnShape,
    ::testing::Values(
        DropCase{"sphere", [] { return static_cast<btCollisionShape*>(new btSphereShape(0.3f)); },
                 1.0 / 240.0},
        DropCase{"box",
                 [] { return static_cast<btCollisionShape*>(new btBoxShape(btVector3(0.3f, 0.2f, 0.3f))); },
                 1.0 / 240.0},
        DropCase{"capsuleX", [] { return static_cast<btCollisionShape*>(new btCapsuleShapeX(0.15f, 0.6f)); },
                 1.0 / 240.0},
        DropCase{"cylinderZ",
                 [] {
                   return static_cast<btCollisionShape*>(new btCylinderShapeZ(btVector3(0.25f, 0.25f, 0.3f)));
                 },
                 1.0 / 240.0},
        DropCase{"compound", makeCompound, 1.0 / 240.0},
        DropCase{"scaledCylinder", makeScaledCylinder, 1.0 / 240.0},
        DropCase{"multiSphere",
                 [] {
                   const btVector3 centres[2] = {btVector3(-0.15f, 0, 0), btVector3(0.15f, 0, 0)};
                   const btScalar radii[2] = {0.2f, 0.25f};
                   return static_cast<btCollisionShape*>(new btMultiSphereShape(centres, radii, 2));
                 },
                 1.0 / 240.0},
        DropCase{"convexHull", makeHull, 1.0 / 240.0},
        DropCase{"sphereSeedStep", [] { return static_cast<btCollisionShape*>(new btSphereShape(0.3f)); },
                 0.00875}),
    [](const ::testing::TestParamInfo<DropCase>& info) { return info.param.name; });

TEST(CapeAction, DynamicBallThrownThroughTheCapeNeverHasAParticleInside) {
  // A dynamic body moves every internal step (its pose spread over one step): the core sweeps it, so the
  // cape is pushed aside, never entered, though the ball (Bullet's, one-way) flies on.
  World w;
  btRigidBody* bar = w.addKinematic(new btBoxShape(btVector3(0.4f, 0.02f, 0.02f)),
                                    btTransform(btQuaternion::getIdentity(), btVector3(0, 1.6f, 0.15f)));
  btSphereShape* ballShape = new btSphereShape(0.12f);
  w.shapes.emplace_back(ballShape);
  btVector3 inertia;
  ballShape->calculateLocalInertia(1, inertia);
  auto state = std::make_unique<btDefaultMotionState>(
      btTransform(btQuaternion::getIdentity(), btVector3(0, 1.1f, 1.0f)));
  auto ball = std::make_unique<btRigidBody>(
      btRigidBody::btRigidBodyConstructionInfo(1, state.get(), ballShape, inertia));
  ball->setLinearVelocity(btVector3(0, 0, -6));
  w.world->setGravity(btVector3(0, 0, 0));  // the ball flies straight; the cape has its own gravity
  w.world->addRigidBody(ball.get());
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.6f, 0.15f)));
  action.attachRow(0, bar);
  w.world->addAction(&action);
  double worstDepth = 0.0;
  btScalar minZ = 1;
  for (int frame = 0; frame < 30; ++frame) {
    w.world->stepSimulation(kFrame, 8, kFixed);
    for (std::size_t i = 0; i < action.particleCount(); ++i) {
      const btScalar d =
          (action.position(std::uint32_t(i)) - ball->getWorldTransform().getOrigin()).length() -
          ballShape->getRadius();
      worstDepth = std::max(worstDepth, double(-d));
    }
    minZ = std::min(minZ, btScalar(action.positions().col(2).minCoeff()));
  }
  EXPECT_LT(worstDepth, 1e-3);
  EXPECT_LT(minZ, 0.0f) << "the ball pushed the cape";
  EXPECT_TRUE(allFinite(action.positions()));
  w.world->removeAction(&action);
  w.world->removeRigidBody(ball.get());
}

TEST(CapeAction, EveryConvexShapeBecomesACoreCollider) {
  // A btConvexHullShape becomes a core convex hull (its margin the thickness), a sphere stays a sphere: no
  // shape is left to a pass after the core's step.
  World w;
  w.addStatic(makeHull(), btTransform::getIdentity());
  w.addStatic(new btSphereShape(0.2f), btTransform(btQuaternion::getIdentity(), btVector3(2, 0, 0)));
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)));
  cape::bullet::CapeActionSettings s;
  s.discoveryMargin = 3.0f;
  action.setActionSettings(s);
  w.world->addAction(&action);
  w.world->stepSimulation(kFrame, 8, kFixed);
  ASSERT_EQ(action.coreColliders().size(), 2u);
  EXPECT_EQ(action.coreColliders()[0].shape, cape::ColliderShape::ConvexHull);
  EXPECT_EQ(action.coreColliders()[0].hull->vertices.size(), 12u);
  EXPECT_EQ(action.coreColliders()[0].hull->planes.size(), 8u);  // a hexagonal prism
  EXPECT_FLOAT_EQ(action.coreColliders()[0].thickness,
                  float(action.activeObjects()[0]->getCollisionShape()->getMargin()));
  EXPECT_EQ(action.coreColliders()[1].shape, cape::ColliderShape::Sphere);
  EXPECT_EQ(action.meshShapeCount(), 0u);
  w.world->removeAction(&action);
}

TEST(CapeAction, StaticPlaneAndTriangleMeshHoldTheCape) {
  World w;
  // A 4 m x 4 m two-triangle ground at y = 0 (a btBvhTriangleMeshShape) and a plane at y = -0.5 below it.
  auto* mesh = new btTriangleMesh();
  mesh->addTriangle(btVector3(-2, 0, -2), btVector3(-2, 0, 2), btVector3(2, 0, 2));
  mesh->addTriangle(btVector3(-2, 0, -2), btVector3(2, 0, 2), btVector3(2, 0, -2));
  auto* shape = new btBvhTriangleMeshShape(mesh, true);
  shape->setMargin(0.0f);
  w.addStatic(shape, btTransform::getIdentity());
  w.addStatic(new btStaticPlaneShape(btVector3(0, 1, 0), -0.5f), btTransform::getIdentity());
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.3)));
  w.world->addAction(&action);
  for (int frame = 0; frame < 90; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_EQ(action.meshShapeCount(), 1u);
  const float lowest = action.positions().col(1).minCoeff();
  EXPECT_GT(lowest, -1e-3f) << "fell through the triangle mesh";
  EXPECT_LT(action.positions().col(1).maxCoeff(), 0.05f) << "should lie on it";
  w.world->removeAction(&action);
  delete mesh;
}

TEST(CapeAction, HeightfieldHoldsTheCape) {
  World w;
  static float heights[9 * 9];
  for (float& h : heights) h = 0.0f;
  auto* terrain =
      new btHeightfieldTerrainShape(9, 9, static_cast<const float*>(heights), -1.0f, 1.0f, 1, false);
  terrain->setLocalScaling(btVector3(0.5f, 1.0f, 0.5f));
  w.addStatic(terrain, btTransform::getIdentity());
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.3)));
  w.world->addAction(&action);
  for (int frame = 0; frame < 90; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_EQ(action.meshShapeCount(), 1u);
  EXPECT_GT(action.positions().col(1).minCoeff(), -1e-3f - terrain->getMargin());
  w.world->removeAction(&action);
}

TEST(CapeAction, BodyExcludedByGroupAndMaskIsIgnored) {
  World w;
  const int kNotCape = 64;  // a user group the cape's mask leaves out
  w.addStatic(new btSphereShape(0.3f), btTransform::getIdentity(), kNotCape, btBroadphaseProxy::AllFilter);
  cape::bullet::CapeActionSettings s;
  s.collisionMask = btBroadphaseProxy::AllFilter & ~kNotCape;
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)), s);
  w.world->addAction(&action);
  for (int frame = 0; frame < 40; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_TRUE(action.activeObjects().empty());
  EXPECT_LT(action.positions().col(1).maxCoeff(), -0.3f) << "the cape fell through the excluded sphere";
  w.world->removeAction(&action);
}

TEST(CapeAction, ExplicitColliderWithoutDiscovery) {
  World w;
  btRigidBody* a = w.addStatic(new btSphereShape(0.3f), btTransform::getIdentity());
  w.addStatic(new btBoxShape(btVector3(1, 0.05f, 1)),
              btTransform(btQuaternion::getIdentity(), btVector3(0, -0.6f, 0)));
  cape::bullet::CapeActionSettings s;
  s.discoverColliders = false;
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)), s);
  action.addCollider(a);
  w.world->addAction(&action);
  for (int frame = 0; frame < 60; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  ASSERT_EQ(action.activeObjects().size(), 1u);
  EXPECT_EQ(action.activeObjects()[0], a);
  EXPECT_GT(action.position(10 * 20 + 10).y(), 0.25f);
  w.world->removeAction(&action);
}

// --- Gravity from the world ------------------------------------------------------------------------------

TEST(CapeAction, TakesGravityFromTheWorldEveryStepUnlessTold) {
  // A free cape in a Z-up world falls along -Z; when the world's gravity turns to +X mid-run, it follows.
  World w;
  w.world->setGravity(btVector3(0, 0, btScalar(-9.8)));
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)));
  w.world->addAction(&action);
  const btVector3 start = action.position(0);
  for (int frame = 0; frame < 30; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  const btVector3 fell = action.position(0) - start;
  EXPECT_LT(fell.z(), btScalar(-0.8));                 // 0.5 g t^2 = 1.2 m in 0.5 s, less the air's drag
  EXPECT_NEAR(fell.y(), btScalar(0), btScalar(1e-4));  // nothing along the settings' -Y
  EXPECT_EQ(action.cape().settings().gravity, cape::Vec3(0, 0, -9.8f));
  w.world->setGravity(btVector3(btScalar(9.8), 0, 0));
  for (int frame = 0; frame < 30; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_GT(action.position(0).x() - start.x(), btScalar(0.5));
  w.world->removeAction(&action);

  // Off: the settings' gravity (-Y) holds whatever the world says.
  cape::bullet::CapeActionSettings own;
  own.useWorldGravity = false;
  CapeAction fixed(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)), own);
  w.world->addAction(&fixed);
  const btVector3 before = fixed.position(0);
  for (int frame = 0; frame < 30; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_NEAR(fixed.position(0).y() - before.y(), fell.z(), btScalar(1e-4));  // the same fall, along -Y
  EXPECT_NEAR(fixed.position(0).x() - before.x(), btScalar(0), btScalar(1e-4));
  w.world->removeAction(&fixed);
}

// --- Unsupported shapes, removed bodies -----------------------------------------------------------------

namespace {
/// A concave shape Bullet does not know: the adapter cannot turn it into anything.
class OddShape : public btConcaveShape {
 public:
  OddShape() { m_shapeType = CUSTOM_CONCAVE_SHAPE_TYPE; }
  void getAabb(const btTransform& t, btVector3& lo, btVector3& hi) const override {
    lo = t.getOrigin() - btVector3(1, 1, 1);
    hi = t.getOrigin() + btVector3(1, 1, 1);
  }
  void processAllTriangles(btTriangleCallback*, const btVector3&, const btVector3&) const override {}
  void setLocalScaling(const btVector3& s) override { scaling_ = s; }
  const btVector3& getLocalScaling() const override { return scaling_; }
  void calculateLocalInertia(btScalar, btVector3& inertia) const override { inertia.setZero(); }
  const char* getName() const override { return "OddShape"; }

 private:
  btVector3 scaling_{1, 1, 1};
};
}  // namespace

TEST(CapeAction, UnsupportedShapeWarnsOnceNamingIt) {
  World w;
  w.addStatic(new OddShape(), btTransform::getIdentity());
  w.addStatic(new OddShape(), btTransform(btQuaternion::getIdentity(), btVector3(0.2f, 0, 0)));
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)));
  std::vector<std::string> warnings;
  action.setWarningHandler([&](const std::string& m) { warnings.push_back(m); });
  w.world->addAction(&action);
  for (int frame = 0; frame < 30; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("OddShape"), std::string::npos);
  EXPECT_TRUE(allFinite(action.positions()));
  w.world->removeAction(&action);
}

TEST(CapeAction, BodyRemovedAndDeletedWhileAttachedIsDroppedAndItsParticlesReleased) {
  World w;
  auto shape = std::make_unique<btSphereShape>(0.1f);
  btDefaultMotionState state(btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
  auto body = std::make_unique<btRigidBody>(btRigidBody::btRigidBodyConstructionInfo(0, &state, shape.get()));
  body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
  w.world->addRigidBody(body.get());
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)));
  std::vector<std::string> warnings;
  action.setWarningHandler([&](const std::string& m) { warnings.push_back(m); });
  ASSERT_EQ(action.attachRow(0, body.get()), 20u);
  w.world->addAction(&action);
  for (int frame = 0; frame < 10; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_EQ(action.cape().state().pins.size(), 20u);
  // The documented rule: removing a body from the world is enough; the action drops it at its next update
  // without touching it (so it may already be deleted: ASan checks that).
  w.world->removeRigidBody(body.get());
  body.reset();
  for (int frame = 0; frame < 10; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_TRUE(action.attachments().empty());
  EXPECT_TRUE(action.cape().state().pins.empty());
  EXPECT_GT(action.cape().state().inverseMasses.minCoeff(), 0.0f);
  EXPECT_EQ(warnings.size(), 1u);
  EXPECT_LT(action.positions().col(1).maxCoeff(), 1.4f) << "released particles fall";
  w.world->removeAction(&action);
}

TEST(CapeAction, DetachBeforeDeletingWarnsAboutNothing) {
  World w;
  btRigidBody* body = w.addKinematic(new btSphereShape(0.1f),
                                     btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)));
  int warnings = 0;
  action.setWarningHandler([&](const std::string&) { ++warnings; });
  const std::uint32_t p = action.attachNearest(body, btVector3(0.3f, 1.5f, 0.15f));
  EXPECT_EQ(p, 19u);
  w.world->addAction(&action);
  w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_LT((action.position(p) - btVector3(0.3f, 1.5f, 0.15f)).length(), 1e-5f);
  action.detach(body);
  w.world->removeRigidBody(body);
  w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_EQ(warnings, 0);
  EXPECT_TRUE(action.attachments().empty());
  w.world->removeAction(&action);
}

// --- Fast motion ----------------------------------------------------------------------------------------

TEST(CapeAction, TeleportFiftyMetresCarriesTheCapeWithoutStretching) {
  World w;
  const btTransform start(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0));
  btRigidBody* body = w.addKinematic(new btBoxShape(btVector3(0.2f, 0.3f, 0.1f)), start);
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.56f, 0.15f)));
  action.attach(0, body, btVector3(-0.3f, 0.06f, 0.15f));
  action.attach(19, body, btVector3(0.3f, 0.06f, 0.15f));
  w.world->addAction(&action);
  for (int frame = 0; frame < 60; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  const float strainBefore = maxStructuralStrain(action.cape());
  // Jump 50 m along X and turn 90 degrees in one frame.
  const btTransform jumped(btQuaternion(btVector3(0, 1, 0), SIMD_HALF_PI), btVector3(50, 1.5f, 0));
  World::moveKinematic(body, jumped);
  w.world->stepSimulation(kFrame, 8, kFixed);
  float worstStrain = maxStructuralStrain(action.cape());
  for (int frame = 0; frame < 30; ++frame) {
    w.world->stepSimulation(kFrame, 8, kFixed);
    worstStrain = std::max(worstStrain, maxStructuralStrain(action.cape()));
  }
  ASSERT_TRUE(allFinite(action.positions()));
  EXPECT_LT(worstStrain, std::max(0.05f, 2.0f * strainBefore));
  for (std::size_t i = 0; i < action.particleCount(); ++i)
    EXPECT_LT((action.position(std::uint32_t(i)) - jumped.getOrigin()).length(), 2.0f);
  EXPECT_LT((action.position(0) - jumped * btVector3(-0.3f, 0.06f, 0.15f)).length(), 1e-4f);
}

TEST(CapeAction, ZeroInertiaCarriesTheCapeAlongWithItsBody) {
  // With no linear inertia the free particles ride with the body: a cape pinned to a body that starts
  // moving fast keeps its shape relative to the body, where a full-inertia cape trails behind.
  // Where the middle of the bottom row ends up relative to the body, after the body accelerates (or not).
  auto relative = [](btScalar inertia, bool moving) {
    World w;
    btRigidBody* body = w.addKinematic(new btSphereShape(0.05f),
                                       btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
    cape::bullet::CapeActionSettings s;
    s.linearInertia = inertia;
    s.discoverColliders = false;
    CapeAction action(cornerFabric(), cape::CapeSettings(),
                      btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)), s);
    action.attachRow(0, body);
    w.world->addAction(&action);
    for (int frame = 0; frame < 60; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
    for (int frame = 1; frame <= 12; ++frame) {
      const float x = moving ? -2.0f * float(frame * frame) / 144.0f : 0.0f;  // 0 -> 20 m/s in 0.2 s
      World::moveKinematic(body, btTransform(btQuaternion::getIdentity(), btVector3(x, 1.5f, 0)));
      w.world->stepSimulation(kFrame, 8, kFixed);
    }
    const btVector3 r = action.position(19 * 20 + 10) - body->getWorldTransform().getOrigin();
    w.world->removeAction(&action);
    return r;
  };
  const btVector3 still = relative(1, false);
  const btScalar glued = (relative(0, true) - still).length(), free = (relative(1, true) - still).length();
  EXPECT_LT(glued, 1e-3f);
  EXPECT_GT(free, 0.05f);
}

TEST(CapeAction, ZeroAngularInertiaTurnsTheCapeWithItsBody) {
  // The body spins a quarter turn about the vertical in 0.2 s: with no angular (and linear) inertia the
  // cape turns with it as if rigid; with full inertia it swings out.
  auto relative = [](btScalar inertia, bool turning) {
    World w;
    btRigidBody* body = w.addKinematic(new btSphereShape(0.05f),
                                       btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
    cape::bullet::CapeActionSettings s;
    s.linearInertia = s.angularInertia = inertia;
    s.discoverColliders = false;
    CapeAction action(cornerFabric(), cape::CapeSettings(),
                      btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)), s);
    action.attachRow(0, body);
    w.world->addAction(&action);
    for (int frame = 0; frame < 60; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
    for (int frame = 1; frame <= 12; ++frame) {
      const btScalar angle = turning ? SIMD_HALF_PI * btScalar(frame) / 12 : 0;
      World::moveKinematic(body, btTransform(btQuaternion(btVector3(0, 1, 0), angle), btVector3(0, 1.5f, 0)));
      w.world->stepSimulation(kFrame, 8, kFixed);
    }
    // In the body's frame.
    const btVector3 r = body->getWorldTransform().invXform(action.position(19 * 20 + 10));
    w.world->removeAction(&action);
    return r;
  };
  const btVector3 still = relative(1, false);
  EXPECT_LT((relative(0, true) - still).length(), 1e-3f);
  EXPECT_GT((relative(1, true) - still).length(), 0.05f);
}

// The speed limits: a body moving at `speed` m/s (or turning at `turn` rad/s) for 0.5 s with the cape's
// limits set feels as a body moving at the limits does. Returns, after each frame, the middle of the bottom
// row in the body's frame.
std::vector<btVector3> limitedPath(btScalar speed, btScalar turn, btScalar maxSpeed, btScalar maxTurn) {
  World w;
  btRigidBody* body = w.addKinematic(new btSphereShape(0.05f),
                                     btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
  cape::bullet::CapeActionSettings s;
  s.discoverColliders = false;
  s.maxLinearSpeed = maxSpeed;
  s.maxAngularSpeed = maxTurn;
  s.teleportDistance = 1e6f;  // 40 m/s is 0.17 m per step: no teleport, whatever the default
  s.teleportAngle = 3.0f;
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)), s);
  action.attachRow(0, body);
  w.world->addAction(&action);
  for (int frame = 0; frame < 60; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  std::vector<btVector3> path;
  for (int frame = 1; frame <= 30; ++frame) {
    const btScalar t = btScalar(frame) * kFrame;
    World::moveKinematic(
        body, btTransform(btQuaternion(btVector3(0, 1, 0), turn * t), btVector3(-speed * t, 1.5f, 0)));
    w.world->stepSimulation(kFrame, 8, kFixed);
    path.push_back(body->getWorldTransform().invXform(action.position(19 * 20 + 10)));
  }
  w.world->removeAction(&action);
  return path;
}

btScalar largestGap(const std::vector<btVector3>& a, const std::vector<btVector3>& b) {
  btScalar gap = 0;
  for (std::size_t k = 0; k < a.size() && k < b.size(); ++k) gap = std::max(gap, (a[k] - b[k]).length());
  return gap;
}

TEST(CapeAction, BeyondTheLinearSpeedLimitTheCapeMovesWithItsBody) {
  // 40 m/s with a 2 m/s limit is, for the cape relative to its body, 2 m/s without a limit; without the
  // limit the cape trails far behind.
  const std::vector<btVector3> limited = limitedPath(40, 0, 2, 0), slow = limitedPath(2, 0, 0, 0),
                               fast = limitedPath(40, 0, 0, 0);
  std::printf("40 m/s limited to 2 against 2 m/s: %.2e m apart; unlimited: %.3f m\n",
              double(largestGap(limited, slow)), double(largestGap(fast, slow)));
  EXPECT_LT(largestGap(limited, slow), 1e-3f);
  EXPECT_GT(largestGap(fast, slow), 0.1f);
  // A limit above the motion changes nothing (the same bits as no limit).
  EXPECT_EQ(largestGap(limitedPath(2, 0, 5, 0), slow), btScalar(0));
}

TEST(CapeAction, BeyondTheAngularSpeedLimitTheCapeTurnsWithItsBody) {
  // A spin at 4 pi rad/s (two turns a second) with a limit of 1 rad/s, against a spin at 1 rad/s.
  const btScalar spin = btScalar(4 * SIMD_PI);
  const std::vector<btVector3> limited = limitedPath(0, spin, 0, 1), slow = limitedPath(0, 1, 0, 0),
                               fast = limitedPath(0, spin, 0, 0);
  std::printf("4 pi rad/s limited to 1 against 1 rad/s: %.2e m apart; unlimited: %.3f m\n",
              double(largestGap(limited, slow)), double(largestGap(fast, slow)));
  EXPECT_LT(largestGap(limited, slow), 1e-3f);
  EXPECT_GT(largestGap(fast, slow), 0.1f);
  // Not finite or negative: no limit.
  EXPECT_EQ(largestGap(limitedPath(0, spin, -1, std::numeric_limits<btScalar>::quiet_NaN()), fast),
            btScalar(0));
}

TEST(CapeAction, MeshHandsOutTheRenderMeshInTheWorld) {
  World w;
  btRigidBody* body = w.addKinematic(new btSphereShape(0.05f),
                                     btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
  cape::bullet::CapeActionSettings s;
  s.discoverColliders = false;
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)), s);
  action.attachRow(0, body);
  w.world->addAction(&action);
  for (int frame = 0; frame < 30; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  const cape::CapeMesh& front = action.mesh();
  const cape::Fabric& fabric = action.cape().fabric();
  ASSERT_EQ(front.positions.rows(), static_cast<Eigen::Index>(fabric.particleCount()));
  EXPECT_EQ(front.positions, action.positions());
  EXPECT_EQ(front.indices, fabric.triangles());
  EXPECT_EQ(front.uvs.size(), fabric.particleCount());
  for (Eigen::Index i = 0; i < front.normals.rows(); ++i)
    EXPECT_NEAR(front.normals.row(i).norm(), 1.0f, 1e-5f);
  // Hanging from a row along X, the cape's faces look along Z (their normals mostly +-Z).
  EXPECT_GT(std::fabs(front.normals.col(2).mean()), 0.8f);
  // Refreshed in place: the same buffers after more steps, holding the new positions.
  const float* buffer = front.positions.data();
  World::moveKinematic(body, btTransform(btQuaternion::getIdentity(), btVector3(0.5f, 1.5f, 0)));
  for (int frame = 0; frame < 10; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  const cape::CapeMesh& again = action.mesh();
  EXPECT_EQ(again.positions.data(), buffer);
  EXPECT_EQ(again.positions, action.positions());
  // Two-sided: the back copy after the front, its normals flipped.
  const cape::CapeMesh& both = action.mesh(true);
  ASSERT_TRUE(both.twoSided());
  const Eigen::Index n = static_cast<Eigen::Index>(fabric.particleCount());
  ASSERT_EQ(both.positions.rows(), 2 * n);
  EXPECT_EQ(both.indices.size(), 2 * fabric.triangles().size());
  for (Eigen::Index i = 0; i < n; ++i)
    EXPECT_LT((both.normals.row(i) + both.normals.row(n + i)).norm(), 1e-6f);
  w.world->removeAction(&action);
}

TEST(CapeAction, DebugDrawDrawsEveryTriangleEdge) {
  struct Counter : btIDebugDraw {
    int lines = 0;
    void drawLine(const btVector3&, const btVector3&, const btVector3&) override { ++lines; }
    void drawContactPoint(const btVector3&, const btVector3&, btScalar, int, const btVector3&) override {}
    void reportErrorWarning(const char*) override {}
    void draw3dText(const btVector3&, const char*) override {}
    void setDebugMode(int) override {}
    int getDebugMode() const override { return DBG_DrawWireframe; }
  } counter;
  CapeAction action(cornerFabric(), cape::CapeSettings());
  action.debugDraw(&counter);
  // Each triangle drawn filled (btIDebugDraw's drawTriangle falls back to its three edges for a drawer
  // that draws lines only) and, in the wireframe mode, its edges: 6 lines per triangle; no pins here.
  EXPECT_EQ(counter.lines, 2 * 3 * 2 * 19 * 19);
}

TEST(CapeAction, WalkOnTheSimpleBodyPinnedToTheShoulders) {
  // docs/SCENES.md's walk on kinematic Bullet bodies (torso, shoulders, legs as rigid parts of the moving
  // character frame; the legs do not swing here), the cape pinned by its corners to the shoulder spheres,
  // over the ground, stepped by stepSimulation(1/60, 8, 1/240) for 2 s.
  World w;
  SimpleWalk walk(w, btVector3(0, 0, 0), cape::bullet::CapeActionSettings(), true);
  const CapeAction& action = *walk.action;
  double worstDepth = 0.0, worstPin = 0.0;
  float worstStrain = 0.0f;
  for (int frame = 1; frame <= 120; ++frame) {
    walk.advance();
    worstPin = std::max(worstPin, double(action.maxPinError()));
    worstStrain = std::max(worstStrain, maxStructuralStrain(action.cape()));
    for (auto& p : walk.parts)
      for (std::size_t i = 0; i < action.particleCount(); ++i) {
        const btScalar d = cape::bullet::shapeSignedDistance(
            p.first->getCollisionShape(), p.first->getWorldTransform(), action.position(std::uint32_t(i)));
        worstDepth = std::max(worstDepth, double(-d));
      }
  }
  ASSERT_TRUE(allFinite(action.positions()));
  EXPECT_EQ(action.coreColliders().size(), 6u);
  EXPECT_LT(worstPin, 1e-5);
  EXPECT_LT(worstDepth, 1e-3);
  EXPECT_LT(worstStrain, 0.1f);
  RecordProperty("max_strain", std::to_string(worstStrain));
}

// --- Discovery through the broadphase, bodies leaving the world (issue 12) --------------------------------

TEST(CapeAction, DiscoveryFindsTheNearBoxAndIgnoresTheFarTheFilteredAndTheGhost) {
  World w;
  btRigidBody* near = w.addStatic(new btBoxShape(btVector3(0.4f, 0.05f, 0.6f)),
                                  btTransform(btQuaternion::getIdentity(), btVector3(0, 0, 0)));
  w.addStatic(new btBoxShape(btVector3(0.4f, 0.05f, 0.6f)),
              btTransform(btQuaternion::getIdentity(), btVector3(0, 0.2f, 30)));
  // In the cape's way, but the cape's mask leaves the first out and the second's mask leaves the cape out.
  const int kNotCape = 64;
  w.addStatic(new btBoxShape(btVector3(0.1f, 0.1f, 0.1f)),
              btTransform(btQuaternion::getIdentity(), btVector3(0.15f, 0.25f, 0)), kNotCape,
              btBroadphaseProxy::AllFilter);
  w.addStatic(new btBoxShape(btVector3(0.1f, 0.1f, 0.1f)),
              btTransform(btQuaternion::getIdentity(), btVector3(-0.15f, 0.25f, 0)),
              btBroadphaseProxy::StaticFilter,
              btBroadphaseProxy::AllFilter & ~btBroadphaseProxy::DefaultFilter);
  btRigidBody* ghost = w.addStatic(new btBoxShape(btVector3(0.1f, 0.1f, 0.1f)),
                                   btTransform(btQuaternion::getIdentity(), btVector3(0, 0.25f, 0.3f)));
  ghost->setCollisionFlags(ghost->getCollisionFlags() | btCollisionObject::CF_NO_CONTACT_RESPONSE);
  cape::bullet::CapeActionSettings s;
  s.collisionMask = btBroadphaseProxy::AllFilter & ~kNotCape;
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)), s);
  w.world->addAction(&action);
  for (int frame = 0; frame < 60; ++frame) {
    w.world->stepSimulation(kFrame, 8, kFixed);
    for (const btCollisionObject* o : action.activeObjects()) EXPECT_EQ(o, near) << "frame " << frame;
  }
  ASSERT_EQ(action.activeObjects().size(), 1u);
  EXPECT_EQ(action.activeObjects()[0], near);
  // It lies on the near box (top at 0.05), through the filtered boxes and the ghost (tops at 0.35).
  EXPECT_GT(action.position(10 * 20 + 10).y(), 0.05f);
  EXPECT_LT(action.position(10 * 20 + 10).y(), 0.1f);
  w.world->removeAction(&action);
}

TEST(CapeAction, ObjectsDiscoveredInOneStepFollowTheWorldArrayOrderNotTheBroadphaseTrees) {
  // Fourteen objects scattered around the cape (sizes and places from a fixed sequence), all within the
  // discovery margin at the first step: the broadphase reports them in its trees' order, the colliders come
  // in the world's array order.
  World w;
  std::vector<const btCollisionObject*> added;
  unsigned seed = 12345u;
  const auto next = [&]() {
    seed = seed * 1664525u + 1013904223u;
    return float(seed >> 8) / float(1 << 24);
  };
  for (int i = 0; i < 14; ++i) {
    const btVector3 at(2.0f * next() - 1.0f, -0.6f + next(), 2.0f * next() - 1.0f);
    btCollisionShape* shape =
        i % 2 ? static_cast<btCollisionShape*>(new btSphereShape(0.05f + 0.1f * next()))
              : new btBoxShape(btVector3(0.1f + 0.1f * next(), 0.05f, 0.1f + 0.1f * next()));
    added.push_back(w.addStatic(shape, btTransform(btQuaternion(btVector3(0, 1, 0), next()), at)));
  }
  cape::bullet::CapeActionSettings s;
  s.discoveryMargin = 3.0f;
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.7)), s);
  w.world->addAction(&action);
  w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_EQ(action.activeObjects(), added);
  // Two leave the world from the middle of the array (the last objects are swapped into their slots) and
  // one comes back (at the end of the array): the others keep their order, the returning one comes last.
  w.world->removeRigidBody(w.bodies[2].get());
  w.world->removeRigidBody(w.bodies[7].get());
  w.world->stepSimulation(kFrame, 8, kFixed);
  std::vector<const btCollisionObject*> expected;
  for (std::size_t i = 0; i < added.size(); ++i)
    if (i != 2 && i != 7) expected.push_back(added[i]);
  EXPECT_EQ(action.activeObjects(), expected);
  w.world->addRigidBody(w.bodies[2].get());
  w.world->stepSimulation(kFrame, 8, kFixed);
  expected.push_back(added[2]);
  EXPECT_EQ(action.activeObjects(), expected);
  w.world->removeAction(&action);
}

TEST(CapeAction, BodiesRemovedFromTheMiddleOfTheArrayAreDroppedAndTheCapeKeepsItsOtherColliders) {
  // The world's array: [far0, holder, left, right, ground, far1, far2, far3]. The cape hangs from the holder
  // over the two spheres and the ground; the far boxes (20 m away) are never followed.
  World w;
  const auto farBox = [&](btScalar x) {
    return w.addStatic(new btBoxShape(btVector3(0.1f, 0.1f, 0.1f)),
                       btTransform(btQuaternion::getIdentity(), btVector3(x, 0, 0)));
  };
  btRigidBody* far0 = farBox(20);
  btRigidBody* holder = w.addKinematic(new btSphereShape(0.05f),
                                       btTransform(btQuaternion::getIdentity(), btVector3(0, 0.6f, 0.6f)));
  btRigidBody* left = w.addStatic(new btSphereShape(0.1f),
                                  btTransform(btQuaternion::getIdentity(), btVector3(-0.15f, 0, 0.1f)));
  btRigidBody* right = w.addStatic(new btSphereShape(0.1f),
                                   btTransform(btQuaternion::getIdentity(), btVector3(0.15f, 0, 0.1f)));
  btRigidBody* ground = w.addStatic(new btBoxShape(btVector3(1.5f, 0.05f, 1.5f)),
                                    btTransform(btQuaternion::getIdentity(), btVector3(0, -0.3f, 0)));
  btRigidBody* far1 = farBox(21);
  btRigidBody* far2 = farBox(22);
  btRigidBody* far3 = farBox(23);
  const btCollisionObjectArray& array = w.world->getCollisionObjectArray();
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)));
  std::vector<std::string> warnings;
  action.setWarningHandler([&](const std::string& m) { warnings.push_back(m); });
  ASSERT_EQ(action.attachRow(0, holder), 20u);
  w.world->addAction(&action);
  for (int frame = 0; frame < 40; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  const std::vector<const btCollisionObject*> before = action.activeObjects();
  for (const btCollisionObject* o : {left, right, ground})
    ASSERT_NE(std::find(before.begin(), before.end(), o), before.end()) << "the cape hangs over the spheres";
  for (const btCollisionObject* o : {far0, far1, far2, far3})
    EXPECT_EQ(std::find(before.begin(), before.end(), o), before.end());
  EXPECT_TRUE(warnings.empty());

  // Between two steps the attachment body leaves from slot 1 and the left sphere from slot 2; Bullet swaps
  // the last boxes into their slots, so every followed object's old index is still inside the array. Both
  // are deleted.
  w.world->removeRigidBody(holder);
  w.world->removeRigidBody(left);
  ASSERT_EQ(array.size(), 6);
  ASSERT_EQ(array[1], far3);
  ASSERT_EQ(array[2], far2);
  for (auto& body : w.bodies)
    if (body.get() == holder || body.get() == left) body.reset();
  w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_TRUE(action.attachments().empty());
  EXPECT_TRUE(action.cape().state().pins.empty());
  EXPECT_GT(action.cape().state().inverseMasses.minCoeff(), 0.0f);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("20 cape particle(s)"), std::string::npos) << warnings[0];
  std::vector<const btCollisionObject*> expected;
  for (const btCollisionObject* o : before)
    if (o != holder && o != left) expected.push_back(o);
  EXPECT_EQ(action.activeObjects(), expected) << "the remaining colliders, in their order";

  // Boxes nobody follows leave: from the end, then from slot 0, which moves the ground (now last) there.
  w.world->removeRigidBody(far1);
  w.world->removeRigidBody(far0);
  ASSERT_EQ(array[0], ground);
  double worstDepth = 0.0;
  int touching[2] = {0, 0};  // frames with a particle within 2 cm of the ground, of the right sphere
  const btRigidBody* kept[2] = {ground, right};
  for (int frame = 0; frame < 90; ++frame) {
    w.world->stepSimulation(kFrame, 8, kFixed);
    for (int k = 0; k < 2; ++k) {
      btScalar nearest = BT_LARGE_FLOAT;
      for (std::size_t i = 0; i < action.particleCount(); ++i)
        nearest = std::min(nearest, cape::bullet::shapeSignedDistance(kept[k]->getCollisionShape(),
                                                                      kept[k]->getWorldTransform(),
                                                                      action.position(std::uint32_t(i))));
      worstDepth = std::max(worstDepth, double(-nearest));
      touching[k] += nearest < btScalar(0.02) ? 1 : 0;
    }
  }
  EXPECT_EQ(warnings.size(), 1u);
  EXPECT_EQ(action.activeObjects(), expected);
  ASSERT_TRUE(allFinite(action.positions()));
  EXPECT_GT(touching[0], 0) << "the released cape falls onto the ground";
  EXPECT_GT(touching[1], 0) << "and meets the right sphere";
  EXPECT_LT(worstDepth, 1e-3) << "the cape still collides with the ground and the right sphere";
  EXPECT_GT(action.positions().col(1).minCoeff(), -0.25f - 1e-3f) << "it lies on the ground";
  w.world->removeAction(&action);
}
