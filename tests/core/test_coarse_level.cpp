// The coarse level of detail (Cape::setCoarseLevel, Fabric::coarseLevel; issue 15): a grid fabric's coarse
// level, a cape stepping it in its place with its particles interpolated from it, and what carries state
// across the switches. The canonical cape hung by its corners (or its whole top row) among still colliders.
#include "CapeTestFixture.h"
#include "HangingCape.h"

#include "cape/core/Cape.h"
#include "cape/scenes/Scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace cape {
namespace {

using test::Hanging;

// The walk's settings, as the canonical scenes run.
CapeSettings walkSettings() {
  return settingsForScene(SceneKind::Walk, CapeSettings());
}

float largestDifference(const Points& a, const Points& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

bool sameBits(const Points& a, const Points& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(float) * a.size()) == 0;
}

float largestPinError(const Cape& cape) {
  float worst = 0.0f;
  for (const Pin& p : cape.state().pins)
    worst = std::max(worst, (cape.state().positions.row(p.particle).transpose() - p.target).norm());
  return worst;
}

}  // namespace

TEST(CoarseFabric, AGridsCoarseLevelIsHalfTheParticlesOverTheSameRectangleAndShared) {
  GridDesc g;
  g.columns = 20;
  g.rows = 21;
  g.width = 0.6f;
  g.height = 1.0f;
  g.totalMass = 0.4f;
  g.tetherAnchors = {0, 19, 9, 10};  // the top corners and two middle particles of the top row
  const FabricPtr fine = Fabric::grid(g).fabric;
  ASSERT_TRUE(fine);
  const FabricPtr coarse = fine->coarseLevel();
  ASSERT_TRUE(coarse);
  EXPECT_EQ(coarse, fine->coarseLevel());  // built once, shared
  EXPECT_EQ(coarse->gridColumns(), 10);
  EXPECT_EQ(coarse->gridRows(), 11);
  EXPECT_NEAR(coarse->totalMass(), fine->totalMass(), 1e-5f);
  // The same rectangle: the corners coincide.
  EXPECT_EQ(coarse->restPositions().row(9), fine->restPositions().row(19));
  EXPECT_EQ(coarse->restPositions().row(10 * 11 - 1), fine->restPositions().row(20 * 21 - 1));
  // The King's graph of the coarse grid, and tethers to the anchors carried over: the corners and the coarse
  // particles nearest 9 and 10 (columns 9 * 9 / 19 = 4.26 -> 4 and 10 * 9 / 19 = 4.74 -> 5).
  EXPECT_EQ(static_cast<long>(coarse->springs(SpringFamily::Structural).size() +
                              coarse->springs(SpringFamily::Shear).size()),
            kingsGraphSpringCount(10, 11));
  std::vector<std::uint32_t> anchors(coarse->tethers().anchor);
  std::sort(anchors.begin(), anchors.end());
  anchors.erase(std::unique(anchors.begin(), anchors.end()), anchors.end());
  EXPECT_EQ(anchors, (std::vector<std::uint32_t>{0, 4, 5, 9}));
  // Nothing coarser than a 3 x 3 grid, and nothing for a mesh fabric.
  EXPECT_TRUE(test::makeGrid(3, 3)->coarseLevel());
  EXPECT_FALSE(test::makeGrid(2, 8)->coarseLevel());
  MeshDesc m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  m.triangles = {0, 1, 2};
  const FabricPtr mesh = Fabric::fromMesh(m).fabric;
  ASSERT_TRUE(mesh);
  EXPECT_FALSE(mesh->coarseLevel());
  Cape onMesh(mesh, CapeSettings());
  const Status s = onMesh.setCoarseLevel(true);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("coarse level"), std::string::npos) << s.message();
  EXPECT_FALSE(onMesh.coarseLevel());
}

TEST(CoarseFabric, OnAndOffBeforeAStepChangesNoBit) {
  Hanging plain(walkSettings()), toggled(walkSettings());
  plain.frames(30);
  toggled.frames(30);
  ASSERT_TRUE(toggled.cape.setCoarseLevel(true).ok());
  ASSERT_TRUE(toggled.cape.setCoarseLevel(false).ok());
  plain.frames(60);
  toggled.frames(60);
  EXPECT_FALSE(toggled.cape.steppedCoarse());
  EXPECT_EQ(stateHash(plain.cape.state()), stateHash(toggled.cape.state()));
}

