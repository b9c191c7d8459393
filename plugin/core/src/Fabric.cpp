#include "cape/core/Fabric.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <utility>

namespace cape {

const char* toString(SpringFamily family) {
  switch (family) {
    case SpringFamily::Structural:
      return "structural";
    case SpringFamily::Shear:
      return "shear";
    case SpringFamily::Bend:
      return "bend";
  }
  return "?";
}

std::size_t Fabric::springCount() const {
  std::size_t n = 0;
  for (const auto& s : springs_) n += s.size();
  return n;
}

namespace {

void addSpring(SpringSet& set, std::uint32_t a, std::uint32_t b) {
  set.first.push_back(a);
  set.second.push_back(b);
}

bool finitePositive(float v) {
  return std::isfinite(v) && v > 0.0f;
}

// Greedy graph colouring of a family's springs (first fit, in build order), then a stable sort by colour.
// Within a colour no two springs share a particle.
void colour(SpringSet& set, std::size_t particles) {
  std::vector<std::vector<bool>> used(particles);
  std::vector<std::uint32_t> colourOf(set.size());
  std::uint32_t colours = 0;
  for (std::size_t s = 0; s < set.size(); ++s) {
    auto& a = used[set.first[s]];
    auto& b = used[set.second[s]];
    std::uint32_t c = 0;
    while ((c < a.size() && a[c]) || (c < b.size() && b[c])) ++c;
    if (a.size() <= c) a.resize(c + 1, false);
    if (b.size() <= c) b.resize(c + 1, false);
    a[c] = b[c] = true;
    colourOf[s] = c;
    colours = std::max(colours, c + 1);
  }
  std::vector<std::size_t> order(set.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t l, std::size_t r) { return colourOf[l] < colourOf[r]; });
  SpringSet sorted;
  sorted.colourStart.assign(colours + 1, 0);
  for (std::size_t k : order) {
    sorted.first.push_back(set.first[k]);
    sorted.second.push_back(set.second[k]);
    ++sorted.colourStart[colourOf[k] + 1];
  }
  for (std::uint32_t c = 0; c < colours; ++c) sorted.colourStart[c + 1] += sorted.colourStart[c];
  set = std::move(sorted);
}

// Reorders the springs within each colour so that as many as can be fall into blocks of four with a vector
// layout (blockLayout's patterns): the greedy colouring leaves a grid's rows and diagonals in build order,
// where a row's end breaks the pattern of every block after it in that colour. Walking the colour's springs
// by their first particle, each one not yet taken starts a block of the first pattern whose other three
// springs are all in the colour and not yet taken; what is left keeps its order at the colour's end
// (gathered and scalar). Springs of one colour share no particle, so their order within it changes no bit
// of the solve.
void orderForVectors(SpringSet& set) {
  using Key = std::pair<std::int64_t, std::int64_t>;
  // The four springs of each pattern starting at (p, q), as blockLayout reads them.
  const auto patterns = [](std::int64_t p, std::int64_t q) {
    return std::array<std::array<Key, 4>, 4>{{
        {{{p, q}, {p + 1, q + 1}, {p + 2, q + 2}, {p + 3, q + 3}}},      // Contiguous
        {{{p, q}, {p + 1, q - 1}, {p + 2, q + 2}, {p + 3, q + 1}}},      // PairSwapped
        {{{p, p + 1}, {p + 2, p + 3}, {p + 4, p + 5}, {p + 6, p + 7}}},  // Interleaved
        {{{p, p + 2}, {p + 1, p + 3}, {p + 4, p + 6}, {p + 5, p + 7}}},  // Pairs
    }};
  };
  std::vector<std::uint32_t> first, second;
  std::map<Key, std::size_t> where;  // a spring of the colour by its ends -> its index
  std::vector<std::size_t> byFirst, order;
  std::vector<bool> taken;
  for (std::size_t c = 0; c < set.colourCount(); ++c) {
    const std::size_t begin = set.colourStart[c], end = set.colourStart[c + 1];
    where.clear();
    byFirst.clear();
    for (std::size_t s = begin; s < end; ++s) {
      where.emplace(Key{set.first[s], set.second[s]}, s);
      byFirst.push_back(s);
    }
    std::stable_sort(byFirst.begin(), byFirst.end(),
                     [&](std::size_t l, std::size_t r) { return set.first[l] < set.first[r]; });
    taken.assign(end - begin, false);
    order.clear();
    std::array<std::size_t, 4> block{};
    for (std::size_t s : byFirst) {
      if (taken[s - begin]) continue;
      const std::int64_t p = set.first[s], q = set.second[s];
      for (const std::array<Key, 4>& want : patterns(p, q)) {
        if (want[0] != Key{p, q}) continue;  // the pattern does not start with this spring
        bool all = true;
        for (std::size_t k = 0; k < 4 && all; ++k) {
          const auto it = where.find(want[k]);
          all = it != where.end() && !taken[it->second - begin];
          if (all) block[k] = it->second;
        }
        if (!all) continue;
        for (std::size_t k : block) {
          taken[k - begin] = true;
          order.push_back(k);
        }
        break;
      }
    }
    for (std::size_t s = begin; s < end; ++s)
      if (!taken[s - begin]) order.push_back(s);
    first.clear();
    second.clear();
    for (std::size_t s : order) {
      first.push_back(set.first[s]);
      second.push_back(set.second[s]);
    }
    std::copy(first.begin(), first.end(), set.first.begin() + static_cast<std::ptrdiff_t>(begin));
    std::copy(second.begin(), second.end(), set.second.begin() + static_cast<std::ptrdiff_t>(begin));
  }
}

// The vector layout of springs [s, s + 4) of one colour: Gathered when their indices follow no pattern.
SpringLayout blockLayout(const SpringSet& set, std::size_t s) {
  const auto f = [&](std::size_t k) { return static_cast<std::int64_t>(set.first[s + k]); };
  const auto g = [&](std::size_t k) { return static_cast<std::int64_t>(set.second[s + k]); };
  const bool firstContiguous = f(1) == f(0) + 1 && f(2) == f(0) + 2 && f(3) == f(0) + 3;
  if (firstContiguous && g(1) == g(0) + 1 && g(2) == g(0) + 2 && g(3) == g(0) + 3)
    return SpringLayout::Contiguous;
  if (firstContiguous && g(1) == g(0) - 1 && g(2) == g(0) + 2 && g(3) == g(0) + 1)
    return SpringLayout::PairSwapped;
  bool interleaved = true, pairs = true;
  constexpr std::int64_t kPairOffset[4] = {0, 1, 4, 5};
  for (std::size_t k = 0; k < 4; ++k) {
    interleaved = interleaved && f(k) == f(0) + 2 * static_cast<std::int64_t>(k) && g(k) == f(k) + 1;
    pairs = pairs && f(k) == f(0) + kPairOffset[k] && g(k) == f(k) + 2;
  }
  if (interleaved) return SpringLayout::Interleaved;
  if (pairs) return SpringLayout::Pairs;
  return SpringLayout::Gathered;
}

// Cuts each colour into blocks of four (each with its vector layout) and a scalar tail of up to three. Blocks
// never straddle two colours (the four springs of a block must share no particle); consecutive blocks of one
// layout and colour, and consecutive scalar springs, share a run, since a run is solved block after block in
// order. A vector run stays inside one colour, so that any of its blocks share no particle and may be solved
// together (the eight-wide kernels take two at a time).
void planRuns(SpringSet& set) {
  set.runs.clear();
  std::size_t lastColour = 0;
  const auto add = [&](std::size_t begin, std::size_t end, SpringLayout layout, std::size_t colour) {
    const bool joins = !set.runs.empty() && set.runs.back().end == begin &&
                       set.runs.back().layout == layout &&
                       (layout == SpringLayout::Scalar || colour == lastColour);
    lastColour = colour;
    if (joins) {
      set.runs.back().end = static_cast<std::uint32_t>(end);
    } else {
      set.runs.push_back({static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end), layout});
    }
  };
  for (std::size_t c = 0; c < set.colourCount(); ++c) {
    const std::size_t end = set.colourStart[c + 1];
    std::size_t s = set.colourStart[c];
    while (s < end) {
      const SpringLayout layout = s + 4 > end ? SpringLayout::Scalar : blockLayout(set, s);
      const std::size_t next = layout == SpringLayout::Scalar ? s + 1 : s + 4;
      add(s, next, layout, c);
      s = next;
    }
  }
}

}  // namespace

