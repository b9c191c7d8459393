// Both integrators against closed-form physics: free fall, the elastic equilibrium of a hanging strip, and
// the energy of the undamped explicit mode.
#include "CapeTestFixture.h"

#include <limits>

#include <algorithm>
#include <random>

namespace cape {
namespace {

using test::CapeTestContext;
using test::makeGrid;
using test::row;

// An unpinned cape at rest length falls as one body: every particle follows the free-fall prediction.
TEST(Integrators, UnpinnedCapeFallsFreely) {
  CapeSettings s = test::quietSettings();
  s.gravity = Vec3(0.0f, -9.8f, 0.0f);
  s.damping = 0.5f;
  s.substeps = 4;
  CapeTestContext ctx(makeGrid(8, 8), s);
  const Points x0 = ctx.cape().state().positions;
  ctx.simulate(0.5f);  // 30 frames of 4 substeps
  const float h = ctx.frameTime() / 4.0f;
  const Points& x = ctx.cape().state().positions;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const Vec3 expected =
        CapeTestContext::predictPosition(row(x0, i), Vec3::Zero(), s.gravity, s.damping, h, 120);
    EXPECT_NEAR((row(x, i) - expected).norm(), 0.0f, 1e-4f) << "particle " << i;
  }
  // And it did fall: about g t^2 / 2 less the damping, over a metre.
  EXPECT_LT(x(0, 1) - x0(0, 1), -1.0f);
}

struct StripCase {
  Integrator integrator;
  int substeps;
};

// A 2 x R strip hung from its two top particles, shear and bend off, no tethers, no colliders: two
// independent chains joined by rungs that stay at rest length by symmetry. Spring j of a column (from row j
// to row j + 1) carries the weight of the R - 1 - j particles below it, so at equilibrium it is stretched by
// e_j = (R - 1 - j) m g / k. XPBD with compliance 1/k has the same fixed point (the tension per substep is
// lambda / h^2), up to a Gauss-Seidel error of order w k h^2.
class HangingStrip : public ::testing::TestWithParam<StripCase> {};

TEST_P(HangingStrip, SettlesAtTheAnalyticExtension) {
  const int rows = 10;
  const float spacing = 0.1f, width = 0.2f, totalMass = 0.4f, k = 50.0f, g = 9.8f;
  FabricPtr fabric = makeGrid(2, rows, width, spacing * (rows - 1), totalMass, /*bend=*/false);
  ASSERT_TRUE(fabric);
  CapeSettings s = test::quietSettings();
  s.integrator = GetParam().integrator;
  s.gravity = Vec3(0.0f, -g, 0.0f);
  s.structuralStiffness = k;
  s.shearStiffness = 0.0f;
  s.bendStiffness = 0.0f;
  s.damping = 10.0f;  // every mode decays quickly; 5 s leave the chain at rest
  s.substeps = GetParam().substeps;
  CapeTestContext ctx(fabric, s);
  Cape& cape = ctx.cape();
  cape.pin(0, row(cape.state().positions, 0));
  cape.pin(1, row(cape.state().positions, 1));
  ctx.simulate(5.0f);

  const float mg = totalMass / static_cast<float>(2 * rows) * g;
  const Points& x = cape.state().positions;
  const Points& rest = fabric->restPositions();
  ASSERT_TRUE(x.allFinite());
  for (int c = 0; c < 2; ++c) {
    float expectedDrop = 0.0f;
    for (int j = 0; j + 1 < rows; ++j) {
      const Eigen::Index top = 2 * j + c, bottom = 2 * (j + 1) + c;
      const float extension = static_cast<float>(rows - 1 - j) * mg / k;
      const float measured = (row(x, bottom) - row(x, top)).norm() - spacing;
      EXPECT_NEAR(measured, extension, 0.02f * extension) << "column " << c << " spring " << j;
      expectedDrop += extension;
      // The whole column below has dropped by the sum of the extensions above, and stays vertical.
      EXPECT_NEAR(x(bottom, 1) - rest(bottom, 1), -expectedDrop, 0.02f * expectedDrop) << "row " << j + 1;
      EXPECT_NEAR(x(bottom, 0), rest(bottom, 0), 1e-4f);
      EXPECT_NEAR(x(bottom, 2), 0.0f, 1e-4f);
    }
    // Bottom particle: m g / k * R (R - 1) / 2 in all.
    EXPECT_NEAR(expectedDrop, mg / k * rows * (rows - 1) / 2.0f, 1e-5f);
  }
  // At rest: what speed is left is float round-off. Velocities are position changes over a substep, so a
  // one-ulp change of a coordinate near 1 m reads as eps / h (1.4e-4 m/s at 20 substeps of 1/60 s).
  const float quantum =
      std::numeric_limits<float>::epsilon() / (ctx.frameTime() / static_cast<float>(s.substeps));
  EXPECT_LT(cape.state().velocities.rowwise().norm().mean(), 5.0f * quantum);
  EXPECT_LT(cape.state().velocities.rowwise().norm().maxCoeff(), 30.0f * quantum);
}

INSTANTIATE_TEST_SUITE_P(Integrators, HangingStrip,
                         ::testing::Values(StripCase{Integrator::Xpbd, 20},
                                           StripCase{Integrator::ExplicitSpring, 4}),
                         [](const auto& info) { return std::string(toString(info.param.integrator)); });

// Symplectic Euler conserves a shadow Hamiltonian within O(h omega) of the true energy: with no damping the
// energy oscillates around its start and does not drift. A dissipative or unstable integrator fails this.
TEST(Integrators, UndampedExplicitEnergyStaysBounded) {
  const int n = 8;
  FabricPtr fabric = makeGrid(n, n, 0.6f, 0.6f, 0.4f, /*bend=*/true);
  ASSERT_TRUE(fabric);
  CapeSettings s = test::quietSettings();
  s.integrator = Integrator::ExplicitSpring;
  s.structuralStiffness = 5.0f;
  s.shearStiffness = 2.0f;
  s.bendStiffness = 0.5f;
  s.damping = 0.0f;
  s.substeps = 1;
  s.timeStep = 0.001f;  // the stability bound is ~0.02 s: h omega_max <~ 0.1
  Cape cape(fabric, s);
  ASSERT_TRUE(cape.ok()) << cape.status().message();
  // Perturb every particle by up to 2 cm in each direction (fixed seed).
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.02f, 0.02f);
  Points& x = cape.mutableState().positions;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (int c = 0; c < 3; ++c) x(i, c) += u(rng);

