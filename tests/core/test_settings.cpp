// Bad input is rejected with a clear message: settings, fabrics, capes, pins and steps.
#include "CapeTestFixture.h"

#include <cmath>
#include <limits>

namespace cape {
namespace {

using test::makeGrid;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

void expectRejected(const CapeSettings& s, const char* field) {
  const Status st = s.validate();
  EXPECT_FALSE(st.ok()) << field;
  EXPECT_NE(st.message().find(field), std::string::npos)
      << "message should name " << field << ": " << st.message();
}

TEST(Settings, DefaultsAndSeedAreValid) {
  EXPECT_TRUE(CapeSettings().validate().ok());
  EXPECT_TRUE(CapeSettings::unitySeed().validate().ok());
  // The seed's set-up: explicit springs, 4 steps of 0.00875 s per 0.035 s frame.
  const CapeSettings seed = CapeSettings::unitySeed();
  EXPECT_EQ(seed.integrator, Integrator::ExplicitSpring);
  EXPECT_FLOAT_EQ(seed.timeStep / static_cast<float>(seed.substeps), 0.00875f);
}

TEST(Settings, RejectsBadValues) {
  CapeSettings s;
  s.structuralStiffness = 0.0f;
  expectRejected(s, "structuralStiffness");
  s = {};
  s.structuralStiffness = kNaN;
  expectRejected(s, "structuralStiffness");
  s = {};
  s.shearStiffness = -1.0f;
  expectRejected(s, "shearStiffness");
  s = {};
  s.bendStiffness = kNaN;
  expectRejected(s, "bendStiffness");
  s = {};
  s.damping = -0.1f;
  expectRejected(s, "damping");
  s = {};
  s.damping = kInf;
  expectRejected(s, "damping");
  s = {};
  s.collisionThickness = -0.01f;
  expectRejected(s, "collisionThickness");
  s = {};
  s.friction = kNaN;
  expectRejected(s, "friction");
  s = {};
  s.substeps = 0;
  expectRejected(s, "substeps");
  s = {};
  s.iterations = -3;
  expectRejected(s, "iterations");
  s = {};
  s.gravity.y() = kNaN;
  expectRejected(s, "gravity");
  s = {};
  s.timeStep = 0.0f;
  expectRejected(s, "timeStep");
  s = {};
  s.integrator = Integrator::ExplicitSpring;
  s.structuralStiffness = kInf;
  expectRejected(s, "finite stiffness");
  s = {};
  s.wind.model = WindSettings::Model::Aerodynamic;
  s.wind.direction = Vec3::Zero();
  expectRejected(s, "wind");
}

TEST(Settings, FabricsRejectDegenerateInput) {
  GridDesc g;
  g.columns = 1;
  EXPECT_FALSE(Fabric::grid(g).status.ok());
  g = {};
  g.totalMass = 0.0f;
  EXPECT_FALSE(Fabric::grid(g).status.ok());
  g = {};
  g.totalMass = -1.0f;
  EXPECT_FALSE(Fabric::grid(g).status.ok());
  g = {};
  g.width = kNaN;
  EXPECT_FALSE(Fabric::grid(g).status.ok());
  g = {};
  g.height = 0.0f;
  EXPECT_FALSE(Fabric::grid(g).status.ok());
  g = {};
  g.tetherAnchors = {100000};
  EXPECT_FALSE(Fabric::grid(g).status.ok());
  g = {};
  g.tetherAnchors = {0};
  g.tetherScale = 0.5f;
  EXPECT_FALSE(Fabric::grid(g).status.ok());
  g = {};
  g.columns = g.rows = 1;
  const FabricResult bad = Fabric::grid(g);
  EXPECT_FALSE(bad);
  EXPECT_FALSE(bad.status.message().empty());

  MeshDesc m;
  EXPECT_FALSE(Fabric::fromMesh(m).status.ok());  // no triangles: no springs
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  m.triangles = {0, 1, 5};
  EXPECT_FALSE(Fabric::fromMesh(m).status.ok());  // index out of range
  m.triangles = {0, 1, 1};
  EXPECT_FALSE(Fabric::fromMesh(m).status.ok());  // repeated vertex
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)};
  m.triangles = {0, 1, 2};
  EXPECT_FALSE(Fabric::fromMesh(m).status.ok());  // zero area
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, kNaN, 0)};
  EXPECT_FALSE(Fabric::fromMesh(m).status.ok());  // NaN vertex
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  m.totalMass = -0.4f;
  EXPECT_FALSE(Fabric::fromMesh(m).status.ok());
  m.totalMass = 0.4f;
  EXPECT_TRUE(Fabric::fromMesh(m).status.ok());
}

