// The docs/SCENES.md metrics as library code: strain, penetration, pin error, blow-up, the exact
// triangle-triangle test and the self-intersection count, and the run summary. Then the culled metrics
// against their definitions: the spatially hashed self-intersection count against a brute-force count over
// every pair of triangles, and the culled penetration against the max over every particle and collider, on
// random inputs (crumpled, folded, interpenetrating, degenerate, far away) and on states of real runs. Equal,
// not close: the culling must not change a single result.
#include "CapeTestFixture.h"

#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>

namespace cape {
namespace {

using test::makeGrid;

TEST(Metrics, StrainOfAUniformStretch) {
  FabricPtr f = makeGrid(5, 5);
  Points x = f->restPositions();
  EXPECT_NEAR(structuralStrain(*f, x).max, 0.0f, 1e-6f);
  x.col(0) *= 1.1f;  // rows stretch 10 %, columns not at all
  const StrainStats s = structuralStrain(*f, x);
  EXPECT_NEAR(s.max, 0.1f, 1e-5f);
  EXPECT_NEAR(s.mean, 0.05f, 1e-5f);  // as many row springs as column springs in a square grid
  x = f->restPositions() * 0.9f;      // compression is negative strain
  EXPECT_NEAR(structuralStrain(*f, x).max, -0.1f, 1e-5f);
}

TEST(Metrics, PenetrationIsDepthInsideTheTrueSurface) {
  Points x(3, 3);
  x << 0.0f, 0.0f, 0.0f, 0.0f, 0.45f, 0.0f, 2.0f, 0.0f, 0.0f;
  std::vector<Collider> c{Collider::sphere(0.5f), Collider::plane(Vec3::UnitY(), -1.0f)};
  EXPECT_NEAR(maxPenetration(x, c), 0.5f, 1e-6f);  // the centre is 0.5 m deep
  x.row(0) << 0.0f, 0.499f, 0.0f;
  x.row(1) << 0.0f, 0.6f, 0.0f;
  EXPECT_NEAR(maxPenetration(x, c), 0.001f, 1e-6f);
  c[0].thickness = 0.1f;  // a skin is not the true surface
  EXPECT_NEAR(maxPenetration(x, c), 0.001f, 1e-6f);
  x.row(0) << 0.0f, 0.7f, 0.0f;
  EXPECT_EQ(maxPenetration(x, c), 0.0f);
}

TEST(Metrics, PinErrorAndBlowUp) {
  CapeState st;
  st.positions = Points::Zero(3, 3);
  st.pins.push_back({1, Vec3::Zero(), Vec3(0.0f, 0.003f, 0.004f)});
  EXPECT_NEAR(maxPinError(st), 0.005f, 1e-7f);
  EXPECT_FALSE(isBlownUp(st.positions, Vec3::Zero()));
  st.positions(2, 0) = 10.5f;
  EXPECT_TRUE(isBlownUp(st.positions, Vec3::Zero()));
  st.positions(2, 0) = std::nanf("");
  EXPECT_TRUE(isBlownUp(st.positions, Vec3::Zero()));
}

TEST(Metrics, TriangleTriangleExactTest) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  // Piercing through the middle.
  EXPECT_TRUE(trianglesIntersect(a, b, c, Vec3(0.2f, 0.2f, -1), Vec3(0.2f, 0.2f, 1), Vec3(0.3f, 0.3f, 1)));
  // Above, parallel: no.
  EXPECT_FALSE(trianglesIntersect(a, b, c, Vec3(0, 0, 0.01f), Vec3(1, 0, 0.01f), Vec3(0, 1, 0.01f)));
  // The other's plane crosses ours, but outside our triangle.
  EXPECT_FALSE(trianglesIntersect(a, b, c, Vec3(2, 2, -1), Vec3(2, 2, 1), Vec3(3, 2, 1)));
  // Touching at a point counts.
  EXPECT_TRUE(trianglesIntersect(a, b, c, Vec3(1, 0, 0), Vec3(2, 0, 1), Vec3(2, 0, -1)) ||
              trianglesIntersect(a, b, c, Vec3(1, 0, 0), Vec3(2, 1, 0.5f), Vec3(2, -1, 0.5f)));
  // Coplanar overlapping and coplanar apart.
  EXPECT_TRUE(trianglesIntersect(a, b, c, Vec3(0.2f, 0.2f, 0), Vec3(1.2f, 0.2f, 0), Vec3(0.2f, 1.2f, 0)));
  EXPECT_FALSE(trianglesIntersect(a, b, c, Vec3(2, 2, 0), Vec3(3, 2, 0), Vec3(2, 3, 0)));
  // Symmetric.
  EXPECT_TRUE(trianglesIntersect(Vec3(0.2f, 0.2f, -1), Vec3(0.2f, 0.2f, 1), Vec3(0.3f, 0.3f, 1), a, b, c));
  // A degenerate triangle (corners on a line) across the plane of the other, far from it: its normal is zero,
  // and the interval test alone would say they cross.
  EXPECT_FALSE(trianglesIntersect(Vec3(5, 0, -1), Vec3(5, 0, 1), Vec3(5, 0, 0), a, b, c));
  EXPECT_FALSE(trianglesIntersect(a, b, c, Vec3(5, 0, -1), Vec3(5, 0, 1), Vec3(5, 0, 0)));
  // ...and through it: they do meet.
  EXPECT_TRUE(trianglesIntersect(Vec3(0.2f, 0.2f, -1), Vec3(0.2f, 0.2f, 1), Vec3(0.2f, 0.2f, 0), a, b, c));
}

TEST(Metrics, SelfIntersectionsOfAFlatAndAFoldedCape) {
  FabricPtr f = makeGrid(6, 6, 1.0f, 1.0f);
  SelfIntersectionCounter counter;
  EXPECT_EQ(counter.count(*f, f->restPositions()), 0) << "neighbours sharing a vertex are never counted";
  // Fold the bottom half up through the top half: mirror rows 3..5 about the plane y = -0.5 and tilt them
  // through z = 0, so they pierce the flat upper half.
  Points x = f->restPositions();
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const float y = x(i, 1);
    if (y < -0.5f) {
      x(i, 1) = -1.0f - y;                // mirrored above the fold line
      x(i, 2) = 0.3f * (x(i, 0) - 0.5f);  // tilted about the x = 0.5 line: crosses z = 0
    }
  }
  EXPECT_GT(counter.count(*f, x), 0);
  // A clean fold (mirrored half 1 cm in front) does not intersect.
  Points clean = f->restPositions();
  for (Eigen::Index i = 0; i < clean.rows(); ++i)
    if (clean(i, 1) < -0.5f) {
      clean(i, 1) = -1.0f - clean(i, 1);
      clean(i, 2) = 0.01f;
    }
  EXPECT_EQ(counter.count(*f, clean), 0);
}

