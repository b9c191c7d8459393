#include "cape/scenes/Textile.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace cape {

namespace {

constexpr float kPi = 3.14159265358979f;

// Settings for a textile test: only gravity (standard), the material's springs and bending, no skin or
// friction, never asleep, the given solve.
CapeSettings textileSettings(const FabricMaterial& m, float spacing, int substeps, int iterations) {
  CapeSettings base;
  base.gravity = Vec3(0.0f, -kStandardGravity, 0.0f);
  base.collisionThickness = 0.0f;
  base.friction = 0.0f;
  base.substeps = substeps;
  base.iterations = iterations;
  base.useTethers = false;
  base.strainLimit = 0.0f;
  base.sleepSpeed = 0.0f;
  return applyFabric(m, spacing, base);
}

float maxSpeedOf(const Cape& cape) {
  return std::sqrt(cape.state().velocities.rowwise().squaredNorm().maxCoeff());
}

// A deterministic value in [-1, 1) from an index and a seed (a 32-bit integer hash, Wellons' lowbias32).
float ripple(std::uint32_t i, unsigned seed) {
  std::uint32_t x = i * 0x9E3779B9u + seed * 0x85EBCA6Bu + 1u;
  x ^= x >> 16;
  x *= 0x7FEB352Du;
  x ^= x >> 15;
  x *= 0x846CA68Bu;
  x ^= x >> 16;
  return static_cast<float>(x >> 8) / static_cast<float>(1u << 23) - 1.0f;
}

}  // namespace

CantileverResult runCantilever(const FabricMaterial& m, const CantileverSpec& spec) {
  CantileverResult result;
  const Status materialOk = m.validate();
  if (!materialOk.ok()) {
    result.status = materialOk;
    return result;
  }
  const float overhang = spec.overhang > 0.0f ? spec.overhang : 2.0f * m.bendingLength();
  if (!std::isfinite(overhang) || spec.segments < 1 || spec.segments > 4096 || spec.columns < 2 ||
      spec.columns > 64 || !(spec.seconds >= 0.0f && spec.seconds <= 600.0f) || !(spec.damping >= 0.0f) ||
      !std::isfinite(spec.damping)) {
    result.status = Status::error(
        "runCantilever: the overhang must be finite, segments 1..4096, columns 2..64, seconds 0..600, "
        "damping "
        "finite and >= 0");
    return result;
  }
  const float h = overhang / static_cast<float>(spec.segments);
  const int rows = spec.segments + 2;  // rows 0 and 1 are pinned: row 1 is the platform's edge
  GridDesc g;
  g.columns = spec.columns;
  g.rows = rows;
  g.width = h * static_cast<float>(spec.columns - 1);
  g.height = h * static_cast<float>(rows - 1);
  g.totalMass = fabricMass(m, g.width, g.height);
  g.massByArea = true;
  FabricResult fabric = Fabric::grid(g);
  if (!fabric) {
    result.status = fabric.status;
    return result;
  }
  CapeSettings settings = textileSettings(m, h, spec.substeps, spec.iterations);
  settings.damping = spec.damping;
  // The grid lies in its x-y plane with row r at y = -r h: turn it so that the rows run along +X (the
  // overhang) and the columns along +Z, horizontal, gravity along -Y.
  Eigen::Matrix3f r;
  r.col(0) = Vec3::UnitZ();   // grid x (across the strip) -> world z
  r.col(1) = -Vec3::UnitX();  // grid y (up the strip, towards row 0) -> world -x
  r.col(2) = -Vec3::UnitY();
  Pose placement;
  placement.rotation = Quat(r);
  Cape cape(fabric.fabric, settings, placement);
  if (!cape.ok()) {
    result.status = cape.status();
    return result;
  }
  for (int i = 0; i < 2 * spec.columns; ++i) {
    const auto p = static_cast<std::uint32_t>(i);
    cape.pin(p, cape.state().positions.row(i).transpose());
  }
  const int frames = static_cast<int>(std::lround(spec.seconds * 60.0f));
  for (int f = 0; f < frames; ++f) cape.step(1.0f / 60.0f, ColliderSpan());

  const Points& x = cape.state().positions;
  Vec3 edge = Vec3::Zero(), tip = Vec3::Zero();
  for (int c = 0; c < spec.columns; ++c) {
    edge += x.row(spec.columns + c).transpose();
    tip += x.row((rows - 1) * spec.columns + c).transpose();
  }
  result.overhang = overhang;
  result.theta = std::atan2(edge.y() - tip.y(), tip.x() - edge.x());
  result.bendingLength =
      overhang * std::cbrt(std::cos(result.theta / 2.0f) / (8.0f * std::tan(result.theta)));
  result.expected = m.bendingLength();
  result.maxSpeed = maxSpeedOf(cape);
  result.positions = x;
  result.fabric = fabric.fabric;
  return result;
}

