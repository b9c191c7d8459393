// Levels of detail (issue 15): a cape that steps once every few internal steps of the world, or with fewer
// substeps, set by hand (CapeAction::setDetailLevel) or by distance from a viewpoint (CapeGroup). Real
// Bullet worlds: the walk of docs/SCENES.md on the simple body, against a full-detail twin.
#include "BulletFixture.h"

#include "cape/bullet/CapeGroup.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

using namespace capetest;
using cape::bullet::CapeAction;
using cape::bullet::CapeGroup;
using cape::bullet::DetailBand;
using cape::bullet::DetailLevel;

namespace {

/// The largest distance between the same particle of two capes, m.
float largestGap(const cape::Points& a, const cape::Points& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

/// The largest difference between two capes' motion of the same particle over one frame, m: a cape that
/// pops at a switch of detail moves differently from its full-detail twin in that frame.
float largestMotionGap(const cape::Points& a0, const cape::Points& a1, const cape::Points& b0,
                       const cape::Points& b1) {
  return ((a1 - a0) - (b1 - b0)).rowwise().norm().maxCoeff();
}

/// Two walks side by side in worlds of their own: `full` at full detail, `lod` switched as the test says.
struct Twins {
  World fullWorld, lodWorld;
  SimpleWalk full{fullWorld, btVector3(0, 0, 0), cape::bullet::CapeActionSettings(), true};
  SimpleWalk lod{lodWorld, btVector3(0, 0, 0), cape::bullet::CapeActionSettings(), true};
  void advance() {
    full.advance();
    lod.advance();
  }
};

/// A cape with nothing pinned, in a world without gravity, with particle 0 (its detail point) at `at`.
std::unique_ptr<CapeAction> floatingCape(const btVector3& at) {
  return std::make_unique<CapeAction>(cornerFabric(), cape::CapeSettings(),
                                      btTransform(btQuaternion::getIdentity(), at));
}

}  // namespace

TEST(DetailLevel, FullDetailSetByHandKeepsEveryBit) {
  Twins t;
  ASSERT_TRUE(t.lod.action->setDetailLevel(DetailLevel{4, 2}).ok());
  ASSERT_TRUE(t.lod.action->setDetailLevel(DetailLevel{}).ok());  // before any step: back to full
  for (int f = 0; f < 120; ++f) t.advance();
  EXPECT_EQ(cape::stateHash(t.full.action->cape().state()), cape::stateHash(t.lod.action->cape().state()));
  EXPECT_EQ(t.lod.action->stepCount(), 480u);
}

TEST(DetailLevel, AnIntervalStepsOncePerIntervalOverTheWholeTime) {
  for (int interval : {2, 4}) {
    World w;
    SimpleWalk walk(w, btVector3(0, 0, 0), cape::bullet::CapeActionSettings(), true);
    ASSERT_TRUE(walk.action->setDetailLevel(DetailLevel{interval, 0}).ok());
    for (int f = 0; f < 60; ++f) {
      walk.advance();
      // The frame's four internal steps make 4 / interval steps of the cape, the last at the frame's end.
      EXPECT_FALSE(walk.action->stepDue());
      EXPECT_NEAR(walk.action->cape().state().time, (f + 1) / 60.0, 1e-5) << "interval " << interval;
    }
    EXPECT_EQ(walk.action->stepCount(), std::uint64_t(240 / interval));
    EXPECT_TRUE(walk.action->positions().allFinite());
  }
}

TEST(DetailLevel, CoarseLevelsWalkCloseToFullDetail) {
  // Every second internal step, once a frame (4 -> 3 substeps a frame), and once a frame with 2 substeps:
  // after the first second (the drop onto the body) the walk stays within a few cm of the full-detail twin,
  // pinned, out of the body and stretched by a few per cent.
  for (const DetailLevel level :
       {DetailLevel{2, 0}, DetailLevel{4, 0}, DetailLevel{4, 2}, DetailLevel{1, 0, true},
        DetailLevel{4, 0, true}, DetailLevel{4, 2, true}}) {
    Twins t;
    ASSERT_TRUE(t.lod.action->setDetailLevel(level).ok());
    for (int f = 0; f < 60; ++f) t.advance();
    float gap = 0, fullStrain = 0, lodStrain = 0, penetration = 0;
    for (int f = 60; f < 240; ++f) {
      t.advance();
      penetration =
          std::max(penetration, cape::maxPenetration(t.lod.action->cape().state().positions,
                                                     cape::ColliderSpan(t.lod.action->coreColliders())));
      gap = std::max(gap, largestGap(t.full.action->positions(), t.lod.action->positions()));
      fullStrain = std::max(fullStrain, maxStructuralStrain(t.full.action->cape()));
      lodStrain = std::max(lodStrain, maxStructuralStrain(t.lod.action->cape()));
    }
    const std::string what = "interval " + std::to_string(level.stepInterval) + ", substeps " +
                             std::to_string(level.substeps) + (level.coarseFabric ? ", coarse fabric" : "");
    EXPECT_LT(gap, 0.04f) << what;
    // With 2 substeps a frame the strain refinement (CapeSettings::strainLimit, 5 %) is what holds it.
    EXPECT_LT(lodStrain, 1.2f * t.lod.action->cape().settings().strainLimit) << what;
    EXPECT_LT(t.lod.action->maxPinError(), 1e-4f) << what;
    EXPECT_LT(penetration, 1e-3f) << what;
    std::printf("[ detail ] %s: largest gap to full detail %.2f cm, max strain %.2f %% (full %.2f %%)\n",
                what.c_str(), 100 * gap, 100 * lodStrain, 100 * fullStrain);
  }
}

TEST(DetailLevel, SwitchingEitherWayMovesNoParticle) {
  // Full -> every 4th step -> full -> once a frame with 2 substeps -> full, one second each: in the frame
  // of each switch no particle moves more than 1 cm differently from the full-detail twin.
  Twins t;
  const DetailLevel plan[] = {
      DetailLevel{},     DetailLevel{4, 0},       DetailLevel{}, DetailLevel{4, 2},
      DetailLevel{},     DetailLevel{4, 2, true}, DetailLevel{}, DetailLevel{1, 0, true},
      DetailLevel{4, 0}, DetailLevel{4, 0, true}, DetailLevel{}};
  float worstSwitch = 0;
  for (int f = 0; f < 660; ++f) {
    if (f % 60 == 0) {
      ASSERT_TRUE(t.lod.action->setDetailLevel(plan[f / 60]).ok());
    }
    const cape::Points a0 = t.full.action->positions(), b0 = t.lod.action->positions();
    t.advance();
    if (f % 60 == 0 && f > 0) {
      const float jump = largestMotionGap(a0, t.full.action->positions(), b0, t.lod.action->positions());
      worstSwitch = std::max(worstSwitch, jump);
      EXPECT_LT(jump, 0.01f) << "switch at frame " << f;
    }
  }
  std::printf("[ detail ] the largest particle jump at a switch, against the full-detail twin: %.2f mm\n",
              1000 * worstSwitch);
  EXPECT_TRUE(t.lod.action->positions().allFinite());
}

TEST(DetailLevel, BackToFullDetailStepsOverTheSkippedTime) {
  World w;
  SimpleWalk walk(w, btVector3(0, 0, 0), cape::bullet::CapeActionSettings(), true);
  ASSERT_TRUE(walk.action->setDetailLevel(DetailLevel{4, 0}).ok());
  // Two internal steps at interval 4: skipped, nothing stepped yet.
  w.world->stepSimulation(2 * kFixed, 8, kFixed);
  EXPECT_EQ(walk.action->stepCount(), 0u);
  EXPECT_EQ(walk.action->cape().state().time, 0.0);
  ASSERT_TRUE(walk.action->setDetailLevel(DetailLevel{}).ok());
  w.world->stepSimulation(kFixed, 8, kFixed);
  EXPECT_EQ(walk.action->stepCount(), 1u);
  EXPECT_NEAR(walk.action->cape().state().time, 3 * kFixed, 1e-6);
}

TEST(DetailLevel, BadLevelsAreRefusedAndTheLevelKept) {
  World w;
  SimpleWalk walk(w, btVector3(0, 0, 0), cape::bullet::CapeActionSettings(), true);
  ASSERT_TRUE(walk.action->setDetailLevel(DetailLevel{2, 3}).ok());
  for (const DetailLevel bad : {DetailLevel{0, 0}, DetailLevel{-1, 0}, DetailLevel{65, 0}, DetailLevel{1, -1},
                                DetailLevel{1, 1001}}) {
    const cape::Status s = walk.action->setDetailLevel(bad);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("DetailLevel"), std::string::npos) << s.message();
    EXPECT_EQ(walk.action->detailLevel(), (DetailLevel{2, 3}));
    EXPECT_EQ(walk.action->cape().substepOverride(), 3);
  }
  EXPECT_FALSE(walk.action->cape().setSubstepOverride(-2).ok());
  EXPECT_EQ(walk.action->cape().substepOverride(), 3);
}