TEST(Metrics, RecorderSummarisesFrames) {
  MetricsRecorder rec(0.5);  // two frames per second
  for (int i = 1; i <= 20; ++i) {
    FrameMetrics m;
    m.maxStrain = 0.01f * static_cast<float>(i);
    m.meanStrain = 0.001f;
    m.maxPenetration = i == 7 ? 0.002f : 0.0005f;
    m.selfIntersections = i == 3 ? 4 : 0;
    m.pinError = 1e-6f;
    m.meanSpeed = i > 18 ? 0.1f : 1.0f;
    m.guardRestored = i == 5 || i == 9 ? 3u : 0u;
    rec.add(m);
  }
  const RunSummary s = rec.summary();
  EXPECT_EQ(s.frames, 20);
  EXPECT_EQ(s.guardRestored, 6);
  EXPECT_EQ(s.framesGuardRestored, 2);
  EXPECT_FLOAT_EQ(s.maxStrain, 0.2f);
  EXPECT_NEAR(s.medianFrameMaxStrain, 0.10f, 0.0051f);
  EXPECT_FLOAT_EQ(s.p95FrameMaxStrain, 0.19f);
  EXPECT_FLOAT_EQ(s.maxPenetration, 0.002f);
  EXPECT_EQ(s.framesPenetrationOver1mm, 1);
  EXPECT_EQ(s.selfIntersectionsMax, 4);
  EXPECT_EQ(s.framesWithSelfIntersections, 1);
  EXPECT_NEAR(s.restJitter, 0.1f, 1e-6f);  // the last second = the last two frames
  EXPECT_FALSE(s.blowUp);
}

TEST(Metrics, ACompressedRunHasANegativeMaxStrain) {
  MetricsRecorder rec;
  for (int i = 1; i <= 3; ++i) {
    FrameMetrics m;
    m.maxStrain = -0.01f * static_cast<float>(i);
    rec.add(m);
  }
  EXPECT_FLOAT_EQ(rec.summary().maxStrain, -0.01f);
}

// Every solver compared goes through one measureFrame: on the arrays of a cape it gives the cape's own
// figures, and a blown-up frame says only that.
TEST(Metrics, OneMeasureFrameForEverySolver) {
  Cape cape(makeGrid(6, 6), CapeSettings(), Pose{Vec3(-0.3f, 1.5f, 0.0f), Quat::Identity()});
  cape.pin(0, Vec3(-0.3f, 1.5f, 0.0f));
  cape.pin(5, Vec3(0.3f, 1.5f, 0.0f));
  const std::vector<Collider> body{Collider::sphere(0.2f, Pose{Vec3(0.0f, 1.0f, 0.05f), Quat::Identity()})};
  for (int frame = 0; frame < 20; ++frame) cape.step(1.0f / 60.0f, body);
  SelfIntersectionCounter c1, c2;
  const FrameMetrics a = measureFrame(cape, body, Vec3(0.0f, 1.0f, 0.0f), &c1);
  const CapeState& st = cape.state();
  const FrameMetrics b =
      measureFrame(cape.fabric(), st.positions, st.velocities, st.pins, body, Vec3(0.0f, 1.0f, 0.0f), &c2);
  EXPECT_EQ(a.maxStrain, b.maxStrain);
  EXPECT_EQ(a.meanStrain, b.meanStrain);
  EXPECT_EQ(a.maxPenetration, b.maxPenetration);
  EXPECT_EQ(a.selfIntersections, b.selfIntersections);
  EXPECT_EQ(a.pinError, b.pinError);
  EXPECT_EQ(a.meanSpeed, b.meanSpeed);
  EXPECT_GT(a.meanSpeed, 0.0f);
  EXPECT_FALSE(a.blowUp);

  Points far = st.positions;
  far(3, 1) = std::nanf("");
  const FrameMetrics blown =
      measureFrame(cape.fabric(), far, st.velocities, st.pins, body, Vec3::Zero(), &c2);
  EXPECT_TRUE(blown.blowUp);
  EXPECT_EQ(blown.maxStrain, 0.0f);
  EXPECT_EQ(blown.meanSpeed, 0.0f);
}