FabricResult Fabric::grid(const GridDesc& d) {
  FabricResult result;
  if (d.columns < 2 || d.rows < 2) {
    result.status = Status::error("Fabric::grid: needs at least 2 x 2 particles, got " +
                                  std::to_string(d.columns) + " x " + std::to_string(d.rows));
    return result;
  }
  if (static_cast<long>(d.columns) * d.rows > (1L << 24)) {
    result.status = Status::error("Fabric::grid: too many particles");
    return result;
  }
  if (!finitePositive(d.width) || !finitePositive(d.height) || !finitePositive(d.totalMass) ||
      d.width > kMaxFabricCoordinate || d.height > kMaxFabricCoordinate) {
    result.status = Status::error(
        "Fabric::grid: width, height and total mass must be finite and > 0, the sizes at most 1e6 m");
    return result;
  }
  std::shared_ptr<Fabric> f(new Fabric());
  const int nc = d.columns, nr = d.rows;
  const int n = nc * nr;
  auto id = [nc](int r, int c) { return static_cast<std::uint32_t>(r * nc + c); };
  f->gridColumns_ = nc;
  f->gridRows_ = nr;
  f->gridDesc_ = d;
  f->coarse_ = std::make_shared<CoarseCache>();
  f->flatProof_ = std::make_shared<FlatProofCache>();
  f->restPositions_.resize(n, 3);
  f->uvs_.resize(n);
  for (int r = 0; r < nr; ++r) {
    for (int c = 0; c < nc; ++c) {
      const float u = static_cast<float>(c) / static_cast<float>(nc - 1);
      const float v = static_cast<float>(r) / static_cast<float>(nr - 1);
      f->restPositions_.row(id(r, c)) << u * d.width, -v * d.height, 0.0f;
      f->uvs_[id(r, c)] = Eigen::Vector2f(u, v);
    }
  }
  f->masses_ = Eigen::VectorXf::Constant(n, d.totalMass / static_cast<float>(n));

  SpringSet& structural = f->springs_[static_cast<int>(SpringFamily::Structural)];
  SpringSet& shear = f->springs_[static_cast<int>(SpringFamily::Shear)];
  SpringSet& bend = f->springs_[static_cast<int>(SpringFamily::Bend)];
  // Rows first, then columns: the order in which Gauss-Seidel visits them (fixed, so results are
  // deterministic).
  for (int r = 0; r < nr; ++r)
    for (int c = 0; c + 1 < nc; ++c) addSpring(structural, id(r, c), id(r, c + 1));
  for (int r = 0; r + 1 < nr; ++r)
    for (int c = 0; c < nc; ++c) addSpring(structural, id(r, c), id(r + 1, c));
  for (int r = 0; r + 1 < nr; ++r) {
    for (int c = 0; c + 1 < nc; ++c) {
      addSpring(shear, id(r, c), id(r + 1, c + 1));
      addSpring(shear, id(r, c + 1), id(r + 1, c));
    }
  }
  if (d.bendSprings) {
    for (int r = 0; r < nr; ++r)
      for (int c = 0; c + 2 < nc; ++c) addSpring(bend, id(r, c), id(r, c + 2));
    for (int r = 0; r + 2 < nr; ++r)
      for (int c = 0; c < nc; ++c) addSpring(bend, id(r, c), id(r + 2, c));
  }
  // Two triangles per cell, counter-clockwise seen from +Z (x right, y up):
  //   (r,c) ---- (r,c+1)        top-left a, top-right b
  //     |      /   |
  //   (r+1,c) -- (r+1,c+1)      bottom-left c, bottom-right e
  // triangles (c, e, b) and (c, b, a).
  f->triangles_.reserve(static_cast<std::size_t>((nr - 1) * (nc - 1) * 6));
  for (int r = 0; r + 1 < nr; ++r) {
    for (int c = 0; c + 1 < nc; ++c) {
      const std::uint32_t a = id(r, c), b = id(r, c + 1), cc = id(r + 1, c), e = id(r + 1, c + 1);
      f->triangles_.insert(f->triangles_.end(), {cc, e, b, cc, b, a});
    }
  }
  if (d.massByArea) {
    // Each cell of area A gives A / 4 to each corner (the triangles' thirds summed over a cell's two halves
    // give the same for a square grid's interior; this is exact for any aspect ratio).
    const float cell = d.totalMass / static_cast<float>((nr - 1) * (nc - 1)) * 0.25f;
    f->masses_.setZero();
    for (int r = 0; r + 1 < nr; ++r)
      for (int c = 0; c + 1 < nc; ++c)
        for (const std::uint32_t v : {id(r, c), id(r, c + 1), id(r + 1, c), id(r + 1, c + 1)})
          f->masses_[v] += cell;
  }
  result.status = f->finish(d.tetherAnchors, d.tethersPerParticle, d.tetherScale);
  if (result.status.ok()) result.fabric = std::move(f);
  return result;
}

