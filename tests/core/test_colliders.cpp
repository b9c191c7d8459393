// Colliders: signed distances, the seed's push-out to the nearest surface point for every shape, the swept
// test that keeps fast colliders from carrying particles through, and Coulomb friction.
#include "CapeTestFixture.h"

#include "cape/scenes/Metrics.h"

#include <cmath>
#include <string>

namespace cape {
namespace {

using test::makeGrid;
using test::row;

constexpr float kPi = 3.14159265358979f;

// A 2 x 2 cape with springs so soft (k = 1e-6 N/m: compliance 1e6 m/N) that they move nothing measurable:
// particle 0 behaves like a lone particle. No gravity, no skin.
struct LoneParticle {
  LoneParticle() : cape(makeGrid(2, 2, 1.0f, 1.0f, 0.4f, /*bend=*/false), settings()) {}
  static CapeSettings settings() {
    CapeSettings s = test::quietSettings();
    s.structuralStiffness = 1e-6f;
    s.shearStiffness = 1e-6f;
    s.bendStiffness = 0.0f;
    return s;
  }
  /// Puts particle 0 at `p` (at rest) and the others 100 m away, then steps one frame.
  Vec3 pushOut(const Vec3& p, const Collider& c) {
    Points& x = cape.mutableState().positions;
    for (Eigen::Index i = 1; i < x.rows(); ++i)
      x.row(i) = (p + Vec3(100.0f + static_cast<float>(i), 100.0f, 0.0f)).transpose();
    x.row(0) = p.transpose();
    cape.mutableState().velocities.setZero();
    std::vector<Collider> colliders{c};
    cape.step(1.0f / 60.0f, colliders);
    return row(cape.state().positions, 0);
  }
  Cape cape;
};

struct PushOutCase {
  std::string name;
  Collider collider;
  Vec3 inside;    ///< world point inside the collider
  Vec3 expected;  ///< its nearest surface point, worked out by hand
};
// GoogleTest prints parameters on failure; the name is enough.
void PrintTo(const PushOutCase& c, std::ostream* os) {
  *os << c.name;
}

std::vector<PushOutCase> pushOutCases() {
  const Vec3 c(1.0f, 2.0f, 3.0f);
  std::vector<PushOutCase> cases;
  Pose at;
  at.position = c;
  cases.push_back({"sphere", Collider::sphere(0.5f, at), c + Vec3(0.1f, 0.2f, 0.0f),
                   c + 0.5f * Vec3(0.1f, 0.2f, 0.0f).normalized()});
  cases.push_back({"capsule_side", Collider::capsule(0.2f, 0.5f, 1, at), c + Vec3(0.05f, 0.3f, 0.0f),
                   c + Vec3(0.2f, 0.3f, 0.0f)});
  cases.push_back({"capsule_cap", Collider::capsule(0.2f, 0.5f, 1, at), c + Vec3(0.0f, 0.6f, 0.05f),
                   c + Vec3(0.0f, 0.5f, 0.0f) + 0.2f * Vec3(0.0f, 0.1f, 0.05f).normalized()});
  cases.push_back({"capsule_z", Collider::capsule(0.2f, 0.5f, 2, at), c + Vec3(0.0f, 0.1f, -0.4f),
                   c + Vec3(0.0f, 0.2f, -0.4f)});
  cases.push_back({"cylinder_side", Collider::cylinder(0.3f, 0.5f, 0, at), c + Vec3(0.0f, 0.25f, 0.0f),
                   c + Vec3(0.0f, 0.3f, 0.0f)});
  cases.push_back({"cylinder_cap", Collider::cylinder(0.3f, 0.5f, 0, at), c + Vec3(0.45f, 0.1f, 0.0f),
                   c + Vec3(0.5f, 0.1f, 0.0f)});
  // An oriented box: 30 degrees about Y. Local (0.1, 0.15, 0) is nearest the +Y face.
  Pose boxPose = at;
  boxPose.rotation = Quat(Eigen::AngleAxisf(kPi / 6.0f, Vec3::UnitY()));
  cases.push_back({"box_oriented", Collider::box(Vec3(0.5f, 0.2f, 0.3f), boxPose),
                   boxPose.apply(Vec3(0.1f, 0.15f, 0.0f)), boxPose.apply(Vec3(0.1f, 0.2f, 0.0f))});
  // Nearest the local +X face after a rotation about Z by 45 degrees.
  Pose boxPose2 = at;
  boxPose2.rotation = Quat(Eigen::AngleAxisf(kPi / 4.0f, Vec3::UnitZ()));
  cases.push_back({"box_x_face", Collider::box(Vec3(0.5f, 0.4f, 0.3f), boxPose2),
                   boxPose2.apply(Vec3(0.45f, 0.0f, 0.1f)), boxPose2.apply(Vec3(0.5f, 0.0f, 0.1f))});
  cases.push_back({"plane", Collider::plane(Vec3(0.0f, 1.0f, 0.0f), 0.0f), Vec3(0.3f, -0.05f, 0.2f),
                   Vec3(0.3f, 0.0f, 0.2f)});
  cases.push_back({"plane_tilted", Collider::plane(Vec3(1.0f, 1.0f, 0.0f), 0.0f), Vec3(0.0f, -0.2f, 0.5f),
                   Vec3(0.1f, -0.1f, 0.5f)});
  return cases;
}

class PushOut : public ::testing::TestWithParam<PushOutCase> {};

TEST_P(PushOut, LandsOnTheNearestSurfacePoint) {
  const PushOutCase& k = GetParam();
  ASSERT_TRUE(k.collider.validate().ok()) << k.collider.validate().message();
  // The query functions agree with the hand-worked answer...
  EXPECT_LT(signedDistance(k.collider, k.inside), 0.0f);
  EXPECT_LT((closestSurfacePoint(k.collider, k.inside) - k.expected).norm(), 1e-5f);
  EXPECT_NEAR(signedDistance(k.collider, k.expected), 0.0f, 1e-5f);
  // ...and so does the solver: a particle inside at rest ends on the nearest surface point.
  LoneParticle lone;
  ASSERT_TRUE(lone.cape.ok());
  const Vec3 out = lone.pushOut(k.inside, k.collider);
  EXPECT_LT((out - k.expected).norm(), 2e-5f)
      << "got " << out.transpose() << ", expected " << k.expected.transpose();
}

TEST_P(PushOut, ThicknessKeepsTheParticleThatFarOut) {
  PushOutCase k = GetParam();
  k.collider.thickness = 0.02f;
  LoneParticle lone;
  CapeSettings s = LoneParticle::settings();
  s.collisionThickness = 0.005f;
  ASSERT_TRUE(lone.cape.setSettings(s).ok());
  const Vec3 out = lone.pushOut(k.inside, k.collider);
  // Along the same outward normal, 2.5 cm beyond the surface.
  const Vec3 normal = (k.expected - k.inside).normalized();
  EXPECT_LT((out - (k.expected + 0.025f * normal)).norm(), 5e-5f) << "got " << out.transpose();
  EXPECT_NEAR(signedDistance(k.collider, out), 0.025f, 5e-5f);
}

INSTANTIATE_TEST_SUITE_P(Colliders, PushOut, ::testing::ValuesIn(pushOutCases()),
                         [](const auto& info) { return info.param.name; });

TEST(Colliders, SignedDistanceOutside) {
  Pose at;
  at.position = Vec3(0.0f, 1.0f, 0.0f);
  EXPECT_NEAR(signedDistance(Collider::sphere(0.5f, at), Vec3(0.0f, 2.0f, 0.0f)), 0.5f, 1e-6f);
  EXPECT_NEAR(signedDistance(Collider::box(Vec3(0.5f, 0.5f, 0.5f), at), Vec3(1.5f, 2.5f, 0.0f)),
              std::sqrt(2.0f), 1e-6f);
  EXPECT_NEAR(signedDistance(Collider::capsule(0.1f, 0.5f, 1, at), Vec3(0.0f, 2.0f, 0.0f)), 0.4f, 1e-6f);
  EXPECT_NEAR(signedDistance(Collider::cylinder(0.1f, 0.5f, 1, at), Vec3(0.4f, 2.0f, 0.0f)), std::sqrt(0.34f),
              1e-6f);  // rim
  // 2y = 1 is the plane y = 0.5: the normal and the constant scale together.
  EXPECT_NEAR(signedDistance(Collider::plane(Vec3(0.0f, 2.0f, 0.0f), 1.0f), Vec3(3.0f, 4.0f, 0.0f)), 3.5f,
              1e-6f);
}

TEST(Colliders, ValidateRejectsBadSizesAndPoses) {
  EXPECT_FALSE(Collider::sphere(0.0f).validate().ok());
  EXPECT_FALSE(Collider::sphere(-1.0f).validate().ok());
  EXPECT_FALSE(Collider::sphere(std::nanf("")).validate().ok());
  EXPECT_FALSE(Collider::capsule(0.1f, -0.2f, 1).validate().ok());
  EXPECT_FALSE(Collider::capsule(0.1f, 0.2f, 3).validate().ok());
  EXPECT_FALSE(Collider::box(Vec3(0.1f, 0.0f, 0.1f)).validate().ok());
  EXPECT_FALSE(Collider::plane(Vec3::Zero(), 0.0f).validate().ok());
  Collider nanPose = Collider::sphere(0.1f);
  nanPose.current.position.x() = std::numeric_limits<float>::infinity();
  const Status s = nanPose.validate();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("sphere"), std::string::npos) << s.message();
  Collider negativeSkin = Collider::sphere(0.1f);
  negativeSkin.thickness = -0.01f;
  EXPECT_FALSE(negativeSkin.validate().ok());
  EXPECT_TRUE(Collider::sphere(0.1f).validate().ok());
}

// An invalid collider is skipped by the step, and nothing non-finite gets into the cape.
TEST(Colliders, InvalidColliderIsSkippedWithoutNaN) {
  LoneParticle lone;
  Collider bad = Collider::sphere(0.5f);
  bad.current.position = Vec3(std::nanf(""), 0.0f, 0.0f);
  const Vec3 out = lone.pushOut(Vec3(0.1f, 0.0f, 0.0f), bad);
  EXPECT_TRUE(out.allFinite());
  EXPECT_TRUE(lone.cape.state().positions.allFinite());
}

// A thin box (2 cm) sweeping at 20 m/s moves 33 cm per 1/60 s frame, 16 times its thickness: a test at the
// end pose alone would find every particle already behind it. The swept test must catch and carry them.
class FastCollider : public ::testing::TestWithParam<int> {};

TEST_P(FastCollider, ThinBoxAt20MetresPerSecondLeavesNoParticleInside) {
  const int substeps = GetParam();
  FabricPtr fabric = makeGrid(6, 6, 0.4f, 0.4f, 0.1f, true);
  CapeSettings s = test::quietSettings();
  s.substeps = substeps;
  s.collisionThickness = 0.005f;
  Cape cape(fabric, s, Pose{Vec3(-0.2f, 0.2f, 0.0f), Quat::Identity()});  // a square in z = 0 around the axis
  ASSERT_TRUE(cape.ok());
  const float speed = 20.0f, dt = 1.0f / 60.0f;
  Pose boxPose;
  boxPose.position = Vec3(0.0f, 0.0f, -0.2f);
  std::vector<Collider> colliders{Collider::box(Vec3(1.0f, 1.0f, 0.01f), boxPose)};
  for (int frame = 0; frame < 6; ++frame) {
    boxPose.position.z() += speed * dt;
    colliders[0].moveTo(boxPose);
    cape.step(dt, colliders);
    const Points& x = cape.state().positions;
    ASSERT_TRUE(x.allFinite());
    EXPECT_LE(maxPenetration(x, colliders), 1e-4f) << "frame " << frame;
    if (boxPose.position.z() > 0.0f) {
      // Every particle was caught: it is in front of the box, not left behind it.
      EXPECT_GE(x.col(2).minCoeff(), boxPose.position.z() + 0.01f - 1e-4f) << "frame " << frame;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Colliders, FastCollider, ::testing::Values(1, 3));

TEST(Colliders, FastSphereCannotTunnel) {
  FabricPtr fabric = makeGrid(8, 8, 0.4f, 0.4f, 0.1f, true);
  CapeSettings s = test::quietSettings();
  s.substeps = 2;
  Cape cape(fabric, s, Pose{Vec3(-0.2f, 0.2f, 0.0f), Quat::Identity()});
  ASSERT_TRUE(cape.ok());
  Pose p;
  p.position = Vec3(0.0f, 0.0f, -0.5f);
  const float radius = 0.12f;
  std::vector<Collider> colliders{Collider::sphere(radius, p)};
  // 30 m/s: 50 cm per frame, twice the sphere's diameter, 25 cm per substep.
  for (int frame = 0; frame < 3; ++frame) {
    p.position.z() += 0.5f;
    colliders[0].moveTo(p);
    cape.step(1.0f / 60.0f, colliders);
    const Points& x = cape.state().positions;
    EXPECT_LE(maxPenetration(x, colliders), 1e-4f) << "frame " << frame;
    if (frame == 0) {
      // The sphere's centre has reached the cloth's plane: every particle in its path was caught in front of
      // it, none left behind (a test at the end pose alone would push those nearer the back out backwards).
      for (Eigen::Index i = 0; i < x.rows(); ++i)
        if (std::hypot(x(i, 0), x(i, 1)) < 0.9f * radius) {
          EXPECT_GT(x(i, 2), 0.0f) << "particle " << i;
        }
    }
  }
  // Afterwards (no friction) the sphere may slide the cloth aside and pass on: that is not tunnelling.
}

// Coulomb friction: a cape sliding on the ground at 1 m/s decelerates at mu g; without friction it keeps
// its speed.
float slideSpeedAfter(float friction, float seconds) {
  FabricPtr fabric = makeGrid(3, 3, 0.2f, 0.2f, 0.1f, false);
  CapeSettings s = test::quietSettings();
  s.gravity = Vec3(0.0f, -9.8f, 0.0f);
  s.friction = friction;
  s.substeps = 4;
  // Lying flat on the ground: grid (x, y, 0) -> world (x, 0, -y).
  Cape cape(fabric, s, Pose{Vec3::Zero(), Quat(Eigen::AngleAxisf(-kPi / 2.0f, Vec3::UnitX()))});
  EXPECT_TRUE(cape.ok());
  cape.mutableState().velocities.col(0).setConstant(1.0f);
  std::vector<Collider> ground{Collider::plane(Vec3::UnitY(), 0.0f)};
  const int frames = static_cast<int>(std::lround(seconds * 60.0f));
  for (int f = 0; f < frames; ++f) cape.step(1.0f / 60.0f, ground);
  EXPECT_GT(cape.state().positions.col(1).minCoeff(), -1e-4f);
  return cape.state().velocities.col(0).mean();
}

TEST(Colliders, CoulombFrictionDeceleratesAtMuG) {
  EXPECT_NEAR(slideSpeedAfter(0.0f, 0.1f), 1.0f, 0.01f);
  const float mu = 0.5f;
  EXPECT_NEAR(slideSpeedAfter(mu, 0.1f), 1.0f - mu * 9.8f * 0.1f, 0.08f);
  // Friction stops the slide and never reverses it.
  EXPECT_NEAR(slideSpeedAfter(mu, 0.5f), 0.0f, 1e-3f);
}

}  // namespace
}  // namespace cape