/// Every figure of two frames' metrics, to the bit.
void expectSameMetrics(const FrameMetrics& a, const FrameMetrics& b, const std::string& where) {
  EXPECT_EQ(a.maxStrain, b.maxStrain) << where;
  EXPECT_EQ(a.meanStrain, b.meanStrain) << where;
  EXPECT_EQ(a.maxPenetration, b.maxPenetration) << where;
  EXPECT_EQ(a.selfIntersections, b.selfIntersections) << where;
  EXPECT_EQ(a.pinError, b.pinError) << where;
  EXPECT_EQ(a.meanSpeed, b.meanSpeed) << where;
  EXPECT_EQ(a.guardRestored, b.guardRestored) << where;
  EXPECT_EQ(a.blowUp, b.blowUp) << where;
  EXPECT_EQ(a.meanDihedral, b.meanDihedral) << where;
  EXPECT_EQ(a.dihedralChange, b.dihedralChange) << where;
}

// The meter against measuring every frame afresh (measureFrame and a FoldMeter), over a hang that falls
// asleep: the same figures every frame, the sleeping frames reused, and any change to an input measured.
TEST(FrameMeter, ReusesAFrameOnlyWhenItsInputsAreTheSameBits) {
  SimpleScene scene(SceneKind::Hang, 20, PinLayout::Corners, CapeSettings());
  ASSERT_TRUE(scene.status().ok());
  FrameMeter meter(true);
  FoldMeter folds;
  std::int64_t asleepFrames = 0;
  for (int frame = 1; frame <= 900; ++frame) {
    scene.advanceFrame();
    const Cape& cape = scene.cape();
    SelfIntersectionCounter counter;
    FrameMetrics fresh =
        measureFrame(cape, scene.body().bodyColliders(), scene.body().torsoCentre(), &counter);
    const FoldStats fold = folds.measure(cape.fabric(), cape.state().positions);
    fresh.meanDihedral = fold.meanDihedral;
    fresh.dihedralChange = fold.meanChange;
    const FrameMetrics m = meter.measure(cape, scene.body().bodyColliders(), scene.body().torsoCentre());
    expectSameMetrics(m, fresh, "frame " + std::to_string(frame));
    // Only a frame the cape slept through (its state untouched) can be reused here.
    if (meter.lastReused()) {
      EXPECT_TRUE(cape.isAsleep()) << frame;
    }
    asleepFrames += cape.isAsleep() ? 1 : 0;
  }
  ASSERT_TRUE(scene.cape().isAsleep());
  // Every frame after the first it slept through (the frame it fell asleep in changed its state).
  EXPECT_GE(meter.reusedFrames(), asleepFrames - 1);
  EXPECT_GT(meter.reusedFrames(), 100);

  // The same inputs in other arrays: reused. One bit changed anywhere: measured.
  const Cape& cape = scene.cape();
  const CapeState& st = cape.state();
  std::vector<Collider> body(scene.body().bodyColliders().begin(), scene.body().bodyColliders().end());
  const Vec3 centre = scene.body().torsoCentre();
  Points x = st.positions, v = st.velocities;
  std::vector<Pin> pins = st.pins;
  const FrameMetrics rest = meter.measure(cape.fabric(), x, v, pins, body, centre);
  EXPECT_TRUE(meter.lastReused());
  const auto measuredAfter = [&](const char* what, const std::function<void()>& change,
                                 const std::function<void()>& undo) {
    change();
    SelfIntersectionCounter counter;
    FrameMetrics fresh = measureFrame(cape.fabric(), x, v, pins, body, centre, &counter);
    const FrameMetrics m = meter.measure(cape.fabric(), x, v, pins, body, centre);
    EXPECT_FALSE(meter.lastReused()) << what;
    EXPECT_EQ(m.maxPenetration, fresh.maxPenetration) << what;
    EXPECT_EQ(m.meanSpeed, fresh.meanSpeed) << what;
    EXPECT_EQ(m.pinError, fresh.pinError) << what;
    undo();
    meter.measure(cape.fabric(), x, v, pins, body, centre);
    const FrameMetrics back = meter.measure(cape.fabric(), x, v, pins, body, centre);
    EXPECT_TRUE(meter.lastReused()) << what;
    EXPECT_EQ(back.maxStrain, rest.maxStrain) << what;
  };
  const auto nudge = [](float& f) { f = std::nextafter(f, 1e30f); };
  const auto unnudge = [](float& f) { f = std::nextafter(f, -1e30f); };
  measuredAfter(
      "a position", [&] { nudge(x(7, 1)); }, [&] { unnudge(x(7, 1)); });
  measuredAfter(
      "a velocity", [&] { v(3, 0) = 1.0f; }, [&] { v(3, 0) = st.velocities(3, 0); });
  measuredAfter(
      "a pin's target", [&] { nudge(pins[0].target.x()); }, [&] { unnudge(pins[0].target.x()); });
  // A collider moved into the cape by a centimetre: the penetration must be measured again.
  const Vec3 at = body[0].current.position;
  measuredAfter(
      "a collider's pose", [&] { body[0].current.position = Vec3(x.row(200).transpose()); },
      [&] { body[0].current.position = at; });
  measuredAfter(
      "a collider's size", [&] { nudge(body[0].radius); }, [&] { unnudge(body[0].radius); });
  measuredAfter(
      "a collider more", [&] { body.push_back(Collider::sphere(0.1f)); }, [&] { body.pop_back(); });
  // What the numerical guard restored is a blow-up, measured: and the frame after it is measured too.
  const FrameMetrics guarded = meter.measure(cape.fabric(), x, v, pins, body, centre, 3);
  EXPECT_FALSE(meter.lastReused());
  EXPECT_TRUE(guarded.blowUp);
  EXPECT_EQ(guarded.guardRestored, 3u);
  const FrameMetrics after = meter.measure(cape.fabric(), x, v, pins, body, centre);
  EXPECT_FALSE(meter.lastReused());
  EXPECT_FALSE(after.blowUp);
}