struct Fabric::FlatProofCache {
  std::once_flag once;
  FlatProof proof;
};

const Fabric::FlatProof* Fabric::flatProof() const {
  if (!flatProof_ || gridColumns_ < 2 || gridRows_ < 2) return nullptr;
  std::call_once(flatProof_->once, [this] { buildFlatProof(flatProof_->proof); });
  return &flatProof_->proof;
}

bool Fabric::keepsApart(const Points& x, float kappa, std::size_t& startTriangle) const {
  // The flat proof. A grid cape is a map x(u) from its rest rectangle D (convex, in the plane) into space,
  // affine over each triangle t with gradient F_t (3 x 2). For two rest points u, v the segment between them
  // lies in D, so x(v) - x(u) = integral of F (v - u) along it, a weighted mean of the F_t d |v - u| with
  // d = (v - u) / |v - u|. Against any fixed F0 and unit n = F0 d / |F0 d|:
  //   |x(v) - x(u)| >= n . (x(v) - x(u)) >= |v - u| min_t d' S_t d / sqrt(d' G d),
  // S_t = (F0' F_t + F_t' F0) / 2, G = F0' F0. Where every S_t >= lambda G (lambda > 0, the least
  // eigenvalue of G^-1/2 S_t G^-1/2), that is at least kappa |v - u|, kappa = lambda sigma_min(F0): a cape
  // that is stretched and bent by little (F_t near F0) keeps every two of its points at least kappa times
  // their rest distance apart. F0 is the mean gradient.
  const FlatProof* proof = flatProof();
  if (proof == nullptr || !(kappa > 0.0f) || x.rows() != static_cast<Eigen::Index>(particleCount()))
    return false;
  const std::size_t triangles = triangleCount();
  const std::uint32_t* tri = triangles_.data();
  const int columns = gridColumns_, rows = gridRows_;
  const float* inverse = proof->restInverse.data();
  const float *px = x.col(0).data(), *py = x.col(1).data(), *pz = x.col(2).data();
  // Triangle t's gradient: its two columns (u, v), [xb - xa, xc - xa] times the rest inverse.
  const auto gradient = [&](std::size_t t, float* u, float* v) {
    const std::uint32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
    const float* m = inverse + 4 * t;
    const float e1[3] = {px[b] - px[a], py[b] - py[a], pz[b] - pz[a]};
    const float e2[3] = {px[c] - px[a], py[c] - py[a], pz[c] - pz[a]};
    for (int k = 0; k < 3; ++k) {
      u[k] = e1[k] * m[0] + e2[k] * m[1];
      v[k] = e1[k] * m[2] + e2[k] * m[3];
    }
  };
  // F0, the mean of the F_t: the triangles have equal rest areas, so it is the integral of the gradient over
  // the rectangle over its area, which its sides give (x is linear along them): the u column is the mean
  // of the right side less the left over the width, the v column (rest y, which falls with the row) the top
  // row less the bottom over the height, each mean by the trapezoid rule.
  Eigen::Vector3d sideU = Eigen::Vector3d::Zero(), sideV = Eigen::Vector3d::Zero();
  const auto point = [px, py, pz](int i) {
    return Eigen::Vector3d(static_cast<double>(px[i]), static_cast<double>(py[i]),
                           static_cast<double>(pz[i]));
  };
  for (int r = 0; r < rows; ++r) {
    const double w = r == 0 || r == rows - 1 ? 0.5 : 1.0;
    sideU += w * (point(r * columns + columns - 1) - point(r * columns));
  }
  for (int c = 0; c < columns; ++c) {
    const double w = c == 0 || c == columns - 1 ? 0.5 : 1.0;
    sideV += w * (point(c) - point((rows - 1) * columns + c));
  }
  const GridDesc& grid = gridDesc_;
  const Eigen::Vector3d f0u = sideU / (static_cast<double>(grid.width) * (rows - 1));
  const Eigen::Vector3d f0v = sideV / (static_cast<double>(grid.height) * (columns - 1));
  // G and its Cholesky factor L; M = L^-1 = [m11 0; m21 m22], so that M S_t M' has G^-1/2 S_t G^-1/2's
  // eigenvalues.
  const double g11 = f0u.squaredNorm(), g12 = f0u.dot(f0v), g22 = f0v.squaredNorm();
  const double sigma2 = 0.5 * (g11 + g22) - std::sqrt(0.25 * (g11 - g22) * (g11 - g22) + g12 * g12);
  if (!(sigma2 > 0.0) || !(g11 > 0.0)) return false;
  const double l11 = std::sqrt(g11), l21 = g12 / l11, l22sq = g22 - l21 * l21;
  if (!(l22sq > 0.0)) return false;
  const double l22 = std::sqrt(l22sq);
  const double m11 = 1.0 / l11, m22 = 1.0 / l22, m21 = -l21 / (l11 * l22);
  // The M S_t M' average to the identity (F0 is the mean gradient), so their least eigenvalue is at most 1
  // somewhere and kappa at most sigma_min(F0): a cape that cannot pass is told so without the second pass.
  if (!(static_cast<double>(kappa) <= std::sqrt(sigma2))) return false;
  const float lambda = static_cast<float>(static_cast<double>(kappa) / std::sqrt(sigma2));
  // M S_t M' = [a11 a12; a12 a22], each entry linear in F_t's columns: a = p . u + q . v.
  const Eigen::Vector3f p11 = (m11 * m11 * f0u).cast<float>();
  const Eigen::Vector3f p12 = (m11 * m21 * f0u + 0.5 * m11 * m22 * f0v).cast<float>(),
                        q12 = (0.5 * m11 * m22 * f0u).cast<float>();
  const Eigen::Vector3f p22 = (m21 * m21 * f0u + m21 * m22 * f0v).cast<float>(),
                        q22 = (m21 * m22 * f0u + m22 * m22 * f0v).cast<float>();
  // From the triangle that failed the last proof: a cape that cannot pass mostly fails where it failed
  // before (a pinned corner, a fluttering hem), and is then told so at once.
  const std::size_t first = startTriangle < triangles ? startTriangle : 0;
  for (std::size_t k = 0; k < triangles; ++k) {
    const std::size_t t = first + k < triangles ? first + k : first + k - triangles;
    float u[3], v[3];
    gradient(t, u, v);
    const Eigen::Vector3f fu(u[0], u[1], u[2]), fv(v[0], v[1], v[2]);
    const float a11 = p11.dot(fu) - lambda, a22 = p22.dot(fu) + q22.dot(fv) - lambda;
    const float a12 = p12.dot(fu) + q12.dot(fv);
    // The least eigenvalue of M S_t M' at least lambda: [a11 a12; a12 a22] (lambda taken off) >= 0.
    // (As a difference, so that products too large for a float fail rather than compare inf with inf.)
    if (!(a11 >= 0.0f && a22 >= 0.0f && a11 * a22 - a12 * a12 >= 0.0f)) {
      startTriangle = t;
      return false;
    }
  }
  return true;
}

