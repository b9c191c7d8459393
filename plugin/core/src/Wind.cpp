#include "cape/core/Wind.h"

#include <array>
#include <cmath>
#include <cstdint>

namespace cape {

namespace {

constexpr double kTwoPi = 6.28318530717958647692;
constexpr int kModes = 4;  // travelling waves per component

/// SplitMix64 (Steele, Lea and Flood 2014): a tiny, fully specified generator, so the gust field is the same
/// on every platform and standard library (std::uniform_real_distribution is not specified bit for bit).
struct SplitMix {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
};

/// One travelling wave g = a sin(omega t + phase - k . x).
struct Wave {
  Vec3 k;
  float omega;
  float phase;
  float amplitude;
};

/// Three components (along the wind, and two across it), kModes waves each. Amplitudes sum to 1 per
/// component, so |g| <= 1 and the gusts never exceed gustAmplitude.
struct GustField {
  std::array<std::array<Wave, kModes>, 3> waves;
  Vec3 along, across1, across2;
};

GustField makeField(const WindSettings& w) {
  GustField f;
  f.along = w.direction.normalized();
  f.across1 = f.along.unitOrthogonal();
  f.across2 = f.along.cross(f.across1);
  SplitMix rng{0x5eedull * 0x100000001b3ull + static_cast<std::uint64_t>(w.seed)};
  static constexpr float kAmplitude[kModes] = {0.5f, 0.25f, 0.15f, 0.10f};
  static constexpr float kOctave[kModes] = {1.0f, 1.9f, 3.7f, 7.1f};  // incommensurate: no short period
  for (int c = 0; c < 3; ++c) {
    for (int m = 0; m < kModes; ++m) {
      Wave& wave = f.waves[static_cast<std::size_t>(c)][static_cast<std::size_t>(m)];
      // Gusts travel mostly with the wind: a direction within ~45 degrees of it.
      const Vec3 dir = (f.along + 0.7f * static_cast<float>(rng.uniform() * 2.0 - 1.0) * f.across1 +
                        0.7f * static_cast<float>(rng.uniform() * 2.0 - 1.0) * f.across2)
                           .normalized();
      const float jitter = 0.85f + 0.3f * static_cast<float>(rng.uniform());
      wave.k = dir * static_cast<float>(kTwoPi / w.turbulenceScale) * kOctave[m] * jitter;
      wave.omega = static_cast<float>(kTwoPi * w.gustFrequency) * kOctave[m] * jitter;
      wave.phase = static_cast<float>(kTwoPi * rng.uniform());
      wave.amplitude = kAmplitude[m];
    }
  }
  return f;
}

// Cross-wind turbulence relative to the along-wind gusts.
constexpr float kCrossWind = 0.3f;

/// The gust signal of one component at a time: phase argument wrapped to keep float precision over long runs.
/// The wave's phase at the frame's origin `k . origin` is taken in double, before the wrap: far from the
/// world's origin the float points keep their precision.
float wrappedPhase(const Wave& w, double time, const Eigen::Vector3d& origin) {
  return static_cast<float>(std::fmod(
      static_cast<double>(w.omega) * time + static_cast<double>(w.phase) - w.k.cast<double>().dot(origin),
      kTwoPi));
}

}  // namespace

Vec3 windVelocity(const WindSettings& wind, const Vec3& point, double time) {
  Points p(1, 3), out(1, 3);
  p.row(0) = point.transpose();
  windVelocities(wind, p, time, out);
  return out.row(0).transpose();
}

void windVelocities(const WindSettings& wind, const Points& points, double time, Points& out,
                    const Eigen::Vector3d& origin) {
  switch (wind.model) {
    case WindSettings::Model::None:
      out.setZero();
      return;
    case WindSettings::Model::SineWave: {
      const Vec3 v =
          wind.direction.normalized() * wind.speed *
          (1.0f + wind.gustAmplitude * static_cast<float>(std::sin(kTwoPi * wind.gustFrequency * time)));
      out.rowwise() = v.transpose();
      return;
    }
    case WindSettings::Model::Aerodynamic:
      break;
  }
  const GustField f = makeField(wind);
  const Eigen::Index n = points.rows();
  Eigen::Map<const Eigen::ArrayXf> X(points.col(0).data(), n), Y(points.col(1).data(), n),
      Z(points.col(2).data(), n);
  // The three gust signals first, in place in `out` (no scratch, no allocation)...
  for (int c = 0; c < 3; ++c) {
    auto g = out.col(c).array();
    g.setZero();
    for (const Wave& w : f.waves[static_cast<std::size_t>(c)]) {
      g += w.amplitude * (wrappedPhase(w, time, origin) - (X * w.k.x() + Y * w.k.y() + Z * w.k.z())).sin();
    }
  }
  // ...then v = U (along (1 + a g0) + c a (across1 g1 + across2 g2)), a 3 x 3 map of each row.
  const float u = wind.speed, a = wind.gustAmplitude;
  Eigen::Matrix3f m;
  m.col(0) = u * a * f.along;
  m.col(1) = u * kCrossWind * a * f.across1;
  m.col(2) = u * kCrossWind * a * f.across2;
  const Vec3 mean = u * f.along;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3 g = out.row(i).transpose();
    out.row(i) = (m * g + mean).transpose();
  }
}

Vec3 aerodynamicForce(const Vec3& relativeAir, const Vec3& areaNormal, float airDensity,
                      float dragCoefficient, float liftCoefficient) {
  const float area = areaNormal.norm();
  const float speed = relativeAir.norm();
  if (!(area > 0.0f) || !(speed > 0.0f)) return Vec3::Zero();
  const Vec3 n = areaNormal / area;
  const Vec3 uHat = relativeAir / speed;
  const float un = relativeAir.dot(n);  // signed: either side of the cloth
  const float q = 0.5f * airDensity * area * speed * un;
  return q * (dragCoefficient * n + liftCoefficient * (n - n.dot(uHat) * uHat));
}

}  // namespace cape
