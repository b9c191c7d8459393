// Weight maps (cape/core/WeightMap.h): a grayscale image sampled at the fabric's UVs, and a mesh's vertex
// colours, mapped onto a range; bad input refused with a message; a map drives a motion constraint.
#include "cape/core/WeightMap.h"

#include "CapeTestFixture.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace cape {
namespace {

using test::makeGrid;

// A 5 x 3 image whose value grows along x (0, 1/4, ..., 1), the same in every row: bilinear between pixel
// centres, held at the edges, so a particle at u gets clamp(5u - 1/2, 0, 4) / 4.
TEST(WeightMap, AnImageIsSampledBilinearlyAtTheUVs) {
  FabricPtr fabric = makeGrid(9, 7);
  GrayImage image;
  image.width = 5;
  image.height = 3;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) image.pixels.push_back(static_cast<float>(x) / 4.0f);
  const WeightMapResult map = weightMapFromImage(*fabric, image, 0.02f, 0.12f);
  ASSERT_TRUE(map) << map.status.message();
  ASSERT_EQ(map.values.size(), static_cast<Eigen::Index>(fabric->particleCount()));
  for (std::size_t i = 0; i < fabric->particleCount(); ++i) {
    const float u = fabric->uvs()[i].x();
    const float expected = 0.02f + 0.1f * std::clamp(5.0f * u - 0.5f, 0.0f, 4.0f) / 4.0f;
    EXPECT_NEAR(map.values[static_cast<Eigen::Index>(i)], expected, 1e-6f) << "particle " << i << ", u " << u;
  }
  // Rows: v = 0 is the image's top row (the grid's top row, the pinned one).
  GrayImage rows;
  rows.width = 1;
  rows.height = 2;
  rows.pixels = {1.0f, 0.0f};  // white at the top, black at the bottom
  const WeightMapResult top = weightMapFromImage(*fabric, rows, 0.0f, 1.0f);
  ASSERT_TRUE(top);
  EXPECT_FLOAT_EQ(top.values[0], 1.0f);  // top-left particle
  EXPECT_FLOAT_EQ(top.values[static_cast<Eigen::Index>(fabric->particleCount() - 1)], 0.0f);  // bottom-right
}

TEST(WeightMap, VertexColoursGiveTheirLuminance) {
  FabricPtr fabric = makeGrid(3, 3);
  std::vector<Vec3> colours(9, Vec3(0.0f, 0.0f, 0.0f));
  colours[4] = Vec3(1.0f, 1.0f, 1.0f);
  colours[1] = Vec3(0.0f, 1.0f, 0.0f);
  const WeightMapResult map = weightMapFromColours(*fabric, colours, 0.5f, 1.5f);
  ASSERT_TRUE(map) << map.status.message();
  EXPECT_FLOAT_EQ(map.values[0], 0.5f);
  EXPECT_FLOAT_EQ(map.values[4], 1.5f);
  EXPECT_FLOAT_EQ(map.values[1], 0.5f + 0.7152f);
}

TEST(WeightMap, BadInputIsRefusedWithAMessage) {
  FabricPtr fabric = makeGrid(3, 3);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  GrayImage image;
  image.width = 2;
  image.height = 2;
  image.pixels = {0.0f, 0.5f, 1.0f};  // one short
  EXPECT_FALSE(weightMapFromImage(*fabric, image, 0.0f, 1.0f));
  image.pixels = {0.0f, 0.5f, 1.0f, 1.5f};  // out of 0..1
  EXPECT_FALSE(weightMapFromImage(*fabric, image, 0.0f, 1.0f));
  image.pixels = {0.0f, 0.5f, 1.0f, nan};
  EXPECT_FALSE(weightMapFromImage(*fabric, image, 0.0f, 1.0f));
  image.pixels = {0.0f, 0.5f, 1.0f, 0.25f};
  EXPECT_TRUE(weightMapFromImage(*fabric, image, 0.0f, 1.0f));
  EXPECT_FALSE(weightMapFromImage(*fabric, image, 0.0f, std::numeric_limits<float>::infinity()));
  GrayImage huge;
  huge.width = 1 << 20;
  huge.height = 1 << 20;  // the size is checked before anything is read
  EXPECT_FALSE(weightMapFromImage(*fabric, huge, 0.0f, 1.0f));
  // A fabric made without UVs.
  MeshDesc d;
  d.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  d.triangles = {0, 1, 2};
  FabricResult noUv = Fabric::fromMesh(d);
  ASSERT_TRUE(noUv);
  const WeightMapResult r = weightMapFromImage(*noUv.fabric, image, 0.0f, 1.0f);
  EXPECT_FALSE(r);
  EXPECT_NE(r.status.message().find("no UVs"), std::string::npos) << r.status.message();
  EXPECT_FALSE(weightMapFromColours(*fabric, std::vector<Vec3>(8, Vec3::Zero()), 0.0f, 1.0f));
  std::vector<Vec3> colours(9, Vec3::Zero());
  colours[3].y() = nan;
  EXPECT_FALSE(weightMapFromColours(*fabric, colours, 0.0f, 1.0f));
  colours[3].y() = -0.1f;
  EXPECT_FALSE(weightMapFromColours(*fabric, colours, 0.0f, 1.0f));
}

// A painted max distance: 0 (held) at the black top of the image, 10 cm at its white bottom, read by the
// motion constraints; the top rows cannot swing, the bottom ones can.
TEST(WeightMap, APaintedMaxDistanceHoldsTheTopAndFreesTheBottom) {
  const int side = 10;
  CapeSettings s;
  Cape cape(makeGrid(side, side), s);
  GrayImage image;
  image.width = 1;
  image.height = 4;
  image.pixels = {0.0f, 0.0f, 1.0f, 1.0f};
  const WeightMapResult map = weightMapFromImage(cape.fabric(), image, 0.0f, 0.1f);
  ASSERT_TRUE(map);
  MotionConstraints c;
  c.maxDistance = map.values;
  ASSERT_TRUE(cape.setMotionConstraints(c).ok());
  const Vec3 left = test::row(cape.state().positions, 0), right = test::row(cape.state().positions, side - 1);
  const std::size_t a = cape.pin(0, left), b = cape.pin(side - 1, right);
  float topMost = 0.0f, bottomMost = 0.0f;
  for (int f = 1; f <= 90; ++f) {
    const Vec3 shift(0.3f * std::sin(0.3f * static_cast<float>(f)), 0.0f, 0.0f);
    cape.movePin(a, left + shift);
    cape.movePin(b, right + shift);
    cape.step(1.0f / 60.0f, {});
    const Points d = cape.state().positions - cape.animatedPositions();
    for (int i = 0; i < side * side; ++i) {
      const float gap = d.row(i).norm();
      EXPECT_LE(gap, map.values[i] + 1e-5f);
      if (i < side) topMost = std::max(topMost, gap);
      if (i >= side * (side - 1)) bottomMost = std::max(bottomMost, gap);
    }
  }
  EXPECT_LT(topMost, 1e-5f);
  EXPECT_GT(bottomMost, 0.05f);
}

}  // namespace
}  // namespace cape
