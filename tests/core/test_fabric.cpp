// Fabric: topology and rest state of grids and meshes (docs/SCENES.md "The cape").
#include "CapeTestFixture.h"

#include <map>
#include <set>
#include <utility>

namespace cape {
namespace {

using test::makeGrid;
using test::row;

constexpr SpringFamily kFamilies[] = {SpringFamily::Structural, SpringFamily::Shear, SpringFamily::Bend};

// Every colour of every family: no particle appears twice; the offsets cover the family exactly.
void expectColoursShareNoParticle(const Fabric& f) {
  for (SpringFamily fam : kFamilies) {
    const SpringSet& set = f.springs(fam);
    if (set.size() == 0) continue;
    ASSERT_GE(set.colourStart.size(), 2u) << toString(fam);
    EXPECT_EQ(set.colourStart.front(), 0u) << toString(fam);
    EXPECT_EQ(set.colourStart.back(), set.size()) << toString(fam);
    for (std::size_t c = 0; c < set.colourCount(); ++c) {
      std::set<std::uint32_t> seen;
      EXPECT_LE(set.colourStart[c], set.colourStart[c + 1]);
      for (std::size_t s = set.colourStart[c]; s < set.colourStart[c + 1]; ++s) {
        EXPECT_TRUE(seen.insert(set.first[s]).second)
            << toString(fam) << " colour " << c << " particle " << set.first[s];
        EXPECT_TRUE(seen.insert(set.second[s]).second)
            << toString(fam) << " colour " << c << " particle " << set.second[s];
      }
    }
  }
}

// Rest lengths are > 0 and equal the distance between the ends at rest.
void expectRestLengths(const Fabric& f) {
  for (SpringFamily fam : kFamilies) {
    const SpringSet& set = f.springs(fam);
    ASSERT_EQ(set.restLength.size(), set.size());
    for (std::size_t s = 0; s < set.size(); ++s) {
      const float d = (row(f.restPositions(), set.first[s]) - row(f.restPositions(), set.second[s])).norm();
      EXPECT_GT(set.restLength[s], 0.0f);
      EXPECT_NEAR(set.restLength[s], d, 1e-6f * (1.0f + d));
    }
  }
}

class GridSizes : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(GridSizes, KingsGraphCountsTrianglesAndMasses) {
  const auto [n, m] = GetParam();  // columns, rows
  const float width = 0.6f, height = 1.0f, mass = 0.4f;
  FabricPtr f = makeGrid(n, m, width, height, mass, /*bend=*/true);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->particleCount(), static_cast<std::size_t>(n * m));
  EXPECT_EQ(f->gridColumns(), n);
  EXPECT_EQ(f->gridRows(), m);

  const std::size_t structural = f->springs(SpringFamily::Structural).size();
  const std::size_t shear = f->springs(SpringFamily::Shear).size();
  EXPECT_EQ(static_cast<long>(structural + shear), kingsGraphSpringCount(n, m));
  EXPECT_EQ(static_cast<long>(structural + shear), 4L * n * m - 3L * (n + m) + 2);
  EXPECT_EQ(structural, static_cast<std::size_t>(n * (m - 1) + m * (n - 1)));
  EXPECT_EQ(shear, static_cast<std::size_t>(2 * (n - 1) * (m - 1)));
  // Bend: every second particle along rows (m rows of n - 2) and columns (n columns of m - 2).
  EXPECT_EQ(f->springs(SpringFamily::Bend).size(), static_cast<std::size_t>(m * (n - 2) + n * (m - 2)));
  EXPECT_EQ(f->springCount(), structural + shear + f->springs(SpringFamily::Bend).size());

  FabricPtr noBend = makeGrid(n, m, width, height, mass, /*bend=*/false);
  ASSERT_TRUE(noBend);
  EXPECT_EQ(noBend->springs(SpringFamily::Bend).size(), 0u);
  EXPECT_EQ(static_cast<long>(noBend->springCount()), kingsGraphSpringCount(n, m));