struct Fabric::CoarseCache {
  std::once_flag once;
  FabricPtr fabric;
};

FabricPtr Fabric::coarseLevel() const {
  if (!coarse_ || gridColumns_ < 3 || gridRows_ < 3) return nullptr;
  std::call_once(coarse_->once, [this] {
    GridDesc d = gridDesc_;
    d.columns = (gridColumns_ + 1) / 2;
    d.rows = (gridRows_ + 1) / 2;
    // Each anchor to the coarse particle nearest it (the grids span the same rectangle), once.
    const auto nearest = [](int i, int fine, int coarse) {
      return static_cast<int>(std::lround(static_cast<double>(i) * (coarse - 1) / (fine - 1)));
    };
    std::vector<std::uint32_t> anchors;
    for (const std::uint32_t a : gridDesc_.tetherAnchors) {
      const int r = nearest(static_cast<int>(a) / gridColumns_, gridRows_, d.rows);
      const int c = nearest(static_cast<int>(a) % gridColumns_, gridColumns_, d.columns);
      anchors.push_back(static_cast<std::uint32_t>(r * d.columns + c));
    }
    std::sort(anchors.begin(), anchors.end());
    anchors.erase(std::unique(anchors.begin(), anchors.end()), anchors.end());
    d.tetherAnchors = std::move(anchors);
    coarse_->fabric = grid(d).fabric;  // the fine grid's description was valid, so is this one
  });
  return coarse_->fabric;
}

FabricResult Fabric::fromMesh(const MeshDesc& d) {
  FabricResult result;
  const std::size_t n = d.positions.size();
  if (n < 3 || d.triangles.empty() || d.triangles.size() % 3 != 0) {
    result.status =
        Status::error("Fabric::fromMesh: needs at least one triangle (3 indices each) over 3+ vertices");
    return result;
  }
  if (!finitePositive(d.totalMass)) {
    result.status = Status::error("Fabric::fromMesh: total mass must be finite and > 0");
    return result;
  }
  if (!d.uvs.empty() && d.uvs.size() != n) {
    result.status = Status::error("Fabric::fromMesh: uvs must be empty or one per vertex");
    return result;
  }
  for (const Vec3& p : d.positions) {
    if (!p.allFinite() || !(p.cwiseAbs().maxCoeff() <= kMaxFabricCoordinate)) {
      result.status = Status::error(
          "Fabric::fromMesh: a vertex position is not finite or beyond +-1e6 m (kMaxFabricCoordinate)");
      return result;
    }
  }
  for (std::uint32_t i : d.triangles) {
    if (i >= n) {
      result.status =
          Status::error("Fabric::fromMesh: triangle index " + std::to_string(i) + " out of range");
      return result;
    }
  }
  std::shared_ptr<Fabric> f(new Fabric());
  f->restPositions_.resize(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) f->restPositions_.row(static_cast<Eigen::Index>(i)) = d.positions[i];
  f->triangles_ = d.triangles;
  f->uvs_ = d.uvs.empty() ? std::vector<Eigen::Vector2f>(n, Eigen::Vector2f::Zero()) : d.uvs;

  // Lumped masses: each triangle gives a third of its area-share of the mass to each corner.
  Eigen::VectorXd area = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  double totalArea = 0.0;
  // Edges in a sorted map (deterministic order), with the far vertex of each triangle on them.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edges;
  for (std::size_t t = 0; t < d.triangles.size(); t += 3) {
    const std::uint32_t v[3] = {d.triangles[t], d.triangles[t + 1], d.triangles[t + 2]};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
      result.status =
          Status::error("Fabric::fromMesh: triangle " + std::to_string(t / 3) + " repeats a vertex");
      return result;
    }
    const double a = 0.5 * (d.positions[v[1]] - d.positions[v[0]])
                               .cast<double>()
                               .cross((d.positions[v[2]] - d.positions[v[0]]).cast<double>())
                               .norm();
    totalArea += a;
    for (int k = 0; k < 3; ++k) {
      area[v[k]] += a / 3.0;
      std::uint32_t p = v[k], q = v[(k + 1) % 3];
      if (p > q) std::swap(p, q);
      edges[{p, q}].push_back(v[(k + 2) % 3]);
    }
  }
  if (!(totalArea > 0.0)) {
    result.status = Status::error("Fabric::fromMesh: the mesh has zero area");
    return result;
  }
  f->masses_.resize(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const double m = d.totalMass * area[static_cast<Eigen::Index>(i)] / totalArea;
    if (!(m > 0.0)) {
      result.status = Status::error("Fabric::fromMesh: vertex " + std::to_string(i) +
                                    " belongs to no triangle of nonzero area");
      return result;
    }
    f->masses_[static_cast<Eigen::Index>(i)] = static_cast<float>(m);
  }
  SpringSet& structural = f->springs_[static_cast<int>(SpringFamily::Structural)];
  SpringSet& bend = f->springs_[static_cast<int>(SpringFamily::Bend)];
  for (const auto& [edge, far] : edges) {
    addSpring(structural, edge.first, edge.second);
    if (d.bendSprings && far.size() == 2 && far[0] != far[1]) addSpring(bend, far[0], far[1]);
  }
  result.status = f->finish(d.tetherAnchors, d.tethersPerParticle, d.tetherScale);
  if (result.status.ok()) result.fabric = std::move(f);
  return result;
}

