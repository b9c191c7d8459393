#include "cape/scenes/Metrics.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <unordered_map>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cape {

StrainStats structuralStrain(const Fabric& fabric, const Points& x) {
  const SpringSet& set = fabric.springs(SpringFamily::Structural);
  StrainStats s;
  if (set.size() == 0) return s;
  double sum = 0.0;
  s.max = -std::numeric_limits<float>::infinity();
  for (std::size_t k = 0; k < set.size(); ++k) {
    const float len = (x.row(set.first[k]) - x.row(set.second[k])).norm();
    const float strain = (len - set.restLength[k]) / set.restLength[k];
    s.max = std::max(s.max, strain);
    sum += strain;
  }
  s.mean = static_cast<float>(sum / static_cast<double>(set.size()));
  return s;
}

namespace {

// The penetration metric culls with a ball about each collider's origin that holds its solid: a particle
// farther than kReach times its radius from the origin cannot be inside, so it cannot raise the max of
// max(0, -distance) and its exact distance is not computed. Exact, not approximate, because the margin covers
// everything between the true distance from the origin and the float figures the shape's distance is made
// of: a valid pose's quaternion has |q|^2 within 1e-3 of 1, and rotating by it (Eigen's formula, for a unit
// quaternion) scales a vector's length by a factor in [1 - 2e-3, 1 + 2e-3]; the subtraction and the
// distances' own float rounding add a few 1e-7 more. Past kReach the local point is more than 0.7 % of the
// ball's radius outside it, where every shape's float distance is positive.
constexpr double kReach = 1.01;
// The culling is only used where that float arithmetic is ordinary: balls of at least kSmallestBound (no
// denormal squares) and coordinates under kFar (no overflow). Anything else takes the exact path.
constexpr double kSmallestBound = 1e-10;
constexpr float kFar = 1e18f;

// The radius of a ball about the collider's local origin that holds every point whose signed distance can be
// negative, or -1 for a shape left on the exact path (a plane is unbounded; a hull's planes are not checked
// against its vertices' radius, so its solid is not known to lie within it).
double solidBound(const Collider& c) {
  switch (c.shape) {
    case ColliderShape::Sphere:
      return c.radius;
    case ColliderShape::Capsule:  // within radius of the segment
      return static_cast<double>(c.radius) + c.halfHeight;
    case ColliderShape::Cylinder:  // rho <= radius and |t| <= halfHeight
      return std::hypot(static_cast<double>(c.radius), static_cast<double>(c.halfHeight));
    case ColliderShape::Box:  // |p_k| <= halfExtents_k
      return c.halfExtents.cast<double>().norm();
    default:
      return -1.0;
  }
}

}  // namespace

float maxPenetration(const Points& x, ColliderSpan colliders) {
  float worst = 0.0f;
  // The particles' bounding box, when every coordinate is finite and under kFar (else nothing is culled).
  bool boxed = x.rows() > 0;
  float lo[3] = {kFar, kFar, kFar}, hi[3] = {-kFar, -kFar, -kFar};
  for (Eigen::Index i = 0; i < x.rows() && boxed; ++i)
    for (int k = 0; k < 3; ++k) {
      const float v = x(i, k);
      boxed = boxed && std::abs(v) < kFar;  // false for NaN
      lo[k] = std::min(lo[k], v);
      hi[k] = std::max(hi[k], v);
    }
  for (const Collider& c : colliders) {
    if (!c.validate().ok()) continue;
    // A triangle mesh's distance is unsigned (no inside): never a penetration.
    if (c.shape == ColliderShape::TriangleMesh) continue;
    const double bound = solidBound(c);
    const Vec3& centre = c.current.position;
    if (!boxed || !(bound >= kSmallestBound) || !(bound < kFar) || !(centre.cwiseAbs().maxCoeff() < kFar)) {
      for (Eigen::Index i = 0; i < x.rows(); ++i)
        worst = std::max(worst, -signedDistance(c, x.row(i).transpose()));
      continue;
    }
    const double reach2 = kReach * kReach * bound * bound;
    // The whole collider: the ball misses the particles' box.
    double gap2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double g =
          std::max({static_cast<double>(lo[k]) - centre[k], centre[k] - static_cast<double>(hi[k]), 0.0});
      gap2 += g * g;
    }
    if (gap2 > reach2) continue;
    // Particle by particle.
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      const Vec3 p = x.row(i).transpose();
      const Vec3 d = p - centre;
      const double d2 = static_cast<double>(d.x()) * d.x() + static_cast<double>(d.y()) * d.y() +
                        static_cast<double>(d.z()) * d.z();
      if (d2 > reach2) continue;
      worst = std::max(worst, -signedDistance(c, p));
    }
  }
  return worst;
}

float maxPinError(const Points& x, const std::vector<Pin>& pins) {
  float worst = 0.0f;
  for (const Pin& p : pins) worst = std::max(worst, (x.row(p.particle).transpose() - p.target).norm());
  return worst;
}

float maxPinError(const CapeState& state) {
  return maxPinError(state.positions, state.pins);
}

bool isBlownUp(const Points& x, const Vec3& centre, float radius) {
  if (!x.allFinite()) return true;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if ((x.row(i).transpose() - centre).squaredNorm() > radius * radius) return true;
  return false;
}