// A triangle mesh's triangles are refilled in place between steps: the meter compares them, not the pointer.
TEST(FrameMeter, ComparesATriangleMeshByItsTriangles) {
  Cape cape(makeGrid(6, 6), CapeSettings(), Pose{Vec3(-0.3f, 1.5f, 0.0f), Quat::Identity()});
  auto soup = std::make_shared<TriangleSoup>();
  soup->corners = {Vec3(-1.0f, 0.0f, -1.0f), Vec3(1.0f, 0.0f, -1.0f), Vec3(0.0f, 0.0f, 1.0f)};
  const std::vector<Collider> body{Collider::triangleMesh(soup)};
  FrameMeter meter;
  const FrameMetrics first = meter.measure(cape, body, Vec3(0.0f, 1.0f, 0.0f));
  meter.measure(cape, body, Vec3(0.0f, 1.0f, 0.0f));
  EXPECT_TRUE(meter.lastReused());
  // The same soup, its triangle raised into the cape: measured again.
  for (Vec3& c : soup->corners) c.y() = 1.2f;
  const FrameMetrics raised = meter.measure(cape, body, Vec3(0.0f, 1.0f, 0.0f));
  EXPECT_FALSE(meter.lastReused());
  EXPECT_EQ(first.maxPenetration, 0.0f);
  SelfIntersectionCounter counter;
  EXPECT_EQ(raised.maxPenetration, measureFrame(cape, body, Vec3(0.0f, 1.0f, 0.0f), &counter).maxPenetration);
}

TEST(Metrics, WorstOfTwoFrames) {
  FrameMetrics a, b;
  a.maxStrain = -0.02f;
  a.meanStrain = -0.03f;
  b.maxStrain = -0.01f;
  b.meanStrain = -0.04f;
  a.maxPenetration = 0.002f;
  b.selfIntersections = 3;
  b.blowUp = true;
  const FrameMetrics w = worstOf(a, b);
  EXPECT_EQ(w.maxStrain, -0.01f);
  EXPECT_EQ(w.meanStrain, -0.03f);
  EXPECT_EQ(w.maxPenetration, 0.002f);
  EXPECT_EQ(w.selfIntersections, 3);
  EXPECT_TRUE(w.blowUp);
}

TEST(Metrics, PercentileNearestRank) {
  EXPECT_EQ(percentile({}, 50), 0.0);
  EXPECT_EQ(percentile({3, 1, 2}, 50), 2.0);
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) v.push_back(i);
  EXPECT_EQ(percentile(v, 95), 95.0);
  EXPECT_EQ(percentile(v, 100), 100.0);
}

// The culled metrics against their definitions.

// --- Self-intersections --------------------------------------------------------------------------------

/// The definition: every pair of triangles i < j that shares no vertex, through the exact test.
int bruteForceCount(const Fabric& fabric, const Points& x) {
  const std::vector<std::uint32_t>& tri = fabric.triangles();
  const std::size_t nt = tri.size() / 3;
  int found = 0;
  for (std::size_t i = 0; i < nt; ++i) {
    const std::uint32_t* a = &tri[3 * i];
    for (std::size_t j = i + 1; j < nt; ++j) {
      const std::uint32_t* b = &tri[3 * j];
      bool shares = false;
      for (int u = 0; u < 3; ++u)
        for (int v = 0; v < 3; ++v) shares = shares || a[u] == b[v];
      if (shares) continue;
      if (trianglesIntersect(x.row(a[0]), x.row(a[1]), x.row(a[2]), x.row(b[0]), x.row(b[1]), x.row(b[2])))
        ++found;
    }
  }
  return found;
}

using Rng = std::mt19937;

float uniform(Rng& rng, float lo, float hi) {
  return std::uniform_real_distribution<float>(lo, hi)(rng);
}

Quat randomRotation(Rng& rng) {
  std::normal_distribution<float> n;
  Quat q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q;
}