Status Fabric::finish(const std::vector<std::uint32_t>& anchors, int tethersPerParticle, float tetherScale) {
  const std::size_t n = particleCount();
  if (springCount() == 0) return Status::error("Fabric: no springs");
  for (auto& set : springs_) {
    colour(set, n);
    orderForVectors(set);
    planRuns(set);
  }
  for (auto& set : springs_) {
    set.restLength.resize(set.size());
    for (std::size_t s = 0; s < set.size(); ++s) {
      const float len = (restPositions_.row(set.first[s]) - restPositions_.row(set.second[s])).norm();
      if (!std::isfinite(len)) {
        return Status::error("Fabric: spring between particles " + std::to_string(set.first[s]) + " and " +
                             std::to_string(set.second[s]) + " is too long for a float (keep the fabric's " +
                             "coordinates within +-1e6 m)");
      }
      if (!(len > 1e-7f)) {
        return Status::error("Fabric: spring between particles " + std::to_string(set.first[s]) + " and " +
                             std::to_string(set.second[s]) + " has zero rest length");
      }
      set.restLength[s] = len;
    }
  }
  // Rest diameter from the bounding box diagonal: an upper bound on any rest distance.
  restDiameter_ = (restPositions_.colwise().maxCoeff() - restPositions_.colwise().minCoeff()).norm();
  {
    const SpringSet& structural = springs_[static_cast<int>(SpringFamily::Structural)];
    double sum = 0.0;
    for (float l : structural.restLength) sum += l;
    meanSpacing_ =
        structural.size() > 0 ? static_cast<float>(sum / static_cast<double>(structural.size())) : 0.01f;
  }
  buildTriangleTables();
  buildComponents();
  buildHinges();
  return buildTethers(anchors, tethersPerParticle, tetherScale);
}

void Fabric::buildHinges() {
  // Each particle's structural neighbours (sorted: deterministic), each one paired with its most opposite
  // neighbour when the choice is mutual and the two arms are within 20 degrees of a straight line: a
  // grid's rows and columns, a triangulated grid's diagonals too, a mesh's nearest to straight lines.
  constexpr float kMinStraightness = -0.94f;  // cos of 160 degrees: the arms' unit vectors dot at most this
  const std::size_t n = particleCount();
  const SpringSet& structural = springs_[static_cast<int>(SpringFamily::Structural)];
  std::vector<std::vector<std::uint32_t>> neighbours(n);
  for (std::size_t s = 0; s < structural.size(); ++s) {
    neighbours[structural.first[s]].push_back(structural.second[s]);
    neighbours[structural.second[s]].push_back(structural.first[s]);
  }
  hinges_ = HingeSet();
  const double totalArea = particleAreas_.cast<double>().sum();
  const double totalMass = masses_.cast<double>().sum();
  if (!(totalArea > 0.0) || !(totalMass > 0.0)) return;
  const double areaPerMass = totalArea / totalMass;
  std::vector<Vec3> arm;
  std::vector<std::size_t> best;
  std::vector<std::array<std::uint32_t, 2>> pairs;
  for (std::size_t j = 0; j < n; ++j) {
    std::vector<std::uint32_t>& nb = neighbours[j];
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    if (nb.size() < 2 || nb.size() > kMaxHingeNeighbours) continue;
    arm.resize(nb.size());
    for (std::size_t a = 0; a < nb.size(); ++a)
      arm[a] = (restPositions_.row(nb[a]) - restPositions_.row(static_cast<Eigen::Index>(j)))
                   .transpose()
                   .normalized();
    best.assign(nb.size(), nb.size());
    for (std::size_t a = 0; a < nb.size(); ++a) {
      float lowest = kMinStraightness;
      for (std::size_t b = 0; b < nb.size(); ++b) {
        const float c = arm[a].dot(arm[b]);
        if (b != a && c < lowest) {
          lowest = c;
          best[a] = b;
        }
      }
    }
    pairs.clear();
    for (std::size_t a = 0; a < nb.size(); ++a)
      if (best[a] > a && best[a] < nb.size() && best[best[a]] == a) pairs.push_back({nb[a], nb[best[a]]});
    if (pairs.empty()) continue;
    // One or two hinges (a grid's row and column) each take the whole area: each measures its own
    // direction's curvature, exactly along it. Three or more (a triangle mesh's) share it as 8 / (3 n): over
    // every direction a cylinder may bend along, the mean of cos^4 is 3/8, so n hinges then store the
    // plate's energy on average, and exactly at any angle for an equilateral mesh's three lines.
    const double share = masses_[static_cast<Eigen::Index>(j)] * areaPerMass *
                         (pairs.size() <= 2 ? 1.0 : 8.0 / (3.0 * static_cast<double>(pairs.size())));
    for (const auto& [i, k] : pairs) {
      const Vec3 xj = restPositions_.row(static_cast<Eigen::Index>(j)).transpose();
      const Vec3 ei = restPositions_.row(i).transpose() - xj, ek = restPositions_.row(k).transpose() - xj;
      const float li = ei.norm(), lk = ek.norm();
      const double mean = 0.5 * (static_cast<double>(li) + lk);
      hinges_.first.push_back(i);
      hinges_.middle.push_back(static_cast<std::uint32_t>(j));
      hinges_.second.push_back(k);
      hinges_.firstWeight.push_back(1.0f / li);
      hinges_.secondWeight.push_back(1.0f / lk);
      hinges_.restBend.push_back((ei / li + ek / lk).norm());
      hinges_.areaOverLength2.push_back(static_cast<float>(share / (mean * mean)));
    }
  }
  scheduleHinges();
}