namespace {

using V = Eigen::Vector3d;

// Parameters along the line direction where a triangle crosses the other's plane, given its vertices'
// projections p[] on the line and signed distances d[] to the plane. The lone vertex is the one whose
// distance has a sign the other two do not share.
bool interval(const double p[3], const double d[3], double& lo, double& hi) {
  int lone = -1;
  // Pick the vertex strictly on one side with both others on the other side or on it.
  for (int k = 0; k < 3 && lone < 0; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    if ((d[k] > 0 && d[a] <= 0 && d[b] <= 0) || (d[k] < 0 && d[a] >= 0 && d[b] >= 0)) lone = k;
  }
  if (lone < 0) {
    // Two vertices on the plane and one on it too is the coplanar case (handled elsewhere); otherwise
    // the vertices on the plane give the interval.
    bool any = false;
    for (int k = 0; k < 3; ++k) {
      if (d[k] == 0) {
        lo = any ? std::min(lo, p[k]) : p[k];
        hi = any ? std::max(hi, p[k]) : p[k];
        any = true;
      }
    }
    return any;
  }
  const int a = (lone + 1) % 3, b = (lone + 2) % 3;
  const double ta = p[lone] + (p[a] - p[lone]) * d[lone] / (d[lone] - d[a]);
  const double tb = p[lone] + (p[b] - p[lone]) * d[lone] / (d[lone] - d[b]);
  lo = std::min(ta, tb);
  hi = std::max(ta, tb);
  return true;
}

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

bool segmentsIntersect2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                         const Eigen::Vector2d& d) {
  const double d1 = cross2(b - a, c - a), d2 = cross2(b - a, d - a);
  const double d3 = cross2(d - c, a - c), d4 = cross2(d - c, b - c);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  auto onSegment = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r) {
    return std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) &&
           std::min(p.y(), q.y()) <= r.y() && r.y() <= std::max(p.y(), q.y());
  };
  return (d1 == 0 && onSegment(a, b, c)) || (d2 == 0 && onSegment(a, b, d)) ||
         (d3 == 0 && onSegment(c, d, a)) || (d4 == 0 && onSegment(c, d, b));
}

bool pointInTriangle2d(const Eigen::Vector2d& p, const Eigen::Vector2d t[3]) {
  const double a = cross2(t[1] - t[0], p - t[0]), b = cross2(t[2] - t[1], p - t[1]),
               c = cross2(t[0] - t[2], p - t[2]);
  return (a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0);
}

bool coplanarIntersect(const V P[3], const V Q[3], const V& n) {
  // Project onto the coordinate plane where the normal is largest.
  int drop = 0;
  n.cwiseAbs().maxCoeff(&drop);
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  Eigen::Vector2d p[3], q[3];
  for (int k = 0; k < 3; ++k) {
    p[k] = {P[k][u], P[k][v]};
    q[k] = {Q[k][u], Q[k][v]};
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segmentsIntersect2d(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3])) return true;
  return pointInTriangle2d(p[0], q) || pointInTriangle2d(q[0], p);
}

// The interval test alone, on triangles whose boxes overlap.
bool intervalTest(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0, const Vec3& q1,
                  const Vec3& q2) {
  const V P[3] = {p0.cast<double>(), p1.cast<double>(), p2.cast<double>()};
  const V Q[3] = {q0.cast<double>(), q1.cast<double>(), q2.cast<double>()};
  const V nQ = (Q[1] - Q[0]).cross(Q[2] - Q[0]);
  double dP[3];
  for (int k = 0; k < 3; ++k) dP[k] = nQ.dot(P[k] - Q[0]);
  if ((dP[0] > 0 && dP[1] > 0 && dP[2] > 0) || (dP[0] < 0 && dP[1] < 0 && dP[2] < 0)) return false;
  const V nP = (P[1] - P[0]).cross(P[2] - P[0]);
  double dQ[3];
  for (int k = 0; k < 3; ++k) dQ[k] = nP.dot(Q[k] - P[0]);
  if ((dQ[0] > 0 && dQ[1] > 0 && dQ[2] > 0) || (dQ[0] < 0 && dQ[1] < 0 && dQ[2] < 0)) return false;
  if (dP[0] == 0 && dP[1] == 0 && dP[2] == 0) return coplanarIntersect(P, Q, nP);
  // Both triangles cross the line where the planes meet; compare their intervals along it.
  const V dir = nP.cross(nQ);
  double pp[3], pq[3];
  for (int k = 0; k < 3; ++k) {
    pp[k] = dir.dot(P[k]);
    pq[k] = dir.dot(Q[k]);
  }
  double a0, a1, b0, b1;
  if (!interval(pp, dP, a0, a1) || !interval(pq, dQ, b0, b1)) return false;
  return a0 <= b1 && b0 <= a1;
}

}  // namespace

