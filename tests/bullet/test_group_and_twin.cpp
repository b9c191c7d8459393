// Many capes on a thread pool (bitwise identical whatever the thread count), and the btSoftBody twin.
#include "BulletFixture.h"

#include "cape/bullet/CapeGroup.h"
#include "cape/bullet/SoftBodyTwin.h"

#include <gtest/gtest.h>

#include <cstring>

using namespace capetest;
using cape::bullet::CapeAction;

namespace {

/// Two capes pinned to two kinematic bodies that walk and turn, over a sphere each, stepped by a group
/// of `threads`; returns every cape's final positions.
std::vector<cape::Points> runGroup(int threads) {
  World w;
  std::vector<std::unique_ptr<CapeAction>> capes;
  std::vector<btRigidBody*> bodies;
  cape::bullet::CapeGroup group(threads);
  for (int k = 0; k < 2; ++k) {
    const btVector3 at(btScalar(2 * k), btScalar(1.5), 0);
    bodies.push_back(w.addKinematic(new btBoxShape(btVector3(0.2f, 0.3f, 0.1f)),
                                    btTransform(btQuaternion::getIdentity(), at)));
    w.addStatic(new btSphereShape(0.25f),
                btTransform(btQuaternion::getIdentity(), at + btVector3(0, -0.6f, 0.3f)));
    capes.push_back(std::make_unique<CapeAction>(
        cornerFabric(), cape::CapeSettings(),
        btTransform(btQuaternion::getIdentity(), at + btVector3(-0.3f, 0.06f, 0.15f))));
    capes.back()->attach(0, bodies.back(), btVector3(-0.3f, 0.06f, 0.15f));
    capes.back()->attach(19, bodies.back(), btVector3(0.3f, 0.06f, 0.15f));
    group.add(capes.back().get());
  }
  w.world->addAction(&group);
  for (int frame = 1; frame <= 40; ++frame) {
    const double t = frame / 60.0;
    for (int k = 0; k < 2; ++k)
      World::moveKinematic(bodies[std::size_t(k)],
                           btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.8 * t * (k + 1))),
                                       btVector3(btScalar(2 * k), btScalar(1.5 + 0.03 * std::sin(12.0 * t)),
                                                 btScalar(-1.4 * t))));
    w.world->stepSimulation(kFrame, 8, kFixed);
  }
  w.world->removeAction(&group);
  std::vector<cape::Points> out;
  for (const auto& c : capes) out.push_back(c->positions());
  return out;
}

}  // namespace

TEST(CapeGroup, OneAndTwoThreadsGiveIdenticalBits) {
  const std::vector<cape::Points> one = runGroup(1), two = runGroup(2);
  ASSERT_EQ(one.size(), 2u);
  for (std::size_t k = 0; k < one.size(); ++k) {
    ASSERT_TRUE(one[k].allFinite());
    ASSERT_EQ(one[k].size(), two[k].size());
    EXPECT_EQ(0, std::memcmp(one[k].data(), two[k].data(), sizeof(float) * std::size_t(one[k].size())))
        << "cape " << k;
  }
  // Each body turns at its own rate, so the two capes differ: the comparison is not of two copies.
  EXPECT_GT((one[0].rowwise() - one[0].row(0)).norm(), 0.0f);
  EXPECT_GT((one[0] - one[1]).cwiseAbs().maxCoeff(), 0.0f);
}

TEST(CapeGroup, SameResultAsTheCapeAddedAlone) {
  auto run = [](bool grouped) {
    World w;
    btRigidBody* body = w.addKinematic(new btSphereShape(0.05f),
                                       btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, 0)));
    CapeAction action(cornerFabric(), cape::CapeSettings(),
                      btTransform(btQuaternion::getIdentity(), btVector3(-0.3f, 1.5f, 0.15f)));
    action.attachRow(0, body);
    cape::bullet::CapeGroup group(2);
    group.add(&action);
    btActionInterface* added = grouped ? static_cast<btActionInterface*>(&group) : &action;
    w.world->addAction(added);
    for (int frame = 1; frame <= 30; ++frame) {
      World::moveKinematic(body,
                           btTransform(btQuaternion::getIdentity(), btVector3(0, 1.5f, -0.02f * frame)));
      w.world->stepSimulation(kFrame, 8, kFixed);
    }
    w.world->removeAction(added);
    return cape::Points(action.positions());
  };
  const cape::Points a = run(false), b = run(true);
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), sizeof(float) * std::size_t(a.size())));
}

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

  cape::bullet::SoftBodyTwinSettings settings;
  std::unique_ptr<btSoftBody> twin = cape::bullet::makeSoftBodyTwin(*w.soft(), action, settings);
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
  std::unique_ptr<btSoftBody> full = cape::bullet::makeSoftBodyTwin(*w.soft(), action, settings);
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
  std::unique_ptr<btSoftBody> twin = cape::bullet::makeSoftBodyTwin(*w.soft(), action);
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
  std::unique_ptr<cape::bullet::DeformableTwin> twin = cape::bullet::makeDeformableTwin(*w.deformable(), action);
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
