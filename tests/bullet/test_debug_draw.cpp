// CapeAction::debugDraw as Bullet's debug drawers expect it: filled triangles with normals, pins, contact
// points on request, edges, normals and bounds by the drawer's debug mode; through the world's own
// debugDrawWorld() too.
#include "BulletFixture.h"

#include <LinearMath/btIDebugDraw.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace capetest;
using cape::bullet::CapeAction;

namespace {

/// Records every call a cape's debugDraw may make.
struct RecordingDrawer : btIDebugDraw {
  struct Triangle {
    btVector3 a, b, c, normal;
  };
  struct ContactPoint {
    btVector3 point, normal;
    btScalar distance;
  };
  int mode = 0;
  std::vector<Triangle> triangles;
  std::vector<std::pair<btVector3, btVector3>> lines;
  std::vector<std::pair<btVector3, btScalar>> spheres;
  std::vector<ContactPoint> contacts;
  std::vector<std::pair<btVector3, btVector3>> boxes;

  void drawLine(const btVector3& from, const btVector3& to, const btVector3&) override {
    lines.emplace_back(from, to);
  }
  void drawTriangle(const btVector3& a, const btVector3& b, const btVector3& c, const btVector3& n0,
                    const btVector3&, const btVector3&, const btVector3&, btScalar) override {
    triangles.push_back({a, b, c, n0});
  }
  void drawSphere(const btVector3& p, btScalar radius, const btVector3&) override {
    spheres.emplace_back(p, radius);
  }
  void drawContactPoint(const btVector3& point, const btVector3& normal, btScalar distance, int,
                        const btVector3&) override {
    contacts.push_back({point, normal, distance});
  }
  void drawAabb(const btVector3& from, const btVector3& to, const btVector3&) override {
    boxes.emplace_back(from, to);
  }
  void reportErrorWarning(const char*) override {}
  void draw3dText(const btVector3&, const char*) override {}
  void setDebugMode(int m) override { mode = m; }
  int getDebugMode() const override { return mode; }
  void clear() {
    triangles.clear();
    lines.clear();
    spheres.clear();
    contacts.clear();
    boxes.clear();
  }
};

/// The canonical cape pinned by its top corners to a kinematic bar, hanging over a static ball 0.2 m in
/// front of the bar's line, stepped for a second.
struct DrapedCape {
  World w;
  btRigidBody* bar = nullptr;
  btVector3 ballCentre{0, btScalar(0.9), btScalar(0.12)};
  btScalar ballRadius = btScalar(0.15);
  std::unique_ptr<CapeAction> action;
  DrapedCape() {
    bar = w.addKinematic(new btBoxShape(btVector3(btScalar(0.4), btScalar(0.02), btScalar(0.02))),
                         btTransform(btQuaternion::getIdentity(), btVector3(0, btScalar(1.55), 0)));
    w.addStatic(new btSphereShape(ballRadius), btTransform(btQuaternion::getIdentity(), ballCentre));
    action = std::make_unique<CapeAction>(
        cornerFabric(), cape::CapeSettings(),
        btTransform(btQuaternion::getIdentity(), btVector3(btScalar(-0.3), btScalar(1.5), 0)));
    EXPECT_TRUE(action->ok());
    EXPECT_EQ(action->attachNearest(bar, btVector3(btScalar(-0.3), btScalar(1.5), 0)), 0u);
    EXPECT_EQ(action->attachNearest(bar, btVector3(btScalar(0.3), btScalar(1.5), 0)), 19u);
    w.world->addAction(action.get());
    for (int frame = 0; frame < 60; ++frame) w.world->stepSimulation(kFrame, 8, kFixed);
  }
  ~DrapedCape() { w.world->removeAction(action.get()); }
};

btScalar distance(const btVector3& a, const btVector3& b) {
  return (a - b).length();
}

}  // namespace

TEST(DebugDraw, EveryTriangleIsDrawnFilledWithItsCounterClockwiseNormal) {
  DrapedCape scene;
  RecordingDrawer drawer;
  drawer.mode = 0;
  scene.action->debugDraw(&drawer);
  const std::vector<std::uint32_t>& tri = scene.action->cape().fabric().triangles();
  ASSERT_EQ(drawer.triangles.size(), tri.size() / 3);
  EXPECT_TRUE(drawer.lines.empty()) << "edges only with DBG_DrawWireframe";
  EXPECT_TRUE(drawer.contacts.empty()) << "contacts only with DBG_DrawContactPoints";
  EXPECT_TRUE(drawer.boxes.empty());
  for (std::size_t k = 0; k < drawer.triangles.size(); ++k) {
    const RecordingDrawer::Triangle& t = drawer.triangles[k];
    EXPECT_EQ(t.a, scene.action->position(tri[3 * k]));
    EXPECT_EQ(t.b, scene.action->position(tri[3 * k + 1]));
    EXPECT_EQ(t.c, scene.action->position(tri[3 * k + 2]));
    const btVector3 cross = (t.b - t.a).cross(t.c - t.a);
    EXPECT_NEAR(t.normal.length(), 1.0, 1e-5);
    EXPECT_GT(t.normal.dot(cross.normalized()), btScalar(0.9999)) << "triangle " << k;
  }
}