bool trianglesIntersect(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0, const Vec3& q1,
                        const Vec3& q2) {
  // Triangles whose (closed) boxes are apart on an axis do not meet. Written as comparisons of every pair of
  // corners, so that a NaN coordinate decides nothing here, as before.
  for (int k = 0; k < 3; ++k) {
    const float p[3] = {p0[k], p1[k], p2[k]}, q[3] = {q0[k], q1[k], q2[k]};
    bool qAbove = true, qBelow = true;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        qAbove = qAbove && q[j] > p[i];
        qBelow = qBelow && q[j] < p[i];
      }
    if (qAbove || qBelow) return false;
  }
  return intervalTest(p0, p1, p2, q0, q1, q2);
}

namespace {

// The grid of the self-intersection count: cubic cells as large as the largest triangle box (a box's
// largest side), but at most kMaxCellPerMean times the mean one (larger triangles are loose), indices
// clamped to [0, kCellsPerAxis) so that huge or far coordinates stay integers.
constexpr double kMaxCellPerMean = 2.0;
constexpr std::int32_t kCellsPerAxis = 1 << 20;
// The arrays of the cell order are this much longer than the triangles in it, so that four-wide loads at
// the last triangles stay inside them.
constexpr std::size_t kPad = 3;
// The radix sort's digit.
constexpr int kDigitBits = 8;

std::int32_t cellOf(float v, double origin, double inverseSize) {
  // Monotone in v (a rounded difference and product, the clamp and the truncation of a value >= 0 are).
  // (Truncation rather than std::floor, a libm call without SSE4.1.)
  const double c = (static_cast<double>(v) - origin) * inverseSize;
  return static_cast<std::int32_t>(std::clamp(c, 0.0, static_cast<double>(kCellsPerAxis - 1)));
}

// What the count does with a triangle (SelfIntersectionCounter::isLoose_): hashed; loose as it is larger than
// the cells; or loose and unboxed as it is not finite (tested against every other triangle without a box
// test, as the brute-force count would).
constexpr std::uint8_t kHashed = 0, kTooLarge = 1, kUnboxed = 2;

bool shareVertex(const std::uint32_t* a, const std::uint32_t* b) {
  return a[0] == b[0] || a[0] == b[1] || a[0] == b[2] || a[1] == b[0] || a[1] == b[1] || a[1] == b[2] ||
         a[2] == b[0] || a[2] == b[1] || a[2] == b[2];
}

template <class Box>
bool boxesOverlap(const Box& a, const Box& b) {
  return !(b.lo[0] > a.hi[0] || b.hi[0] < a.lo[0] || b.lo[1] > a.hi[1] || b.hi[1] < a.lo[1] ||
           b.lo[2] > a.hi[2] || b.hi[2] < a.lo[2]);
}

double largestSide(const float lo[3], const float hi[3]) {
  return std::max({static_cast<double>(hi[0]) - lo[0], static_cast<double>(hi[1]) - lo[1],
                   static_cast<double>(hi[2]) - lo[2]});
}

}  // namespace

void SelfIntersectionCounter::testAgainst(const Points& x, std::uint32_t a, const Run* runs, int runCount) {
  // A pair: boxes that overlap (closed), no shared vertex (most pairs that overlap share one), then the
  // exact test with the lower triangle first, as a brute-force loop over i < j calls it (its rounding is not
  // symmetric).
  const auto exact = [&](std::uint32_t b) {
    const std::uint32_t p = triangle_[a] < triangle_[b] ? a : b, q = p == a ? b : a;
    if (intervalTest(x.row(vertex_[0][p]), x.row(vertex_[1][p]), x.row(vertex_[2][p]), x.row(vertex_[0][q]),
                     x.row(vertex_[1][q]), x.row(vertex_[2][q])))
      ++found_;
  };
#if defined(__SSE2__)
  // Four at a time: the six box comparisons and the nine corner comparisons as lane masks.
  const __m128 alo[3] = {_mm_set1_ps(lo_[0][a]), _mm_set1_ps(lo_[1][a]), _mm_set1_ps(lo_[2][a])};
  const __m128 ahi[3] = {_mm_set1_ps(hi_[0][a]), _mm_set1_ps(hi_[1][a]), _mm_set1_ps(hi_[2][a])};
  const __m128i av[3] = {_mm_set1_epi32(static_cast<int>(vertex_[0][a])),
                         _mm_set1_epi32(static_cast<int>(vertex_[1][a])),
                         _mm_set1_epi32(static_cast<int>(vertex_[2][a]))};
  for (int r = 0; r < runCount; ++r) {
    const std::uint32_t end = runs[r].end;
    for (std::uint32_t j = runs[r].begin; j < end; j += 4) {
      __m128 overlap = _mm_castsi128_ps(_mm_set1_epi32(-1));
      __m128i shared = _mm_setzero_si128();
      for (int k = 0; k < 3; ++k) {
        overlap = _mm_and_ps(overlap, _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(&lo_[k][j]), ahi[k]),
                                                 _mm_cmpge_ps(_mm_loadu_ps(&hi_[k][j]), alo[k])));
        const __m128i bv = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&vertex_[k][j]));
        shared = _mm_or_si128(
            shared, _mm_or_si128(_mm_cmpeq_epi32(bv, av[0]),
                                 _mm_or_si128(_mm_cmpeq_epi32(bv, av[1]), _mm_cmpeq_epi32(bv, av[2]))));
      }
      int lanes = _mm_movemask_ps(_mm_andnot_ps(_mm_castsi128_ps(shared), overlap));
      if (end - j < 4) lanes &= (1 << (end - j)) - 1;
      for (; lanes != 0; lanes &= lanes - 1) exact(j + static_cast<std::uint32_t>(__builtin_ctz(lanes)));
    }
  }
