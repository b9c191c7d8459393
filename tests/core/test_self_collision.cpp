// Self-collision: predictive particle-triangle contacts keep a fast layer of cloth from passing through
// another, and switching them off leaves the solver exactly as it was.
#include "CapeTestFixture.h"
#include "SelfCollision.h"

#include "cape/core/Geometry.h"
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <utility>

namespace cape {
namespace {

constexpr float kPi = 3.14159265358979f;

/// Two 6 x 6 sheets, 0.3 m square, lying flat: the lower one at y = 0 (its border pinned), the upper one
/// 4 cm above it and falling at `speed` m/s: 6.7 cm per 1/60 s frame at 4 m/s, more than the gap.
struct TwoLayers {
  explicit TwoLayers(bool selfCollision, float speed = 4.0f) {
    FabricPtr grid = test::makeGrid(6, 6, 0.3f, 0.3f, 0.05f, false);
    MeshDesc d;
    const Eigen::Index n = grid->restPositions().rows();
    for (int layer = 0; layer < 2; ++layer) {
      for (Eigen::Index i = 0; i < n; ++i) {
        const Vec3 r = test::row(grid->restPositions(), i);
        d.positions.push_back(Vec3(r.x(), 0.04f * static_cast<float>(layer), r.y()));  // flat in y
      }
      for (std::uint32_t v : grid->triangles())
        d.triangles.push_back(v + static_cast<std::uint32_t>(layer * n));
    }
    d.totalMass = 0.1f;
    FabricResult r = Fabric::fromMesh(d);
    EXPECT_TRUE(r) << r.status.message();
    CapeSettings s;
    s.selfCollision = selfCollision;
    s.gravity = Vec3::Zero();
    s.useTethers = false;
    cape = std::make_unique<Cape>(r.fabric, s);
    for (int row = 0; row < 6; ++row)
      for (int col = 0; col < 6; ++col)
        if (row == 0 || row == 5 || col == 0 || col == 5) {
          const auto p = static_cast<std::uint32_t>(row * 6 + col);
          cape->pin(p, test::row(cape->state().positions, p));
        }
    for (Eigen::Index i = n; i < 2 * n; ++i) cape->mutableState().velocities(i, 1) = -speed;
    lowerCount = n;
  }
  std::unique_ptr<Cape> cape;
  Eigen::Index lowerCount = 0;
};

TEST(SelfCollision, AFastLayerDoesNotPassThroughAnother) {
  TwoLayers on(true);
  ASSERT_TRUE(on.cape->ok()) << on.cape->status().message();
  SelfIntersectionCounter counter;
  std::size_t contacts = 0;
  for (int f = 0; f < 30; ++f) {
    on.cape->step(1.0f / 60.0f, {});
    contacts = std::max(contacts, on.cape->selfContactCount());
    ASSERT_EQ(counter.count(on.cape->fabric(), on.cape->state().positions), 0) << "frame " << f;
  }
  EXPECT_GT(contacts, 0u);
  // Every particle of the upper sheet is still above the lower sheet's particle beneath it.
  const Points& x = on.cape->state().positions;
  for (Eigen::Index i = 0; i < on.lowerCount; ++i)
    EXPECT_GT(x(on.lowerCount + i, 1), x(i, 1)) << "particle " << i;

  // The same drop without self-collision goes straight through: the test can fail.
  TwoLayers off(false);
  for (int f = 0; f < 30; ++f) off.cape->step(1.0f / 60.0f, {});
  const Points& y = off.cape->state().positions;
  EXPECT_LT(y.bottomRows(off.lowerCount).col(1).mean(), y.topRows(off.lowerCount).col(1).mean());
}

/// The canonical 20 x 20 cape dropped flat from 0.5 m onto a collider standing on the ground, for 5 s;
/// returns the largest self-intersection count of any frame.
int dropOnto(const Collider& collider, bool selfCollision) {
  CapeSettings s;
  s.selfCollision = selfCollision;
  GridDesc g;
  FabricResult fabric = Fabric::grid(g);
  Cape cape(fabric.fabric, s,
            Pose{Vec3(-0.3f, 0.5f, -0.5f), Quat(Eigen::AngleAxisf(-kPi / 2.0f, Vec3::UnitX()))});
  EXPECT_TRUE(cape.ok());
  std::vector<Collider> colliders{collider, Collider::plane(Vec3::UnitY(), 0.0f)};
  SelfIntersectionCounter counter;
  int worst = 0;
  for (int f = 0; f < 5 * 60; ++f) {
    cape.step(1.0f / 60.0f, colliders);
    worst = std::max(worst, counter.count(cape.fabric(), cape.state().positions));
  }
  EXPECT_LE(maxPenetration(cape.state().positions, colliders), 1e-3f);
  return worst;
}

TEST(SelfCollision, CapeFoldedOverARodKeepsZeroSelfIntersections) {
  // A rod 0.3 m above the ground: the halves fold down either side and pile up on the ground.
  const Collider rod = Collider::capsule(0.03f, 0.5f, 0, Pose{Vec3(0.0f, 0.3f, 0.0f), Quat::Identity()});
  EXPECT_EQ(dropOnto(rod, true), 0);
  EXPECT_GT(dropOnto(rod, false), 0) << "without self-collision the folds pass through each other";
}

TEST(SelfCollision, CapeCrumpledOntoASphereKeepsZeroSelfIntersections) {
  EXPECT_EQ(dropOnto(Collider::sphere(0.15f, Pose{Vec3(0.0f, 0.2f, 0.0f), Quat::Identity()}), true), 0);
}

// The spatial hash misses nothing: after every step that searched once (at its start), every particle
// near a triangle it is not local to (a corner, or the far corner across an edge) at the start of the step
// is among the contacts. Checked by brute force over every pair while a cape folds over
// a rod and piles up on the ground.
TEST(SelfCollision, TheSearchFindsEveryNearPairThatBruteForceFinds) {
  CapeSettings s;
  s.selfCollision = true;
  Cape cape(test::makeGrid(20, 20), s,
            Pose{Vec3(-0.3f, 0.5f, -0.5f), Quat(Eigen::AngleAxisf(-kPi / 2.0f, Vec3::UnitX()))});
  ASSERT_TRUE(cape.ok());
  const std::vector<Collider> colliders{
      Collider::capsule(0.03f, 0.5f, 0, Pose{Vec3(0.0f, 0.3f, 0.0f), Quat::Identity()}),
      Collider::plane(Vec3::UnitY(), 0.0f)};
  // Each triangle's local particles: its corners and the far corners of the triangles across its edges.
  const std::vector<std::uint32_t>& tri = cape.fabric().triangles();
  const std::size_t triangles = tri.size() / 3;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::size_t>> edges;
  for (std::size_t t = 0; t < triangles; ++t)
    for (std::size_t k = 0; k < 3; ++k)
      edges[std::minmax(tri[3 * t + k], tri[3 * t + (k + 1) % 3])].push_back(t);
  std::vector<std::set<std::uint32_t>> local(triangles);
  for (std::size_t t = 0; t < triangles; ++t) local[t].insert({tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]});
  for (const auto& [edge, owners] : edges) {
    if (owners.size() != 2) continue;
    for (std::size_t k = 0; k < 2; ++k)
      for (std::size_t c = 0; c < 3; ++c) local[owners[k]].insert(tri[3 * owners[1 - k] + c]);
  }
  // The search keeps every pair that could come within the thickness, plus a quarter of the mean spacing
  // for the solver's own corrections: the solve holds contacts at the thickness, so pairs sit just beyond
  // it, and the check reaches a little farther (a fifth of the spacing).
  const SpringSet& structural = cape.fabric().springs(SpringFamily::Structural);
  float meanSpacing = 0.0f;
  for (const float l : structural.restLength) meanSpacing += l / static_cast<float>(structural.size());
  const float reach = cape.selfCollisionThickness() + 0.2f * meanSpacing;
  std::size_t checkedSteps = 0, pairsWithin = 0;
  for (int f = 0; f < 150; ++f) {
    const Points start = cape.state().positions;
    const std::uint64_t searches = cape.selfContactSearches();
    cape.step(1.0f / 60.0f, colliders);
    if (cape.selfContactSearches() != searches + 1) continue;  // a fast frame searched again mid-step
    ++checkedSteps;
    std::set<std::pair<std::uint32_t, std::uint32_t>> found;
    for (const Cape::SelfContact& k : cape.selfContacts()) found.insert({k.particle, k.triangle});
    // Every pair, with a bounding sphere first only to keep this affordable under the sanitizers (a point
    // farther than reach + radius from the centroid is farther than reach from the triangle).
    std::vector<Vec3> centroid(triangles);
    std::vector<float> radius(triangles);
    for (std::size_t t = 0; t < triangles; ++t) {
      const Vec3 a = test::row(start, tri[3 * t]), b = test::row(start, tri[3 * t + 1]),
                 c = test::row(start, tri[3 * t + 2]);
      centroid[t] = (a + b + c) / 3.0f;
      radius[t] = std::max({(a - centroid[t]).norm(), (b - centroid[t]).norm(), (c - centroid[t]).norm()});
    }
    for (Eigen::Index q = 0; q < start.rows(); ++q) {
      const Vec3 p = test::row(start, q);
      for (std::size_t t = 0; t < triangles; ++t) {
        if ((p - centroid[t]).norm() > reach + radius[t] + 1e-4f) continue;
        if (local[t].count(static_cast<std::uint32_t>(q)) != 0) continue;
        const Vec3 a = test::row(start, tri[3 * t]), b = test::row(start, tri[3 * t + 1]),
                   c = test::row(start, tri[3 * t + 2]);
        const TriangleNearest w = nearestOnTriangle(p, a, b, c);
        if ((p - (w.wa * a + w.wb * b + w.wc * c)).norm() > reach) continue;
        ++pairsWithin;
        EXPECT_EQ(found.count({static_cast<std::uint32_t>(q), static_cast<std::uint32_t>(t)}), 1u)
            << "frame " << f << ": particle " << q << " near triangle " << t << " was not found";
      }
    }
  }
  EXPECT_GT(checkedSteps, 100u);
  EXPECT_GT(pairsWithin, 100u) << "the cape should fold onto itself";
}

// A particle that is a far corner of one half of a grid cell (across the edge it shares with the next cell
// down) is not local to the other half: folded back over that half, it is a contact. The search passes over
// a cell only for the particles local to both its halves (its corners).
TEST(SelfCollision, AWingOfOneHalfOfACellFoldedOntoTheOtherHalfIsAContact) {
  // 2 x 3 particles, 0.1 m apart: cell 0 is particles 0 1 / 2 3 with triangles 0 = (2, 3, 1) and
  // 1 = (2, 1, 0); particle 4 (row 2) is the far corner of triangle 0 across its edge 2-3.
  CapeSettings s = test::quietSettings();
  s.selfCollision = true;
  Cape cape(test::makeGrid(2, 3, 0.1f, 0.2f, 0.01f, false), s);
  ASSERT_TRUE(cape.ok());
  ASSERT_EQ(cape.fabric().triangles()[3], 2u);
  ASSERT_EQ(cape.fabric().triangles()[4], 1u);
  ASSERT_EQ(cape.fabric().triangles()[5], 0u);
  // Row 2 folded up over cell 0: particle 4 just in front of triangle 1's face, particle 5 beside it.
  Points& x = cape.mutableState().positions;
  const Vec3 a = test::row(x, 0), b = test::row(x, 1), c = test::row(x, 2);
  const Vec3 over = (a + b + c) / 3.0f + Vec3(0.0f, 0.0f, 0.4f * cape.selfCollisionThickness());
  x.row(4) = over.transpose();
  x.row(5) = (over + Vec3(0.1f, 0.0f, 0.0f)).transpose();
  cape.step(1.0f / 60.0f, {});
  bool found = false;
  for (const Cape::SelfContact& k : cape.selfContacts())
    found = found || (k.particle == 4 && k.triangle == 1);
  EXPECT_TRUE(found) << "particle 4 folded onto triangle 1 is not a contact";
}

TEST(SelfCollision, ClosestPointsOfTwoSegmentsAreTheSampledMinimum) {
  // Random segments in a unit box (some short, some nearly parallel, some crossing): the closest points'
  // distance is the minimum over a fine sampling of both, never above it and at most the sampling's error
  // below; `interior` exactly when both parameters are strictly inside and the segments are not parallel.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const auto rnd = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  int interiors = 0;
  for (int k = 0; k < 400; ++k) {
    const Vec3 p0 = rnd(), q0 = rnd();
    Vec3 p1 = rnd(), q1 = rnd();
    if (k % 4 == 1) q1 = q0 + (p1 - p0) * 0.7f + Vec3::Constant(1e-5f);  // nearly parallel
    if (k % 4 == 2) p1 = p0 + 0.01f * (p1 - p0);                         // short
    float s = -1, t = -1;
    bool interior = true;
    ASSERT_TRUE(detail::closestOnSegments(p0, p1, q0, q1, s, t, interior));
    ASSERT_GE(s, 0.0f);
    ASSERT_LE(s, 1.0f);
    ASSERT_GE(t, 0.0f);
    ASSERT_LE(t, 1.0f);
    const float found = ((p0 + s * (p1 - p0)) - (q0 + t * (q1 - q0))).norm();
    float sampled = std::numeric_limits<float>::max();
    constexpr int kSamples = 400;
    for (int i = 0; i <= kSamples; ++i)
      for (int j = 0; j <= kSamples; ++j) {
        const float si = static_cast<float>(i) / kSamples, tj = static_cast<float>(j) / kSamples;
        sampled = std::min(sampled, ((p0 + si * (p1 - p0)) - (q0 + tj * (q1 - q0))).norm());
      }
    const float step = ((p1 - p0).norm() + (q1 - q0).norm()) / kSamples;
    EXPECT_LE(found, sampled + 1e-4f) << "pair " << k;  // rounding, nearly parallel ones most
    EXPECT_GE(found, sampled - step - 1e-5f) << "pair " << k;
    if (interior) {
      ++interiors;
      EXPECT_GT(s, 0.0f);
      EXPECT_LT(s, 1.0f);
      EXPECT_GT(t, 0.0f);
      EXPECT_LT(t, 1.0f);
      // The gap is along the common normal.
      const Vec3 n = (p1 - p0).cross(q1 - q0).normalized();
      const Vec3 gap = (p0 + s * (p1 - p0)) - (q0 + t * (q1 - q0));
      EXPECT_NEAR(std::abs(n.dot(gap)), gap.norm(), 1e-4f) << "pair " << k;
    }
  }
  EXPECT_GT(interiors, 20);
  // Crossing segments meet; a degenerate one has no closest points.
  float s, t;
  bool interior;
  ASSERT_TRUE(detail::closestOnSegments(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(0, 1, 0), s, t,
                                        interior));
  EXPECT_TRUE(interior);
  EXPECT_FLOAT_EQ(s, 0.5f);
  EXPECT_FLOAT_EQ(t, 0.5f);
  EXPECT_FALSE(
      detail::closestOnSegments(Vec3::Zero(), Vec3::Zero(), Vec3(0, -1, 0), Vec3(0, 1, 0), s, t, interior));
}

/// Two triangles (a, b, c) and (b, a, d) of a grid cell's size, 0.1 m: the hinge ab on the x axis, c at
/// (0.1, -0.1), d folded about ab from (0, 0.1) to `degrees` (180: onto abc, its edge b d crossing a c at
/// their midpoints). No particle is near a triangle it is not local to, so no particle-triangle contact can
/// act: only the hinge's opposite edges can keep it from folding through itself.
struct FoldedHinge {
  explicit FoldedHinge(float degrees) {
    MeshDesc d;
    d.positions = {Vec3(0, 0, 0), Vec3(0.1f, 0, 0), Vec3(0.1f, -0.1f, 0), Vec3(0, 0.1f, 0)};
    d.triangles = {0, 1, 2, 1, 0, 3};
    d.totalMass = 0.01f;
    FabricResult r = Fabric::fromMesh(d);
    EXPECT_TRUE(r) << r.status.message();
    fabric = r.fabric;
    state.positions = fabric->restPositions();
    state.positions.row(3) = wing(degrees).transpose();
    state.velocities = Points::Zero(4, 3);
    state.inverseMasses = Eigen::VectorXf::Ones(4);
  }
  static Vec3 wing(float degrees) {
    const float r = degrees * kPi / 180.0f;
    return Vec3(0.0f, 0.1f * std::cos(r), 0.1f * std::sin(r));
  }
  /// The signed distance of edge b d from edge a c along their common normal (0 where their closest points
  /// are not inside both).
  float separation() const {
    const Points& x = state.positions;
    const Vec3 a = test::row(x, 0), b = test::row(x, 1), c = test::row(x, 2), dd = test::row(x, 3);
    float s, t;
    bool interior;
    if (!detail::closestOnSegments(a, c, b, dd, s, t, interior) || !interior) return 0.0f;
    const Vec3 n = (c - a).cross(dd - b).normalized();
    return n.dot((a + s * (c - a)) - (b + t * (dd - b)));
  }
  /// One 1/60 s frame of 8 substeps driving d at a constant velocity from `from` to `to` degrees, the
  /// self-contacts searched as Cape::step searches them and solved after every substep (or not at all).
  void drive(float from, float to, bool solve) {
    constexpr float dt = 1.0f / 60.0f;
    constexpr int substeps = 8;
    const float h = dt / substeps;
    state.velocities.row(3) = ((wing(to) - wing(from)) / dt).transpose();
    CapeSettings settings = test::quietSettings();
    settings.selfCollision = true;
    const Eigen::VectorXf free = Eigen::VectorXf::Ones(4);
    detail::SelfCollision self(*fabric);
    const int every = self.schedule(state, free, settings, dt, substeps);
    for (int k = 0; k < substeps; ++k) {
      if (every > 0 && k % every == 0)
        self.searchFor(state, free, settings, h * static_cast<float>(std::min(every, substeps - k)));
      state.positions += h * state.velocities;
      if (solve) self.solve(state.positions, state.inverseMasses.data(), self.thickness(settings));
      edgeContacts = std::max(edgeContacts, self.edgeContacts().size());
      pointContacts = std::max(pointContacts, self.contacts().size());
    }
    thickness = self.thickness(settings);
  }
  FabricPtr fabric;
  CapeState state;
  std::size_t edgeContacts = 0, pointContacts = 0;
  float thickness = 0.0f;
};

// Two grid cells that share a side, folded flat over it and on, cross their diagonals in an X with every
// vertex 0.6 spacings or more from the other triangle (the sprint-turn's remaining self-intersections, in
// docs/SOLVER.md): the hinge's opposite edges are an edge-edge contact that keeps them on their sides.
TEST(SelfCollision, AHingeFoldedOnDoesNotCrossItsOppositeEdges) {
  FoldedHinge held(165.0f);
  const float before = held.separation();
  ASSERT_GT(before, 0.0f);
  held.drive(165.0f, 200.0f, true);
  EXPECT_EQ(held.pointContacts, 0u);
  EXPECT_GT(held.edgeContacts, 0u);
  const float after = held.separation();
  EXPECT_GT(after, 0.9f * detail::kEdgeThicknessFraction * held.thickness) << "before " << before;
  for (Eigen::Index i = 0; i < 4; ++i) EXPECT_TRUE(held.state.positions.row(i).allFinite());

  // The same fold without the solve crosses: the test can fail.
  FoldedHinge free(165.0f);
  free.drive(165.0f, 200.0f, false);
  EXPECT_LT(free.separation(), 0.0f);
}

/// A flat 20 x 20 grid at rest and its own search, with self-collision on.
struct FlatGridSearch {
  FlatGridSearch() : grid(test::makeGrid(20, 20)), self(*grid) {
    state.positions = grid->restPositions();
    state.velocities = Points::Zero(state.positions.rows(), 3);
    settings.selfCollision = true;
    free = Eigen::VectorXf::Ones(state.positions.rows());
  }
  /// One 1/60 s step of 4 substeps' schedule (SelfCollision::schedule).
  int schedule() { return self.schedule(state, free, settings, 1.0f / 60.0f, 4); }
  FabricPtr grid;
  detail::SelfCollision self;
  CapeState state;
  CapeSettings settings;
  Eigen::VectorXf free;
};

// An open hinge's opposite edges are out of reach: a flat grid has no edge-edge contacts, and neither has a
// hinge folded by a right angle.
TEST(SelfCollision, OpenHingesAreNoEdgeContacts) {
  for (const float degrees : {0.0f, 45.0f, 90.0f}) {
    FoldedHinge open(degrees);
    open.drive(degrees, degrees + 5.0f, true);
    EXPECT_EQ(open.edgeContacts, 0u) << degrees << " degrees";
  }
  // Every hinge of a grid has two pairs of opposite edges: 20 x 20 has 19 * 19 * 3 - 2 * 19 interior edges.
  FlatGridSearch flat;
  EXPECT_EQ(flat.schedule(), 0);
  EXPECT_EQ(flat.self.edgePairs().size(), 2u * (19u * 19u * 3u - 2u * 19u));
  EXPECT_TRUE(flat.self.edgeContacts().empty());
}

// The search sizes its scratch at its first search if nothing has (Cape does it when self-collision is
// turned on), and the next searches on the same cape do not grow it.
TEST(SelfCollision, TheSearchScratchIsAllocatedAtTheFirstSearch) {
  FlatGridSearch flat;
  EXPECT_EQ(flat.self.scratchBytes(), 0u);
  EXPECT_EQ(flat.schedule(), 0);
  const std::size_t first = flat.self.scratchBytes();
  // At least the contacts' reserve (32 per particle) and the hash (two buckets per particle).
  EXPECT_GE(first, 400u * (32u * sizeof(Cape::SelfContact) + 2u * sizeof(std::uint32_t)));
  for (int f = 1; f <= 10; ++f) {
    flat.state.time = f / 60.0;
    flat.state.positions.col(1).array() -= 0.001f * static_cast<float>(f);
    EXPECT_EQ(flat.schedule(), 0);
  }
  EXPECT_EQ(flat.self.searches(), 11u);
  EXPECT_EQ(flat.self.scratchBytes(), first);
}

// A cape holds the scratch only with self-collision on, and gets it when it is turned on, not at a step.
TEST(SelfCollision, ACapeHoldsTheSearchScratchOnlyWithSelfCollisionOn) {
  CapeSettings off = test::quietSettings();
  Cape cape(test::makeGrid(20, 20), off);
  ASSERT_TRUE(cape.ok());
  for (int f = 0; f < 5; ++f) cape.step(1.0f / 60.0f, {});
  EXPECT_EQ(cape.selfCollisionScratchBytes(), 0u);
  CapeSettings on = off;
  on.selfCollision = true;
  ASSERT_TRUE(cape.setSettings(on).ok());
  const std::size_t bytes = cape.selfCollisionScratchBytes();
  EXPECT_GT(bytes, 400u * 32u * sizeof(Cape::SelfContact));
  EXPECT_EQ(cape.selfContactSearches(), 0u);
  for (int f = 0; f < 5; ++f) cape.step(1.0f / 60.0f, {});
  EXPECT_GT(cape.selfContactSearches(), 0u);
  EXPECT_EQ(cape.selfCollisionScratchBytes(), bytes);
  Cape born(test::makeGrid(20, 20), on);
  EXPECT_EQ(born.selfCollisionScratchBytes(), bytes);
}

TEST(SelfCollision, NeighboursAreNeverContactsOnAFlatCape) {
  CapeSettings s;
  s.selfCollision = true;
  SimpleScene scene(SceneKind::Hang, 20, PinLayout::Corners, s);
  scene.advanceFrame();
  // Falling flat from horizontal: every particle moves with its neighbours, no fold is near.
  EXPECT_EQ(scene.cape().selfContactCount(), 0u);
}

// The other half of a grid cell is the nearest triangle a particle does not belong to: 2.71 cm from it
// on this 0.6 m x 1.0 m grid (cells 3.16 x 5.26 cm), where the next nearest are 3.16 cm away. With a
// thickness of 1.9 cm the search reaches 2.95 cm: the halves are excluded by topology (their particle
// reaches them only by folding the cell flat), the rest are out of reach, so a flat cape has no contacts.
TEST(SelfCollision, TheOtherHalfOfAGridCellIsNeverAContact) {
  CapeSettings s;
  s.selfCollision = true;
  s.selfCollisionThickness = 0.019f;
  Cape cape(test::makeGrid(20, 20), s);
  ASSERT_TRUE(cape.ok());
  cape.pin(0, test::row(cape.state().positions, 0));
  cape.pin(19, test::row(cape.state().positions, 19));
  cape.step(1.0f / 60.0f, {});
  EXPECT_EQ(cape.selfContactCount(), 0u);
  EXPECT_EQ(cape.selfContactSearches(), 1u);
}

// A frame in which particles move more than a spacing is searched again every few substeps, each search
// with that stretch's motion. Relative to the two sheets' mean motion, the upper one at 12 m/s moves 10 cm
// in the first frame (mean edge 6.7 cm: the mesh's diagonals are edges too); at 0.5 m/s, 0.4 cm.
TEST(SelfCollision, AFastFrameIsSearchedEveryFewSubsteps) {
  TwoLayers fast(true, 12.0f);
  ASSERT_TRUE(fast.cape->ok());
  fast.cape->step(1.0f / 60.0f, {});
  EXPECT_GE(fast.cape->selfContactSearches(), 2u);
  // A calm one covers its whole frame with one search.
  TwoLayers calm(true, 0.5f);
  calm.cape->step(1.0f / 60.0f, {});
  EXPECT_EQ(calm.cape->selfContactSearches(), 1u);
}

TEST(SelfCollision, APairToldBesideAndApartIsOneTheSolveLeavesAsItIs) {
  // The solve's shortcut (detail::besideAndApart) against the full test it stands for: wherever it says
  // yes, the particle is not over the grown face by the solve's own weights, and the nearest point of the
  // triangle is at least the thickness away. Triangles of every shape (slivers too) and scale, particles
  // around them and far off.
  using detail::besideAndApart;
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(1, 1, 0);
  EXPECT_TRUE(besideAndApart(Vec3(-1, 0, 0), a, b, c, 0.35f));  // the 2-ring of a flat grid
  EXPECT_TRUE(besideAndApart(Vec3(2, 2, 0.1f), a, b, c, 0.35f));
  EXPECT_FALSE(besideAndApart(Vec3(0.6f, 0.2f, 0.5f), a, b, c, 0.35f));   // over the face
  EXPECT_FALSE(besideAndApart(Vec3(-0.2f, 0.0f, 0.0f), a, b, c, 0.35f));  // beside, within the thickness
  EXPECT_FALSE(besideAndApart(Vec3(1.2f, 0.5f, 0.0f), a, b, c, 0.35f));   // over the grown face's margin

  std::mt19937 rng(20261206);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), fraction(0.0f, 1.0f);
  int told = 0, cases = 0;
  for (int i = 0; i < 200000; ++i) {
    const float scale = std::pow(10.0f, 4.0f * fraction(rng) - 3.0f);  // 1 mm to 10 m
    const Vec3 origin = Vec3(unit(rng), unit(rng), unit(rng)) * 100.0f * fraction(rng);
    Vec3 corner[3];
    for (Vec3& k : corner) k = origin + scale * Vec3(unit(rng), unit(rng), unit(rng));
    if (i % 4 == 0)
      corner[2] = corner[0] + fraction(rng) * (corner[1] - corner[0]) +
                  1e-3f * scale * Vec3(unit(rng), unit(rng), unit(rng));  // a sliver
    const Vec3 p = origin + (i % 3 == 0 ? 8.0f : 2.0f) * scale * Vec3(unit(rng), unit(rng), unit(rng));
    const float thickness = scale * (0.05f + fraction(rng));
    ++cases;
    if (!besideAndApart(p, corner[0], corner[1], corner[2], thickness)) continue;
    ++told;
    float wa = 0, wb = 0, wc = 0;
    if (detail::planeBarycentric(p, corner[0], corner[1], corner[2], wa, wb, wc)) {
      ASSERT_TRUE(wa < -detail::kFaceMargin || wb < -detail::kFaceMargin || wc < -detail::kFaceMargin)
          << "case " << i << ": over the grown face (" << wa << ", " << wb << ", " << wc << ")";
    }
    const TriangleNearest w = nearestOnTriangle(p, corner[0], corner[1], corner[2]);
    const Vec3 nearest = w.wa * corner[0] + w.wb * corner[1] + w.wc * corner[2];
    ASSERT_GE((p - nearest).norm(), thickness) << "case " << i;
  }
  // It does tell most of such pairs: a shortcut that never said yes would pass the checks above.
  EXPECT_GT(told, cases / 10) << told << " of " << cases;
}