MeshDesc drapeSpecimen(const FabricMaterial& m, const DrapeSpec& spec) {
  MeshDesc mesh;
  const float radius = 0.5f * spec.specimenDiameter, h = spec.spacing;
  if (!(std::isfinite(radius) && radius > 0.0f && radius <= 10.0f) || !(std::isfinite(h) && h > 0.0f) ||
      radius / h > 2000.0f)
    return mesh;
  // Rows of the lattice along x, spaced h sqrt(3) / 2 along z, every other row shifted by h / 2.
  const float dz = h * std::sqrt(3.0f) / 2.0f;
  const int half = static_cast<int>(std::floor(radius / dz));
  const int across = static_cast<int>(std::floor(radius / h)) + 1;
  std::vector<std::vector<std::int64_t>> index(static_cast<std::size_t>(2 * half + 1));
  for (int r = -half; r <= half; ++r) {
    std::vector<std::int64_t>& row = index[static_cast<std::size_t>(r + half)];
    row.assign(static_cast<std::size_t>(2 * across + 2), -1);
    const float shift = (r & 1) != 0 ? 0.5f * h : 0.0f;
    for (int c = -across; c <= across + 1; ++c) {
      const Vec3 p(static_cast<float>(c) * h - shift, 0.0f, static_cast<float>(r) * dz);
      if (p.squaredNorm() > radius * radius * (1.0f + 1e-6f)) continue;
      row[static_cast<std::size_t>(c + across)] = static_cast<std::int64_t>(mesh.positions.size());
      mesh.positions.push_back(p);
      mesh.uvs.emplace_back(0.5f + p.x() / (2.0f * radius), 0.5f + p.z() / (2.0f * radius));
    }
  }
  const auto at = [&](int r, int c) -> std::int64_t {
    if (r < -half || r > half || c < -across || c > across + 1) return -1;
    return index[static_cast<std::size_t>(r + half)][static_cast<std::size_t>(c + across)];
  };
  // Between rows r and r + 1, upward triangles (two points of row r, one of row r + 1) and downward ones;
  // which neighbours they join depends on which of the two rows is shifted.
  const auto add = [&](std::int64_t a, std::int64_t b, std::int64_t c) {
    if (a < 0 || b < 0 || c < 0) return;
    mesh.triangles.insert(mesh.triangles.end(), {static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b),
                                                 static_cast<std::uint32_t>(c)});
  };
  for (int r = -half; r < half; ++r) {
    const bool odd = (r & 1) != 0;  // row r shifted by -h/2; row r + 1 not (or the reverse)
    for (int c = -across; c <= across; ++c) {
      if (odd) {
        // Row r point c at (c - 1/2) h; row r + 1 point c at c h.
        add(at(r, c), at(r, c + 1), at(r + 1, c));
        add(at(r + 1, c), at(r, c), at(r + 1, c - 1));
      } else {
        // Row r point c at c h; row r + 1 point c at (c - 1/2) h.
        add(at(r, c), at(r, c + 1), at(r + 1, c + 1));
        add(at(r + 1, c + 1), at(r, c), at(r + 1, c));
      }
    }
  }
  // Every triangle counter-clockwise seen from +y (its normal up).
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const Vec3& a = mesh.positions[mesh.triangles[t]];
    const Vec3& b = mesh.positions[mesh.triangles[t + 1]];
    const Vec3& c = mesh.positions[mesh.triangles[t + 2]];
    if ((b - a).cross(c - a).y() < 0.0f) std::swap(mesh.triangles[t + 1], mesh.triangles[t + 2]);
  }
  // Points of the circle in no whole triangle (at its rim) are dropped, the rest renumbered in order.
  std::vector<std::int64_t> renumber(mesh.positions.size(), -1);
  for (std::uint32_t v : mesh.triangles) renumber[v] = 0;
  std::vector<Vec3> kept;
  std::vector<Eigen::Vector2f> keptUvs;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    if (renumber[i] < 0) continue;
    renumber[i] = static_cast<std::int64_t>(kept.size());
    kept.push_back(mesh.positions[i]);
    keptUvs.push_back(mesh.uvs[i]);
  }
  for (std::uint32_t& v : mesh.triangles) v = static_cast<std::uint32_t>(renumber[v]);
  mesh.positions = std::move(kept);
  mesh.uvs = std::move(keptUvs);
  const float area = shadowArea(
      [&] {
        Points p(static_cast<Eigen::Index>(mesh.positions.size()), 3);
        for (std::size_t i = 0; i < mesh.positions.size(); ++i)
          p.row(static_cast<Eigen::Index>(i)) = mesh.positions[i].transpose();
        return p;
      }(),
      mesh.triangles, std::min(5e-4f, 0.1f * h));
  mesh.totalMass = m.arealDensity * area;
  mesh.bendSprings = false;
  return mesh;
}