  // Triangles: 2 per cell, counter-clockwise seen from +Z, each half a cell, together the whole sheet.
  ASSERT_EQ(f->triangleCount(), static_cast<std::size_t>(2 * (n - 1) * (m - 1)));
  const float cellArea = width / static_cast<float>(n - 1) * height / static_cast<float>(m - 1);
  double area = 0.0;
  const auto& tri = f->triangles();
  for (std::size_t t = 0; t < f->triangleCount(); ++t) {
    const Vec3 a = row(f->restPositions(), tri[3 * t]), b = row(f->restPositions(), tri[3 * t + 1]),
               c = row(f->restPositions(), tri[3 * t + 2]);
    const Vec3 normal = (b - a).cross(c - a);
    EXPECT_GT(normal.z(), 0.0f) << "triangle " << t << " is clockwise seen from +Z";
    EXPECT_NEAR(normal.z(), cellArea, 1e-4f * cellArea);
    area += 0.5 * normal.z();
  }
  EXPECT_NEAR(area, width * height, 1e-4 * width * height);

  expectRestLengths(*f);
  expectColoursShareNoParticle(*f);
  EXPECT_NEAR(f->totalMass(), mass, 1e-5f * mass);
  EXPECT_TRUE((f->masses().array() > 0.0f).all());
  EXPECT_EQ(f->tethers().size(), 0u) << "no anchors given, so no tethers";
  EXPECT_NEAR(f->restDiameter(), std::hypot(width, height), 1e-5f);
}

INSTANTIATE_TEST_SUITE_P(Fabric, GridSizes,
                         ::testing::Values(std::make_pair(2, 2), std::make_pair(3, 5), std::make_pair(20, 20),
                                           std::make_pair(32, 17), std::make_pair(64, 64)),
                         [](const auto& info) {
                           return std::to_string(info.param.first) + "x" + std::to_string(info.param.second);
                         });

TEST(Fabric, GridLayoutIsRowMajorFromTheTopLeft) {
  FabricPtr f = makeGrid(4, 3, 0.6f, 1.0f);
  ASSERT_TRUE(f);
  // Particle (r, c) = r * columns + c at (c * w / (n - 1), -r * h / (m - 1), 0).
  EXPECT_TRUE(row(f->restPositions(), 0).isApprox(Vec3(0, 0, 0)));
  EXPECT_NEAR((row(f->restPositions(), 3) - Vec3(0.6f, 0.0f, 0.0f)).norm(), 0.0f, 1e-6f);
  EXPECT_NEAR((row(f->restPositions(), 2 * 4 + 1) - Vec3(0.2f, -1.0f, 0.0f)).norm(), 0.0f, 1e-6f);
}

TEST(Fabric, TethersOnlyWithAnchors) {
  const int n = 6;
  FabricPtr plain = makeGrid(n, n);
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->tethers().size(), 0u);

  GridDesc g;
  g.columns = g.rows = n;
  g.tetherAnchors = {0, static_cast<std::uint32_t>(n - 1)};
  g.tethersPerParticle = 2;
  g.tetherScale = 1.1f;
  FabricResult r = Fabric::grid(g);
  ASSERT_TRUE(r) << r.status.message();
  const TetherSet& t = r.fabric->tethers();
  // Every particle but the two anchors tethers to both anchors.
  EXPECT_EQ(t.size(), static_cast<std::size_t>((n * n - 2) * 2));
  for (std::size_t k = 0; k < t.size(); ++k) {
    EXPECT_TRUE(t.anchor[k] == 0u || t.anchor[k] == static_cast<std::uint32_t>(n - 1));
    EXPECT_NE(t.particle[k], t.anchor[k]);
    const float d =
        (row(r.fabric->restPositions(), t.particle[k]) - row(r.fabric->restPositions(), t.anchor[k])).norm();
    EXPECT_NEAR(t.maxLength[k], 1.1f * d, 1e-5f);
  }

  g.tethersPerParticle = 1;
  r = Fabric::grid(g);
  ASSERT_TRUE(r);
  EXPECT_EQ(r.fabric->tethers().size(), static_cast<std::size_t>(n * n - 2));
}

// Unique undirected edges of a triangle list, with how many triangles use each.
std::map<std::pair<std::uint32_t, std::uint32_t>, int> edgeUse(const std::vector<std::uint32_t>& tri) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> use;
  for (std::size_t t = 0; t + 2 < tri.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      std::uint32_t a = tri[t + k], b = tri[t + (k + 1) % 3];
      if (a > b) std::swap(a, b);
      ++use[{a, b}];
    }
  return use;
}