/// `sheets` flat 3 x 3-particle sheets of 0.1 m spacing, `gap` m above one another, sheet `moving` moving at
/// `velocity`, all turned by `turn`: the self-contacts between different sheets that one search over 1/60 s
/// finds.
std::size_t contactsBetweenSheets(int sheets, float gap, int moving, const Vec3& velocity,
                                  const Quat& turn = Quat::Identity()) {
  MeshDesc d;
  for (int sheet = 0; sheet < sheets; ++sheet) {
    const std::uint32_t first = static_cast<std::uint32_t>(d.positions.size());
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        d.positions.push_back(turn * Vec3(0.1f * static_cast<float>(j), gap * static_cast<float>(sheet),
                                          0.1f * static_cast<float>(i)));
    for (std::uint32_t i = 0; i < 2; ++i)
      for (std::uint32_t j = 0; j < 2; ++j) {
        const std::uint32_t v = first + 3 * i + j;
        d.triangles.insert(d.triangles.end(), {v, v + 1, v + 4, v, v + 4, v + 3});
      }
  }
  d.totalMass = 0.1f;
  const FabricResult fabric = Fabric::fromMesh(d);
  EXPECT_TRUE(fabric) << fabric.status.message();
  CapeSettings settings;
  settings.selfCollision = true;
  settings.gravity = Vec3::Zero();
  CapeState state;
  state.positions = fabric.fabric->restPositions();
  state.velocities = Points::Zero(state.positions.rows(), 3);
  for (Eigen::Index i = 9 * moving; i < 9 * (moving + 1); ++i)
    state.velocities.row(i) = (turn * velocity).transpose();
  state.inverseMasses = Eigen::VectorXf::Ones(state.positions.rows());
  detail::SelfCollision self(*fabric.fabric);
  self.searchFor(state, Eigen::VectorXf::Ones(state.positions.rows()), settings, 1.0f / 60.0f);
  std::size_t between = 0;
  for (const Cape::SelfContact& k : self.contacts())
    between += k.particle / 9 != fabric.fabric->triangles()[3 * k.triangle] / 9 ? 1 : 0;
  return between;
}