#else
  for (int r = 0; r < runCount; ++r)
    for (std::uint32_t b = runs[r].begin; b < runs[r].end; ++b) {
      bool overlap = true, shared = false;
      for (int k = 0; k < 3; ++k) {
        overlap = overlap && lo_[k][b] <= hi_[k][a] && hi_[k][b] >= lo_[k][a];
        shared = shared || vertex_[k][b] == vertex_[0][a] || vertex_[k][b] == vertex_[1][a] ||
                 vertex_[k][b] == vertex_[2][a];
      }
      if (overlap && !shared) exact(b);
    }
#endif
}

void SelfIntersectionCounter::sortByCell(const std::vector<std::uint32_t>& tri, std::uint64_t largestKey) {
  // A stable least-significant-digit radix sort of the keys (triangles in ascending order to start with, so
  // ascending within each cell after), as many digits as the largest key has.
  const std::size_t n = order_[0].size();
  int passes = 0;
  while (passes * kDigitBits < 64 && (largestKey >> (passes * kDigitBits)) != 0) ++passes;
  keys_[1].resize(n);
  order_[1].resize(n);
  int from = 0;
  for (int pass = 0; pass < passes; ++pass, from ^= 1) {
    const int shift = pass * kDigitBits;
    histogram_.assign(std::size_t{1} << kDigitBits, 0);
    for (std::size_t i = 0; i < n; ++i) ++histogram_[(keys_[from][i] >> shift) & ((1u << kDigitBits) - 1)];
    std::uint32_t sum = 0;
    for (std::uint32_t& h : histogram_) {
      const std::uint32_t c = h;
      h = sum;
      sum += c;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t at = histogram_[(keys_[from][i] >> shift) & ((1u << kDigitBits) - 1)]++;
      keys_[from ^ 1][at] = keys_[from][i];
      order_[from ^ 1][at] = order_[from][i];
    }
  }
  // The structure of arrays in that order; the padding past the end is never read as a match (lanes past a
  // run are masked off).
  for (int k = 0; k < 3; ++k) {
    lo_[k].assign(n + kPad, 0.0f);
    hi_[k].assign(n + kPad, 0.0f);
    vertex_[k].assign(n + kPad, 0u);
  }
  triangle_.resize(n);
  key_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t t = order_[from][i];
    for (int k = 0; k < 3; ++k) {
      lo_[k][i] = boxes_[t].lo[k];
      hi_[k][i] = boxes_[t].hi[k];
      vertex_[k][i] = tri[3 * t + static_cast<std::size_t>(k)];
    }
    triangle_[i] = t;
    key_[i] = keys_[from][i];
  }
}

