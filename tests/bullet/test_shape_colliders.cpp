// Bullet shapes -> core colliders: sizes with scaling and margins, axes, compound transforms, and the
// signed distance to Bullet's own surfaces against closed forms.
#include "cape/bullet/Convert.h"
#include "cape/bullet/ShapeColliders.h"

#include <btBulletCollisionCommon.h>
#include <gtest/gtest.h>

#include <BulletCollision/CollisionShapes/btTriangleShape.h>

#include <memory>

using cape::ColliderShape;
using cape::bullet::convertShape;

TEST(ShapeColliders, SphereRadiusWithScaling) {
  btSphereShape s(0.2f);
  s.setLocalScaling(btVector3(1.5f, 1.5f, 1.5f));
  const auto c = convertShape(&s);
  ASSERT_EQ(c.primitives.size(), 1u);
  EXPECT_EQ(c.primitives[0].collider.shape, ColliderShape::Sphere);
  EXPECT_NEAR(c.primitives[0].collider.radius, 0.3f, 1e-6f);
}

TEST(ShapeColliders, BoxHalfExtentsIncludeTheMarginAndScaling) {
  btBoxShape b(btVector3(0.1f, 0.2f, 0.3f));  // margin 0.04 inside these extents
  b.setLocalScaling(btVector3(2, 1, 1));
  const auto c = convertShape(&b);
  ASSERT_EQ(c.primitives.size(), 1u);
  EXPECT_EQ(c.primitives[0].collider.shape, ColliderShape::Box);
  EXPECT_NEAR(c.primitives[0].collider.halfExtents.x(), 0.2f, 1e-5f);
  EXPECT_NEAR(c.primitives[0].collider.halfExtents.y(), 0.2f, 1e-5f);
  EXPECT_NEAR(c.primitives[0].collider.halfExtents.z(), 0.3f, 1e-5f);
}

TEST(ShapeColliders, CapsulesAndCylindersOnEveryAxis) {
  btCapsuleShapeX cx(0.1f, 0.4f);
  btCapsuleShape cy(0.1f, 0.4f);
  btCapsuleShapeZ cz(0.1f, 0.4f);
  const btCollisionShape* capsules[3] = {&cx, &cy, &cz};
  for (int axis = 0; axis < 3; ++axis) {
    const auto c = convertShape(capsules[axis]);
    ASSERT_EQ(c.primitives.size(), 1u);
    EXPECT_EQ(c.primitives[0].collider.shape, ColliderShape::Capsule);
    EXPECT_EQ(c.primitives[0].collider.axis, axis);
    EXPECT_NEAR(c.primitives[0].collider.radius, 0.1f, 1e-6f);
    EXPECT_NEAR(c.primitives[0].collider.halfHeight, 0.2f, 1e-6f);  // half the distance between the centres
  }
  btCylinderShapeX yx(btVector3(0.3f, 0.1f, 0.1f));
  btCylinderShape yy(btVector3(0.1f, 0.3f, 0.1f));
  btCylinderShapeZ yz(btVector3(0.1f, 0.1f, 0.3f));
  const btCollisionShape* cylinders[3] = {&yx, &yy, &yz};
  for (int axis = 0; axis < 3; ++axis) {
    const auto c = convertShape(cylinders[axis]);
    ASSERT_EQ(c.primitives.size(), 1u);
    EXPECT_EQ(c.primitives[0].collider.shape, ColliderShape::Cylinder);
    EXPECT_EQ(c.primitives[0].collider.axis, axis);
    EXPECT_NEAR(c.primitives[0].collider.radius, 0.1f, 1e-5f);
    EXPECT_NEAR(c.primitives[0].collider.halfHeight, 0.3f, 1e-5f);
  }
  // A capsule scaled along its axis and across it.
  btCapsuleShape scaled(0.1f, 0.4f);
  scaled.setLocalScaling(btVector3(2, 3, 2));
  const auto c = convertShape(&scaled);
  EXPECT_NEAR(c.primitives[0].collider.radius, 0.2f, 1e-5f);
  EXPECT_NEAR(c.primitives[0].collider.halfHeight, 0.6f, 1e-5f);
}

TEST(ShapeColliders, NestedCompoundComposesChildTransforms) {
  btSphereShape sphere(0.1f);
  btCompoundShape inner;
  inner.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(0, 0.5f, 0)), &sphere);
  btCompoundShape outer;
  outer.addChildShape(btTransform(btQuaternion(btVector3(0, 0, 1), SIMD_HALF_PI), btVector3(1, 0, 0)),
                      &inner);
  const auto c = convertShape(&outer);
  ASSERT_EQ(c.primitives.size(), 1u);
  // Rotating (0, 0.5, 0) by 90 degrees about Z gives (-0.5, 0, 0); then the offset (1, 0, 0).
  const btVector3 centre = c.primitives[0].local.getOrigin();
  EXPECT_NEAR(centre.x(), 0.5f, 1e-6f);
  EXPECT_NEAR(centre.y(), 0.0f, 1e-6f);
}