void expectMeshFabricMatchesEdges(const MeshDesc& d) {
  FabricResult r = Fabric::fromMesh(d);
  ASSERT_TRUE(r) << r.status.message();
  const Fabric& f = *r.fabric;
  const auto use = edgeUse(d.triangles);
  std::size_t interior = 0;
  for (const auto& [e, count] : use) interior += count == 2 ? 1 : 0;

  const SpringSet& structural = f.springs(SpringFamily::Structural);
  ASSERT_EQ(structural.size(), use.size());
  std::set<std::pair<std::uint32_t, std::uint32_t>> springEdges;
  for (std::size_t s = 0; s < structural.size(); ++s) {
    auto e = std::minmax(structural.first[s], structural.second[s]);
    EXPECT_TRUE(use.count({e.first, e.second})) << "structural spring on a non-edge";
    springEdges.insert({e.first, e.second});
  }
  EXPECT_EQ(springEdges.size(), use.size()) << "one structural spring per unique edge";
  EXPECT_EQ(f.springs(SpringFamily::Bend).size(), interior) << "one bend spring per interior edge";
  EXPECT_EQ(f.springs(SpringFamily::Shear).size(), 0u);
  EXPECT_EQ(f.tethers().size(), 0u);
  EXPECT_NEAR(f.totalMass(), d.totalMass, 1e-6f);
  expectRestLengths(f);
  expectColoursShareNoParticle(f);

  MeshDesc noBend = d;
  noBend.bendSprings = false;
  r = Fabric::fromMesh(noBend);
  ASSERT_TRUE(r);
  EXPECT_EQ(r.fabric->springs(SpringFamily::Bend).size(), 0u);
}

TEST(Fabric, FromMeshTwoTriangles) {
  MeshDesc d;
  d.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  d.triangles = {0, 1, 2, 0, 2, 3};
  d.totalMass = 0.6f;
  expectMeshFabricMatchesEdges(d);
  FabricResult r = Fabric::fromMesh(d);
  ASSERT_TRUE(r);
  // 5 edges, 1 interior (0-2); the bend spring joins the far vertices 1 and 3.
  EXPECT_EQ(r.fabric->springs(SpringFamily::Structural).size(), 5u);
  const SpringSet& bend = r.fabric->springs(SpringFamily::Bend);
  ASSERT_EQ(bend.size(), 1u);
  EXPECT_EQ(std::min(bend.first[0], bend.second[0]), 1u);
  EXPECT_EQ(std::max(bend.first[0], bend.second[0]), 3u);
  EXPECT_NEAR(bend.restLength[0], std::sqrt(2.0f), 1e-6f);
  // Masses by area: the shared corners 0 and 2 carry a third of both triangles, 1 and 3 of one.
  const Eigen::VectorXf& m = r.fabric->masses();
  EXPECT_NEAR(m[0], 0.2f, 1e-6f);
  EXPECT_NEAR(m[2], 0.2f, 1e-6f);
  EXPECT_NEAR(m[1], 0.1f, 1e-6f);
  EXPECT_NEAR(m[3], 0.1f, 1e-6f);
}

TEST(Fabric, FromMeshOfAGridsTriangles) {
  FabricPtr g = makeGrid(3, 3, 1.0f, 1.0f);
  ASSERT_TRUE(g);
  MeshDesc d;
  for (Eigen::Index i = 0; i < g->restPositions().rows(); ++i)
    d.positions.push_back(row(g->restPositions(), i));
  d.triangles = g->triangles();
  d.tetherAnchors = {0, 2};
  expectMeshFabricMatchesEdges([&] {
    MeshDesc noAnchors = d;
    noAnchors.tetherAnchors.clear();
    return noAnchors;
  }());
  FabricResult r = Fabric::fromMesh(d);
  ASSERT_TRUE(r);
  // 12 grid edges + 4 cell diagonals; 24 triangle edges = 2 * interior + boundary(8), so 8 interior.
  EXPECT_EQ(r.fabric->springs(SpringFamily::Structural).size(), 16u);
  EXPECT_EQ(r.fabric->springs(SpringFamily::Bend).size(), 8u);
  EXPECT_EQ(r.fabric->tethers().size(), 7u * 2u) << "tethers appear with anchors";
}

}  // namespace
}  // namespace cape