TEST(CapeGroupDetail, BandsByDistanceWithHysteresis) {
  World w;
  w.world->setGravity(btVector3(0, 0, 0));  // the capes stay where they are put
  std::vector<std::unique_ptr<CapeAction>> capes;
  for (float x : {0.0f, 12.0f, 40.0f}) capes.push_back(floatingCape(btVector3(x, 1, 0)));
  CapeGroup group(1);
  for (auto& c : capes) group.add(c.get());
  w.world->addAction(&group);
  const DetailLevel half{2, 0}, frame{4, 2};
  ASSERT_TRUE(group.setDetailPolicy(btVector3(0, 1, 0), {{10, half}, {30, frame}}, 0.5f).ok());
  w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_EQ(group.detailCounts(), (std::vector<std::size_t>{1, 1, 1}));
  EXPECT_EQ(capes[0]->detailLevel(), DetailLevel());
  EXPECT_EQ(capes[1]->detailLevel(), half);
  EXPECT_EQ(capes[2]->detailLevel(), frame);
  EXPECT_EQ(capes[0]->stepCount(), 4u);
  EXPECT_EQ(capes[1]->stepCount(), 2u);
  EXPECT_EQ(capes[2]->stepCount(), 1u);
  EXPECT_EQ(capes[2]->cape().substepOverride(), 2);
  // The middle cape at 9.7 m: still inside the hysteresis of the 10 m band, so it keeps its level...
  group.setViewpoint(btVector3(2.3f, 1, 0));
  w.world->stepSimulation(kFixed, 8, kFixed);
  EXPECT_EQ(capes[1]->detailLevel(), half);
  // ...and at 9.4 m it comes back to full detail; going out again it waits for 10.5 m.
  group.setViewpoint(btVector3(2.6f, 1, 0));
  w.world->stepSimulation(kFixed, 8, kFixed);
  EXPECT_EQ(capes[1]->detailLevel(), DetailLevel());
  group.setViewpoint(btVector3(1.8f, 1, 0));
  w.world->stepSimulation(kFixed, 8, kFixed);
  EXPECT_EQ(capes[1]->detailLevel(), DetailLevel());
  group.setViewpoint(btVector3(1.4f, 1, 0));
  w.world->stepSimulation(kFixed, 8, kFixed);
  EXPECT_EQ(capes[1]->detailLevel(), half);
  // A cape added later gets its band at the next step; a policy without bands puts everyone back.
  capes.push_back(floatingCape(btVector3(-50, 1, 0)));
  group.add(capes.back().get());
  w.world->stepSimulation(kFixed, 8, kFixed);
  EXPECT_EQ(capes[3]->detailLevel(), frame);
  EXPECT_EQ(group.detailCounts(), (std::vector<std::size_t>{1, 1, 2}));
  // A cape removed keeps the level it had; the others keep theirs.
  group.remove(capes[1].get());
  w.world->stepSimulation(kFixed, 8, kFixed);
  EXPECT_EQ(group.detailCounts(), (std::vector<std::size_t>{1, 0, 2}));
  EXPECT_EQ(capes[1]->detailLevel(), half);
  EXPECT_EQ(capes[3]->detailLevel(), frame);
  group.add(capes[1].get());
  ASSERT_TRUE(group.setDetailPolicy(btVector3(0, 1, 0), {}).ok());
  for (auto& c : capes) EXPECT_EQ(c->detailLevel(), DetailLevel());
  EXPECT_TRUE(group.detailCounts().empty());
  w.world->removeAction(&group);
}