float shadowArea(const Points& x, const std::vector<std::uint32_t>& tri, float pixel) {
  if (x.rows() == 0 || tri.empty() || !(pixel > 0.0f) || !x.allFinite()) return 0.0f;
  const float x0 = x.col(0).minCoeff(), z0 = x.col(2).minCoeff();
  const float x1 = x.col(0).maxCoeff(), z1 = x.col(2).maxCoeff();
  const auto nx = static_cast<std::int64_t>(std::ceil((x1 - x0) / pixel)) + 1;
  const auto nz = static_cast<std::int64_t>(std::ceil((z1 - z0) / pixel)) + 1;
  if (nx * nz > (std::int64_t{1} << 28)) return 0.0f;  // beyond 256 Mpixel: refuse rather than allocate
  std::vector<std::uint8_t> covered(static_cast<std::size_t>(nx * nz), 0);
  for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
    const Eigen::Vector2f a(x(tri[t], 0), x(tri[t], 2)), b(x(tri[t + 1], 0), x(tri[t + 1], 2)),
        c(x(tri[t + 2], 0), x(tri[t + 2], 2));
    const float det = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (det == 0.0f) continue;
    const auto lo = [&](float v, float o) { return static_cast<std::int64_t>(std::floor((v - o) / pixel)); };
    const std::int64_t i0 = std::max<std::int64_t>(0, lo(std::min({a.x(), b.x(), c.x()}), x0));
    const std::int64_t i1 = std::min<std::int64_t>(nx - 1, lo(std::max({a.x(), b.x(), c.x()}), x0) + 1);
    const std::int64_t k0 = std::max<std::int64_t>(0, lo(std::min({a.y(), b.y(), c.y()}), z0));
    const std::int64_t k1 = std::min<std::int64_t>(nz - 1, lo(std::max({a.y(), b.y(), c.y()}), z0) + 1);
    for (std::int64_t k = k0; k <= k1; ++k) {
      for (std::int64_t i = i0; i <= i1; ++i) {
        const Eigen::Vector2f p(x0 + (static_cast<float>(i) + 0.5f) * pixel,
                                z0 + (static_cast<float>(k) + 0.5f) * pixel);
        // Barycentric coordinates of p; inside when all three are >= 0 (for either winding).
        const float u = ((b - p).x() * (c - p).y() - (b - p).y() * (c - p).x()) / det;
        const float v = ((c - p).x() * (a - p).y() - (c - p).y() * (a - p).x()) / det;
        const float w = 1.0f - u - v;
        if (u >= 0.0f && v >= 0.0f && w >= 0.0f) covered[static_cast<std::size_t>(k * nx + i)] = 1;
      }
    }
  }
  std::int64_t count = 0;
  for (std::uint8_t v : covered) count += v;
  return static_cast<float>(count) * pixel * pixel;
}