  const double e0 = cape.energy();
  ASSERT_GT(e0, 1e-4) << "the perturbation must store spring energy";
  const int steps = 20000, window = 2000;
  double maxDeviation = 0.0, firstMean = 0.0, lastMean = 0.0, maxKinetic = 0.0;
  const Eigen::VectorXf& m = fabric->masses();
  for (int k = 0; k < steps; ++k) {
    cape.step(s.timeStep, {});
    const double e = cape.energy();
    maxDeviation = std::max(maxDeviation, std::abs(e - e0));
    if (k < window) firstMean += e / window;
    if (k >= steps - window) lastMean += e / window;
    if (k % 100 == 0) {
      double kinetic = 0.0;
      for (Eigen::Index i = 0; i < x.rows(); ++i)
        kinetic += 0.5 * m[i] * static_cast<double>(cape.state().velocities.row(i).squaredNorm());
      maxKinetic = std::max(maxKinetic, kinetic);
    }
  }
  ASSERT_TRUE(cape.state().positions.allFinite());
  EXPECT_GT(maxKinetic, 0.2 * e0) << "the cape must actually oscillate for the test to mean anything";
  EXPECT_LT(maxDeviation, 0.03 * e0) << "E0 = " << e0;
  EXPECT_LT(std::abs(lastMean - firstMean), 0.005 * e0)
      << "energy drifts: first mean " << firstMean << ", last mean " << lastMean;
}

// A pin carried at a constant velocity u gives its particle that velocity after every step, whatever the
// substeps: the pin's velocity is its move over the substep (from where the substep started to the target),
// not the move left after the prediction already carried the particle by h v. Read by the wind (a triangle's
// velocity relative to the air) and by self-collision's motion bounds.
TEST(Integrators, APinMovedAtAConstantVelocityGivesItsParticleThatVelocity) {
  const Vec3 u(0.9f, -0.3f, 0.45f);  // m/s
  for (const Integrator integrator : {Integrator::Xpbd, Integrator::ExplicitSpring}) {
    for (int substeps = 1; substeps <= 4; ++substeps) {
      CapeSettings s = test::quietSettings();
      s.integrator = integrator;
      s.gravity = Vec3(0.0f, -9.8f, 0.0f);
      s.substeps = substeps;
      if (integrator == Integrator::ExplicitSpring) {
        s.structuralStiffness = 5.0f;
        s.shearStiffness = 2.0f;
        s.bendStiffness = 0.5f;
      }
      CapeTestContext ctx(makeGrid(4, 4), s);
      Cape& cape = ctx.cape();
      ASSERT_TRUE(cape.ok()) << cape.status().message();
      const Vec3 start = row(cape.state().positions, 0);
      const std::size_t pin = cape.pin(0, start);
      const float dt = ctx.frameTime();
      for (int frame = 1; frame <= 6; ++frame) {
        cape.movePin(pin, start + (static_cast<float>(frame) * dt) * u);
        cape.step(dt, ctx.colliders());
        const Vec3 v = row(cape.state().velocities, 0);
        EXPECT_LT((v - u).norm(), 1e-3f * u.norm())
            << toString(integrator) << ", " << substeps << " substeps, frame " << frame
            << ": v = " << v.transpose() << ", u = " << u.transpose();
        EXPECT_LT((row(cape.state().positions, 0) - (start + (static_cast<float>(frame) * dt) * u)).norm(),
                  1e-5f);
      }
    }
  }
}

}  // namespace
}  // namespace cape