#if defined(__SSE2__)
TEST(SelfCollision, TheSolvesFourWideApartTestsAreTheScalarOnesLaneByLane) {
  // SelfCollision::solve passes over apart contacts four at a time (detail::apartLanes): each lane must
  // answer what the scalar test (detail::contactApart) answers, bit for bit, or the solve would differ from
  // a loop over the contacts one by one. Particles near and far, on either side or none, triangles of every
  // shape (slivers, collapsed ones), coordinates far from the origin, and some not finite.
  std::mt19937 rng(20261207);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), fraction(0.0f, 1.0f);
  std::uniform_int_distribution<int> sideOf(-1, 1);
  constexpr std::uint32_t kBlocks = 50000;
  // Every contact its own particle and triangle (particle 4k, corners 4k+1..4k+3) so that the lanes gather
  // from anywhere in the array.
  Points x(16 * kBlocks, 3);
  std::vector<std::uint32_t> triangles;
  std::vector<Cape::SelfContact> contacts;
  for (std::uint32_t i = 0; i < 4 * kBlocks; ++i) {
    const float scale = std::pow(10.0f, 3.0f * fraction(rng) - 3.0f);
    const Vec3 origin = Vec3(unit(rng), unit(rng), unit(rng)) * (i % 5 == 0 ? 1e5f : 10.0f) * fraction(rng);
    Vec3 corner[3];
    for (Vec3& k : corner) k = origin + scale * Vec3(unit(rng), unit(rng), unit(rng));
    if (i % 7 == 0) corner[2] = corner[0] + fraction(rng) * (corner[1] - corner[0]);  // on a line
    if (i % 11 == 0) corner[1] = corner[0];                                           // collapsed
    const Vec3 p = origin + (i % 3 == 0 ? 6.0f : 1.5f) * scale * Vec3(unit(rng), unit(rng), unit(rng));
    const std::uint32_t base = 4 * i;
    x.row(base) = p.transpose();
    for (int k = 0; k < 3; ++k) x.row(base + 1 + static_cast<std::uint32_t>(k)) = corner[k].transpose();
    if (i % 97 == 0)
      x(base + 1 + i % 3, static_cast<Eigen::Index>(i % 3)) = std::numeric_limits<float>::quiet_NaN();
    triangles.insert(triangles.end(), {base + 1, base + 2, base + 3});
    contacts.push_back({base, i, static_cast<float>(sideOf(rng))});
  }
  int apart = 0, near = 0;
  for (std::uint32_t block = 0; block < kBlocks; ++block) {
    // A thickness per block (the solve's is the same for all of its contacts).
    const float thickness = std::pow(10.0f, 3.0f * fraction(rng) - 3.5f);
    const int lanes = detail::apartLanes(x, triangles, &contacts[4 * block], thickness);
    for (int lane = 0; lane < 4; ++lane) {
      const Cape::SelfContact& k = contacts[4 * block + static_cast<std::uint32_t>(lane)];
      const auto at = [&](std::uint32_t i) -> Vec3 { return x.row(i).transpose(); };
      const std::uint32_t* t = &triangles[3 * k.triangle];
      const bool scalar =
          detail::contactApart(at(k.particle), at(t[0]), at(t[1]), at(t[2]), k.side, thickness);
      ASSERT_EQ((lanes >> lane & 1) != 0, scalar)
          << "contact " << 4 * block + static_cast<std::uint32_t>(lane);
      (scalar ? apart : near) += 1;
    }
  }
  // Both answers are common, so that a lane stuck at either would fail above.
  EXPECT_GT(apart, static_cast<int>(kBlocks / 2)) << apart;
  EXPECT_GT(near, static_cast<int>(kBlocks / 2)) << near;
}
#endif

