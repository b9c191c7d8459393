// The comparison's twins in real Bullet worlds: the btSoftBody twin has the cape's nodes, masses, links,
// faces and anchors and collides with the same rigid bodies; the deformable-world twin hangs from and follows
// the body it is anchored to.
#include "BulletFixture.h"

#include "cape/compare/SoftBodyTwin.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace capetest;
using cape::bullet::CapeAction;

TEST(SoftBodyTwin, SameNodesMassesLinksAndAnchorsAsTheCape) {
  World w(true);
  btRigidBody* body = w.addKinematic(new btBoxShape(btVector3(0.2f, 0.3f, 0.1f)),
                                     btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
  w.addStatic(new btSphereShape(0.2f), btTransform(btQuaternion::getIdentity(), btVector3(0, 0.8f, 0.4f)));
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.56f, 0.15f)));
  action.attach(0, body, btVector3(-0.3f, 0.06f, 0.15f));
  action.attach(19, body, btVector3(0.3f, 0.06f, 0.15f));
  const cape::Fabric& fabric = action.cape().fabric();

  cape::compare::SoftBodyTwinSettings settings;
  std::unique_ptr<btSoftBody> twin = cape::compare::makeSoftBodyTwin(*w.soft(), action, settings);
  ASSERT_NE(twin, nullptr);
  EXPECT_EQ(twin->m_nodes.size(), int(fabric.particleCount()));
  EXPECT_EQ(twin->m_links.size(), int(cape::kingsGraphSpringCount(20, 20)));
  EXPECT_EQ(twin->m_faces.size(), int(fabric.triangleCount()));
  EXPECT_EQ(twin->m_anchors.size(), 2);
  EXPECT_NEAR(twin->getTotalMass(), fabric.totalMass(), 1e-4);
  for (int i = 0; i < twin->m_nodes.size(); ++i)
    EXPECT_LT((twin->m_nodes[i].m_x - action.position(std::uint32_t(i))).length(), 1e-6f);

  // Bend links too: every spring of the fabric.
  settings.bendLinks = true;
  std::unique_ptr<btSoftBody> full = cape::compare::makeSoftBodyTwin(*w.soft(), action, settings);
  EXPECT_EQ(full->m_links.size(), int(fabric.springCount()));
  w.soft()->removeSoftBody(full.get());

  // It steps in the soft-rigid world next to the cape: anchored nodes follow the kinematic body, nothing
  // blows up.
  w.world->addAction(&action);
  for (int frame = 1; frame <= 60; ++frame) {
    World::moveKinematic(body, btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, -0.02f * frame)));
    w.world->stepSimulation(kFrame, 8, kFixed);
  }
  const btVector3 pin = body->getWorldTransform() * btVector3(-0.3f, 0.06f, 0.15f);
  EXPECT_LT((twin->m_nodes[0].m_x - pin).length(), 0.05f);
  EXPECT_LT((action.position(0) - pin).length(), 1e-5f);
  for (int i = 0; i < twin->m_nodes.size(); ++i) {
    ASSERT_TRUE(std::isfinite(twin->m_nodes[i].m_x.y()));
    EXPECT_LT((twin->m_nodes[i].m_x - pin).length(), 3.0f);
  }
  w.world->removeAction(&action);
  w.soft()->removeSoftBody(twin.get());
}

TEST(SoftBodyTwin, CollidesWithTheSameRigidBodies) {
  // Dropped flat on a static sphere, the twin rests on it (Bullet's own soft-rigid contacts): its middle
  // node stays on top, outside the sphere but for Bullet's tolerance.
  World w(true);
  w.addStatic(new btSphereShape(0.3f), btTransform::getIdentity());
  CapeAction action(cornerFabric(), cape::CapeSettings(), horizontalAt(btScalar(0.5)));
  std::unique_ptr<btSoftBody> twin = cape::compare::makeSoftBodyTwin(*w.soft(), action);
  ASSERT_NE(twin, nullptr);
  for (int frame = 0; frame < 60; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  const btVector3 middle = twin->m_nodes[10 * 20 + 10].m_x;
  EXPECT_TRUE(std::isfinite(middle.y()));
  EXPECT_GT(middle.y(), 0.25f);
  EXPECT_GT(middle.length(), 0.28f);
  w.soft()->removeSoftBody(twin.get());
}

// The deformable-world twin: the same nodes, links and anchors, driven by Bullet's mass-spring and
// gravity forces; carried along by a kinematic body walking at 1.2 m/s, it hangs below its pins, follows
// them and stays finite.
TEST(DeformableTwin, HangsFromTheBodyItIsAnchoredToAndFollowsIt) {
  World w{DeformableWorldTag{}};
  btRigidBody* body = w.addKinematic(new btBoxShape(btVector3(0.2f, 0.3f, 0.1f)),
                                     btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
  CapeAction action(cornerFabric(), cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.56f, 0.15f)));
  action.attach(0, body, btVector3(-0.3f, 0.06f, 0.15f));
  action.attach(19, body, btVector3(0.3f, 0.06f, 0.15f));
  const cape::Fabric& fabric = action.cape().fabric();
  std::unique_ptr<cape::compare::DeformableTwin> twin =
      cape::compare::makeDeformableTwin(*w.deformable(), action);
  ASSERT_NE(twin, nullptr);
  const btSoftBody& b = twin->body();
  EXPECT_EQ(b.m_nodes.size(), int(fabric.particleCount()));
  EXPECT_EQ(b.m_links.size(), int(cape::kingsGraphSpringCount(20, 20)));
  EXPECT_EQ(b.m_faces.size(), int(fabric.triangleCount()));
  EXPECT_EQ(b.m_deformableAnchors.size(), 2);
  EXPECT_NEAR(b.getTotalMass(), fabric.totalMass(), 1e-4);

  for (int frame = 1; frame <= 60; ++frame) {
    World::moveKinematic(body, btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, -0.02f * frame)));
    w.world->stepSimulation(kFrame, 8, kFixed);
  }
  const btVector3 pin = body->getWorldTransform() * btVector3(-0.3f, 0.06f, 0.15f);
  EXPECT_LT((b.m_nodes[0].m_x - pin).length(), 0.05f);
  btVector3 mean(0, 0, 0);
  for (int i = 0; i < b.m_nodes.size(); ++i) {
    ASSERT_TRUE(std::isfinite(b.m_nodes[i].m_x.y()));
    mean += b.m_nodes[i].m_x / btScalar(b.m_nodes.size());
  }
  EXPECT_LT(mean.y(), pin.y() - 0.3f) << "hangs";
  EXPECT_LT(std::abs(mean.z() - pin.z()), 0.3f) << "follows the body (it walked 1.2 m)";
}