void Fabric::scheduleHinges() {
  // Level scheduling of the Gauss-Seidel sweep (the build order: particle after particle, a grid's row-major
  // sweep): a hinge's level is one past the highest level of the earlier hinges it shares a particle with.
  // Hinges of one level share no particle, and every two hinges that do keep their order, so solving level
  // after level gives the build order's bits exactly while the hinges of a level run side by side.
  const std::size_t count = hinges_.size();
  std::vector<std::uint32_t> levelOf(count);
  std::vector<std::uint32_t> next(particleCount(), 0);  // the lowest level still free at each particle
  std::uint32_t levels = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint32_t ends[3] = {hinges_.first[k], hinges_.middle[k], hinges_.second[k]};
    const std::uint32_t level = std::max({next[ends[0]], next[ends[1]], next[ends[2]]});
    for (const std::uint32_t e : ends) next[e] = level + 1;
    levelOf[k] = level;
    levels = std::max(levels, level + 1);
  }
  std::vector<std::size_t> order(count);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t l, std::size_t r) { return levelOf[l] < levelOf[r]; });
  HingeSet sorted;
  sorted.levelStart.assign(levels + 1, 0);
  for (const std::size_t k : order) {
    sorted.first.push_back(hinges_.first[k]);
    sorted.middle.push_back(hinges_.middle[k]);
    sorted.second.push_back(hinges_.second[k]);
    sorted.firstWeight.push_back(hinges_.firstWeight[k]);
    sorted.secondWeight.push_back(hinges_.secondWeight[k]);
    sorted.restBend.push_back(hinges_.restBend[k]);
    sorted.areaOverLength2.push_back(hinges_.areaOverLength2[k]);
    ++sorted.levelStart[levelOf[k] + 1];
  }
  for (std::uint32_t c = 0; c < levels; ++c) sorted.levelStart[c + 1] += sorted.levelStart[c];
  hinges_ = std::move(sorted);
}