TEST(SelfCollision, ASearchKeepsThePairsThatApproachAndDropsThoseThatSlidePastOrPart) {
  // The reach: the thickness (0.35 of the 0.1 m spacing) and the slack (a quarter of it), 6 cm. A sheet
  // 15 cm above another coming down at 6 m/s (10 cm in the 1/60 s window) comes within it: its pairs are
  // kept, though 15 cm apart now. One 9 cm from its neighbours, sliding between them or rising away at 6
  // m/s, never does: its swept box (10 cm along the motion) stays clear of theirs, though the pairs are
  // within the thickness, the slack and their relative motion of each other (which boxes of the motion's
  // length in every direction kept). (The middle of three sheets slides, so that the cape's fitted rigid
  // motion, which the search takes out, is a translation alone.)
  EXPECT_GT(contactsBetweenSheets(2, 0.15f, 1, Vec3(0.0f, -6.0f, 0.0f)), 0u);
  EXPECT_GT(contactsBetweenSheets(2, 0.05f, 1, Vec3::Zero()), 0u);  // within reach, still
  EXPECT_EQ(contactsBetweenSheets(2, 0.09f, 1, Vec3::Zero()), 0u);
  EXPECT_EQ(contactsBetweenSheets(2, 0.09f, 1, Vec3(0.0f, 6.0f, 0.0f)), 0u);
  EXPECT_EQ(contactsBetweenSheets(3, 0.09f, 1, Vec3(6.0f, 0.0f, 0.0f)), 0u);
  EXPECT_EQ(contactsBetweenSheets(3, 0.09f, 1, Vec3(0.0f, 0.0f, 6.0f)), 0u);
  EXPECT_GT(contactsBetweenSheets(3, 0.09f, 1, Vec3(0.0f, 3.0f, 0.0f)), 0u);  // towards the upper sheet
  // Turned 45 degrees about z and x, the approaching pairs are kept all the same.
  const Quat turn(Eigen::AngleAxisf(kPi / 4.0f, Vec3::UnitZ()) *
                  Eigen::AngleAxisf(kPi / 4.0f, Vec3::UnitX()));
  EXPECT_GT(contactsBetweenSheets(2, 0.15f, 1, Vec3(0.0f, -6.0f, 0.0f), turn), 0u);
  EXPECT_GT(contactsBetweenSheets(3, 0.09f, 1, Vec3(0.0f, 3.0f, 0.0f), turn), 0u);
}