TEST(DetailLevel, ACoarseFabricNeedsAGridFabric) {
  // A fabric built from a mesh has no coarse level: setDetailLevel refuses it and keeps the level in use; a
  // group's policy gives such a cape the band's interval and substeps on its own fabric.
  cape::MeshDesc m;
  m.positions = {cape::Vec3(0, 0, 0), cape::Vec3(0.5f, 0, 0), cape::Vec3(0, -0.5f, 0),
                 cape::Vec3(0.5f, -0.5f, 0)};
  m.triangles = {2, 3, 1, 2, 1, 0};
  const cape::FabricPtr mesh = cape::Fabric::fromMesh(m).fabric;
  ASSERT_TRUE(mesh);
  World w;
  w.world->setGravity(btVector3(0, 0, 0));
  CapeAction onMesh(mesh, cape::CapeSettings(),
                    btTransform(btQuaternion::getIdentity(), btVector3(40, 1, 0)));
  ASSERT_TRUE(onMesh.setDetailLevel(DetailLevel{2, 0}).ok());
  const cape::Status s = onMesh.setDetailLevel(DetailLevel{4, 2, true});
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("coarse level"), std::string::npos) << s.message();
  EXPECT_EQ(onMesh.detailLevel(), (DetailLevel{2, 0}));
  EXPECT_FALSE(onMesh.cape().coarseLevel());
  std::unique_ptr<CapeAction> onGrid = floatingCape(btVector3(-40, 1, 0));
  CapeGroup group(1);
  group.add(&onMesh);
  group.add(onGrid.get());
  w.world->addAction(&group);
  ASSERT_TRUE(group.setDetailPolicy(btVector3(0, 1, 0), {{30, DetailLevel{4, 2, true}}}).ok());
  w.world->stepSimulation(kFrame, 8, kFixed);
  EXPECT_EQ(onMesh.detailLevel(), (DetailLevel{4, 2}));
  EXPECT_EQ(onGrid->detailLevel(), (DetailLevel{4, 2, true}));
  EXPECT_TRUE(onGrid->cape().steppedCoarse());
  EXPECT_FALSE(onMesh.cape().steppedCoarse());
  EXPECT_EQ(onMesh.stepCount(), 1u);
  EXPECT_EQ(onGrid->stepCount(), 1u);
  w.world->removeAction(&group);
}