int SelfIntersectionCounter::count(const Fabric& fabric, const Points& x) {
  // A grid cape stretched and bent by little cannot meet itself: the flat proof says so in one pass over
  // its triangles (most frames of a walk), the count below takes a box per triangle, a sort and the pairs.
  if (flatProof_) {
    const Fabric::FlatProof* proof = fabric.flatProof();
    if (proof != nullptr && proof->disjointTriangles > 0.0f &&
        fabric.keepsApart(x, kFlatProofKappa, proofStart_)) {
      ++provenApart_;
      return 0;
    }
  }
  const std::vector<std::uint32_t>& tri = fabric.triangles();
  const std::size_t nt = tri.size() / 3;
  boxes_.resize(nt);
  cells_.resize(3 * nt);
  isLoose_.assign(nt, kHashed);
  loose_.clear();

  // Boxes, their mean and largest extent and the box of them all (finite triangles only: the others are
  // loose and unboxed).
  double extentSum = 0.0, extentMax = 0.0;
  std::size_t finite = 0;
  float all[2][3] = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}};
  for (std::size_t t = 0; t < nt; ++t) {
    Box& b = boxes_[t];
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const float u = x(tri[3 * t], k), v = x(tri[3 * t + 1], k), w = x(tri[3 * t + 2], k);
      ok = ok && std::isfinite(u) && std::isfinite(v) && std::isfinite(w);
      b.lo[k] = std::min({u, v, w});
      b.hi[k] = std::max({u, v, w});
    }
    if (!ok) {
      isLoose_[t] = kUnboxed;
      loose_.push_back(static_cast<std::uint32_t>(t));
      continue;
    }
    const double extent = largestSide(b.lo, b.hi);
    extentSum += extent;
    extentMax = std::max(extentMax, extent);
    for (int k = 0; k < 3; ++k) {
      all[0][k] = finite == 0 ? b.lo[k] : std::min(all[0][k], b.lo[k]);
      all[1][k] = finite == 0 ? b.hi[k] : std::max(all[1][k], b.hi[k]);
    }
    ++finite;
  }

  // The cell size: the largest extent (at most kMaxCellPerMean times the mean one), or coarser if the boxes
  // span more than kCellsPerAxis cells. Two boxes of extents up to `size` that overlap have least corners
  // at most `size` apart on every axis, so their cells differ by at most one on each: the cells are made
  // larger by a millionth, so that no rounding of the cell index (well under a millionth of a cell below
  // kCellsPerAxis) can make that two.
  double span = 0.0;
  for (int k = 0; k < 3; ++k) span = std::max(span, static_cast<double>(all[1][k]) - all[0][k]);
  const double mean = finite > 0 ? extentSum / static_cast<double>(finite) : 0.0;
  const double size =
      std::max(std::min(extentMax, kMaxCellPerMean * mean), span / static_cast<double>(kCellsPerAxis - 1));
  const double inverse = size > 0.0 ? 1.0 / (size * (1.0 + 1e-6)) : 0.0;
  std::int32_t largest[3] = {0, 0, 0};
  order_[0].clear();
  for (std::size_t t = 0; t < nt; ++t) {
    if (isLoose_[t] != kHashed) continue;
    const Box& b = boxes_[t];
    if (largestSide(b.lo, b.hi) > size) {
      isLoose_[t] = kTooLarge;
      loose_.push_back(static_cast<std::uint32_t>(t));
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      cells_[3 * t + static_cast<std::size_t>(k)] = cellOf(b.lo[k], all[0][k], inverse);
      largest[k] = std::max(largest[k], cells_[3 * t + static_cast<std::size_t>(k)]);
    }
    order_[0].push_back(static_cast<std::uint32_t>(t));
  }
  // A cell's key, (i * dy + j + 1) * dz + k + 1, orders the cells by i, then j, then k; a free index on
  // either side of j and k keeps the neighbours' keys from wrapping into another row.
  const std::uint64_t dy = static_cast<std::uint64_t>(largest[1]) + 3;
  const std::uint64_t dz = static_cast<std::uint64_t>(largest[2]) + 3;
  keys_[0].resize(order_[0].size());
  std::uint64_t largestKey = 0;
  for (std::size_t i = 0; i < order_[0].size(); ++i) {
    const std::int32_t* c = &cells_[3 * static_cast<std::size_t>(order_[0][i])];
    keys_[0][i] = (static_cast<std::uint64_t>(c[0]) * dy + static_cast<std::uint64_t>(c[1]) + 1) * dz +
                  static_cast<std::uint64_t>(c[2]) + 1;
    largestKey = std::max(largestKey, keys_[0][i]);
  }
  sortByCell(tri, largestKey);

  found_ = 0;
  // Every cell (a run of one key) with the rest of itself and its 13 forward neighbours: the cell after it
  // in its row (k + 1), the three of the next row (j + 1; k - 1 to k + 1) and the nine of the next plane
  // (i + 1; j - 1 to j + 1, each k - 1 to k + 1). The keys of each such group are consecutive, so each is one
  // run of the order; as the cells come in ascending order, so do the runs, found by cursors that only move
  // forward.
  const std::uint32_t total = static_cast<std::uint32_t>(key_.size());
  const std::uint64_t rowOffset[4] = {dz, dy * dz - dz, dy * dz, dy * dz + dz};
  std::uint32_t from[4] = {0, 0, 0, 0}, to[4] = {0, 0, 0, 0};
  for (std::uint32_t begin = 0, end = 0; begin < total; begin = end) {
    const std::uint64_t key = key_[begin];
    for (end = begin + 1; end < total && key_[end] == key; ++end) {
    }
    std::uint32_t next = end;
    while (next < total && key_[next] == key + 1) ++next;
    Run runs[5] = {{0, next}, {0, 0}, {0, 0}, {0, 0}, {0, 0}};
    for (int r = 0; r < 4; ++r) {
      const std::uint64_t first = key + rowOffset[r] - 1, last = key + rowOffset[r] + 1;
      while (from[r] < total && key_[from[r]] < first) ++from[r];
      to[r] = std::max(to[r], from[r]);
      while (to[r] < total && key_[to[r]] <= last) ++to[r];
      runs[r + 1] = {from[r], to[r]};
    }
    for (std::uint32_t i = begin; i < end; ++i) {
      runs[0].begin = i + 1;
      testAgainst(x, i, runs, 5);
    }
  }
  int found = found_;
  // Loose triangles against every other (a pair of two loose ones once), without the box test when either
  // is unboxed: the pair (a < b, as a brute-force loop over i < j would call it) through trianglesIntersect,
  // or once its boxes are known to overlap, through the interval test it ends with.
  auto intersect = [&](std::uint32_t a, std::uint32_t b, bool boxesChecked) {
    const std::uint32_t *ta = &tri[3 * a], *tb = &tri[3 * b];
    if (shareVertex(ta, tb)) return false;
    const Vec3 p0 = x.row(ta[0]), p1 = x.row(ta[1]), p2 = x.row(ta[2]);
    const Vec3 q0 = x.row(tb[0]), q1 = x.row(tb[1]), q2 = x.row(tb[2]);
    return boxesChecked ? intervalTest(p0, p1, p2, q0, q1, q2) : trianglesIntersect(p0, p1, p2, q0, q1, q2);
  };
  for (const std::uint32_t a : loose_) {
    for (std::uint32_t b = 0; b < nt; ++b) {
      if (b == a || (isLoose_[b] != kHashed && b < a)) continue;
      const bool boxed = isLoose_[a] != kUnboxed && isLoose_[b] != kUnboxed;
      if (boxed && !boxesOverlap(boxes_[a], boxes_[b])) continue;
      if (intersect(std::min(a, b), std::max(a, b), boxed)) ++found;
    }
  }
  return found;
}