/// The grid folded over itself about a random line across it, the folded part at a random small distance
/// in front, then crumpled by noise of amplitude `noise` (m) and turned to a random orientation.
Points foldedAndCrumpled(const Fabric& f, Rng& rng, float noise) {
  Points x = f.restPositions();
  const float foldY = uniform(rng, -0.8f, -0.2f), tilt = uniform(rng, -0.3f, 0.3f),
              gap = uniform(rng, -0.02f, 0.05f);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const float line = foldY + tilt * (x(i, 0) - 0.3f);
    if (x(i, 1) < line) {
      x(i, 1) = 2.0f * line - x(i, 1);
      x(i, 2) = gap + tilt * 0.5f * x(i, 0);
    }
  }
  std::normal_distribution<float> n(0.0f, noise);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (int k = 0; k < 3; ++k) x(i, k) += n(rng);
  const Eigen::Matrix3f r = randomRotation(rng).toRotationMatrix();
  return x * r.transpose();
}

/// The left half of the grid left flat, the right half turned about a random axis through the middle so that
/// the two sheets cross, with a little noise.
Points twoSheetsCrossing(const Fabric& f, Rng& rng) {
  Points x = f.restPositions();
  const Eigen::Matrix3f r = randomRotation(rng).toRotationMatrix();
  const Vec3 pivot(uniform(rng, 0.2f, 0.4f), uniform(rng, -0.7f, -0.3f), 0.0f);
  std::normal_distribution<float> n(0.0f, 0.005f);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    Vec3 p = x.row(i).transpose();
    if (p.x() > 0.3f) p = pivot + r * (p - pivot - Vec3(0.3f, 0.0f, 0.0f));
    x.row(i) = (p + Vec3(n(rng), n(rng), n(rng))).transpose();
  }
  return x;
}

/// Degenerate geometry: coordinates snapped to a coarse lattice (coplanar, touching and zero-area
/// triangles), some particles collapsed onto others (coincident points), some rows squashed onto a line.
Points degenerate(const Fabric& f, Rng& rng) {
  Points x = foldedAndCrumpled(f, rng, 0.03f);
  const float step = uniform(rng, 0.02f, 0.1f);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (int k = 0; k < 3; ++k) x(i, k) = step * std::round(x(i, k) / step);
  std::uniform_int_distribution<Eigen::Index> pick(0, x.rows() - 1);
  for (int c = 0; c < static_cast<int>(x.rows() / 10); ++c) x.row(pick(rng)) = x.row(pick(rng));
  for (Eigen::Index i = 0; i < x.rows() / 8; ++i) x(i, 2) = x(i, 1) = 0.0f;
  return x;
}

/// Every particle anywhere in a box: long slivers crossing everything (many too large to hash).
Points scattered(const Fabric& f, Rng& rng, float size) {
  Points x(f.restPositions().rows(), 3);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (int k = 0; k < 3; ++k) x(i, k) = uniform(rng, -size, size);
  return x;
}

struct CountCase {
  std::string name;
  Points x;
};

/// The random inputs on one grid: crumpled folds at several noise levels (up to well across the layers),
/// crossing sheets, degenerate ones, scattered ones, the same far away (1e6 m) and scaled up (1e6). `all`
/// false keeps two noise levels and leaves out the degenerate and scattered ones (a large grid's brute-force
/// count is long).
std::vector<CountCase> randomCases(const Fabric& f, std::uint32_t seed, int repeats, bool all = true) {
  Rng rng(seed);
  std::vector<CountCase> cases;
  for (int r = 0; r < repeats; ++r) {
    for (float noise : {0.0f, 0.003f, 0.01f, 0.03f, 0.1f})
      if (all || noise == 0.003f || noise == 0.03f)
        cases.push_back({"folded, noise " + std::to_string(noise), foldedAndCrumpled(f, rng, noise)});
    cases.push_back({"two sheets crossing", twoSheetsCrossing(f, rng)});
    if (all) {
      cases.push_back({"degenerate", degenerate(f, rng)});
      cases.push_back({"scattered", scattered(f, rng, uniform(rng, 0.05f, 1.0f))});
    }
    Points far = foldedAndCrumpled(f, rng, 0.02f);
    far.rowwise() += Eigen::RowVector3f(1e6f, -1e6f, 3e5f);
    cases.push_back({"folded, 1e6 m away", far});
    cases.push_back({"folded, scaled by 1e6", foldedAndCrumpled(f, rng, 0.02f) * 1e6f});
  }
  return cases;
}

void expectBruteForceCounts(const Fabric& f, const std::vector<CountCase>& cases, SelfIntersectionCounter& c,
                            int& positive) {
  for (const CountCase& k : cases) {
    const int brute = bruteForceCount(f, k.x);
    EXPECT_EQ(c.count(f, k.x), brute) << k.name;
    positive += brute > 0 ? 1 : 0;
  }
}

// The brute-force counts take minutes in the unoptimised sanitizer build, which runs a sixth of the 20 x 20
// inputs and 32 x 32 for 64 x 64 (every path of the count all the same).
#ifdef NDEBUG
constexpr int kRandomRepeats = 6, kLargeGrid = 64;
#else
constexpr int kRandomRepeats = 1, kLargeGrid = 32;
#endif