void Fabric::buildComponents() {
  // Union-find over every spring (path halving, union by index: deterministic), then labels 0, 1, ... in the
  // order of each component's first particle.
  const std::size_t n = particleCount();
  std::vector<std::uint32_t> parent(n);
  for (std::size_t i = 0; i < n; ++i) parent[i] = static_cast<std::uint32_t>(i);
  const auto root = [&](std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const SpringSet& set : springs_)
    for (std::size_t s = 0; s < set.size(); ++s) {
      const std::uint32_t a = root(set.first[s]), b = root(set.second[s]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  components_.assign(n, 0);
  componentCount_ = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t r = root(static_cast<std::uint32_t>(i));
    components_[i] = r == i ? componentCount_++ : components_[r];
  }
}

Status Fabric::buildTethers(const std::vector<std::uint32_t>& anchors, int tethersPerParticle,
                            float tetherScale) {
  const std::size_t n = particleCount();
  if (!anchors.empty()) {
    if (tethersPerParticle < 1) return Status::error("Fabric: tethersPerParticle must be >= 1");
    if (!(std::isfinite(tetherScale) && tetherScale >= 1.0f))
      return Status::error("Fabric: tetherScale must be >= 1");
    for (std::uint32_t a : anchors)
      if (a >= n) return Status::error("Fabric: tether anchor " + std::to_string(a) + " out of range");
    std::vector<std::uint32_t> sortedAnchors = anchors;
    std::sort(sortedAnchors.begin(), sortedAnchors.end());
    sortedAnchors.erase(std::unique(sortedAnchors.begin(), sortedAnchors.end()), sortedAnchors.end());
    const std::size_t k =
        std::min<std::size_t>(static_cast<std::size_t>(tethersPerParticle), sortedAnchors.size());
    std::vector<std::pair<float, std::uint32_t>> byDistance(sortedAnchors.size());
    std::vector<std::vector<std::pair<std::uint32_t, std::pair<float, std::uint32_t>>>> nearest(k);
    for (std::size_t i = 0; i < n; ++i) {
      if (std::binary_search(sortedAnchors.begin(), sortedAnchors.end(), static_cast<std::uint32_t>(i)))
        continue;
      for (std::size_t a = 0; a < sortedAnchors.size(); ++a) {
        byDistance[a] = {
            (restPositions_.row(static_cast<Eigen::Index>(i)) - restPositions_.row(sortedAnchors[a])).norm(),
            sortedAnchors[a]};
      }
      std::partial_sort(byDistance.begin(), byDistance.begin() + static_cast<std::ptrdiff_t>(k),
                        byDistance.end());
      for (std::size_t j = 0; j < k; ++j)
        nearest[j].push_back({static_cast<std::uint32_t>(i), byDistance[j]});
    }
    // Nearest anchors of every particle first, then the second nearest...: consecutive tethers then belong to
    // different particles and do not wait on each other in the solver.
    for (const auto& rank : nearest) {
      for (const auto& [particle, anchor] : rank) {
        tethers_.particle.push_back(particle);
        tethers_.anchor.push_back(anchor.second);
        tethers_.maxLength.push_back(anchor.first * tetherScale);
      }
    }
  }
  return Status::success();
}

namespace {

/// The distance from point p to segment a-b in the plane.
double segmentDistance2d(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

/// The distance from point p to triangle (a, b, c) in the plane: 0 inside or on it.
double triangleDistance2d(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                          const Eigen::Vector2d& c) {
  const auto side = [](const Eigen::Vector2d& o, const Eigen::Vector2d& q, const Eigen::Vector2d& r) {
    return (q.x() - o.x()) * (r.y() - o.y()) - (q.y() - o.y()) * (r.x() - o.x());
  };
  const double s0 = side(a, b, p), s1 = side(b, c, p), s2 = side(c, a, p);
  if ((s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0)) return 0.0;
  return std::min({segmentDistance2d(p, a, b), segmentDistance2d(p, b, c), segmentDistance2d(p, c, a)});
}

/// The distance between segments p0-p1 and q0-q1 in the plane: 0 where they cross or touch (or lie on one
/// line), else the nearest of their ends' distances from the other segment.
double segmentsDistance2d(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1, const Eigen::Vector2d& q0,
                          const Eigen::Vector2d& q1) {
  const auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() * v.y() - u.y() * v.x();
  };
  const double a = cross(p1 - p0, q0 - p0), b = cross(p1 - p0, q1 - p0), c = cross(q1 - q0, p0 - q0),
               d = cross(q1 - q0, p1 - q0);
  if (((a <= 0.0 && b >= 0.0) || (a >= 0.0 && b <= 0.0)) &&
      ((c <= 0.0 && d >= 0.0) || (c >= 0.0 && d <= 0.0)))
    return 0.0;
  return std::min({segmentDistance2d(p0, q0, q1), segmentDistance2d(p1, q0, q1),
                   segmentDistance2d(q0, p0, p1), segmentDistance2d(q1, p0, p1)});
}

}  // namespace

void Fabric::buildFlatProof(FlatProof& proof) const {
  // Per triangle, the inverse of its rest edge matrix; and by king's moves, the least rest distance from a
  // particle to a triangle not local to it, among the triangles of the cells up to kProofReach rows and
  // columns around the particle (every triangle of at most kProofReach moves is there); the triangle of a
  // cell farther out is at least kProofReach of the smaller spacings away (`beyond`).
  const int nc = gridColumns_, nr = gridRows_;
  const std::size_t triangles = triangleCount();
  const auto rest = [this](std::uint32_t i) {
    return Eigen::Vector2d(restPositions_(i, 0), restPositions_(i, 1));
  };
  proof.restInverse.assign(4 * triangles, 0.0f);
  for (std::size_t t = 0; t < triangles; ++t) {
    const Eigen::Vector2d a = rest(triangles_[3 * t]), e1 = rest(triangles_[3 * t + 1]) - a,
                          e2 = rest(triangles_[3 * t + 2]) - a;
    Eigen::Matrix2d m;
    m << e1, e2;
    const Eigen::Matrix2d inverse = m.inverse();  // a grid's rest triangles are never degenerate
    for (int k = 0; k < 4; ++k)
      proof.restInverse[4 * t + static_cast<std::size_t>(k)] = static_cast<float>(inverse(k % 2, k / 2));
  }
  // The triangles of each cell (a triangle's cell: its corners' least row and column).
  const auto cellOf = [nc](std::uint32_t i, std::uint32_t j, std::uint32_t k) {
    return std::make_pair(std::min({i, j, k}) / static_cast<std::uint32_t>(nc),
                          std::min({i % nc, j % nc, k % nc}));
  };
  const std::size_t cells = static_cast<std::size_t>(nr - 1) * static_cast<std::size_t>(nc - 1);
  std::vector<std::uint32_t> cellStart(cells + 1, 0u), cellTriangles(triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    const auto [r, c] = cellOf(triangles_[3 * t], triangles_[3 * t + 1], triangles_[3 * t + 2]);
    ++cellStart[r * static_cast<std::size_t>(nc - 1) + c + 1];
  }
  std::partial_sum(cellStart.begin(), cellStart.end(), cellStart.begin());
  {
    std::vector<std::uint32_t> cursor(cellStart.begin(), cellStart.end() - 1);
    for (std::size_t t = 0; t < triangles; ++t) {
      const auto [r, c] = cellOf(triangles_[3 * t], triangles_[3 * t + 1], triangles_[3 * t + 2]);
      cellTriangles[cursor[r * static_cast<std::size_t>(nc - 1) + c]++] = static_cast<std::uint32_t>(t);
    }
  }
  // Each cell's rest rectangle (its triangles' bounding box).
  std::vector<Eigen::Vector2d> cellLo(cells,
                                      Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity())),
      cellHi(cells, Eigen::Vector2d::Constant(-std::numeric_limits<double>::infinity()));
  for (std::size_t cell = 0; cell < cells; ++cell)
    for (std::uint32_t k = cellStart[cell]; k < cellStart[cell + 1]; ++k)
      for (int corner = 0; corner < 3; ++corner) {
        const Eigen::Vector2d r = rest(triangles_[3 * cellTriangles[k] + static_cast<std::size_t>(corner)]);
        cellLo[cell] = cellLo[cell].cwiseMin(r);
        cellHi[cell] = cellHi[cell].cwiseMax(r);
      }
  constexpr int kReach = kProofReach;
  const double dx = static_cast<double>(gridDesc_.width) / (nc - 1),
               dy = static_cast<double>(gridDesc_.height) / (nr - 1);
  std::vector<double> least(kReach + 1, std::numeric_limits<double>::infinity());
  // King's moves between particle q at (r, c) and particle i.
  const auto king = [nc](int r, int c, std::uint32_t i) {
    return std::max(std::abs(static_cast<int>(i) / nc - r), std::abs(static_cast<int>(i) % nc - c));
  };
  for (int r = 0; r < nr; ++r)
    for (int c = 0; c < nc; ++c) {
      const std::uint32_t q = static_cast<std::uint32_t>(r * nc + c);
      const Eigen::Vector2d p = rest(q);
      for (int i = std::max(0, r - kReach); i <= std::min(nr - 2, r + kReach - 1); ++i)
        for (int j = std::max(0, c - kReach); j <= std::min(nc - 2, c + kReach - 1); ++j) {
          const std::size_t cell =
              static_cast<std::size_t>(i) * static_cast<std::size_t>(nc - 1) + static_cast<std::size_t>(j);
          const double gapX = std::max({0.0, cellLo[cell].x() - p.x(), p.x() - cellHi[cell].x()});
          const double gapY = std::max({0.0, cellLo[cell].y() - p.y(), p.y() - cellHi[cell].y()});
          const double gap2 = gapX * gapX + gapY * gapY;
          for (std::uint32_t k = cellStart[cell]; k < cellStart[cell + 1]; ++k) {
            const std::uint32_t t = cellTriangles[k];
            const std::uint32_t a = triangles_[3 * t], b = triangles_[3 * t + 1], cc = triangles_[3 * t + 2];
            const int hops = std::max(
                {king(r, c, a), king(r, c, b), king(r, c, cc)});  // <= kReach: the cells' rows and columns
            double& slot = least[static_cast<std::size_t>(hops)];
            // Most triangles are farther than the least found already: their cell's rectangle says so.
            if (gap2 >= slot * slot) continue;
            const std::uint32_t* local = triangleLocal_[t].v;
            if (std::find(local, local + 6, q) != local + 6) continue;
            slot = std::min(slot, triangleDistance2d(p, rest(a), rest(b), rest(cc)));
          }
        }
    }
  proof.particleTriangle.assign(least.size(), std::numeric_limits<float>::infinity());
  for (std::size_t h = 0; h < least.size(); ++h)
    if (std::isfinite(least[h])) proof.particleTriangle[h] = static_cast<float>(least[h]);
  proof.beyond = static_cast<float>(kReach * std::min(dx, dy));
  // Two triangles that share no corner: the least distance from a particle to a triangle of a cell it is a
  // corner of, not being one of the triangle's; the cells it is not a corner of are at least the smaller
  // spacing away.
  double disjoint = std::min(dx, dy);
  for (int r = 0; r < nr; ++r)
    for (int c = 0; c < nc; ++c) {
      const std::uint32_t q = static_cast<std::uint32_t>(r * nc + c);
      for (int i = std::max(0, r - 1); i <= std::min(nr - 2, r); ++i)
        for (int j = std::max(0, c - 1); j <= std::min(nc - 2, c); ++j) {
          const std::size_t cell =
              static_cast<std::size_t>(i) * static_cast<std::size_t>(nc - 1) + static_cast<std::size_t>(j);
          for (std::uint32_t k = cellStart[cell]; k < cellStart[cell + 1]; ++k) {
            const std::uint32_t* corner = &triangles_[3 * static_cast<std::size_t>(cellTriangles[k])];
            if (corner[0] == q || corner[1] == q || corner[2] == q) continue;
            disjoint = std::min(
                disjoint, triangleDistance2d(rest(q), rest(corner[0]), rest(corner[1]), rest(corner[2])));
          }
        }
    }
  proof.disjointTriangles = static_cast<float>(disjoint);
  // Every hinge: triangle (a, b, c) and the far corner d across its edge a b (triangleLocal()), the quad
  // a-c-b-d and its opposite edges (a c, b d) and (b c, a d), as the search lists them (from both triangles
  // here: the same pairs).
  // How many king's moves apart two edges' farthest ends are.
  const auto moves = [&](std::uint32_t p0, std::uint32_t p1, std::uint32_t q0, std::uint32_t q1) {
    const auto from = [&](std::uint32_t i, std::uint32_t j) {
      return king(static_cast<int>(i) / nc, static_cast<int>(i) % nc, j);
    };
    return static_cast<std::size_t>(std::max({from(p0, q0), from(p0, q1), from(p1, q0), from(p1, q1)}));
  };
  std::vector<double> edges;
  for (std::size_t t = 0; t < triangles; ++t)
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = triangles_[3 * t + k], b = triangles_[3 * t + (k + 1) % 3],
                          cc = triangles_[3 * t + (k + 2) % 3], d = triangleLocal_[t].v[3 + k];
      if (d == ~0u || d == a || d == b) continue;
      const std::size_t hopsAC = moves(a, cc, b, d), hopsBC = moves(b, cc, a, d);
      const std::size_t hops = std::max(hopsAC, hopsBC);
      if (edges.size() <= hops) edges.resize(hops + 1, std::numeric_limits<double>::infinity());
      edges[hopsAC] = std::min(edges[hopsAC], segmentsDistance2d(rest(a), rest(cc), rest(b), rest(d)));
      edges[hopsBC] = std::min(edges[hopsBC], segmentsDistance2d(rest(b), rest(cc), rest(a), rest(d)));
    }
  proof.edgeEdge.assign(edges.size(), std::numeric_limits<float>::infinity());
  for (std::size_t h = 0; h < edges.size(); ++h)
    if (std::isfinite(edges[h])) proof.edgeEdge[h] = static_cast<float>(edges[h]);
}