TEST(ShapeColliders, MultiSpherePlaneConvexMeshAndEmpty) {
  const btVector3 centres[2] = {btVector3(-0.2f, 0, 0), btVector3(0.2f, 0, 0)};
  const btScalar radii[2] = {0.1f, 0.15f};
  btMultiSphereShape multi(centres, radii, 2);
  auto m = convertShape(&multi);
  ASSERT_EQ(m.primitives.size(), 3u);  // the two spheres and the sampled hull between them
  EXPECT_EQ(m.primitives[2].collider.shape, ColliderShape::ConvexHull);
  EXPECT_NEAR(m.primitives[1].collider.radius, 0.15f, 1e-6f);
  EXPECT_NEAR(m.primitives[1].local.getOrigin().x(), 0.2f, 1e-6f);

  btStaticPlaneShape plane(btVector3(0, 1, 0), 0.5f);
  auto p = convertShape(&plane);
  ASSERT_EQ(p.primitives.size(), 1u);
  EXPECT_EQ(p.primitives[0].collider.shape, ColliderShape::Plane);
  EXPECT_NEAR(p.primitives[0].collider.constant, 0.5f, 1e-6f);

  // Any other convex shape: its support mapping sampled into a hull, whose every vertex lies on the
  // shape's surface without margin (the margin is the collider's thickness).
  btConeShape cone(0.2f, 0.5f);
  auto k = convertShape(&cone);
  ASSERT_EQ(k.primitives.size(), 1u);
  const cape::Collider& hull = k.primitives[0].collider;
  ASSERT_EQ(hull.shape, ColliderShape::ConvexHull);
  EXPECT_TRUE(hull.hull->validate().ok());
  EXPECT_FLOAT_EQ(hull.thickness, float(cone.getMargin()));
  for (const cape::Vec3& v : hull.hull->vertices) {
    EXPECT_LE(v.y(), 0.25f + 1e-5f);
    EXPECT_GE(v.y(), -0.25f - 1e-5f);
    // Inside the cone without margin: radius at height y is 0.2 (0.25 - y) / 0.5.
    EXPECT_LE(std::hypot(v.x(), v.z()), 0.2f * (0.25f - v.y()) / 0.5f + 1e-4f) << v.transpose();
  }
  // A flat shape (a triangle) has no volume: reported, not collided with.
  btTriangleShape flat(btVector3(0, 0, 0), btVector3(1, 0, 0), btVector3(0, 0, 1));
  auto f = convertShape(&flat);
  EXPECT_TRUE(f.primitives.empty());
  EXPECT_EQ(f.unsupported.size(), 1u);

  btEmptyShape empty;
  auto e = convertShape(&empty);
  EXPECT_TRUE(e.empty());
  EXPECT_TRUE(e.unsupported.empty());
}

TEST(ShapeColliders, SignedDistanceToBulletSurfacesMatchesClosedForms) {
  const btTransform at(btQuaternion(btVector3(0, 1, 0), 0.4f), btVector3(1, 2, 3));
  btSphereShape sphere(0.3f);
  EXPECT_NEAR(cape::bullet::shapeSignedDistance(&sphere, at, at * btVector3(0, 0.5f, 0)), 0.2f, 1e-4f);
  btBoxShape box(btVector3(0.2f, 0.3f, 0.4f));
  EXPECT_NEAR(cape::bullet::shapeSignedDistance(&box, at, at * btVector3(0, 0.5f, 0)), 0.2f, 1e-4f);
  EXPECT_NEAR(cape::bullet::shapeSignedDistance(&box, at, at * btVector3(0, 0.25f, 0)), -0.05f, 1e-4f);
  btCapsuleShape capsule(0.1f, 0.4f);
  EXPECT_NEAR(cape::bullet::shapeSignedDistance(&capsule, at, at * btVector3(0.3f, 0.1f, 0)), 0.2f, 1e-4f);
  EXPECT_NEAR(cape::bullet::shapeSignedDistance(&capsule, at, at * btVector3(0, 0.5f, 0)), 0.2f, 1e-4f);
  btStaticPlaneShape plane(btVector3(0, 1, 0), 0.5f);
  EXPECT_NEAR(cape::bullet::shapeSignedDistance(&plane, btTransform::getIdentity(), btVector3(3, 0.2f, 1)),
              -0.3f, 1e-6f);
}