TEST(SelfCollision, SwitchedOffTheSolverIsBitForBitUnchanged) {
  CapeSettings off;
  CapeSettings offOtherThickness = off;
  offOtherThickness.selfCollisionThickness = 0.05f;  // read only when self-collision is on
  SimpleScene a(SceneKind::SprintTurn, 16, PinLayout::Corners, off);
  SimpleScene b(SceneKind::SprintTurn, 16, PinLayout::Corners, offOtherThickness);
  for (int i = 0; i < 120; ++i) {
    a.advanceFrame();
    b.advanceFrame();
  }
  EXPECT_EQ(test::hashPoints(a.cape().state().positions), test::hashPoints(b.cape().state().positions));
  EXPECT_EQ(b.cape().selfContactCount(), 0u);
}

// A wild velocity (a teleport handled by hand, a user's bug) makes every search box huge: the search falls
// back to bounded brute force instead of walking millions of cells, and nothing turns non-finite.
TEST(SelfCollision, HugeMotionStaysBoundedAndFinite) {
  CapeSettings s;
  s.selfCollision = true;
  SimpleScene scene(SceneKind::Walk, 12, PinLayout::Corners, s);
  Points& v = scene.cape().mutableState().velocities;
  for (Eigen::Index i = 0; i < v.rows(); i += 2) v.row(i) << 400.0f, -300.0f, 500.0f;
  for (int f = 0; f < 5; ++f) scene.advanceFrame();
  EXPECT_TRUE(scene.cape().state().positions.allFinite());
}