void Fabric::buildTriangleTables() {
  const std::vector<std::uint32_t>& tri = triangles_;
  const std::size_t triangles = triangleCount();
  // Each particle's share of the cloth's rest area: a third of each triangle it belongs to.
  particleAreas_ = Eigen::VectorXf::Zero(static_cast<Eigen::Index>(particleCount()));
  for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
    const Vec3 a = restPositions_.row(tri[t]).transpose(), b = restPositions_.row(tri[t + 1]).transpose(),
               c = restPositions_.row(tri[t + 2]).transpose();
    const float third = (b - a).cross(c - a).norm() / 6.0f;
    for (int k = 0; k < 3; ++k) particleAreas_[tri[t + static_cast<std::size_t>(k)]] += third;
  }
  // The far corners across each triangle's edges: sort the edges (as vertex pairs) to meet each one's two
  // triangles. An edge of more than two triangles (a non-manifold mesh) gets no wings.
  struct HalfEdge {
    std::uint64_t key;
    std::uint32_t slot;  // 3 * triangle + edge
    std::uint32_t far;
  };
  std::vector<HalfEdge> edges;
  edges.reserve(tri.size());
  for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t u = tri[t + k], v = tri[t + (k + 1) % 3], far = tri[t + (k + 2) % 3];
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(u, v)) << 32) | std::max(u, v);
      edges.push_back({key, static_cast<std::uint32_t>(t + k), far});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const HalfEdge& a, const HalfEdge& b) {
    return a.key != b.key ? a.key < b.key : a.slot < b.slot;
  });
  TriangleLocalSet none;
  std::fill(std::begin(none.v), std::end(none.v), ~0u);
  triangleLocal_.assign(triangles, none);
  for (std::size_t t = 0; t < triangles; ++t)
    for (std::size_t k = 0; k < 3; ++k) triangleLocal_[t].v[k] = tri[3 * t + k];
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    if (j - i == 2) {  // slot = 3 * triangle + edge: the wing goes to v[3 + edge]
      triangleLocal_[edges[i].slot / 3].v[3 + edges[i].slot % 3] = edges[i + 1].far;
      triangleLocal_[edges[i + 1].slot / 3].v[3 + edges[i + 1].slot % 3] = edges[i].far;
    }
    i = j;
  }
  // Clusters: consecutive triangles that share an edge go in pairs (a grid's cells come out as pairs).
  clusterStart_.assign(1, 0u);
  for (std::size_t t = 0; t < triangles;) {
    std::size_t next = t + 1;
    if (next < triangles) {
      int shared = 0;
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j) shared += tri[3 * t + i] == tri[3 * next + j] ? 1 : 0;
      if (shared == 2) ++next;
    }
    clusterStart_.push_back(static_cast<std::uint32_t>(next));
    t = next;
  }
  // The particles local to every triangle of a cluster (at most four kept): the first triangle's local set,
  // less what the others lack.
  ClusterLocalSet noLocal;
  std::fill(std::begin(noLocal.v), std::end(noLocal.v), ~0u);
  clusterLocal_.assign(clusterCount(), noLocal);
  for (std::size_t g = 0; g < clusterCount(); ++g) {
    std::size_t kept = 0;
    for (const std::uint32_t q : triangleLocal_[clusterStart_[g]].v) {
      if (q == ~0u || kept == 4) continue;
      bool inAll = true;
      for (std::uint32_t t = clusterStart_[g] + 1; t < clusterStart_[g + 1]; ++t) {
        const std::uint32_t* v = triangleLocal_[t].v;
        inAll = inAll && std::find(v, v + 8, q) != v + 8;
      }
      if (inAll) clusterLocal_[g].v[kept++] = q;
    }
  }
}

}  // namespace cape