FrameMetrics measureFrame(const Fabric& fabric, const Points& x, const Points& v,
                          const std::vector<Pin>& pins, ColliderSpan bodyColliders, const Vec3& torsoCentre,
                          SelfIntersectionCounter* selfIntersections) {
  FrameMetrics m;
  m.blowUp = isBlownUp(x, torsoCentre);
  if (m.blowUp) return m;
  const StrainStats s = structuralStrain(fabric, x);
  m.maxStrain = s.max;
  m.meanStrain = s.mean;
  m.maxPenetration = maxPenetration(x, bodyColliders);
  m.pinError = maxPinError(x, pins);
  m.meanSpeed = v.rows() > 0 ? static_cast<float>(v.rowwise().norm().mean()) : 0.0f;
  if (selfIntersections) m.selfIntersections = selfIntersections->count(fabric, x);
  return m;
}

FrameMetrics measureFrame(const Cape& cape, ColliderSpan bodyColliders, const Vec3& torsoCentre,
                          SelfIntersectionCounter* selfIntersections) {
  const CapeState& state = cape.state();
  return measureFrame(cape.fabric(), state.positions, state.velocities, state.pins, bodyColliders,
                      torsoCentre, selfIntersections);
}

namespace {

/// Bitwise equality of two point arrays (NaNs of the same bits are equal; 0 and -0 are not).
bool sameBits(const Points& a, const Points& b) {
  return a.rows() == b.rows() &&
         (a.size() == 0 || std::memcmp(a.data(), b.data(), sizeof(float) * std::size_t(a.size())) == 0);
}

}  // namespace

FrameMetrics FrameMeter::measure(const Fabric& fabric, const Points& x, const Points& v,
                                 const std::vector<Pin>& pins, ColliderSpan bodyColliders,
                                 const Vec3& torsoCentre, std::uint32_t guardRestored) {
  const auto samePins = [&]() {
    if (pins.size() != pins_.size()) return false;
    for (std::size_t k = 0; k < pins.size(); ++k)
      if (pins[k].particle != pins_[k].particle ||
          std::memcmp(pins[k].target.data(), pins_[k].target.data(), sizeof(float) * 3) != 0)
        return false;
    return true;
  };
  lastReused_ = have_ && guardRestored == 0 && last_.guardRestored == 0 && &fabric == fabric_ &&
                std::memcmp(torsoCentre.data(), centre_.data(), sizeof(float) * 3) == 0 &&
                sameBits(x, positions_) && sameBits(v, velocities_) && samePins() &&
                colliders_.same(bodyColliders);
  if (lastReused_) {
    ++reused_;
    last_.dihedralChange = 0.0f;  // every angle as it was
    return last_;
  }
  FrameMetrics m = measureFrame(fabric, x, v, pins, bodyColliders, torsoCentre, &counter_);
  m.guardRestored = guardRestored;
  m.blowUp = m.blowUp || guardRestored > 0;
  if (measureFolds_ && !m.blowUp) {
    const FoldStats fold = folds_.measure(fabric, x);
    m.meanDihedral = fold.meanDihedral;
    m.dihedralChange = fold.meanChange;
  }
  // Kept for the next frame (the buffers keep their capacity).
  have_ = true;
  fabric_ = &fabric;
  positions_ = x;
  velocities_ = v;
  pins_ = pins;
  centre_ = torsoCentre;
  colliders_.remember(bodyColliders);
  last_ = m;
  return m;
}

FrameMetrics FrameMeter::measure(const Cape& cape, ColliderSpan bodyColliders, const Vec3& torsoCentre,
                                 std::uint32_t guardRestored) {
  const CapeState& state = cape.state();
  return measure(cape.fabric(), state.positions, state.velocities, state.pins, bodyColliders, torsoCentre,
                 guardRestored);
}

FrameMetrics worstOf(const FrameMetrics& a, const FrameMetrics& b) {
  FrameMetrics m;
  m.maxStrain = std::max(a.maxStrain, b.maxStrain);
  m.meanStrain = std::max(a.meanStrain, b.meanStrain);
  m.maxPenetration = std::max(a.maxPenetration, b.maxPenetration);
  m.selfIntersections = std::max(a.selfIntersections, b.selfIntersections);
  m.pinError = std::max(a.pinError, b.pinError);
  m.meanSpeed = std::max(a.meanSpeed, b.meanSpeed);
  m.guardRestored = std::max(a.guardRestored, b.guardRestored);
  m.blowUp = a.blowUp || b.blowUp;
  m.meanDihedral = std::max(a.meanDihedral, b.meanDihedral);
  m.dihedralChange = std::max(a.dihedralChange, b.dihedralChange);
  return m;
}

