// The numerical guard and the cape's frame: no NaN or runaway particle outlives the step it appeared in, a
// cape recovers from any pose its pins are given, absurd steps are defined, and a cape whose frame is moved
// far from the world's origin keeps the precision it has at the origin.
#include "CapeTestFixture.h"

#include "SpringSolver.h"

#include "cape/core/Wind.h"
#include "cape/scenes/Metrics.h"

#include <cmath>
#include <limits>

namespace cape {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// The canonical 20 x 20 cape hanging from its top corners at the origin, settled for half a second.
struct Hanging {
  Hanging() : fabric(test::makeGrid(20, 20)), cape(fabric, CapeSettings()) {
    EXPECT_TRUE(cape.ok()) << cape.status().message();
    cape.pin(0, test::row(cape.state().positions, 0));
    cape.pin(19, test::row(cape.state().positions, 19));
    for (int f = 0; f < 30; ++f) cape.step(1.0f / 60.0f, {});
  }
  bool sane() const {
    const Points& x = cape.state().positions;
    return x.allFinite() && cape.state().velocities.allFinite() && structuralStrain(*fabric, x).max < 0.5f &&
           !isBlownUp(x, Vec3(0.3f, -0.5f, 0.0f), 3.0f);
  }
  FabricPtr fabric;
  Cape cape;
};

TEST(Guard, ANaNParticleIsRestoredInTheStepItAppearsIn) {
  Hanging h;
  ASSERT_TRUE(h.sane());
  EXPECT_EQ(h.cape.guard().total, 0u) << "a healthy cape never trips the guard";
  h.cape.mutableState().positions(210, 1) = kNaN;
  h.cape.mutableState().velocities(77, 0) = std::numeric_limits<float>::infinity();
  h.cape.step(1.0f / 60.0f, {});
  EXPECT_TRUE(h.sane());
  // The NaN spread through its springs and collisions in the step; the guard restored all it reached.
  EXPECT_GE(h.cape.guard().lastStep, 2u);
  EXPECT_EQ(h.cape.guard().steps, 1u);
  EXPECT_EQ(h.cape.guard().total, h.cape.guard().lastStep);
  h.cape.step(1.0f / 60.0f, {});
  EXPECT_EQ(h.cape.guard().lastStep, 0u);
  EXPECT_TRUE(h.sane());
}

TEST(Guard, ARunawayParticleIsBroughtBackNearItsPins) {
  Hanging h;
  h.cape.mutableState().positions.row(399) << 1e20f, -1e20f, 3e19f;  // finite, but 1e20 m away
  h.cape.step(1.0f / 60.0f, {});
  EXPECT_GE(h.cape.guard().lastStep, 1u);
  EXPECT_TRUE(h.sane());
}

TEST(Guard, ACapeRecoversWithinOneStepFromAnyState) {
  // What a body moved by 1e20 m and back does to a cape in float world coordinates: its particles come back
  // as garbage up to 1e13 m across, some of it not finite. Its pins are where the body holds them again.
  Hanging h;
  CapeState& state = h.cape.mutableState();
  for (Eigen::Index i = 0; i < state.positions.rows(); ++i)
    for (int c = 0; c < 3; ++c) {
      const float garbage = static_cast<float>((i * 7919 + c * 104729) % 2001 - 1000) * 1e10f;
      state.positions(i, c) = i % 17 == 0 ? kNaN : garbage;
      state.velocities(i, c) = -garbage;
    }
  h.cape.movePin(0, Vec3(0.0f, 0.0f, 0.0f));
  h.cape.movePin(1, Vec3(0.6f, 0.0f, 0.0f));
  h.cape.step(1.0f / 60.0f, {});
  EXPECT_TRUE(h.sane()) << "strain " << structuralStrain(*h.fabric, h.cape.state().positions).max;
  EXPECT_GE(h.cape.guard().lastStep, 390u);
  // The reference the particles went back to stands where the pins hold the cape.
  const Pose& ref = h.cape.referencePose();
  EXPECT_LT((ref.apply(test::row(h.fabric->restPositions(), 0)) - Vec3::Zero()).norm(), 1e-3f);
  EXPECT_LT((ref.apply(test::row(h.fabric->restPositions(), 19)) - Vec3(0.6f, 0.0f, 0.0f)).norm(), 1e-3f);
  for (int f = 0; f < 60; ++f) h.cape.step(1.0f / 60.0f, {});
  EXPECT_TRUE(h.sane());
  EXPECT_EQ(h.cape.guard().lastStep, 0u);
}

TEST(Guard, ThePinsFitTheReferencePoseAndTheirFreeTurnKeepsThePreviousOne) {
  // Two pins leave the turn about the line through them free: the fit keeps the placement's.
  FabricPtr fabric = test::makeGrid(6, 6, 0.5f, 0.5f);
  const Pose placement{Vec3(1.0f, 2.0f, 3.0f), Quat(Eigen::AngleAxisf(0.3f, Vec3::UnitY()))};
  Cape cape(fabric, test::quietSettings(), placement);
  cape.pin(0, test::row(cape.state().positions, 0));
  cape.pin(5, test::row(cape.state().positions, 5));
  cape.mutableState().positions(20, 0) = kNaN;
  cape.step(1.0f / 60.0f, {});
  EXPECT_EQ(cape.guard().lastStep, 1u) << "nothing acts on the cape but the NaN: only it is restored";
  EXPECT_TRUE((cape.referencePose().position - placement.position).isZero(1e-4f));
  EXPECT_GT(std::abs(cape.referencePose().rotation.dot(placement.rotation)), 1.0f - 1e-6f);
  EXPECT_TRUE(
      (test::row(cape.state().positions, 20) - placement.apply(test::row(fabric->restPositions(), 20)))
          .isZero(1e-4f));
}

TEST(Guard, APieceNoPinHoldsMayGoAnywhere) {
  // A cape with no pins falls for 10 s (~47 m through the air's damping): the guard lets it, and would only
  // catch a NaN.
  Cape cape(test::makeGrid(10, 10), CapeSettings());
  for (int f = 0; f < 600; ++f) cape.step(1.0f / 60.0f, {});
  EXPECT_LT(cape.state().positions.col(1).maxCoeff(), -40.0f);
  EXPECT_EQ(cape.guard().total, 0u);
  cape.mutableState().positions(3, 2) = kNaN;
  cape.step(1.0f / 60.0f, {});
  EXPECT_TRUE(cape.state().positions.allFinite());
  EXPECT_GE(cape.guard().lastStep, 1u);
}

TEST(Guard, AStretchTheSpringsCanHoldIsNotLost) {
  // The reach is far beyond any stretch: a cape yanked 1 m in one frame by one pin is not restored.
  Hanging h;
  h.cape.movePin(1, Vec3(1.6f, 0.0f, 0.0f));
  h.cape.step(1.0f / 60.0f, {});
  EXPECT_EQ(h.cape.guard().total, 0u);
}

TEST(SpringKernel, ASpringWhoseSquaredLengthOverflowsIsLeftAlone) {
  // |d| = 2e19 m: |d|^2 overflows to inf; once it passed the zero-length test and gave inf / inf = NaN.
  FabricPtr fabric = test::makeGrid(2, 2, 1.0f, 1.0f, 0.4f, false);
  const SpringSet& set = fabric->springs(SpringFamily::Structural);
  for (const bool vector : {false, true}) {
    std::vector<float> x{0.0f, 2e19f, 0.0f, 1.0f}, y{0.0f, 0.0f, -1.0f, -1.0f}, z(4, 0.0f), w(4, 1.0f);
    std::vector<float> lambda(set.size(), 0.0f);
    detail::SpringSolveArrays a;
    a.px = x.data();
    a.py = y.data();
    a.pz = z.data();
    a.inverseMass = w.data();
    a.first = set.first.data();
    a.second = set.second.data();
    a.restLength = set.restLength.data();
    a.lambda = lambda.data();
    if (vector)
      for (const SpringRun& run : set.runs) detail::solveSpringRun(a, run, 0.0f);
    else
      detail::solveSpringsScalar(a, 0, static_cast<std::uint32_t>(set.size()), 0.0f);
    for (int i = 0; i < 4; ++i)
      EXPECT_TRUE(std::isfinite(x[i]) && std::isfinite(y[i]) && std::isfinite(z[i])) << i << " " << vector;
    for (float l : lambda) EXPECT_TRUE(std::isfinite(l));
  }
}

TEST(Step, AnAbsurdStepIsSimulatedAsTheLongestOne) {
  // dt = 1e9 s once overflowed the substep count (float to int: undefined behaviour, caught by UBSan).
  Hanging h;
  const double before = h.cape.state().time;
  h.cape.step(1e9f, {});
  EXPECT_DOUBLE_EQ(h.cape.state().time - before, static_cast<double>(Cape::kMaxStep));
  EXPECT_TRUE(h.sane());
  h.cape.step(std::numeric_limits<float>::max(), {});
  EXPECT_TRUE(h.sane());
}

TEST(Frame, SetOriginKeepsTheWorldAndRelocateMovesTheCapeExactly) {
  Hanging h;
  const Points world = h.cape.state().positions;
  const Eigen::Vector3d far(10000.0, 0.0, -250.0);
  h.cape.setOrigin(far);
  EXPECT_EQ(h.cape.origin(), far);
  for (Eigen::Index i = 0; i < world.rows(); ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(static_cast<double>(h.cape.state().positions(i, c)) + far[c],
                  static_cast<double>(world(i, c)), 1e-3);
  // Relocating leaves the frame coordinates as they are, however far it goes.
  const Points local = h.cape.state().positions;
  h.cape.relocate(Eigen::Vector3d(1e20, 0.0, 0.0));
  EXPECT_EQ(h.cape.state().positions, local);
  h.cape.relocate(Eigen::Vector3d(std::nan(""), 0.0, 0.0));
  EXPECT_EQ(h.cape.origin(), Eigen::Vector3d(1e20, 0.0, 0.0)) << "a non-finite origin is ignored";
}

TEST(Frame, ACapeFarFromTheWorldsOriginInItsOwnFrameGivesTheBitsOfOneAtTheOrigin) {
  // Everything given in the frame, the solver cannot tell where the frame is: same bits (wind off).
  Hanging near;
  Hanging far;
  far.cape.relocate(Eigen::Vector3d(1e5, 2e4, -3e5));
  for (int f = 0; f < 60; ++f) {
    near.cape.step(1.0f / 60.0f, {});
    far.cape.step(1.0f / 60.0f, {});
  }
  EXPECT_EQ(stateHash(near.cape.state()), stateHash(far.cape.state()));
}

TEST(Frame, TheWindIsTheWorldsWhereverTheFrameIs) {
  WindSettings wind;
  wind.model = WindSettings::Model::Aerodynamic;
  wind.speed = 6.0f;
  wind.gustAmplitude = 0.5f;
  const Eigen::Vector3d origin(1.25, -0.5, 2.0);
  Points local(3, 3), world(3, 3), a(3, 3), b(3, 3);
  local << 0.1f, 0.2f, 0.3f, -0.4f, 1.0f, 0.0f, 0.5f, -0.25f, 0.75f;
  world = local.rowwise() + origin.cast<float>().transpose();
  windVelocities(wind, local, 12.5, a, origin);
  windVelocities(wind, world, 12.5, b);
  EXPECT_TRUE(a.isApprox(b, 1e-4f)) << a << "\n" << b;
  // Without the origin the same points are elsewhere in the field: the test can fail.
  Points c(3, 3);
  windVelocities(wind, local, 12.5, c);
  EXPECT_FALSE(a.isApprox(c, 1e-3f));
}

}  // namespace
}  // namespace cape

