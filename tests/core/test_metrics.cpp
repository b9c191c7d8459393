// The docs/SCENES.md metrics as library code: strain, penetration, pin error, blow-up, the exact
// triangle-triangle test and the self-intersection count, and the run summary.
#include "CapeTestFixture.h"

#include "cape/scenes/Metrics.h"

#include <cmath>

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

}  // namespace
}  // namespace cape
