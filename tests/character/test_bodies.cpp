// Kinematic Bullet bodies: shapes, flags, groups, ownership, and that they follow the skeleton in a real
// btDiscreteDynamicsWorld stepped as docs/SCENES.md says (stepSimulation(1/60, 8, 1/240)).
#include "cape/character/Character.h"

#include "CharacterTestWorld.h"

#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <memory>

using namespace cape::character;
using capetest::World;

namespace {

UrdfModelPtr humanoid() {
  const UrdfLoadResult r = UrdfModel::humanoid();
  EXPECT_TRUE(r.ok()) << r.status.message();
  return r.model;
}

const btCollisionShape* onlyChild(const btCollisionShape* shape, btTransform* local = nullptr) {
  if (shape->getShapeType() != COMPOUND_SHAPE_PROXYTYPE) return shape;
  const auto* compound = static_cast<const btCompoundShape*>(shape);
  EXPECT_EQ(compound->getNumChildShapes(), 1);
  if (local) *local = compound->getChildTransform(0);
  return compound->getChildShape(0);
}

double maxDifference(const btTransform& a, const Eigen::Isometry3d& b) {
  double d = 0.0;
  for (int i = 0; i < 3; ++i) {
    d = std::max(d, std::abs(double(a.getOrigin()[i]) - b.translation()[i]));
    for (int j = 0; j < 3; ++j) d = std::max(d, std::abs(double(a.getBasis()[i][j]) - b.linear()(i, j)));
  }
  return d;
}

}  // namespace

TEST(CharacterBodies, OneKinematicBodyPerLinkWithTheLinksShapes) {
  World w;
  Skeleton skeleton(humanoid());
  {
    CharacterBodies bodies(w.world, skeleton);
    EXPECT_EQ(bodies.bodies().size(), 15u);  // every link but base_link, which has no shapes
    EXPECT_EQ(w.world.getNumCollisionObjects(), 15);
    EXPECT_EQ(bodies.bodyForLink("base_link"), nullptr);
    EXPECT_EQ(bodies.bodyForLink("no_such_link"), nullptr);

    for (btRigidBody* body : bodies.bodies()) {
      EXPECT_TRUE(body->isKinematicObject());
      EXPECT_EQ(body->getActivationState(), DISABLE_DEACTIVATION);
      EXPECT_EQ(body->getBroadphaseHandle()->m_collisionFilterGroup, btBroadphaseProxy::CharacterFilter);
      EXPECT_EQ(body->getBroadphaseHandle()->m_collisionFilterMask & btBroadphaseProxy::CharacterFilter, 0);
      const auto* tag = static_cast<const LinkBodyTag*>(body->getUserPointer());
      ASSERT_NE(tag, nullptr);
      EXPECT_EQ(tag->owner, &bodies);
      EXPECT_EQ(bodies.linkOf(body), tag->link);
      EXPECT_EQ(body->getUserIndex(), tag->link);
      EXPECT_EQ(bodies.bodyForLink(tag->linkName), body);
    }

    // A sphere centred on the link origin needs no compound.
    const btCollisionShape* shoulder = bodies.bodyForLink("left_shoulder")->getCollisionShape();
    ASSERT_EQ(shoulder->getShapeType(), SPHERE_SHAPE_PROXYTYPE);
    EXPECT_FLOAT_EQ(static_cast<const btSphereShape*>(shoulder)->getRadius(), 0.08f);

    // An offset box: a compound with the collision origin as child transform; the margin stays inside.
    btTransform local;
    const btCollisionShape* torso = onlyChild(bodies.bodyForLink("torso")->getCollisionShape(), &local);
    ASSERT_EQ(torso->getShapeType(), BOX_SHAPE_PROXYTYPE);
    const btVector3 half = static_cast<const btBoxShape*>(torso)->getHalfExtentsWithMargin();
    EXPECT_NEAR(half.x(), 0.12, 1e-6);
    EXPECT_NEAR(half.y(), 0.20, 1e-6);
    EXPECT_NEAR(half.z(), 0.30, 1e-6);
    EXPECT_NEAR(local.getOrigin().z(), 0.30, 1e-6);

    // URDF cylinders lie along local z.
    const btCollisionShape* thigh = onlyChild(bodies.bodyForLink("right_thigh")->getCollisionShape());
    ASSERT_EQ(thigh->getShapeType(), CYLINDER_SHAPE_PROXYTYPE);
    const auto* cylinder = static_cast<const btCylinderShape*>(thigh);
    EXPECT_EQ(cylinder->getUpAxis(), 2);
    EXPECT_NEAR(cylinder->getRadius(), 0.07, 1e-6);
    EXPECT_NEAR(cylinder->getHalfExtentsWithMargin().z(), 0.20, 1e-6);

    // Several elements: one compound child each, in the order of shapes(link).
    const int head = skeleton.model().findLink("head");
    const auto* compound = static_cast<const btCompoundShape*>(bodies.bodyForLink(head)->getCollisionShape());
    ASSERT_EQ(compound->getShapeType(), COMPOUND_SHAPE_PROXYTYPE);
    ASSERT_EQ(compound->getNumChildShapes(), 2);
    ASSERT_EQ(bodies.shapes(head).size(), 2u);
    EXPECT_EQ(compound->getChildShape(0)->getShapeType(), SPHERE_SHAPE_PROXYTYPE);
    EXPECT_EQ(compound->getChildShape(1)->getShapeType(), CYLINDER_SHAPE_PROXYTYPE);
  }
  EXPECT_EQ(w.world.getNumCollisionObjects(), 0);  // the destructor removed what it added
}