int countFolds(const Points& x) {
  constexpr int kBins = 360, kWindow = 7;  // one degree a bin, smoothed over 15
  std::vector<float> radius(kBins, -1.0f);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const float r = std::hypot(x(i, 0), x(i, 2));
    if (!std::isfinite(r)) continue;
    const float phi = std::atan2(x(i, 2), x(i, 0));
    const int bin =
        std::clamp(static_cast<int>(std::floor((phi + kPi) / (2.0f * kPi) * kBins)), 0, kBins - 1);
    radius[static_cast<std::size_t>(bin)] = std::max(radius[static_cast<std::size_t>(bin)], r);
  }
  // Empty bins (coarse meshes) take the nearest filled bin's radius, searching outwards.
  std::vector<float> filled(radius);
  for (int b = 0; b < kBins; ++b) {
    for (int d = 1; filled[static_cast<std::size_t>(b)] < 0.0f && d < kBins / 2; ++d) {
      const float l = radius[static_cast<std::size_t>((b - d + kBins) % kBins)];
      const float r = radius[static_cast<std::size_t>((b + d) % kBins)];
      filled[static_cast<std::size_t>(b)] = std::max(l, r);
    }
    if (filled[static_cast<std::size_t>(b)] < 0.0f) return 0;
  }
  std::vector<float> smooth(kBins, 0.0f);
  float mean = 0.0f;
  for (int b = 0; b < kBins; ++b) {
    float s = 0.0f;
    for (int d = -kWindow; d <= kWindow; ++d) s += filled[static_cast<std::size_t>((b + d + kBins) % kBins)];
    smooth[static_cast<std::size_t>(b)] = s / static_cast<float>(2 * kWindow + 1);
    mean += smooth[static_cast<std::size_t>(b)];
  }
  mean /= static_cast<float>(kBins);
  const auto [lo, hi] = std::minmax_element(smooth.begin(), smooth.end());
  // A lobe counts when the outline rises above mean + band after having been below mean - band: ripples
  // smaller than a fifth of the outline's range are not folds.
  const float band = 0.2f * (*hi - *lo);
  if (!(band > 1e-4f)) return 0;  // a round shadow (under 0.5 mm of waviness): no folds
  int start = 0;                  // begin the walk at the deepest point, below the band
  for (int b = 0; b < kBins; ++b)
    if (smooth[static_cast<std::size_t>(b)] < smooth[static_cast<std::size_t>(start)]) start = b;
  int crossings = 0;
  bool high = false;
  for (int k = 1; k <= kBins; ++k) {
    const float v = smooth[static_cast<std::size_t>((start + k) % kBins)];
    if (!high && v > mean + band) {
      high = true;
      ++crossings;
    } else if (high && v < mean - band) {
      high = false;
    }
  }
  return crossings;
}

DrapeResult runDrape(const FabricMaterial& m, const DrapeSpec& spec) {
  DrapeResult result;
  const Status materialOk = m.validate();
  if (!materialOk.ok()) {
    result.status = materialOk;
    return result;
  }
  if (!(spec.discDiameter > 0.0f && spec.discDiameter < spec.specimenDiameter) ||
      !(spec.seconds >= 0.0f && spec.seconds <= 600.0f) || !(spec.damping >= 0.0f) ||
      !std::isfinite(spec.damping) || !(std::abs(spec.perturbation) < 0.1f * spec.spacing)) {
    result.status = Status::error(
        "runDrape: the disc must be smaller than the specimen, seconds 0..600, damping finite and >= 0, the "
        "perturbation under a tenth of the spacing");
    return result;
  }
  MeshDesc mesh = drapeSpecimen(m, spec);
  if (mesh.positions.empty()) {
    result.status = Status::error(
        "runDrape: the specimen's diameter (at most 20 m) and spacing must be > 0, "
        "with at most 2000 edges across its radius");
    return result;
  }
  const float discRadius = 0.5f * spec.discDiameter;
  std::vector<std::uint32_t> clamped;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    if (mesh.positions[i].squaredNorm() <= discRadius * discRadius)
      clamped.push_back(static_cast<std::uint32_t>(i));
  mesh.tetherAnchors = clamped;
  FabricResult fabric = Fabric::fromMesh(mesh);
  if (!fabric) {
    result.status = fabric.status;
    return result;
  }
  CapeSettings settings = textileSettings(m, fabric.fabric->meanSpacing(), spec.substeps, spec.iterations);
  settings.damping += spec.damping;
  settings.useTethers = true;
  settings.selfCollision = spec.selfCollision;
  Cape cape(fabric.fabric, settings, Pose());
  if (!cape.ok()) {
    result.status = cape.status();
    return result;
  }
  for (const std::uint32_t i : clamped) cape.pin(i, mesh.positions[i]);
  // The starting ripple: each free particle raised or lowered by up to `perturbation`.
  Points& x = cape.mutableState().positions;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if (cape.state().inverseMasses[i] > 0.0f)
      x(i, 1) += spec.perturbation * ripple(static_cast<std::uint32_t>(i), spec.seed);
  const int frames = static_cast<int>(std::lround(spec.seconds * 60.0f));
  for (int f = 0; f < frames; ++f) cape.step(1.0f / 60.0f, ColliderSpan());

  result.positions = cape.state().positions;
  result.fabric = fabric.fabric;
  const float pixel = std::min(5e-4f, 0.1f * spec.spacing);
  result.shadowArea = shadowArea(result.positions, fabric.fabric->triangles(), pixel);
  result.specimenArea = shadowArea(fabric.fabric->restPositions(), fabric.fabric->triangles(), pixel);
  result.discArea = kPi * discRadius * discRadius;
  result.coefficient = (result.shadowArea - result.discArea) / (result.specimenArea - result.discArea);
  result.folds = countFolds(result.positions);
  result.maxSpeed = maxSpeedOf(cape);
  return result;
}

}  // namespace cape