namespace {

/// acos(c) for c in [-1, 1], within 1e-6 rad: Abramowitz and Stegun 4.4.46 (acos x = sqrt(1 - x) times a
/// polynomial of degree 7 for x in [0, 1], error 2e-8 rad) and acos(-x) = pi - acos(x). Branch-free, so that
/// a loop of it vectorises (std::acos does not).
inline float acosOfCosine(float c) {
  const float x = std::fabs(c);
  float p = -0.0012624911f;
  p = p * x + 0.0066700901f;
  p = p * x - 0.0170881256f;
  p = p * x + 0.0308918810f;
  p = p * x - 0.0501743046f;
  p = p * x + 0.0889789874f;
  p = p * x - 0.2145988016f;
  p = p * x + 1.5707963050f;
  const float a = std::sqrt(std::max(0.0f, 1.0f - x)) * p;
  return c < 0.0f ? 3.14159265358979f - a : a;
}

}  // namespace

void FoldMeter::findEdges(const Fabric& fabric) {
  // Each interior edge once, from the triangle that runs along it from the lower index; the triangle
  // across it runs along it the other way (both counter-clockwise) and has the edge's far corner.
  const std::vector<TriangleLocalSet>& local = fabric.triangleLocal();
  std::unordered_map<std::uint64_t, std::uint32_t> byEdge;  // directed edge (a, b) -> its triangle
  byEdge.reserve(3 * local.size());
  const auto key = [](std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; };
  for (std::size_t t = 0; t < local.size(); ++t)
    for (std::size_t k = 0; k < 3; ++k)
      byEdge.emplace(key(local[t].v[k], local[t].v[(k + 1) % 3]), static_cast<std::uint32_t>(t));
  edges_[0].clear();
  edges_[1].clear();
  for (std::size_t t = 0; t < local.size(); ++t) {
    const std::uint32_t* v = local[t].v;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = v[k], b = v[(k + 1) % 3], far = v[3 + k];
      if (far == ~0u || a > b) continue;
      const auto across = byEdge.find(key(b, a));
      if (across == byEdge.end()) continue;
      const std::uint32_t* w = local[across->second].v;
      if (w[0] != far && w[1] != far && w[2] != far) continue;
      edges_[0].push_back(static_cast<std::uint32_t>(t));
      edges_[1].push_back(across->second);
    }
  }
  for (std::vector<float>& n : normal_) n.assign(local.size(), 0.0f);
  last_.assign(edges_[0].size(), std::numeric_limits<float>::quiet_NaN());
  fabric_ = &fabric;
}

FoldStats FoldMeter::measure(const Fabric& fabric, const Points& x) {
  if (fabric_ != &fabric || normal_[0].size() != fabric.triangleLocal().size()) findEdges(fabric);
  FoldStats f;
  if (static_cast<std::size_t>(x.rows()) != fabric.particleCount()) return f;
  // Every triangle's unit normal once (0 for a degenerate or non-finite one: such edges are left out).
  const std::vector<TriangleLocalSet>& local = fabric.triangleLocal();
  for (std::size_t t = 0; t < local.size(); ++t) {
    const std::uint32_t* v = local[t].v;
    const Vec3 a = x.row(v[0]), b = x.row(v[1]), c = x.row(v[2]);
    const Vec3 n = (b - a).cross(c - a);
    const float length = n.norm();
    const bool ok = length > 1e-12f && std::isfinite(length);
    for (int k = 0; k < 3; ++k) normal_[k][t] = ok ? n[k] / length : 0.0f;
  }
  double sum = 0.0, change = 0.0;
  std::size_t changed = 0;
  const float none = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t e = 0; e < edges_[0].size(); ++e) {
    const std::uint32_t s = edges_[0][e], t = edges_[1][e];
    const float c =
        normal_[0][s] * normal_[0][t] + normal_[1][s] * normal_[1][t] + normal_[2][s] * normal_[2][t];
    float& last = last_[e];
    const bool ok = (normal_[0][s] != 0.0f || normal_[1][s] != 0.0f || normal_[2][s] != 0.0f) &&
                    (normal_[0][t] != 0.0f || normal_[1][t] != 0.0f || normal_[2][t] != 0.0f);
    if (!ok) {
      last = none;
      continue;
    }
    const float angle = acosOfCosine(std::clamp(c, -1.0f, 1.0f));
    sum += static_cast<double>(angle);
    ++f.edges;
    if (!std::isnan(last)) {
      change += static_cast<double>(std::fabs(angle - last));
      ++changed;
    }
    last = angle;
  }
  if (f.edges > 0) f.meanDihedral = static_cast<float>(sum / static_cast<double>(f.edges));
  if (changed > 0) f.meanChange = static_cast<float>(change / static_cast<double>(changed));
  return f;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double rank = std::ceil(p / 100.0 * static_cast<double>(v.size()));
  const std::size_t k = static_cast<std::size_t>(std::clamp(rank, 1.0, static_cast<double>(v.size()))) - 1;
  return v[k];
}

namespace {
// The histogram's buckets per sign: magnitudes kSmallest g^k, k = 0..kTop, reach kLargest.
const double kGrowth =
    (1.0 + PercentileEstimator::kRelativeError) / (1.0 - PercentileEstimator::kRelativeError);
const std::size_t kTop = static_cast<std::size_t>(
    std::ceil(std::log(PercentileEstimator::kLargest / PercentileEstimator::kSmallest) / std::log(kGrowth)));
const std::size_t kZero = kTop + 1;  // the bucket of |v| < kSmallest; negative ones below, positive above
}  // namespace