TEST(MetricsFast, SelfIntersectionCountIsTheBruteForceCountOnRandomCloth) {
  FabricPtr small = makeGrid(20, 20), large = makeGrid(kLargeGrid, kLargeGrid);
  SelfIntersectionCounter counter;  // one counter over sizes: its scratch is reused, grown and shrunk
  int positive = 0;
  const std::vector<CountCase> smallCases = randomCases(*small, 1u, kRandomRepeats);
  expectBruteForceCounts(*small, smallCases, counter, positive);
  expectBruteForceCounts(*large, randomCases(*large, 2u, 1, false), counter, positive);
  expectBruteForceCounts(*small, smallCases, counter, positive);
  EXPECT_GT(positive, static_cast<int>(smallCases.size()));  // most inputs do intersect
}

TEST(MetricsFast, SelfIntersectionCountOfSpecialInputs) {
  FabricPtr f = makeGrid(12, 9);
  SelfIntersectionCounter counter;
  Rng rng(3u);
  Points x = f->restPositions();
  EXPECT_EQ(counter.count(*f, x), 0);
  x.setZero();  // every point the same: every pair touches
  EXPECT_EQ(counter.count(*f, x), bruteForceCount(*f, x));
  EXPECT_GT(counter.count(*f, x), 0);
  x.col(0).setLinSpaced(-1.0f, 1.0f);  // all on a line
  EXPECT_EQ(counter.count(*f, x), bruteForceCount(*f, x));
  // Not finite: no box to cull with, and still the brute-force figure.
  x = foldedAndCrumpled(*f, rng, 0.05f);
  x(7, 1) = std::numeric_limits<float>::quiet_NaN();
  x(30, 2) = std::numeric_limits<float>::infinity();
  x(31, 0) = -std::numeric_limits<float>::infinity();
  EXPECT_EQ(counter.count(*f, x), bruteForceCount(*f, x));
  // Huge but finite.
  x = scattered(*f, rng, 3e37f);
  EXPECT_EQ(counter.count(*f, x), bruteForceCount(*f, x));
}

// States of real runs: the sprint-turn with self-collision off, so the cape folds through itself.
TEST(MetricsFast, SelfIntersectionCountIsTheBruteForceCountOnSprintTurnStates) {
  CapeSettings s;
  s.selfCollision = false;
  int positive = 0;
  for (int n : {20, kLargeGrid}) {
    SimpleScene scene(SceneKind::SprintTurn, n, PinLayout::Corners, s);
    ASSERT_TRUE(scene.status().ok());
    SelfIntersectionCounter counter;
    const int every = n == 20 ? 20 : 60, last = n == 20 ? 360 : 240;
    for (int frame = 1; frame <= last; ++frame) {
      scene.advanceFrame();
      if (frame % every != 0) continue;
      const Points& x = scene.cape().state().positions;
      const int brute = bruteForceCount(scene.cape().fabric(), x);
      EXPECT_EQ(counter.count(scene.cape().fabric(), x), brute) << n << " x " << n << ", frame " << frame;
      positive += brute > 0 ? 1 : 0;
    }
  }
  RecordProperty("statesWithSelfIntersections", positive);
}

// The count's flat proof settles a frame only where the count without it finds nothing: every frame of the
// canonical scenes, self-collision on and off, counted with the proof and without (the count without it is
// the brute-force count, above), and a sample of the proven frames against the brute force itself. It
// settles most of a walk's frames, and none that intersects.
#ifdef NDEBUG
constexpr int kProofSizes[] = {20, 32};
#else
constexpr int kProofSizes[] = {20};  // the sanitizer build: 20 x 20 only
#endif
TEST(MetricsFast, TheFlatProofSettlesOnlyCountsOfNothing) {
  std::int64_t frames = 0, proven = 0, intersecting = 0, walkFrames = 0, walkProven = 0;
  for (const SceneKind kind : {SceneKind::Walk, SceneKind::SprintTurn, SceneKind::Wind})
    for (const bool self : {false, true})
      for (const int n : kProofSizes) {
        CapeSettings s;
        s.selfCollision = self;
        SimpleScene scene(kind, n, PinLayout::Corners, s);
        ASSERT_TRUE(scene.status().ok());
        SelfIntersectionCounter withProof, without;
        without.setFlatProof(false);
        const Fabric& fabric = scene.cape().fabric();
        for (int frame = 1; frame <= 240; ++frame) {
          scene.advanceFrame();
          const Points& x = scene.cape().state().positions;
          const std::int64_t before = withProof.countsProvenApart();
          const int count = without.count(fabric, x);
          ASSERT_EQ(withProof.count(fabric, x), count) << n << " x " << n << ", frame " << frame;
          const bool settled = withProof.countsProvenApart() > before;
          if (settled && frame % 60 == 0) {
            EXPECT_EQ(bruteForceCount(fabric, x), 0) << n << " x " << n << ", frame " << frame;
          }
          ++frames;
          proven += settled ? 1 : 0;
          intersecting += count > 0 ? 1 : 0;
          if (kind == SceneKind::Walk && n == 20) {
            ++walkFrames;
            walkProven += settled ? 1 : 0;
          }
        }
        EXPECT_EQ(without.countsProvenApart(), 0);
      }
  std::printf(
      "count's flat proof: %lld of %lld frames settled (%lld frames intersect); the 20 x 20 walk %lld "
      "of %lld\n",
      static_cast<long long>(proven), static_cast<long long>(frames), static_cast<long long>(intersecting),
      static_cast<long long>(walkProven), static_cast<long long>(walkFrames));
  EXPECT_GT(intersecting, 0);                  // the sprint-turn without self-collision passes through itself
  EXPECT_GE(walkProven, 9 * walkFrames / 10);  // a walking cape is flat enough in nearly every frame
}

