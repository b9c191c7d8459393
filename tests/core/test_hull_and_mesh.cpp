// Convex hulls and triangle meshes as first-class colliders of the core: swept inside every substep like the
// analytic shapes, with their own thickness and friction.
#include "CapeTestFixture.h"

#include <limits>

namespace cape {
namespace {

using test::makeGrid;
constexpr float kPi = 3.14159265f;

/// A box as a convex hull: its 8 corners and 6 face planes.
std::shared_ptr<const ConvexHull> boxHull(const Vec3& h) {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i)
    v.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  std::vector<Eigen::Vector4f> planes;
  for (int k = 0; k < 3; ++k)
    for (float s : {1.0f, -1.0f}) {
      Eigen::Vector4f p = Eigen::Vector4f::Zero();
      p[k] = s;
      p[3] = h[k];
      planes.push_back(p);
    }
  return ConvexHull::make(v, planes);
}

/// A regular octahedron of "radius" r (vertices on the axes): faces not aligned with any axis.
std::shared_ptr<const ConvexHull> octahedron(float r) {
  std::vector<Vec3> v{r * Vec3::UnitX(),  -r * Vec3::UnitX(), r * Vec3::UnitY(),
                      -r * Vec3::UnitY(), r * Vec3::UnitZ(),  -r * Vec3::UnitZ()};
  std::vector<Eigen::Vector4f> planes;
  for (int i = 0; i < 8; ++i) {
    const Vec3 n = Vec3(i & 1 ? 1.0f : -1.0f, i & 2 ? 1.0f : -1.0f, i & 4 ? 1.0f : -1.0f).normalized();
    planes.emplace_back(n.x(), n.y(), n.z(), r / std::sqrt(3.0f));
  }
  return ConvexHull::make(v, planes);
}

float worstDepth(const Points& x, const std::vector<Collider>& colliders) {
  float worst = 0.0f;
  for (const Collider& c : colliders)
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      worst = std::max(worst, -signedDistance(c, x.row(i).transpose()));
  return worst;
}

TEST(ConvexHullCollider, SignedDistanceIsTheBoxsInsideAndOverItsFaces) {
  const Vec3 h(0.2f, 0.1f, 0.05f);
  const Collider hull = Collider::convexHull(boxHull(h));
  const Collider box = Collider::box(h);
  ASSERT_TRUE(hull.validate().ok());
  ASSERT_TRUE(hull.hull->validate().ok());
  for (const Vec3& p :
       {Vec3(0.0f, 0.0f, 0.0f), Vec3(0.1f, 0.05f, 0.01f), Vec3(0.0f, 0.3f, 0.0f), Vec3(0.1f, 0.0f, -0.2f)})
    EXPECT_FLOAT_EQ(signedDistance(hull, p), signedDistance(box, p)) << p.transpose();
  // Beside an edge outside: a lower bound of the true distance, never more.
  const Vec3 corner(0.3f, 0.2f, 0.0f);
  EXPECT_LE(signedDistance(hull, corner), signedDistance(box, corner));
  EXPECT_GT(signedDistance(hull, corner), 0.0f);
}

TEST(ConvexHullCollider, ValidateRejectsABrokenHull) {
  EXPECT_FALSE(ConvexHull::make({Vec3::Zero()}, {}).get()->validate().ok());
  std::vector<Vec3> v{Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 5)};
  EXPECT_FALSE(octahedron(1.0f)->validate().ok() == false);  // the octahedron itself is fine
  std::vector<Eigen::Vector4f> planes = octahedron(1.0f)->planes;
  EXPECT_FALSE(ConvexHull::make(v, planes)->validate().ok());  // (0, 0, 5) lies outside
  planes[0][0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(ConvexHull::make(octahedron(1.0f)->vertices, planes)->validate().ok());
  Collider none = Collider::convexHull(nullptr);
  EXPECT_FALSE(none.validate().ok());
}

// The thin-box test of test_colliders.cpp with the box given as a hull, and an octahedron: 20 m/s, 33 cm per
// frame, 16 times the slab's thickness.
class FastHull : public ::testing::TestWithParam<int> {};

TEST_P(FastHull, At20MetresPerSecondLeavesNoParticleInside) {
  const bool slab = GetParam() == 0;
  FabricPtr fabric = makeGrid(8, 8, 0.4f, 0.4f, 0.1f, true);
  CapeSettings s = test::quietSettings();
  s.substeps = 2;
  s.collisionThickness = 0.005f;
  Cape cape(fabric, s, Pose{Vec3(-0.2f, 0.2f, 0.0f), Quat::Identity()});
  ASSERT_TRUE(cape.ok());
  Pose pose;
  pose.position = Vec3(0.0f, 0.0f, -0.3f);
  // A slab 2 cm thick, or an octahedron turned 30 degrees about Y so that its faces meet the cloth at angles.
  pose.rotation = slab ? Quat::Identity() : Quat(Eigen::AngleAxisf(0.5236f, Vec3::UnitY()));
  std::vector<Collider> colliders{
      Collider::convexHull(slab ? boxHull(Vec3(1.0f, 1.0f, 0.01f)) : octahedron(0.12f), pose)};
  const float dt = 1.0f / 60.0f;
  for (int frame = 0; frame < 6; ++frame) {
    pose.position.z() += 20.0f * dt;
    colliders[0].moveTo(pose);
    cape.step(dt, colliders);
    ASSERT_TRUE(cape.state().positions.allFinite());
    EXPECT_LE(worstDepth(cape.state().positions, colliders), 1e-4f) << "frame " << frame;
    if (slab && pose.position.z() > 0.0f) {
      EXPECT_GE(cape.state().positions.col(2).minCoeff(), pose.position.z() + 0.01f - 1e-4f)
          << "frame " << frame;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(ConvexHullCollider, FastHull, ::testing::Values(0, 1));

/// A square floor of two triangles, 4 m across, in the plane y = 0 of its frame (normal +Y by winding).
std::shared_ptr<TriangleSoup> floorSoup() {
  auto soup = std::make_shared<TriangleSoup>();
  const Vec3 a(-2, 0, -2), b(2, 0, -2), c(2, 0, 2), d(-2, 0, 2);
  soup->corners = {a, d, c, a, c, b};  // counter-clockwise seen from +Y
  return soup;
}

/// A cape lying flat (grid (x, y, 0) -> world (x, height, -y)) thrown down at `speed` onto a mesh floor
/// tilted by `tilt` rad about Z, with the floor's own friction; returns the cape after `seconds`.
struct DropResult {
  float lowest;        ///< m, the lowest particle height above the floor's plane, over the run
  float meanDownhill;  ///< m, how far the cape's centre moved along the slope
  float lateDownhill;  ///< m, the same over the second half of the run (after the landing)
};

DropResult dropOnMeshFloor(float speed, float tilt, float floorFriction, float seconds) {
  FabricPtr fabric = makeGrid(10, 10, 0.5f, 0.5f, 0.2f, true);
  CapeSettings s;
  s.collisionThickness = 0.01f;
  s.friction = 0.9f;  // the cape's own setting: the floor's must win
  const Quat slope(Eigen::AngleAxisf(tilt, Vec3::UnitZ()));
  const Pose floorPose{Vec3(0.0f, 0.0f, 0.0f), slope};
  const Pose start{slope * Vec3(-0.25f, 0.3f, 0.25f),
                   slope * Quat(Eigen::AngleAxisf(-kPi / 2.0f, Vec3::UnitX()))};
  Cape cape(fabric, s, start);
  EXPECT_TRUE(cape.ok());
  cape.mutableState().velocities.rowwise() = (slope * Vec3(0.0f, -speed, 0.0f)).transpose();
  Collider floor = Collider::triangleMesh(floorSoup(), floorPose);
  floor.friction = floorFriction;
  floor.thickness = 0.002f;
  std::vector<Collider> colliders{floor};
  const Vec3 up = slope * Vec3::UnitY(), downhill = slope * -Vec3::UnitX();
  const Vec3 centre0 = cape.state().positions.colwise().mean().transpose();
  DropResult r{std::numeric_limits<float>::infinity(), 0.0f, 0.0f};
  const int frames = static_cast<int>(std::lround(seconds * 60.0f));
  Vec3 centreHalf = centre0;
  for (int f = 0; f < frames; ++f) {
    if (f == frames / 2) centreHalf = cape.state().positions.colwise().mean().transpose();
    cape.step(1.0f / 60.0f, colliders);
    EXPECT_TRUE(cape.state().positions.allFinite());
    r.lowest = std::min(r.lowest, (cape.state().positions * up).minCoeff());
  }
  r.meanDownhill = (cape.state().positions.colwise().mean().transpose() - centre0).dot(downhill);
  r.lateDownhill = (cape.state().positions.colwise().mean().transpose() - centreHalf).dot(downhill);
  return r;
}

TEST(TriangleMeshCollider, AMeshFloorHoldsACapeDroppedAt10MetresPerSecond) {
  // 10 m/s is 17 cm per frame, 5.6 cm per substep: five times the skin. No particle gets through or into it.
  const DropResult r = dropOnMeshFloor(10.0f, 0.0f, 0.5f, 1.0f);
  EXPECT_GT(r.lowest, 0.01f - 1e-3f);
  EXPECT_LT(std::abs(r.meanDownhill), 0.01f);
}

TEST(TriangleMeshCollider, TheFloorsOwnFrictionHoldsOrLetsTheCapeSlide) {
  // On a 20-degree slope (tan 20 = 0.36): with the floor's friction 1 the cape stays, with 0 it slides
  // down, whatever the cape's own friction setting (0.9).
  const DropResult grippy = dropOnMeshFloor(2.0f, 0.349f, 1.0f, 1.0f);
  const DropResult slippery = dropOnMeshFloor(2.0f, 0.349f, 0.0f, 1.0f);
  EXPECT_GT(grippy.lowest, 0.01f - 1e-3f);
  EXPECT_GT(slippery.lowest, 0.01f - 1e-3f);
  // Landed, the grippy cape stands still (static friction); the frictionless one accelerates at g sin 20 =
  // 3.35 m/s^2: over the second half second it slides at least 3.35 * (0.5^2) / 2 = 0.42 m.
  EXPECT_LT(std::abs(grippy.lateDownhill), 0.002f);
  EXPECT_LT(grippy.meanDownhill, 0.05f);
  EXPECT_GT(slippery.lateDownhill, 0.42f);
  EXPECT_GT(slippery.meanDownhill, 0.5f);
}

TEST(TriangleMeshCollider, AThinWallOfOneTriangleCannotBePassedAt20MetresPerSecond) {
  // A single two-sided triangle standing in z = 0 and a cape flying at it along +Z at 20 m/s (33 cm a frame,
  // from 10 cm in front): every particle ends on the side it started on.
  FabricPtr fabric = makeGrid(6, 6, 0.3f, 0.3f, 0.05f, true);
  CapeSettings s = test::quietSettings();
  s.collisionThickness = 0.005f;
  s.substeps = 1;
  Cape cape(fabric, s, Pose{Vec3(-0.15f, 0.15f, -0.1f), Quat::Identity()});
  ASSERT_TRUE(cape.ok());
  cape.mutableState().velocities.col(2).setConstant(20.0f);
  auto soup = std::make_shared<TriangleSoup>();
  soup->corners = {Vec3(-2, -2, 0), Vec3(2, -2, 0), Vec3(0, 2, 0)};
  std::vector<Collider> colliders{Collider::triangleMesh(soup)};
  for (int f = 0; f < 5; ++f) {
    cape.step(1.0f / 60.0f, colliders);
    EXPECT_LE(cape.state().positions.col(2).maxCoeff(), -0.005f + 1e-4f) << "frame " << f;
  }
}

TEST(TriangleMeshCollider, AnEmptyMeshOrNoSoupIsHarmless) {
  FabricPtr fabric = makeGrid(4, 4);
  Cape cape(fabric, test::quietSettings());
  std::vector<Collider> colliders{Collider::triangleMesh(std::make_shared<TriangleSoup>()),
                                  Collider::triangleMesh(nullptr)};
  EXPECT_FALSE(colliders[1].validate().ok());
  for (int f = 0; f < 3; ++f) cape.step(1.0f / 60.0f, colliders);
  EXPECT_TRUE(cape.state().positions.allFinite());
  EXPECT_TRUE(std::isinf(signedDistance(colliders[0], Vec3::Zero())));
}

}  // namespace
}  // namespace cape