PercentileEstimator::PercentileEstimator() : buckets_(2 * kTop + 3, 0) {
  values_.reserve(kExactValues);
}

std::size_t PercentileEstimator::bucket(double v) const {
  const double magnitude = std::abs(v);
  if (magnitude < kSmallest) return kZero;
  const double k =
      std::min(std::ceil(std::log(magnitude / kSmallest) / std::log(kGrowth)), static_cast<double>(kTop));
  const std::size_t index = static_cast<std::size_t>(std::max(k, 0.0));
  return v > 0.0 ? kZero + 1 + index : kZero - 1 - index;
}

double PercentileEstimator::bucketValue(std::size_t b) const {
  if (b == kZero) return 0.0;
  const std::size_t k = b > kZero ? b - kZero - 1 : kZero - 1 - b;
  const double magnitude = 2.0 * kSmallest * std::pow(kGrowth, static_cast<double>(k)) / (kGrowth + 1.0);
  return b > kZero ? magnitude : -magnitude;
}

void PercentileEstimator::add(double v) {
  if (std::isnan(v)) return;
  min_ = count_ == 0 ? v : std::min(min_, v);
  max_ = count_ == 0 ? v : std::max(max_, v);
  ++count_;
  if (count_ <= static_cast<std::int64_t>(kExactValues)) {
    values_.push_back(v);
    return;
  }
  if (!values_.empty()) {  // the first value past the exact ones: count those kept so far
    for (double kept : values_) ++buckets_[bucket(kept)];
    values_.clear();
    values_.shrink_to_fit();
  }
  ++buckets_[bucket(v)];
}

double PercentileEstimator::percentile(double p) const {
  if (count_ == 0) return 0.0;
  if (exact()) return cape::percentile(values_, p);
  const double n = static_cast<double>(count_);
  const std::int64_t rank = static_cast<std::int64_t>(std::clamp(std::ceil(p / 100.0 * n), 1.0, n));
  if (rank == 1) return min_;
  if (rank == count_) return max_;
  std::int64_t below = 0;
  for (std::size_t b = 0; b < buckets_.size(); ++b) {
    below += static_cast<std::int64_t>(buckets_[b]);
    if (below >= rank) return std::clamp(bucketValue(b), min_, max_);
  }
  return max_;
}

MetricsRecorder::MetricsRecorder(double frameTime)
    : lastSpeeds_(static_cast<std::size_t>(std::max(0L, std::lround(1.0 / frameTime)))) {}

void MetricsRecorder::add(const FrameMetrics& f) {
  RunSummary& r = running_;
  // Signed: a run whose every spring stayed compressed has a negative max strain.
  r.maxStrain = r.frames == 0 ? f.maxStrain : std::max(r.maxStrain, f.maxStrain);
  ++r.frames;
  r.blowUp = r.blowUp || f.blowUp;
  r.guardRestored += f.guardRestored;
  r.framesGuardRestored += f.guardRestored > 0 ? 1 : 0;
  meanStrainSum_ += f.meanStrain;
  dihedralSum_ += f.meanDihedral;
  dihedralChangeSum_ += f.dihedralChange;
  frameMaxStrain_.add(f.maxStrain);
  r.maxPenetration = std::max(r.maxPenetration, f.maxPenetration);
  if (f.maxPenetration > 1e-3f) ++r.framesPenetrationOver1mm;
  r.selfIntersectionsMax = std::max(r.selfIntersectionsMax, f.selfIntersections);
  if (f.selfIntersections > 0) ++r.framesWithSelfIntersections;
  r.pinErrorMax = std::max(r.pinErrorMax, f.pinError);
  if (!lastSpeeds_.empty()) {
    lastSpeeds_[nextSpeed_] = f.meanSpeed;
    nextSpeed_ = (nextSpeed_ + 1) % lastSpeeds_.size();
  }
}

RunSummary MetricsRecorder::summary() const {
  RunSummary r = running_;
  if (r.frames > 0) {
    r.meanStrain = meanStrainSum_ / static_cast<double>(r.frames);
    r.meanDihedral = dihedralSum_ / static_cast<double>(r.frames);
    r.meanDihedralChange = dihedralChangeSum_ / static_cast<double>(r.frames);
  }
  r.medianFrameMaxStrain = static_cast<float>(frameMaxStrain_.percentile(50.0));
  r.p95FrameMaxStrain = static_cast<float>(frameMaxStrain_.percentile(95.0));
  // The last second's mean speeds, oldest first.
  const std::size_t kept = std::min(lastSpeeds_.size(), static_cast<std::size_t>(r.frames));
  const std::size_t oldest = kept < lastSpeeds_.size() ? 0 : nextSpeed_;
  double speed = 0.0;
  for (std::size_t i = 0; i < kept; ++i) speed += lastSpeeds_[(oldest + i) % lastSpeeds_.size()];
  if (kept > 0) r.restJitter = static_cast<float>(speed / static_cast<double>(kept));
  return r;
}

}  // namespace cape