// A sheet folded through itself is not settled by the proof, and is counted; the same sheet flat is.
TEST(MetricsFast, TheFlatProofDoesNotSettleAFoldedSheet) {
  const FabricPtr f = makeGrid(12, 12);
  ASSERT_TRUE(f);
  SelfIntersectionCounter counter;
  Points x = f->restPositions();
  EXPECT_EQ(counter.count(*f, x), 0);
  EXPECT_EQ(counter.countsProvenApart(), 1);
  // The lower half folded back up through the upper half: a crease, and triangles crossing.
  Rng rng(11u);
  x = foldedAndCrumpled(*f, rng, 0.0f);
  const int brute = bruteForceCount(*f, x);
  EXPECT_EQ(counter.count(*f, x), brute);
  EXPECT_EQ(counter.countsProvenApart(), 1);
  // Not finite: never proven.
  x = f->restPositions();
  x(40, 2) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(counter.count(*f, x), bruteForceCount(*f, x));
  x(40, 2) = std::numeric_limits<float>::infinity();
  EXPECT_EQ(counter.count(*f, x), bruteForceCount(*f, x));
  EXPECT_EQ(counter.countsProvenApart(), 1);
  // Far from the origin and flat: proven, and nothing to count.
  x = f->restPositions();
  x.rowwise() += Eigen::RowVector3f(4e3f, -2e3f, 1e3f);
  EXPECT_EQ(counter.count(*f, x), 0);
  EXPECT_EQ(bruteForceCount(*f, x), 0);
  EXPECT_EQ(counter.countsProvenApart(), 2);
  // Flat, turned and stretched 1e30 times: the proof's products stay within a float's range, and it settles.
  const Eigen::Matrix3f turn = randomRotation(rng).toRotationMatrix();
  x = (f->restPositions() * 1e30f) * turn.transpose();
  EXPECT_EQ(counter.count(*f, x), 0);
  EXPECT_EQ(bruteForceCount(*f, x), 0);
  EXPECT_EQ(counter.countsProvenApart(), 3);
  // Shrunk 1e30 times: its points are not a hundredth of their rest distance apart, so the proof cannot
  // settle it (it bounds distances against the rest shape's), and the count does.
  x = (f->restPositions() * 1e-30f) * turn.transpose();
  EXPECT_EQ(counter.count(*f, x), bruteForceCount(*f, x));
  EXPECT_EQ(counter.countsProvenApart(), 3);
}

// --- Penetration ---------------------------------------------------------------------------------------

/// The definition: every particle against every valid collider.
float unculledPenetration(const Points& x, ColliderSpan colliders) {
  float worst = 0.0f;
  for (const Collider& c : colliders) {
    if (!c.validate().ok()) continue;
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      worst = std::max(worst, -signedDistance(c, x.row(i).transpose()));
  }
  return worst;
}

std::shared_ptr<const ConvexHull> octahedronHull(float r) {
  std::vector<Vec3> v{r * Vec3::UnitX(),  -r * Vec3::UnitX(), r * Vec3::UnitY(),
                      -r * Vec3::UnitY(), r * Vec3::UnitZ(),  -r * Vec3::UnitZ()};
  std::vector<Eigen::Vector4f> planes;
  for (int i = 0; i < 8; ++i) {
    const Vec3 n = Vec3(i & 1 ? 1.0f : -1.0f, i & 2 ? 1.0f : -1.0f, i & 4 ? 1.0f : -1.0f).normalized();
    planes.emplace_back(n.x(), n.y(), n.z(), r / std::sqrt(3.0f));
  }
  return ConvexHull::make(v, planes);
}

std::shared_ptr<const TriangleSoup> randomSoup(Rng& rng, float size) {
  auto soup = std::make_shared<TriangleSoup>();
  for (int k = 0; k < 30; ++k)
    soup->corners.emplace_back(uniform(rng, -size, size), uniform(rng, -size, size),
                               uniform(rng, -size, size));
  return soup;
}