TEST(CoarseFabric, TheCoarseLevelHangsLikeTheFineOnePinnedAndFinite) {
  for (const PinLayout layout : {PinLayout::Corners, PinLayout::Collar}) {
    Hanging fine(walkSettings(), layout), coarse(walkSettings(), layout);
    ASSERT_TRUE(coarse.cape.setCoarseLevel(true).ok());
    float worstPin = 0.0f;
    for (int f = 0; f < 180; ++f) {
      // Swing the pins sideways and back, a walk's sway.
      const Vec3 d(0.004f * std::sin(0.1f * static_cast<float>(f)), 0.0f, 0.0f);
      fine.movePins(d);
      coarse.movePins(d);
      fine.frames(1);
      coarse.frames(1);
      EXPECT_TRUE(coarse.cape.steppedCoarse());
      worstPin = std::max(worstPin, largestPinError(coarse.cape));
    }
    EXPECT_TRUE(coarse.cape.state().positions.allFinite());
    EXPECT_TRUE(coarse.cape.state().velocities.allFinite());
    EXPECT_EQ(worstPin, 0.0f);  // a fine pinned particle sits on its pin's target
    EXPECT_NEAR(coarse.cape.state().time, 3.0, 1e-6);
    const float gap = largestDifference(fine.cape.state().positions, coarse.cape.state().positions);
    EXPECT_LT(gap, 0.05f) << (layout == PinLayout::Corners ? "corners" : "collar");
    std::printf("[ coarse ] %s: largest gap to the fine cape after 3 s %.2f cm\n",
                layout == PinLayout::Corners ? "corners" : "collar", 100 * gap);
  }
}

TEST(CoarseFabric, SwitchesMoveNoParticleMoreThanACentimetre) {
  // Against a fine twin, the frame of each switch (fine -> coarse, coarse -> fine, again) moves no particle
  // more than 1 cm differently; the fine detail fades over kCoarseBlendTime, and then the cape is the coarse
  // level interpolated.
  Hanging fine(walkSettings()), lod(walkSettings());
  float worst = 0.0f;
  for (int f = 0; f < 240; ++f) {
    const Vec3 d(0.006f * std::sin(0.08f * static_cast<float>(f)), 0.0f, 0.002f * std::cos(0.1f * f));
    fine.movePins(d);
    lod.movePins(d);
    if (f == 60 || f == 180) {
      ASSERT_TRUE(lod.cape.setCoarseLevel(true).ok());
    }
    if (f == 120) {
      ASSERT_TRUE(lod.cape.setCoarseLevel(false).ok());
    }
    const Points a0 = fine.cape.state().positions, b0 = lod.cape.state().positions;
    fine.frames(1);
    lod.frames(1);
    if (f == 60 || f == 120 || f == 180) {
      const float jump = ((lod.cape.state().positions - b0) - (fine.cape.state().positions - a0))
                             .rowwise()
                             .norm()
                             .maxCoeff();
      worst = std::max(worst, jump);
      EXPECT_LT(jump, 0.01f) << "switch at frame " << f;
    }
  }
  std::printf("[ coarse ] the largest particle jump at a switch, against the fine twin: %.2f mm\n",
              1000 * worst);
  EXPECT_TRUE(lod.cape.steppedCoarse());
}

TEST(CoarseFabric, DeterministicAndRigidUnderTeleport) {
  Hanging a(walkSettings()), b(walkSettings());
  ASSERT_TRUE(a.cape.setCoarseLevel(true).ok());
  ASSERT_TRUE(b.cape.setCoarseLevel(true).ok());
  a.frames(40);
  b.frames(40);
  EXPECT_EQ(stateHash(a.cape.state()), stateHash(b.cape.state()));
  // A teleport carries the interpolated cape rigidly, and the coarse level with it.
  Pose delta;
  delta.position = Vec3(3.0f, 0.0f, -2.0f);
  delta.rotation = Quat(Eigen::AngleAxisf(0.7f, Vec3::UnitY()));
  const Points before = a.cape.state().positions;
  a.cape.teleport(delta);
  for (Eigen::Index i = 0; i < before.rows(); ++i)
    EXPECT_LT((a.cape.state().positions.row(i).transpose() - delta.apply(before.row(i).transpose())).norm(),
              1e-5f);
  for (Collider& c : a.colliders) {
    Pose moved;
    moved.position = delta.apply(c.current.position);
    moved.rotation = delta.rotation * c.current.rotation;
    c.teleportTo(moved);
  }
  a.frames(2);
  EXPECT_TRUE(a.cape.steppedCoarse());
  EXPECT_TRUE(a.cape.state().positions.allFinite());
  EXPECT_LT(largestPinError(a.cape), 1e-6f);
}