// A cape that has already blown up (a NaN velocity, a user's bug) is left alone: no contacts, no search
// loop over a non-finite motion, no crash (the Debug + sanitizer build checks the conversions).
TEST(SelfCollision, ANonFiniteCapeFindsNoContacts) {
  CapeSettings s;
  s.selfCollision = true;
  SimpleScene scene(SceneKind::Walk, 8, PinLayout::Corners, s);
  scene.advanceFrame();
  scene.cape().mutableState().velocities(5, 1) = std::nanf("");
  scene.advanceFrame();
  EXPECT_EQ(scene.cape().selfContactCount(), 0u);
  scene.cape().mutableState().velocities(6, 0) = std::numeric_limits<float>::infinity();
  scene.advanceFrame();
  EXPECT_EQ(scene.cape().selfContactCount(), 0u);
}

TEST(SelfCollision, ThicknessIsAutomaticOrAsSetAndBadValuesAreRejected) {
  CapeSettings s;
  s.selfCollision = true;
  Cape automatic(test::makeGrid(20, 20), s);  // 0.6 m x 1.0 m: spacings 3.16 cm and 5.26 cm
  EXPECT_NEAR(automatic.selfCollisionThickness(), 0.35f * 0.5f * (0.6f / 19 + 1.0f / 19), 2e-4f);
  s.selfCollisionThickness = 0.004f;
  Cape set(test::makeGrid(20, 20), s);
  EXPECT_FLOAT_EQ(set.selfCollisionThickness(), 0.004f);
  s.selfCollisionThickness = -kPi;
  EXPECT_FALSE(s.validate().ok());
  s.selfCollisionThickness = std::nanf("");
  EXPECT_FALSE(s.validate().ok());
  s.selfCollisionThickness = 0.0f;
  EXPECT_TRUE(s.validate().ok());
}

// Every canonical scene, 10 s (hang 5 s) on the 20 x 20 cape with self-collision on: not one pair of
// triangles sharing no vertex intersects in any frame (the docs/SCENES.md metric), and nothing else breaks.
class SelfCollisionScenes : public ::testing::TestWithParam<SceneKind> {};

TEST_P(SelfCollisionScenes, ZeroSelfIntersectionsInEveryFrame) {
  CapeSettings s;
  s.selfCollision = true;
  SimpleScene scene(GetParam(), 20, PinLayout::Corners, s);
  ASSERT_TRUE(scene.status().ok());
  SelfIntersectionCounter counter;
  MetricsRecorder rec;
  const int frames = static_cast<int>(std::lround(scene.motion().duration * 60.0));
  for (int f = 0; f < frames; ++f) {
    scene.advanceFrame();
    rec.add(measureFrame(scene.cape(), scene.body().bodyColliders(), scene.body().torsoCentre(), &counter));
  }
  const RunSummary sum = rec.summary();
  EXPECT_EQ(sum.selfIntersectionsMax, 0) << sum.framesWithSelfIntersections << " frames with any";
  EXPECT_FALSE(sum.blowUp);
  EXPECT_EQ(sum.framesPenetrationOver1mm, 0);
}

/// The most self-contacts any particle has in the last search.
std::size_t mostContactsOfOneParticle(const Cape& cape) {
  std::vector<std::size_t> count(static_cast<std::size_t>(cape.state().positions.rows()), 0);
  std::size_t most = 0;
  for (const Cape::SelfContact& k : cape.selfContacts()) most = std::max(most, ++count[k.particle]);
  return most;
}

// The bound on contacts per particle (Cape::kMaxSelfContactsPerParticle) changes nothing in a cape's scenes:
// no particle comes near it, with the canonical corners or gathered onto a collar (where the folds crowd).
TEST_P(SelfCollisionScenes, NoParticleComesNearTheBoundOnContacts) {
  for (PinLayout layout : {PinLayout::Corners, PinLayout::Gathered}) {
    CapeSettings s;
    s.selfCollision = true;
    SimpleScene scene(GetParam(), 20, layout, s);
    ASSERT_TRUE(scene.status().ok());
    std::size_t most = 0;
    const int frames = static_cast<int>(std::lround(scene.motion().duration * 60.0));
    for (int f = 0; f < frames; ++f) {
      scene.advanceFrame();
      most = std::max(most, mostContactsOfOneParticle(scene.cape()));
    }
    EXPECT_LE(2 * most, Cape::kMaxSelfContactsPerParticle)
        << (layout == PinLayout::Corners ? "corners" : "gathered");
    std::printf("%s, %s: at most %zu self-contacts of one particle\n", toString(GetParam()),
                layout == PinLayout::Corners ? "corners" : "gathered", most);
  }
}

INSTANTIATE_TEST_SUITE_P(SelfCollision, SelfCollisionScenes,
                         ::testing::Values(SceneKind::Hang, SceneKind::Walk, SceneKind::SprintTurn,
                                           SceneKind::Wind),
                         [](const auto& info) {
                           std::string name = toString(info.param);
                           name.erase(std::remove(name.begin(), name.end(), '-'), name.end());
                           return name;
                         });

/// A side x side sheet, 0.6 x 1 m, and one long triangle per vertex, from it across the sheet to the two
/// particles half the grid away (tests/fuzz/corpus.cpp's denseFabric, issue 14's hang): the long edges make
/// the mean spacing, and so the automatic thickness, about as long as the sheet.
FabricPtr denseFabric(int side) {
  MeshDesc d;
  const int n = side * side;
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c)
      d.positions.emplace_back(0.6f * static_cast<float>(c) / static_cast<float>(side - 1),
                               1.5f - static_cast<float>(r) / static_cast<float>(side - 1), 0.0f);
  for (int r = 0; r + 1 < side; ++r)
    for (int c = 0; c + 1 < side; ++c) {
      const int p = r * side + c;
      for (int v : {p, p + side, p + 1, p + 1, p + side, p + side + 1})
        d.triangles.push_back(static_cast<std::uint32_t>(v));
    }
  for (int v = 0; v < n; ++v)
    for (int k : {v, (v + n / 2) % n, (v + n / 2 + side) % n})
      d.triangles.push_back(static_cast<std::uint32_t>(k));
  d.totalMass = 0.4f;
  FabricResult made = Fabric::fromMesh(d);
  EXPECT_TRUE(made) << made.status.message();
  return made.fabric;
}