TEST(CharacterBodies, GroupMaskAndEmptyLinksAreConfigurable) {
  World w;
  Skeleton skeleton(humanoid());
  BodySettings settings;
  settings.group = 64;
  settings.mask = 1;
  settings.bodiesForEmptyLinks = true;
  CharacterBodies bodies(w.world, skeleton, settings);
  EXPECT_EQ(bodies.bodies().size(), 16u);
  ASSERT_NE(bodies.bodyForLink("base_link"), nullptr);
  EXPECT_EQ(bodies.bodyForLink("base_link")->getCollisionShape()->getShapeType(), EMPTY_SHAPE_PROXYTYPE);
  EXPECT_EQ(bodies.bodyForLink("torso")->getBroadphaseHandle()->m_collisionFilterGroup, 64);
  EXPECT_EQ(bodies.bodyForLink("torso")->getBroadphaseHandle()->m_collisionFilterMask, 1);
  EXPECT_EQ(bodies.update(0.0).code(), ErrorCode::InvalidArgument);
}

TEST(CharacterBodies, FollowTheSkeletonThroughBulletSteps) {
  for (cape::SceneKind scene : {cape::SceneKind::Walk, cape::SceneKind::SprintTurn}) {
    World w;
    CharacterResult made = Character::create(humanoid(), w.world, Gait::forScene(scene));
    ASSERT_TRUE(made.ok()) << made.status.message();
    Character& c = *made.character;
    const double dt = 1.0 / 60.0;
    std::vector<Eigen::Isometry3d> before(static_cast<std::size_t>(c.skeleton().linkCount()));
    double worst = 0.0, worstVelocity = 0.0;
    for (int frame = 1; frame <= 240; ++frame) {  // 4 s: the sprint-turn's first two turns
      for (int l = 0; l < c.skeleton().linkCount(); ++l)
        before[static_cast<std::size_t>(l)] = c.skeleton().linkPose(l);
      c.advanceTo(frame * dt);
      w.world.stepSimulation(btScalar(1.0 / 60.0), 8, btScalar(1.0 / 240.0));
      for (btRigidBody* body : c.bodies().bodies()) {
        const int l = c.bodies().linkOf(body);
        const Eigen::Isometry3d& pose = c.skeleton().linkPose(l);
        worst = std::max(worst, maxDifference(body->getWorldTransform(), pose));
        btTransform fromMotionState;
        body->getMotionState()->getWorldTransform(fromMotionState);
        worst = std::max(worst, maxDifference(fromMotionState, pose));
        // Velocities: the pose change over the frame, as Bullet computes it for kinematic bodies.
        const Eigen::Vector3d v =
            (pose.translation() - before[static_cast<std::size_t>(l)].translation()) / dt;
        const btVector3& bv = body->getLinearVelocity();
        worstVelocity = std::max(worstVelocity, (Eigen::Vector3d(bv.x(), bv.y(), bv.z()) - v).norm());
      }
    }
    EXPECT_LT(worst, 1e-6) << cape::toString(scene);
    EXPECT_LT(worstVelocity, 2e-3) << cape::toString(scene);
  }
}