TEST(CapeGroupDetail, BadPoliciesAreRefusedAndThePolicyKept) {
  CapeGroup group(1);
  const DetailLevel half{2, 0};
  ASSERT_TRUE(group.setDetailPolicy(btVector3(0, 0, 0), {{10, half}}).ok());
  const btScalar nan = std::numeric_limits<btScalar>::quiet_NaN();
  EXPECT_FALSE(group.setDetailPolicy(btVector3(nan, 0, 0), {{10, half}}).ok());
  EXPECT_FALSE(group.setDetailPolicy(btVector3(0, 0, 0), {{10, half}, {10, half}}).ok());  // not increasing
  EXPECT_FALSE(group.setDetailPolicy(btVector3(0, 0, 0), {{20, half}, {10, half}}).ok());
  EXPECT_FALSE(group.setDetailPolicy(btVector3(0, 0, 0), {{-1, half}}).ok());
  EXPECT_FALSE(group.setDetailPolicy(btVector3(0, 0, 0), {{nan, half}}).ok());
  EXPECT_FALSE(group.setDetailPolicy(btVector3(0, 0, 0), {{10, DetailLevel{0, 0}}}).ok());
  EXPECT_FALSE(group.setDetailPolicy(btVector3(0, 0, 0), {{10, half}}, -1).ok());
  const cape::Status s = group.setDetailPolicy(btVector3(0, 0, 0), {{10, half}}, nan);
  EXPECT_NE(s.message().find("hysteresis"), std::string::npos) << s.message();
  ASSERT_EQ(group.detailBands().size(), 1u);
  EXPECT_EQ(group.detailBands()[0].distance, 10);
  group.setViewpoint(btVector3(nan, 0, 0));  // ignored
}

TEST(CapeGroupDetail, OneAndTwoThreadsGiveIdenticalBitsWithAPolicy) {
  const auto run = [](int threads) {
    World w;
    std::vector<std::unique_ptr<SimpleWalk>> walks;
    CapeGroup group(threads);
    for (int k = 0; k < 3; ++k) {
      walks.push_back(std::make_unique<SimpleWalk>(w, btVector3(btScalar(8 * k), 0, 0),
                                                   cape::bullet::CapeActionSettings(), k == 0));
      w.world->removeAction(walks.back()->action.get());
      group.add(walks.back()->action.get());
    }
    w.world->addAction(&group);
    EXPECT_TRUE(
        group.setDetailPolicy(btVector3(0, 1.5f, 2), {{5, DetailLevel{2, 0}}, {12, DetailLevel{4, 2, true}}})
            .ok());
    for (int f = 0; f < 60; ++f) {
      for (auto& walk : walks) {  // each walk's bodies to this frame's pose, then one step of the world
        ++walk->frame;
        const btTransform at =
            walk->shift * cape::bullet::toBt(cape::motionAt(walk->motion, walk->frame / 60.0).frame());
        for (auto& part : walk->parts) World::moveKinematic(part.first, at * part.second);
      }
      w.world->stepSimulation(kFrame, 8, kFixed);
    }
    w.world->removeAction(&group);
    std::vector<std::uint64_t> hashes;
    for (auto& walk : walks) hashes.push_back(cape::stateHash(walk->action->cape().state()));
    EXPECT_EQ(group.detailCounts(), (std::vector<std::size_t>{1, 1, 1}));
    return hashes;
  };
  EXPECT_EQ(run(1), run(2));
}