// Every particle within the thickness of nearly every triangle: a search keeps the first
// Cape::kMaxSelfContactsPerParticle of each particle, so the contacts grow with the particles, not with
// particles x triangles (32 x 32 made 2.95 million contacts and took 10 s for two frames), and the cape stays
// finite.
TEST(SelfCollision, AMeshWhoseThicknessReachesEveryTriangleKeepsTheBoundPerParticle) {
  for (int side : {12, 32}) {
    FabricPtr fabric = denseFabric(side);
    ASSERT_TRUE(fabric);
    const std::size_t n = fabric->particleCount();
    CapeSettings s;
    s.selfCollision = true;
    // As thick as the fuzz input's automatic thickness made it: every particle within reach of nearly every
    // triangle of the 0.6 x 1 m sheet.
    s.selfCollisionThickness = 0.6f;
    Cape cape(fabric, s);
    ASSERT_TRUE(cape.ok());
    cape.pin(0, test::row(cape.state().positions, 0));
    cape.pin(static_cast<std::uint32_t>(side - 1), test::row(cape.state().positions, side - 1));
    std::size_t largest = 0;
    for (int f = 0; f < 2; ++f) {
      cape.step(1.0f / 60.0f, {});
      largest = std::max(largest, cape.selfContactCount());
      EXPECT_LE(mostContactsOfOneParticle(cape), Cape::kMaxSelfContactsPerParticle);
      EXPECT_TRUE(cape.state().positions.allFinite());
    }
    // Many particles do reach the bound: without it they would have more.
    EXPECT_GT(largest, n * Cape::kMaxSelfContactsPerParticle / 2) << side;
    EXPECT_LE(largest, n * Cape::kMaxSelfContactsPerParticle) << side;
  }
}

// The flat proof's rest gaps (Fabric::FlatProof), against every particle and every triangle: grids square and
// long, coarse and fine, with and without bend springs. Each tier is the least rest distance of the pairs of
// that many king's moves, the pairs it leaves out are at least `beyond` apart, and every pair the search can
// make is in a tier or beyond.
TEST(SelfCollision, TheFlatProofsRestGapsAreTheLeastOverEveryPair) {
  struct Size {
    int columns, rows;
    float width, height;
  };
  for (const Size& g : {Size{20, 20, 0.6f, 1.0f}, Size{7, 3, 0.3f, 0.05f}, Size{3, 11, 0.02f, 0.9f},
                        Size{12, 9, 1.0f, 1.0f}, Size{2, 2, 0.1f, 0.1f}}) {
    const FabricPtr fabric = test::makeGrid(g.columns, g.rows, g.width, g.height);
    ASSERT_TRUE(fabric);
    const Fabric::FlatProof* proof = fabric->flatProof();
    ASSERT_NE(proof, nullptr);
    const Points& rest = fabric->restPositions();
    const auto at2 = [&rest](std::uint32_t i) { return Eigen::Vector2d(rest(i, 0), rest(i, 1)); };
    std::vector<double> tier(proof->particleTriangle.size(), std::numeric_limits<double>::infinity());
    const std::vector<std::uint32_t>& tri = fabric->triangles();
    // The rest distance from particle q to triangle t: 0 over it, else to the nearest of its sides.
    const auto distance = [&](std::uint32_t q, std::size_t t) {
      const Eigen::Vector2d p = at2(q), a = at2(tri[3 * t]), b = at2(tri[3 * t + 1]), c = at2(tri[3 * t + 2]);
      const Eigen::Vector2d corners[3] = {a, b, c};
      double d = std::numeric_limits<double>::infinity();
      bool inside = true;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d& e0 = corners[k];
        const Eigen::Vector2d& e1 = corners[(k + 1) % 3];
        const Eigen::Vector2d side = e1 - e0;
        inside = inside && side.x() * (p - e0).y() - side.y() * (p - e0).x() >= 0.0;  // counter-clockwise
        const double along = std::clamp((p - e0).dot(side) / side.squaredNorm(), 0.0, 1.0);
        d = std::min(d, (p - (e0 + along * side)).norm());
      }
      return inside ? 0.0 : d;
    };
    // The least distance from a particle to a triangle it is not a corner of (the count's gap), and the least
    // between two triangles that share no corner (two disjoint triangles in the plane are closest at a
    // corner).
    double notCorner = std::numeric_limits<double>::infinity(), disjoint = notCorner;
    for (std::uint32_t q = 0; q < fabric->particleCount(); ++q)
      for (std::size_t t = 0; t < fabric->triangleCount(); ++t)
        if (tri[3 * t] != q && tri[3 * t + 1] != q && tri[3 * t + 2] != q)
          notCorner = std::min(notCorner, distance(q, t));
    for (std::size_t s = 0; s < fabric->triangleCount(); ++s)
      for (std::size_t t = s + 1; t < fabric->triangleCount(); ++t) {
        const std::uint32_t* a = &tri[3 * s];
        const std::uint32_t* b = &tri[3 * t];
        if (std::find(a, a + 3, b[0]) != a + 3 || std::find(a, a + 3, b[1]) != a + 3 ||
            std::find(a, a + 3, b[2]) != a + 3)
          continue;
        for (int k = 0; k < 3; ++k) disjoint = std::min({disjoint, distance(a[k], t), distance(b[k], s)});
      }
    EXPECT_NEAR(proof->disjointTriangles, notCorner, 1e-6) << g.columns << " x " << g.rows;
    EXPECT_GT(proof->disjointTriangles, 0.0f) << g.columns << " x " << g.rows;
    if (std::isfinite(disjoint)) {
      EXPECT_LE(proof->disjointTriangles, disjoint + 1e-6) << g.columns << " x " << g.rows;
    }
    for (std::uint32_t q = 0; q < fabric->particleCount(); ++q)
      for (std::size_t t = 0; t < fabric->triangleCount(); ++t) {
        const std::uint32_t* local = fabric->triangleLocal()[t].v;
        if (std::find(local, local + 6, q) != local + 6) continue;
        const double d = distance(q, t);
        int hops = 0;
        for (int k = 0; k < 3; ++k) {
          const int v = static_cast<int>(tri[3 * t + static_cast<std::size_t>(k)]);
          hops = std::max({hops, std::abs(v / g.columns - static_cast<int>(q) / g.columns),
                           std::abs(v % g.columns - static_cast<int>(q) % g.columns)});
        }
        // Sound: the pair is at least its tier's gap apart, or `beyond`.
        const double gap = static_cast<std::size_t>(hops) < tier.size()
                               ? static_cast<double>(proof->particleTriangle[static_cast<std::size_t>(hops)])
                               : std::numeric_limits<double>::infinity();
        EXPECT_TRUE(d >= gap - 1e-6 || d >= proof->beyond - 1e-6)
            << g.columns << " x " << g.rows << ": particle " << q << ", triangle " << t << ", " << hops
            << " moves";
        if (hops <= Fabric::kProofReach)
          tier[static_cast<std::size_t>(hops)] = std::min(tier[static_cast<std::size_t>(hops)], d);
      }
    // The hinges' tiers against the search's own edge pairs: each pair at least its tier's gap apart at
    // rest, and every tier the least of some pair's.
    detail::SelfCollision search(*fabric);
    search.allocate();
    std::vector<double> edgeTier(proof->edgeEdge.size(), std::numeric_limits<double>::infinity());
    for (const detail::SelfCollision::EdgePair& e : search.edgePairs()) {
      int hops = 0;
      for (const std::uint32_t i : {e.p0, e.p1})
        for (const std::uint32_t j : {e.q0, e.q1})
          hops = std::max({hops, std::abs(static_cast<int>(i / g.columns) - static_cast<int>(j / g.columns)),
                           std::abs(static_cast<int>(i % g.columns) - static_cast<int>(j % g.columns))});
      ASSERT_LT(static_cast<std::size_t>(hops), edgeTier.size()) << g.columns << " x " << g.rows;
      // Sampled: the least distance over 201 points of each edge, within 1/200 of an edge's length above it.
      double d = std::numeric_limits<double>::infinity();
      for (int i = 0; i <= 200; ++i)
        for (int j = 0; j <= 200; ++j)
          d = std::min(d, (at2(e.p0) + (at2(e.p1) - at2(e.p0)) * (i / 200.0) -
                           (at2(e.q0) + (at2(e.q1) - at2(e.q0)) * (j / 200.0)))
                              .norm());
      const double length = std::max((at2(e.p1) - at2(e.p0)).norm(), (at2(e.q1) - at2(e.q0)).norm());
      EXPECT_GE(d, proof->edgeEdge[static_cast<std::size_t>(hops)] - 1e-6) << g.columns << " x " << g.rows;
      edgeTier[static_cast<std::size_t>(hops)] =
          std::min(edgeTier[static_cast<std::size_t>(hops)], d - length / 200.0);
    }
    for (std::size_t h = 0; h < edgeTier.size(); ++h)
      if (std::isfinite(proof->edgeEdge[h])) {
        EXPECT_GE(proof->edgeEdge[h], edgeTier[h] - 1e-6)
            << g.columns << " x " << g.rows << " edge tier " << h;
      }
    // Tight: the tiers of up to kProofReach moves take in every such pair, and are their least distance.
    for (int h = 0; h <= Fabric::kProofReach; ++h) {
      const auto k = static_cast<std::size_t>(h);
      if (std::isfinite(tier[k])) {
        EXPECT_NEAR(proof->particleTriangle[k], tier[k], 1e-6)
            << g.columns << " x " << g.rows << " tier " << h;
      } else {
        EXPECT_EQ(proof->particleTriangle[k], std::numeric_limits<float>::infinity()) << h;
      }
    }
  }
}
/// The cape of a scene's frames, searched with and without the flat proof (SelfCollision::provenApart):
/// both must find the same contacts in the same order. Returns how many searches the proof passed over.
std::uint64_t searchBothWays(SceneKind kind, int n, PinLayout layout, int frames, std::uint64_t& searches) {
  CapeSettings s;
  s.selfCollision = true;
  SimpleScene scene(kind, n, layout, s);
  EXPECT_TRUE(scene.status().ok());
  std::uint64_t proven = 0;
  for (int f = 0; f < frames; ++f) {
    scene.advanceFrame();
    const Cape& cape = scene.cape();
    const CapeSettings& settings = cape.settings();
    const Eigen::VectorXf free = (cape.state().inverseMasses.array() > 0.0f).cast<float>();
    detail::SelfCollision with(cape.fabric()), without(cape.fabric());
    without.setFlatProof(false);
    for (float window : {1.0f / 60.0f, 1.0f / 240.0f}) {
      with.searchFor(cape.state(), free, settings, window);
      without.searchFor(cape.state(), free, settings, window);
      ++searches;
      const auto& a = with.contacts();
      const auto& b = without.contacts();
      EXPECT_EQ(a.size(), b.size()) << toString(kind) << " " << n << " frame " << f;
      for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
        EXPECT_TRUE(a[i].particle == b[i].particle && a[i].triangle == b[i].triangle &&
                    a[i].side == b[i].side)
            << toString(kind) << " " << n << " frame " << f << " contact " << i;
      const auto& ea = with.edgeContacts();
      const auto& eb = without.edgeContacts();
      EXPECT_EQ(ea.size(), eb.size()) << toString(kind) << " " << n << " frame " << f;
      for (std::size_t i = 0; i < std::min(ea.size(), eb.size()); ++i)
        EXPECT_TRUE(ea[i].pair == eb[i].pair && ea[i].side == eb[i].side)
            << toString(kind) << " " << n << " frame " << f << " edge contact " << i;
    }
    proven = with.searchesProvenApart() + proven;
  }
  return proven;
}