/// A collider of each shape with random sizes (from 1 mm to 1 m, capsules of zero length included), at a
/// random pose whose quaternion is as far from unit as validation allows.
std::vector<Collider> randomColliders(Rng& rng, const Vec3& around) {
  auto size = [&] { return std::exp(uniform(rng, std::log(0.001f), 0.0f)); };
  std::vector<Collider> c;
  c.push_back(Collider::sphere(size()));
  const int axis = std::uniform_int_distribution<int>(0, 2)(rng);
  c.push_back(Collider::capsule(size(), rng() % 4 == 0 ? 0.0f : size(), axis));
  c.push_back(Collider::cylinder(size(), size(), (axis + 1) % 3));
  c.push_back(Collider::box(Vec3(size(), size(), size())));
  c.push_back(Collider::convexHull(octahedronHull(size())));
  c.push_back(Collider::triangleMesh(randomSoup(rng, size())));
  c.push_back(Collider::plane(randomRotation(rng) * Vec3::UnitY(), around.y() + uniform(rng, -1.0f, 1.0f)));
  for (Collider& k : c) {
    if (k.shape == ColliderShape::Plane) continue;
    Quat q = randomRotation(rng);
    q.coeffs() *= std::sqrt(1.0f + uniform(rng, -9.9e-4f, 9.9e-4f));
    const Vec3 at =
        around + Vec3(uniform(rng, -0.5f, 0.5f), uniform(rng, -0.5f, 0.5f), uniform(rng, -0.5f, 0.5f));
    k.teleportTo(Pose{at, q});
  }
  return c;
}

/// Points around a collider at every scale of distance from its surface: inside, on and near the surface,
/// just inside and outside the culling ball (its radius times 1 +- 1 %), and far.
Points cloudAround(const Collider& c, Rng& rng, int count) {
  const float r =
      std::max({c.radius + c.halfHeight, c.halfExtents.norm(), c.hull ? c.hull->radius : 0.0f, 0.01f});
  Points x(count, 3);
  for (int i = 0; i < count; ++i) {
    std::normal_distribution<float> n;
    const Vec3 dir = Vec3(n(rng), n(rng), n(rng)).normalized();
    float distance = 0.0f;
    switch (i % 5) {
      case 0:
        distance = r * uniform(rng, 0.0f, 1.0f);
        break;
      case 1:
        distance = r * uniform(rng, 0.98f, 1.03f);
        break;
      case 2:
        distance = r * uniform(rng, 0.0f, 3.0f);
        break;
      case 3:
        distance = r * (1.0f + uniform(rng, -1e-5f, 1e-5f));
        break;
      default:
        distance = r * uniform(rng, 0.0f, 20.0f);
        break;
    }
    x.row(i) = c.current.apply(distance * dir).transpose();
  }
  return x;
}

TEST(MetricsFast, CulledPenetrationIsTheUnculledMaxOnRandomClouds) {
  Rng rng(7u);
  int positive = 0, trials = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Vec3 around = trial % 3 == 0 ? Vec3(1e6f, -2e5f, 5e5f) : Vec3(0.0f, 1.0f, 0.0f);
    std::vector<Collider> colliders = randomColliders(rng, around);
    for (const Collider& c : colliders) {
      if (c.shape == ColliderShape::Plane) continue;
      // Each collider alone, against a cloud around itself...
      const Points x = cloudAround(c, rng, 200);
      const ColliderSpan one(&c, 1);
      const float expected = unculledPenetration(x, one);
      EXPECT_EQ(maxPenetration(x, one), expected) << toString(c.shape) << ", trial " << trial;
      positive += expected > 0.0f ? 1 : 0;
      ++trials;
      // ...and all of them (an invalid one among them) against it.
      std::vector<Collider> all = colliders;
      all.push_back(Collider::sphere(-1.0f));
      EXPECT_EQ(maxPenetration(x, all), unculledPenetration(x, all))
          << toString(c.shape) << ", trial " << trial;
    }
  }
  EXPECT_GT(positive, trials / 2);
}

TEST(MetricsFast, CulledPenetrationOfSpecialInputs) {
  Rng rng(11u);
  std::vector<Collider> colliders = randomColliders(rng, Vec3(0.0f, 1.0f, 0.0f));
  Points x = cloudAround(colliders[3], rng, 100);
  EXPECT_EQ(maxPenetration(Points(0, 3), colliders), 0.0f);
  // Not finite, or far beyond anything: the exact path.
  x(5, 0) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(maxPenetration(x, colliders), unculledPenetration(x, colliders));
  x(5, 0) = std::numeric_limits<float>::infinity();
  EXPECT_EQ(maxPenetration(x, colliders), unculledPenetration(x, colliders));
  x(5, 0) = 3e38f;
  EXPECT_EQ(maxPenetration(x, colliders), unculledPenetration(x, colliders));
  // Tiny colliders (denormal squares) and huge ones.
  x = cloudAround(colliders[0], rng, 100);
  std::vector<Collider> odd{Collider::sphere(1e-30f, colliders[0].current),
                            Collider::box(Vec3(1e-20f, 1e-20f, 1e-20f), colliders[0].current),
                            Collider::sphere(1e20f, colliders[0].current)};
  EXPECT_EQ(maxPenetration(x, odd), unculledPenetration(x, odd));
  // The simple body against the real cape states of a walk.
  SimpleScene scene(SceneKind::Walk, 20, PinLayout::Corners, CapeSettings());
  for (int frame = 1; frame <= 120; ++frame) {
    scene.advanceFrame();
    const Points& p = scene.cape().state().positions;
    EXPECT_EQ(maxPenetration(p, scene.body().bodyColliders()),
              unculledPenetration(p, scene.body().bodyColliders()))
        << "frame " << frame;
    EXPECT_EQ(maxPenetration(p, scene.body().colliders()), unculledPenetration(p, scene.body().colliders()));
  }
}

}  // namespace
}  // namespace cape