namespace cape {
namespace {

TEST(Guard, AParticleFarAwayWithSelfCollisionOnIsSearchedWithoutOverflowAndRestored) {
  // The self-collision hash once floored a far particle's box into ints and overflowed their difference
  // (signed overflow, caught by UBSan; found by the fabric fuzz target).
  FabricPtr fabric = test::makeGrid(8, 8, 0.3f, 0.3f);
  CapeSettings s;
  s.selfCollision = true;
  Cape cape(fabric, s);
  cape.pin(0, test::row(cape.state().positions, 0));
  cape.pin(7, test::row(cape.state().positions, 7));
  for (const float far : {3e9f, -3e9f, 1e30f, std::numeric_limits<float>::infinity()}) {
    cape.mutableState().positions(40, 0) = far;
    cape.mutableState().positions(41, 1) = -far;
    cape.step(1.0f / 60.0f, {});
    EXPECT_TRUE(cape.state().positions.allFinite()) << far;
    EXPECT_LT(cape.state().positions.cwiseAbs().maxCoeff(), 2.0f) << far;
  }
  EXPECT_GE(cape.guard().total, 8u);
}

TEST(Fabric, VerticesTooFarApartForAFloatAreRefused) {
  // 1e30 m apart: the spring's rest length was computed as inf (its square overflowed) and accepted.
  MeshDesc d;
  d.positions = {Vec3(0.0f, 0.0f, 0.0f), Vec3(1e30f, 0.0f, 0.0f), Vec3(0.0f, 1.0f, 0.0f)};
  d.triangles = {0, 1, 2};
  const FabricResult r = Fabric::fromMesh(d);
  EXPECT_FALSE(r);
  EXPECT_NE(r.status.message().find("1e6 m"), std::string::npos) << r.status.message();
  d.positions[1] = Vec3(1e6f, 0.0f, 0.0f);
  EXPECT_TRUE(Fabric::fromMesh(d)) << "a kilometre-sized sheet is still a fabric";
  GridDesc g;
  g.width = 1e30f;
  EXPECT_FALSE(Fabric::grid(g));
}

}  // namespace
}  // namespace cape
