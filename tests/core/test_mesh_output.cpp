// Render output: counter-clockwise triangles, area-weighted normals, the two-sided copy, no allocation.
#include "CapeTestFixture.h"

#include "cape/core/CapeMesh.h"
#include "cape/scenes/Scene.h"

namespace cape {
namespace {

using test::makeGrid;
using test::row;

TEST(CapeMesh, FlatGridFacesPlusZ) {
  FabricPtr f = makeGrid(5, 4);
  CapeMesh mesh;
  mesh.allocate(*f, false);
  mesh.update(*f, f->restPositions());
  ASSERT_EQ(mesh.positions.rows(), 20);
  ASSERT_EQ(mesh.indices.size(), 3u * 2u * 4u * 3u);
  ASSERT_EQ(mesh.uvs.size(), 20u);
  for (Eigen::Index i = 0; i < mesh.normals.rows(); ++i)
    EXPECT_LT((row(mesh.normals, i) - Vec3::UnitZ()).norm(), 1e-6f) << "vertex " << i;
  // Counter-clockwise seen from +Z: every triangle's (b - a) x (c - a) points to +Z.
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    const Vec3 a = row(mesh.positions, mesh.indices[t]), b = row(mesh.positions, mesh.indices[t + 1]),
               c = row(mesh.positions, mesh.indices[t + 2]);
    EXPECT_GT((b - a).cross(c - a).z(), 0.0f) << "triangle " << t / 3;
  }
}

TEST(CapeMesh, NormalsAreAreaWeighted) {
  // Two triangles sharing vertex 0: a big one in the z = 0 plane (area 2) and a small one in the x = 0 plane
  // (area 0.5, normal +X). Vertex 0's normal is the normalised sum of 2 * area * unit normal.
  Points x(5, 3);
  x << 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 1, 0, 1, 0;
  const std::vector<std::uint32_t> tri{0, 1, 2, 0, 4, 3};
  Points n(5, 3);
  computeVertexNormals(x, tri, n);
  const Vec3 expected = (Vec3(0, 0, 4) + Vec3(1, 0, 0)).normalized();
  EXPECT_LT((row(n, 0) - expected).norm(), 1e-6f) << row(n, 0).transpose();
  EXPECT_LT((row(n, 1) - Vec3::UnitZ()).norm(), 1e-6f);
  EXPECT_LT((row(n, 3) - Vec3(1, 0, 0)).norm(), 1e-6f);
}

TEST(CapeMesh, TwoSidedBackMirrorsTheFront) {
  CapeSettings s;
  SimpleScene scene(SceneKind::Walk, 8, PinLayout::Corners, s);
  ASSERT_TRUE(scene.status().ok());
  for (int i = 0; i < 30; ++i) scene.advanceFrame();  // a crumpled, moving shape
  const Fabric& f = scene.cape().fabric();
  CapeMesh one, two;
  one.allocate(f, false);
  two.allocate(f, true);
  one.update(f, scene.cape().state().positions);
  two.update(f, scene.cape().state().positions);
  const Eigen::Index n = static_cast<Eigen::Index>(f.particleCount());
  ASSERT_TRUE(two.twoSided());
  ASSERT_EQ(two.positions.rows(), 2 * n);
  ASSERT_EQ(two.indices.size(), 2 * one.indices.size());
  ASSERT_EQ(two.uvs.size(), 2 * one.uvs.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    EXPECT_EQ(row(two.positions, i), row(one.positions, i));
    EXPECT_EQ(row(two.positions, n + i), row(one.positions, i));
    EXPECT_EQ(row(two.normals, i), row(one.normals, i));
    EXPECT_EQ(row(two.normals, n + i), -row(one.normals, i));
    EXPECT_EQ(two.uvs[static_cast<std::size_t>(n + i)], one.uvs[static_cast<std::size_t>(i)]);
  }
  const std::size_t front = one.indices.size();
  for (std::size_t t = 0; t < front; t += 3) {
    EXPECT_EQ(two.indices[t], one.indices[t]);
    // The back triangle: same corners, offset by n, opposite winding.
    const auto nn = static_cast<std::uint32_t>(n);
    EXPECT_EQ(two.indices[front + t], one.indices[t] + nn);
    EXPECT_EQ(two.indices[front + t + 1], one.indices[t + 2] + nn);
    EXPECT_EQ(two.indices[front + t + 2], one.indices[t + 1] + nn);
  }
}

TEST(CapeMesh, UpdateNeverReallocates) {
  FabricPtr f = makeGrid(6, 6);
  CapeMesh mesh;
  mesh.allocate(*f, true);
  const float* p = mesh.positions.data();
  const float* n = mesh.normals.data();
  const std::uint32_t* i = mesh.indices.data();
  Points x = f->restPositions();
  for (int k = 0; k < 5; ++k) {
    x.col(2).array() += 0.01f * static_cast<float>(k);
    mesh.update(*f, x);
  }
  EXPECT_EQ(mesh.positions.data(), p);
  EXPECT_EQ(mesh.normals.data(), n);
  EXPECT_EQ(mesh.indices.data(), i);
}

}  // namespace
}  // namespace cape