TEST(CharacterBodies, AngularVelocityMatchesTheTurn) {
  World w;
  CharacterResult made = Character::create(humanoid(), w.world, Gait::forScene(cape::SceneKind::SprintTurn));
  ASSERT_TRUE(made.ok());
  Character& c = *made.character;
  // In the turn (1.5 s to 2 s) the torso yaws at pi / 0.5 s about +Y (the waist is not driven).
  for (int frame = 1; frame <= 105; ++frame) c.advanceTo(frame / 60.0);
  w.world.stepSimulation(btScalar(1.0 / 60.0), 8, btScalar(1.0 / 240.0));
  const btVector3 omega = c.bodies().bodyForLink("torso")->getAngularVelocity();
  EXPECT_NEAR(omega.y(), 3.14159265 / 0.5, 1e-2);
  EXPECT_NEAR(omega.x(), 0.0, 1e-2);
  EXPECT_NEAR(omega.z(), 0.0, 1e-2);
}

TEST(CharacterBodies, DynamicBodiesAreShovedByTheWalk) {
  // Bullet sees the kinematic motion: a free ball in the character's path is pushed ahead (towards -Z).
  World w;
  w.world.setGravity(btVector3(0, 0, 0));
  btSphereShape ballShape(0.1f);
  btVector3 inertia;
  ballShape.calculateLocalInertia(1.0f, inertia);
  btDefaultMotionState ballState(btTransform(btQuaternion::getIdentity(), btVector3(0, 1.25f, -1.0f)));
  btRigidBody ball(btRigidBody::btRigidBodyConstructionInfo(1.0f, &ballState, &ballShape, inertia));
  ball.setActivationState(DISABLE_DEACTIVATION);
  w.world.addRigidBody(&ball);
  {
    CharacterResult made = Character::create(humanoid(), w.world, Gait::forScene(cape::SceneKind::Walk));
    ASSERT_TRUE(made.ok());
    for (int frame = 1; frame <= 90; ++frame) {
      made.character->advanceTo(frame / 60.0);
      w.world.stepSimulation(btScalar(1.0 / 60.0), 8, btScalar(1.0 / 240.0));
    }
    EXPECT_LT(ball.getLinearVelocity().z(), -1.0f);
    EXPECT_LT(ball.getWorldTransform().getOrigin().z(), -1.3f);
  }
  w.world.removeRigidBody(&ball);
}

TEST(CharacterBodies, ScaledCharacterHasScaledShapes) {
  World w;
  CharacterSettings settings;
  settings.scale = 2.0;
  settings.offset = Eigen::Vector3d(2.0, 0.0, 0.0);  // a crowd member 2 m to the right
  CharacterResult made =
      Character::create(humanoid(), w.world, Gait::forScene(cape::SceneKind::Hang), settings);
  ASSERT_TRUE(made.ok()) << made.status.message();
  const btRigidBody* shoulder = made.character->bodies().bodyForLink("right_shoulder");
  ASSERT_EQ(shoulder->getCollisionShape()->getShapeType(), SPHERE_SHAPE_PROXYTYPE);
  EXPECT_NEAR(static_cast<const btSphereShape*>(shoulder->getCollisionShape())->getRadius(), 0.16, 1e-6);
  const btVector3& p = shoulder->getWorldTransform().getOrigin();
  EXPECT_NEAR(p.x(), 2.0 + 0.44, 1e-6);
  EXPECT_NEAR(p.y(), 3.04, 1e-6);

  CharacterSettings bad;
  bad.scale = -1.0;
  EXPECT_EQ(Character::create(humanoid(), w.world, Gait::forScene(cape::SceneKind::Hang), bad).status.code(),
            ErrorCode::InvalidArgument);
  EXPECT_EQ(Character::create(nullptr, w.world, Gait::forScene(cape::SceneKind::Hang)).status.code(),
            ErrorCode::InvalidArgument);
  EXPECT_EQ(w.world.getNumCollisionObjects(), 15);  // failed creations added nothing
}

TEST(CharacterBodies, GoingBackInTimeIsAJumpWithoutVelocity) {
  World w;
  CharacterResult made = Character::create(humanoid(), w.world, Gait::forScene(cape::SceneKind::Walk));
  ASSERT_TRUE(made.ok());
  Character& c = *made.character;
  c.advanceTo(0.5);
  EXPECT_GT(c.bodies().bodyForLink("torso")->getLinearVelocity().length(), 1.0f);  // 0.5 s in one update
  c.advanceTo(0.1);
  w.world.stepSimulation(btScalar(1.0 / 60.0), 8, btScalar(1.0 / 240.0));
  EXPECT_EQ(c.bodies().bodyForLink("torso")->getLinearVelocity().length(), 0.0f);
  const int torso = c.skeleton().model().findLink("torso");
  EXPECT_EQ(c.bodies().previousTransform(torso).getOrigin(), c.bodies().currentTransform(torso).getOrigin());
  EXPECT_NEAR(c.bodies().currentTransform(torso).getOrigin().z(), -0.14, 1e-6);
}
