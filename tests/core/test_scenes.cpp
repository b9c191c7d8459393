// The canonical scenes of docs/SCENES.md on the simple body: the motions, and the quality bounds the solver
// promises there (issue 2): walk strain median <= 3 %, p95 <= 5 %; sprint-turn penetration <= 1 mm.
#include "CapeTestFixture.h"

#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <cmath>
#include <limits>

namespace cape {
namespace {

constexpr double kPi = 3.14159265358979323846;

float restWidth(const Fabric& f) {
  return f.restPositions().col(0).maxCoeff();
}

TEST(Scenes, ParseNames) {
  SceneKind k;
  for (SceneKind kind :
       {SceneKind::Hang, SceneKind::Walk, SceneKind::SprintTurn, SceneKind::Wind, SceneKind::Crowd}) {
    ASSERT_TRUE(parseSceneKind(toString(kind), k));
    EXPECT_EQ(k, kind);
  }
  EXPECT_FALSE(parseSceneKind("dance", k));
  PinLayout a;
  for (PinLayout layout : {PinLayout::Corners, PinLayout::Collar, PinLayout::Gathered}) {
    ASSERT_TRUE(parsePinLayout(toString(layout), a));
    EXPECT_EQ(a, layout);
  }
  EXPECT_STREQ(toString(PinLayout::Gathered), "gathered");
  EXPECT_FALSE(parsePinLayout("belt", a));
}

TEST(Scenes, WalkMotion) {
  const MotionDesc m = MotionDesc::forScene(SceneKind::Walk);
  EXPECT_FLOAT_EQ(m.speed, 1.4f);
  const BodyPose p = motionAt(m, 1.0);
  EXPECT_NEAR(p.position.z(), -1.4f, 1e-5f);  // walks towards -Z
  EXPECT_NEAR(p.position.x(), 0.0f, 1e-6f);
  EXPECT_NEAR(motionAt(m, 0.25).legAngle, 0.5236f * std::sin(2.0 * kPi * 0.25), 1e-5f);
  // Bob: 3 cm peak to peak at 2 Hz.
  float lo = 1.0f, hi = -1.0f;
  for (int i = 0; i < 100; ++i) {
    const float b = motionAt(m, i * 0.005).bob;
    lo = std::min(lo, b);
    hi = std::max(hi, b);
  }
  EXPECT_NEAR(hi - lo, 0.03f, 2e-3f);
}

TEST(Scenes, SprintTurnMotion) {
  const MotionDesc m = MotionDesc::forScene(SceneKind::SprintTurn);
  EXPECT_FLOAT_EQ(m.speed, 5.0f);
  EXPECT_NEAR(motionAt(m, 1.5).yaw, 0.0f, 1e-6f);
  EXPECT_NEAR(std::fabs(motionAt(m, 2.0).yaw), kPi, 1e-4f);  // half a turn after each 2 s period
  EXPECT_NEAR(std::fabs(motionAt(m, 1.75).yaw), kPi / 2, 1e-4f);
  // Speed along the path is 5 m/s everywhere (closed form, checked by a finite difference).
  for (double t : {0.5, 1.6, 1.8, 3.9}) {
    const float v = (motionAt(m, t + 1e-3).position - motionAt(m, t).position).norm() / 1e-3f;
    EXPECT_NEAR(v, 5.0f, 0.05f) << "t = " << t;
  }
}

TEST(Scenes, SimpleBodyMatchesScenarios) {
  SimpleBody body;
  body.moveTo(BodyPose{}, true);
  const auto& c = body.colliders();
  ASSERT_EQ(c.size(), 6u);
  EXPECT_EQ(c[SimpleBody::kTorso].shape, ColliderShape::Box);
  EXPECT_TRUE(c[SimpleBody::kTorso].halfExtents.isApprox(Vec3(0.20f, 0.30f, 0.12f)));
  EXPECT_TRUE(c[SimpleBody::kTorso].current.position.isApprox(Vec3(0.0f, 1.25f, 0.0f)));
  EXPECT_FLOAT_EQ(c[SimpleBody::kLeftShoulder].radius, 0.08f);
  EXPECT_NEAR(std::fabs(c[SimpleBody::kLeftShoulder].current.position.x()), 0.22f, 1e-6f);
  EXPECT_EQ(c[SimpleBody::kLeftLeg].shape, ColliderShape::Capsule);
  // Total height 0.80 m = 2 * (halfHeight + radius); centre 0.40 m below the hip.
  EXPECT_NEAR(2.0f * (c[SimpleBody::kLeftLeg].halfHeight + c[SimpleBody::kLeftLeg].radius), 0.80f, 1e-6f);
  EXPECT_NEAR(c[SimpleBody::kLeftLeg].current.position.y(), 0.55f, 1e-6f);
  EXPECT_EQ(c[SimpleBody::kGround].shape, ColliderShape::Plane);
  EXPECT_EQ(body.bodyColliders().size, 5u);
}

TEST(Scenes, CapeRigs) {
  const CapeRig corners = makeCapeRig(20, PinLayout::Corners);
  ASSERT_TRUE(corners.fabric);
  EXPECT_EQ(corners.pinnedParticles.size(), 2u);
  EXPECT_NEAR(corners.fabric->totalMass(), 0.4f, 1e-5f);
  EXPECT_NEAR(std::fabs(corners.pinLocalPoints[0].x()), 0.30f, 1e-6f);
  EXPECT_NEAR(corners.pinLocalPoints[0].y(), 1.56f, 1e-6f);
  EXPECT_NEAR(corners.pinLocalPoints[0].z(), 0.15f, 1e-6f);
  const CapeRig collar = makeCapeRig(20, PinLayout::Collar);
  EXPECT_EQ(collar.pinnedParticles.size(), 20u);
}

/// A collar 0.35 m across whose ends come 5 cm forward (narrower and deeper than the default).
CollarShape narrowCollar() {
  CollarShape collar;
  collar.span = 0.35f;
  collar.wrap = 0.05f;
  return collar;
}

TEST(Scenes, AGatheredCapeHangsFromAnArcAcrossTheShoulders) {
  // A 0.6 m cape on narrowCollar(): the whole top row pinned, evenly along X from -0.175 to +0.175, on the
  // parabola z = 0.15 - 0.05 (2x / 0.35)^2 at the pin line's height.
  const CollarShape collar = narrowCollar();
  const CapeRig rig = makeCapeRig(20, PinLayout::Gathered, true, CapeSize(), 0, 0.0f, collar);
  ASSERT_TRUE(rig.fabric);
  ASSERT_EQ(rig.pinnedParticles.size(), 20u);
  EXPECT_NEAR(rig.fabric->totalMass(), 0.4f, 1e-5f);  // the fabric is the canonical one, only gathered
  for (std::size_t k = 0; k < 20; ++k) {
    EXPECT_EQ(rig.pinnedParticles[k], k);
    const Vec3& p = rig.pinLocalPoints[k];
    const float x = -0.175f + 0.35f * static_cast<float>(k) / 19.0f;
    EXPECT_NEAR(p.x(), x, 1e-6f);
    EXPECT_NEAR(p.y(), 1.56f, 1e-6f);
    EXPECT_NEAR(p.z(), 0.15f - 0.05f * (2.0f * x / 0.35f) * (2.0f * x / 0.35f), 1e-6f);
  }
  // The start shape: the top row on the pins, rows below pulled in by span / width and bent back to flat
  // within 6 cm (the third row, 10.5 cm down, is flat at z = 0.15).
  const Pose start = capeStartPlacement(SceneKind::Walk);
  const Points& rest = rig.fabric->restPositions();
  for (std::size_t k = 0; k < 20; ++k)
    EXPECT_LT(
        (start.apply(gatheredPoint(rest.row(k).transpose(), CapeSize(), collar)) - rig.pinLocalPoints[k])
            .norm(),
        1e-6f);
  const Vec3 third = start.apply(gatheredPoint(rest.row(2 * 20 + 19).transpose(), CapeSize(), collar));
  EXPECT_NEAR(third.x(), 0.175f, 1e-6f);
  EXPECT_NEAR(third.z(), 0.15f, 1e-6f);
}

// The hang starts the cape level, sticking out behind (capeStartPlacement turns the grid's -Y onto +Z), from
// the same collar pins as the walk. gatheredPoint bends the top rows forward in the grid's z, which the turn
// makes downward: its top row missed the pins by up to wrap * sqrt(2), 7 cm here (4.2 cm with the default
// collar: 4.5 spacings of a 64 x 64 cape), and the first step snapped it there. gatheredLevelPoint's top row
// is on the pins, and every column straight at its rest spacing.
TEST(Scenes, AGatheredCapeStartingLevelHasItsTopRowOnTheCollarPins) {
  const CollarShape collar = narrowCollar();
  const CapeRig rig = makeCapeRig(20, PinLayout::Gathered, true, CapeSize(), 0, 0.0f, collar);
  ASSERT_TRUE(rig.fabric);
  const Pose hang = capeStartPlacement(SceneKind::Hang);
  const Points& rest = rig.fabric->restPositions();
  float oldMiss = 0.0f;
  for (std::size_t k = 0; k < 20; ++k) {
    const Vec3 local = rest.row(static_cast<Eigen::Index>(k)).transpose();
    EXPECT_LT((hang.apply(gatheredLevelPoint(local, CapeSize(), collar)) - rig.pinLocalPoints[k]).norm(),
              1e-6f)
        << "column " << k;
    oldMiss = std::max(oldMiss,
                       (hang.apply(gatheredPoint(local, CapeSize(), collar)) - rig.pinLocalPoints[k]).norm());
  }
  EXPECT_GT(oldMiss, 0.07f);
  // Each column straight, level (the pin line's height) and at the rest spacing of 1/19 m.
  for (int col = 0; col < 20; ++col)
    for (int row = 0; row + 1 < 20; ++row) {
      const Vec3 a = hang.apply(gatheredLevelPoint(rest.row(row * 20 + col).transpose(), CapeSize(), collar));
      const Vec3 b =
          hang.apply(gatheredLevelPoint(rest.row((row + 1) * 20 + col).transpose(), CapeSize(), collar));
      EXPECT_NEAR((b - a).norm(), 1.0f / 19.0f, 1e-5f);
      EXPECT_NEAR(b.y(), 1.56f, 1e-6f);
      EXPECT_GT(b.z(), a.z());  // out behind
    }
}

// SimpleScene starts a gathered cape as cape_walk does: its top row on the collar pins (gatheredStartPoint),
// where it used to start flat at its full width, 8.5 cm from its end pins, and the first step snapped it
// onto the collar.
TEST(Scenes, ASimpleSceneStartsAGatheredCapeOnItsPins) {
  for (const SceneKind kind : {SceneKind::Hang, SceneKind::Walk, SceneKind::SprintTurn, SceneKind::Wind}) {
    const Vec3 offset(3.0f, 0.0f, -2.0f);
    SimpleScene scene(kind, 20, PinLayout::Gathered, CapeSettings(), offset);
    ASSERT_TRUE(scene.status().ok());
    const Points& x = scene.cape().state().positions;
    float miss = 0.0f;
    for (const Pin& pin : scene.cape().state().pins)
      miss = std::max(miss, (x.row(pin.particle).transpose() - pin.target).norm());
    EXPECT_LT(miss, 1e-5f) << toString(kind);
    // Gathered across, not stretched along: the end columns at their rest spacing below the top 6 cm, where
    // gatheredPoint bends the collar's wrap out (the level start has none).
    const Points& rest = scene.rig().fabric->restPositions();
    for (int col = 0; col < 20; col += 19)
      for (int row = kind == SceneKind::Hang ? 0 : 2; row + 1 < 20; ++row) {
        const Eigen::Index a = row * 20 + col, b = (row + 1) * 20 + col;
        EXPECT_NEAR((x.row(b) - x.row(a)).norm(), (rest.row(b) - rest.row(a)).norm(), 1e-5f)
            << toString(kind) << " column " << col << " row " << row;
      }
  }
}

TEST(Metrics, FoldMeterMeasuresDihedralAnglesAndTheirChange) {
  const CapeRig rig = makeCapeRig(5, PinLayout::Corners);  // 5 x 5: 16 cells, 32 triangles
  const Fabric& f = *rig.fabric;
  // Interior edges of 4 x 4 cells, each halved along one diagonal: 3 x 4 + 4 x 3 between cells, one
  // diagonal in each of the 16 cells.
  Points x = f.restPositions();
  FoldMeter meter;
  FoldStats flat = meter.measure(f, x);
  EXPECT_EQ(flat.edges, 40u);
  EXPECT_NEAR(flat.meanDihedral, 0.0f, 1e-3f);
  EXPECT_EQ(flat.meanChange, 0.0f);  // nothing to compare with yet
  // Folded by 90 degrees along the middle column (x = half the width): exactly the 4 edges on that line
  // bend, by pi / 2; every other interior edge stays flat.
  const float mid = 0.5f * restWidth(f);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    if (x(i, 0) > mid + 1e-6f) {
      const float d = x(i, 0) - mid;
      x(i, 0) = mid;
      x(i, 2) = d;
    }
  }
  const FoldStats folded = meter.measure(f, x);
  EXPECT_EQ(folded.edges, 40u);
  EXPECT_NEAR(folded.meanDihedral, 4.0f * static_cast<float>(kPi / 2) / 40.0f, 1e-4f);
  EXPECT_NEAR(folded.meanChange, folded.meanDihedral, 1e-4f);  // every change since the flat sheet
  const FoldStats again = meter.measure(f, x);
  EXPECT_NEAR(again.meanDihedral, folded.meanDihedral, 1e-6f);
  EXPECT_EQ(again.meanChange, 0.0f);  // the same shape twice
  // A rigid motion changes no angle.
  const Eigen::Matrix3f turn = Eigen::AngleAxisf(0.7f, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  Points moved = (x * turn.transpose()).rowwise() + Eigen::RowVector3f(4, -2, 9);
  const FoldStats rigid = meter.measure(f, moved);
  EXPECT_NEAR(rigid.meanDihedral, folded.meanDihedral, 1e-4f);
  EXPECT_LT(rigid.meanChange, 1e-3f);
  // A collapsed triangle and a NaN are left out, not propagated.
  moved.row(0) = moved.row(1);
  moved(24, 1) = std::numeric_limits<float>::quiet_NaN();
  const FoldStats broken = meter.measure(f, moved);
  EXPECT_LT(broken.edges, 40u);
  EXPECT_TRUE(std::isfinite(broken.meanDihedral));
  EXPECT_TRUE(std::isfinite(broken.meanChange));
}

RunSummary runScene(SceneKind kind, int n = 20, double seconds = -1.0,
                    const CapeSettings& settings = CapeSettings()) {
  SimpleScene scene(kind, n, PinLayout::Corners, settings);
  EXPECT_TRUE(scene.status().ok());
  MetricsRecorder rec;
  SelfIntersectionCounter counter;
  const double length = seconds > 0 ? seconds : scene.motion().duration;
  const int frames = static_cast<int>(std::lround(length * 60.0));
  for (int f = 0; f < frames; ++f) {
    scene.advanceFrame();
    rec.add(measureFrame(scene.cape(), scene.body().bodyColliders(), scene.body().torsoCentre(), &counter));
  }
  return rec.summary();
}

TEST(Scenes, WalkMeetsTheStrainAndPenetrationBounds) {
  const RunSummary s = runScene(SceneKind::Walk);
  EXPECT_EQ(s.frames, 600);
  EXPECT_FALSE(s.blowUp);
  EXPECT_LE(s.medianFrameMaxStrain, 0.03f);
  EXPECT_LE(s.p95FrameMaxStrain, 0.05f);
  EXPECT_EQ(s.framesPenetrationOver1mm, 0) << "max " << s.maxPenetration;
  EXPECT_LT(s.pinErrorMax, 1e-5f);
}

TEST(Scenes, SprintTurnLeavesNoParticleDeeperThan1mm) {
  const RunSummary s = runScene(SceneKind::SprintTurn);
  EXPECT_FALSE(s.blowUp);
  EXPECT_LE(s.maxPenetration, 0.001f);
  EXPECT_EQ(s.framesPenetrationOver1mm, 0);
  EXPECT_LT(s.pinErrorMax, 1e-5f);
}

// Strain-adaptive substepping: the sprint's 180-degree turns stretch a cape stepped at a fixed 3 substeps
// per frame to 60 % at the p95 frame; refining while the strain is over 5 % keeps it near 10 %.
TEST(Scenes, StrainAdaptiveSubstepsHoldTheSprintTurn) {
  const RunSummary adaptive = runScene(SceneKind::SprintTurn);
  CapeSettings fixed;
  fixed.strainLimit = 0.0f;
  const RunSummary plain = runScene(SceneKind::SprintTurn, 20, -1.0, fixed);
  EXPECT_LE(adaptive.p95FrameMaxStrain, 0.15f);
  EXPECT_GT(plain.p95FrameMaxStrain, 2.0f * adaptive.p95FrameMaxStrain)
      << "the refinement must be what helps";
  // Walking never needs it: the cape ends the walk back at the settings' substeps.
  SimpleScene walk(SceneKind::Walk, 20, PinLayout::Corners, CapeSettings());
  for (int f = 0; f < 120; ++f) walk.advanceFrame();
  EXPECT_EQ(walk.cape().substepRefinement(), 1);
  EXPECT_LT(walk.cape().lastMaxStrain(), 0.05f);
}

TEST(Scenes, HangSettles) {
  const RunSummary s = runScene(SceneKind::Hang);
  EXPECT_FALSE(s.blowUp);
  EXPECT_LT(s.restJitter, 0.01f) << "mean particle speed over the last second, m/s";
  EXPECT_EQ(s.framesPenetrationOver1mm, 0);
}

}  // namespace
}  // namespace cape