TEST(DebugDraw, PinsAreDrawnAtTheirTargets) {
  DrapedCape scene;
  RecordingDrawer drawer;
  scene.action->debugDraw(&drawer);
  ASSERT_EQ(drawer.spheres.size(), 2u);
  for (const auto& [centre, radius] : drawer.spheres) {
    EXPECT_GT(radius, btScalar(0));
    // At a pinned particle, which the bar carries at the attachment points.
    bool atAPin = false;
    for (const cape::bullet::Attachment& a : scene.action->attachments())
      atAPin = atAPin || distance(centre, scene.action->position(a.particle)) < btScalar(1e-4);
    EXPECT_TRUE(atAPin) << centre.x() << " " << centre.y() << " " << centre.z();
  }
}

TEST(DebugDraw, ContactPointsOnTheBallWhenTheDrawerAsksForThem) {
  DrapedCape scene;
  RecordingDrawer drawer;
  drawer.mode = btIDebugDraw::DBG_DrawContactPoints;
  scene.action->debugDraw(&drawer);
  ASSERT_FALSE(drawer.contacts.empty()) << "the cape drapes over the ball";
  int onBall = 0;
  for (const RecordingDrawer::ContactPoint& c : drawer.contacts) {
    // Every contact is on a collider's surface with its outward normal: here on the ball (or the bar).
    if (std::abs(distance(c.point, scene.ballCentre) - scene.ballRadius) < btScalar(1e-4)) {
      ++onBall;
      EXPECT_GT(c.normal.dot((c.point - scene.ballCentre).normalized()), btScalar(0.999));
    }
    EXPECT_NEAR(c.normal.length(), 1.0, 1e-5);
    EXPECT_LT(c.distance, btScalar(0.05));
    EXPECT_GT(c.distance, btScalar(-1e-3)) << "no particle is inside";
  }
  EXPECT_GT(onBall, 5);
}

TEST(DebugDraw, WireframeNormalsAndBoundsByTheDebugMode) {
  DrapedCape scene;
  RecordingDrawer drawer;
  drawer.mode = btIDebugDraw::DBG_DrawWireframe;
  scene.action->debugDraw(&drawer);
  const std::size_t triangles = scene.action->cape().fabric().triangles().size() / 3;
  EXPECT_EQ(drawer.lines.size(), 3 * triangles);
  drawer.clear();
  drawer.mode = btIDebugDraw::DBG_DrawNormals;
  scene.action->debugDraw(&drawer);
  ASSERT_EQ(drawer.lines.size(), triangles);
  for (const auto& [from, to] : drawer.lines) EXPECT_NEAR(distance(from, to), 0.05, 1e-5);
  drawer.clear();
  drawer.mode = btIDebugDraw::DBG_DrawAabb;
  scene.action->debugDraw(&drawer);
  ASSERT_EQ(drawer.boxes.size(), 1u);
  const auto& [lo, hi] = drawer.boxes[0];
  for (std::uint32_t i = 0; i < scene.action->particleCount(); ++i) {
    const btVector3 p = scene.action->position(i);
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_LE(lo[axis], p[axis] + btScalar(1e-5));
      EXPECT_GE(hi[axis], p[axis] - btScalar(1e-5));
    }
  }
}

TEST(DebugDraw, TheWorldsDebugDrawWorldDrawsTheCape) {
  DrapedCape scene;
  RecordingDrawer drawer;
  drawer.mode = btIDebugDraw::DBG_DrawWireframe | btIDebugDraw::DBG_DrawContactPoints;
  scene.w.world->setDebugDrawer(&drawer);
  scene.w.world->debugDrawWorld();
  scene.w.world->setDebugDrawer(nullptr);
  EXPECT_EQ(drawer.triangles.size(), scene.action->cape().fabric().triangles().size() / 3);
  EXPECT_FALSE(drawer.contacts.empty());
}