TEST(CoarseFabric, AMovedFrameKeepsTheCoarseLevelWhereItIs) {
  // The Bullet adapter moves a cape's frame along with its character (Cape::setOrigin): the coarse level's
  // frame moves with it, so the cape stays where it is in the world and steps on as its twin does.
  Hanging still(walkSettings()), moved(walkSettings());
  ASSERT_TRUE(still.cape.setCoarseLevel(true).ok());
  ASSERT_TRUE(moved.cape.setCoarseLevel(true).ok());
  still.frames(20);
  moved.frames(20);
  const Eigen::Vector3d origin(16.0, 0.0, -32.0);
  moved.cape.setOrigin(origin);
  const Vec3 shift = (-origin).cast<float>();
  for (Collider& c : moved.colliders) c.teleportTo(test::at(c.current.position + shift));
  for (std::size_t k = 0; k < moved.cape.state().pins.size(); ++k)
    EXPECT_EQ(moved.cape.state().pins[k].target, still.cape.state().pins[k].target + shift);
  still.frames(40);
  moved.frames(40);
  EXPECT_TRUE(moved.cape.steppedCoarse());
  const Points world = moved.cape.state().positions.rowwise() - shift.transpose();
  EXPECT_LT(largestDifference(world, still.cape.state().positions), 1e-4f);
}

TEST(CoarseFabric, ANaNInTheStateOutlivesNoStep) {
  // A particle made NaN (or thrown 1e30 m away) while the coarse level is on: the coarse cape starts again
  // from the state, its numerical guard restores what it sampled from the lost particle, and the cape it
  // drives is finite after that very step, its guard report saying so.
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), 1e30f}) {
    Hanging h(walkSettings());
    ASSERT_TRUE(h.cape.setCoarseLevel(true).ok());
    h.frames(10);
    h.cape.mutableState().positions.row(210).setConstant(bad);
    h.cape.mutableState().velocities.row(45).setConstant(bad);
    h.frames(1);
    EXPECT_TRUE(h.cape.steppedCoarse());
    EXPECT_TRUE(h.cape.state().positions.allFinite()) << bad;
    EXPECT_TRUE(h.cape.state().velocities.allFinite()) << bad;
    EXPECT_GT(h.cape.guard().lastStep, 0u) << bad;
    h.frames(30);
    EXPECT_TRUE(h.cape.state().positions.allFinite()) << bad;
    EXPECT_EQ(largestPinError(h.cape), 0.0f);
  }
}

TEST(CoarseFabric, PerParticleMapsKeepTheCapeOnItsOwnFabric) {
  // A mass scale, a stiffness scale or motion constraints are per particle of the fabric: while one is set
  // the cape steps its own fabric whatever the level, and the same bits as a cape without the level.
  Hanging plain(walkSettings()), lod(walkSettings());
  const Eigen::VectorXf heavier = Eigen::VectorXf::Constant(400, 1.5f);
  ASSERT_TRUE(plain.cape.setMassScale(heavier).ok());
  ASSERT_TRUE(lod.cape.setMassScale(heavier).ok());
  ASSERT_TRUE(lod.cape.setCoarseLevel(true).ok());
  plain.frames(30);
  lod.frames(30);
  EXPECT_FALSE(lod.cape.steppedCoarse());
  EXPECT_TRUE(sameBits(plain.cape.state().positions, lod.cape.state().positions));
  ASSERT_TRUE(lod.cape.setMassScale(Eigen::VectorXf()).ok());
  lod.frames(1);
  EXPECT_TRUE(lod.cape.steppedCoarse());
}

TEST(CoarseFabric, ARestingCoarseCapeSleepsAndWakesWhenAPinMoves) {
  Hanging h(walkSettings());
  ASSERT_TRUE(h.cape.setCoarseLevel(true).ok());
  h.frames(600);
  ASSERT_TRUE(h.cape.isAsleep());
  const Points asleep = h.cape.state().positions;
  const std::uint64_t slept = h.cape.sleptSteps();
  h.frames(10);
  EXPECT_EQ(h.cape.sleptSteps(), slept + 10);
  EXPECT_TRUE(sameBits(asleep, h.cape.state().positions));
  h.movePins(Vec3(0.05f, 0.0f, 0.0f));
  h.frames(1);
  EXPECT_FALSE(h.cape.isAsleep());
  EXPECT_FALSE(sameBits(asleep, h.cape.state().positions));
  EXPECT_EQ(largestPinError(h.cape), 0.0f);
}

}  // namespace cape