// The flat proof passes over a search only where the search would have found nothing: every search of the
// walk, the sprint-turn and the wind, corners and gathered, 20 x 20 and 32 x 32, with the proof and without,
// finds the same contacts. And it does pass over most of a calm walk's searches.
TEST(SelfCollision, TheFlatProofPassesOverOnlySearchesThatFindNothing) {
  std::uint64_t searches = 0, proven = 0;
  for (const SceneKind kind : {SceneKind::Walk, SceneKind::SprintTurn, SceneKind::Wind})
    for (const PinLayout layout : {PinLayout::Corners, PinLayout::Gathered})
      for (const int n : {20, 32}) proven += searchBothWays(kind, n, layout, 100, searches);
  std::uint64_t walkSearches = 0;
  const std::uint64_t walkProven = searchBothWays(SceneKind::Walk, 20, PinLayout::Corners, 200, walkSearches);
  std::printf("flat proof: %llu of %llu searches passed over; the 20 x 20 walk %llu of %llu\n",
              static_cast<unsigned long long>(proven), static_cast<unsigned long long>(searches),
              static_cast<unsigned long long>(walkProven), static_cast<unsigned long long>(walkSearches));
  EXPECT_GT(walkProven, walkSearches / 4);
}

/// A fabric at rest: its rest positions, still, every particle free.
CapeState restStateOf(const Fabric& fabric) {
  CapeState state;
  state.positions = fabric.restPositions();
  state.velocities = Points::Zero(state.positions.rows(), 3);
  state.inverseMasses = Eigen::VectorXf::Ones(state.positions.rows());
  return state;
}

// A sheet folded over itself is not flat: the proof cannot pass over its search, which finds contacts.
TEST(SelfCollision, TheFlatProofDoesNotPassOverAFoldedSheet) {
  const FabricPtr fabric = test::makeGrid(12, 12, 0.5f, 0.5f);
  ASSERT_TRUE(fabric);
  CapeState state = restStateOf(*fabric);
  // Fold the lower half back under the upper, 1.5 cm below it.
  for (Eigen::Index i = 0; i < state.positions.rows(); ++i) {
    const float y = state.positions(i, 1);
    if (y < -0.25f) state.positions.row(i) << state.positions(i, 0), -0.5f - y, -0.015f;
  }
  CapeSettings settings = test::quietSettings();
  settings.selfCollision = true;
  detail::SelfCollision self(*fabric);
  self.searchFor(state, Eigen::VectorXf::Ones(state.positions.rows()), settings, 1.0f / 60.0f);
  EXPECT_EQ(self.searchesProvenApart(), 0u);
  EXPECT_GT(self.contacts().size(), 0u);
  // The same sheet unfolded is proven apart.
  detail::SelfCollision flat(*fabric);
  flat.searchFor(restStateOf(*fabric), Eigen::VectorXf::Ones(state.positions.rows()), settings, 1.0f / 60.0f);
  EXPECT_EQ(flat.searchesProvenApart(), 1u);
  EXPECT_TRUE(flat.contacts().empty());
}

}  // namespace
}  // namespace cape
