// The simple body as kinematic Bullet bodies (cape::BulletSimpleBody, library cape::scenes_bullet): the
// bodies the demos' Bullet scene and the adapter's tests put in a world for the simple body of
// docs/SCENES.md.
#include "BulletFixture.h"

#include "cape/bullet/Convert.h"
#include "cape/bullet/ShapeColliders.h"
#include "cape/scenes/BulletSimpleBody.h"

#include <gtest/gtest.h>

using namespace capetest;
using cape::bullet::toBt;

TEST(BulletSimpleBody, OneKinematicBodyPerColliderOnItsTrueSurfaceFollowingThePose) {
  World w;
  const cape::MotionDesc walk = cape::MotionDesc::forScene(cape::SceneKind::Walk);
  {
    cape::BulletSimpleBody body(*w.world, cape::Vec3(2.0f, 0.0f, 0.0f), cape::motionAt(walk, 0.0));
    ASSERT_EQ(body.rigidBodyCount(), cape::SimpleBody::kGround);  // torso, shoulders, legs; no ground
    EXPECT_EQ(w.world->getNumCollisionObjects(), body.rigidBodyCount());
    for (int frame = 1; frame <= 30; ++frame) {
      body.moveTo(cape::motionAt(walk, frame / 60.0));
      w.world->stepSimulation(kFrame, 8, kFixed);
    }
    for (int i = 0; i < body.rigidBodyCount(); ++i) {
      const btRigidBody* b = body.rigidBody(i);
      const cape::Collider& c = body.body().colliders()[std::size_t(i)];
      EXPECT_EQ(w.world->getCollisionObjectArray()[i], b) << c.name << ": added in SimpleBody's order";
      EXPECT_TRUE(b->isKinematicObject()) << c.name;
      EXPECT_EQ(b->getActivationState(), DISABLE_DEACTIVATION) << c.name;
      // Where the collider is after the walk's half second, and the same surface: Bullet's signed distance
      // of probe points around it equals the core's.
      EXPECT_LT((b->getWorldTransform().getOrigin() - toBt(c.current.position)).length(), 1e-5f) << c.name;
      for (const cape::Vec3& d : {cape::Vec3(0.3f, 0.0f, 0.0f), cape::Vec3(0.0f, 0.5f, 0.0f),
                                  cape::Vec3(0.0f, -0.2f, 0.15f), cape::Vec3(0.01f, 0.02f, -0.03f)}) {
        const cape::Vec3 p = c.current.position + d;
        EXPECT_NEAR(
            cape::bullet::shapeSignedDistance(b->getCollisionShape(), b->getWorldTransform(), toBt(p)),
            cape::signedDistance(c, p), 1e-4f)
            << c.name;
      }
    }
    // The torso walked 30 frames at 1.4 m/s towards -Z.
    EXPECT_NEAR(body.rigidBody(cape::SimpleBody::kTorso)->getWorldTransform().getOrigin().z(), -0.7f, 1e-4f);
  }
  EXPECT_EQ(w.world->getNumCollisionObjects(), 0) << "removed from the world when destroyed";
}