TEST(Settings, CapeWithBadInputIsEmptyAndInert) {
  Cape none(nullptr, CapeSettings());
  EXPECT_FALSE(none.ok());
  none.step(1.0f / 60.0f, {});  // does nothing, does not crash

  CapeSettings bad;
  bad.substeps = 0;
  Cape badSettings(makeGrid(4, 4), bad);
  EXPECT_FALSE(badSettings.ok());
  EXPECT_NE(badSettings.status().message().find("substeps"), std::string::npos);
  badSettings.step(1.0f / 60.0f, {});

  Pose nanPlacement;
  nanPlacement.position.x() = kNaN;
  Cape badPlacement(makeGrid(4, 4), CapeSettings(), nanPlacement);
  EXPECT_FALSE(badPlacement.ok());
}

TEST(Settings, SetSettingsKeepsTheOldOnesWhenRejected) {
  Cape cape(makeGrid(4, 4), CapeSettings());
  ASSERT_TRUE(cape.ok());
  CapeSettings bad;
  bad.damping = -1.0f;
  EXPECT_FALSE(cape.setSettings(bad).ok());
  EXPECT_EQ(cape.settings().damping, CapeSettings().damping);
  // The explicit mode beyond its stability bound is refused with the bound in the message.
  CapeSettings explicitStiff;
  explicitStiff.integrator = Integrator::ExplicitSpring;
  explicitStiff.substeps = 1;
  const Status st = cape.setSettings(explicitStiff);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("stability bound"), std::string::npos) << st.message();
  EXPECT_EQ(cape.settings().integrator, Integrator::Xpbd);
}

TEST(Settings, NonFiniteStepAndPinInputAreIgnored) {
  Cape cape(makeGrid(4, 4), CapeSettings());
  const Points before = cape.state().positions;
  cape.step(kNaN, {});
  cape.step(-1.0f, {});
  cape.step(0.0f, {});
  EXPECT_EQ(cape.state().positions, before);
  EXPECT_EQ(cape.pin(0, Vec3(kNaN, 0, 0)), static_cast<std::size_t>(-1));
  EXPECT_EQ(cape.pin(1000, Vec3::Zero()), static_cast<std::size_t>(-1));
  const std::size_t k = cape.pin(0, Vec3::Zero());
  ASSERT_EQ(k, 0u);
  cape.movePin(k, Vec3(kInf, 0, 0));  // ignored: the pin holds still
  cape.step(1.0f / 60.0f, {});
  EXPECT_TRUE(cape.state().positions.allFinite());
  EXPECT_EQ(test::row(cape.state().positions, 0), Vec3::Zero());
  Pose nanTeleport;
  nanTeleport.position.y() = kNaN;
  cape.teleport(nanTeleport);
  EXPECT_TRUE(cape.state().positions.allFinite());
}

TEST(Settings, UnpinRestoresTheMass) {
  FabricPtr f = makeGrid(4, 4);
  Cape cape(f, CapeSettings());
  cape.pin(5, Vec3::Zero());
  EXPECT_EQ(cape.state().inverseMasses[5], 0.0f);
  cape.unpin(5);
  EXPECT_FLOAT_EQ(cape.state().inverseMasses[5], 1.0f / f->masses()[5]);
  EXPECT_TRUE(cape.state().pins.empty());
}

TEST(Settings, ASubstepOverrideStepsAsTheSettingsSubstepsWouldAndIsRefusedOutOfRange) {
  // A level of detail's substeps (Cape::setSubstepOverride): 2 per 1/60 s in place of the settings' 3 gives
  // the bits of settings with 2, and 0 gives the settings' own back, from the state as it is.
  FabricPtr f = makeGrid(8, 8, 0.6f, 1.0f, 0.4f, true, {0, 7});
  CapeSettings two;
  two.substeps = 2;
  Cape lod(f, CapeSettings()), ref(f, two), full(f, CapeSettings());
  for (Cape* c : {&lod, &ref, &full}) {
    c->pin(0, test::row(f->restPositions(), 0));
    c->pin(7, test::row(f->restPositions(), 7));
  }
  ASSERT_TRUE(lod.setSubstepOverride(2).ok());
  EXPECT_EQ(lod.substepOverride(), 2);
  for (int k = 0; k < 30; ++k) {
    lod.step(1.0f / 60.0f, {});
    ref.step(1.0f / 60.0f, {});
  }
  EXPECT_EQ(stateHash(lod.state()), stateHash(ref.state()));
  ASSERT_TRUE(lod.setSubstepOverride(0).ok());
  full.mutableState() = lod.state();
  for (int k = 0; k < 30; ++k) {
    lod.step(1.0f / 60.0f, {});
    full.step(1.0f / 60.0f, {});
  }
  EXPECT_EQ(stateHash(lod.state()), stateHash(full.state()));
  for (int bad : {-1, 1001}) {
    const Status s = lod.setSubstepOverride(bad);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("setSubstepOverride"), std::string::npos) << s.message();
    EXPECT_EQ(lod.substepOverride(), 0);
  }
}

}  // namespace
}  // namespace cape
