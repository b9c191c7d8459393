// Self-collision: predictive particle-triangle contacts (Lewin 2018, "Cloth Self Collision with Predictive
// Contacts", GDC). At the start of a step (and every few substeps while the cape moves fast) every particle
// that could come within the thickness of a triangle it does not belong to before the next search is paired
// with it, and the side of the triangle it is on is noted. The substeps then keep the particle on that side,
// at least the thickness away: as long as the cape starts free of intersections, and its pairs stay within
// the slack of their predicted motion, no particle can pass through a triangle, however fast the fold. A
// fast turn's pairs leave their prediction by more than the slack in some windows (docs/PERFORMANCE.md,
// "Self-contacts: swept boxes").
#include "SelfCollision.h"

#include "cape/core/Geometry.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

// The per-pair test is called from three loops; inlined, the search runs a few percent faster (measured).
#if defined(__GNUC__)
#define CAPE_ALWAYS_INLINE __attribute__((always_inline))
#else
#define CAPE_ALWAYS_INLINE
#endif

namespace cape::detail {

namespace {

/// The farthest a contact's correction may move a triangle's corner, in multiples of the contact's violation
/// (thickness - distance). With equal masses a corner moves at most the violation while the particle can
/// move, and at most 1.4 times it while only the three corners can: this bound is not reached. It is reached
/// where the particle and some corners are held (pinned, or resting on a body in the last pass) and the free
/// corners' barycentric weights are small: a free corner of weight w alone then moves by violation / w, which
/// for a nearest point close to the held corners throws it metres away (a character jumping 0.5 m in one
/// frame drove a 32 x 32 cape to 15,000 % strain this way, and the numerical guard restored particles every
/// frame after).
constexpr float kMaxCornerAmplification = 2.0f;

/// The most self-contacts one search keeps for a particle (Cape::kMaxSelfContactsPerParticle; its scan stops
/// there). Without a bound a mesh of a few long triangles, whose mean spacing (and so the automatic
/// thickness) is as long as the sheet, paired every particle with every triangle: a 1,024-particle fabric of
/// 32 x 32 and one long triangle per vertex made 2.95 million contacts and took 10 s for two frames (issue
/// 14).
constexpr std::size_t kMaxContactsPerParticle = Cape::kMaxSelfContactsPerParticle;

inline bool overFace(float wa, float wb, float wc) {
  return wa >= -kFaceMargin && wb >= -kFaceMargin && wc >= -kFaceMargin;
}

inline Vec3 at(const Points& x, std::uint32_t i) {
  return Vec3(x(i, 0), x(i, 1), x(i, 2));
}

// A hash entry keeps its cluster's index in the unused fourth lane of the box's low corner, as the bits of
// a float that every comparison below passes (fewer than 2^25 clusters: a positive finite float).
inline float indexBits(std::uint32_t i) {
  float f;
  std::memcpy(&f, &i, sizeof f);
  return f;
}
inline std::uint32_t bitsIndex(float f) {
  std::uint32_t i;
  std::memcpy(&i, &f, sizeof i);
  return i;
}

inline std::uint32_t bucketOf(int ix, int iy, int iz, std::uint32_t mask) {
  const std::uint32_t h = static_cast<std::uint32_t>(ix) * 73856093u ^
                          static_cast<std::uint32_t>(iy) * 19349663u ^
                          static_cast<std::uint32_t>(iz) * 83492791u;
  return h & mask;
}

// A box spanning more cells than this per axis (a fast or huge motion) is not binned: such triangles go on
// a list every particle checks, and such a particle checks every triangle. Bounded work, whatever the motion.
constexpr int kMaxSpan = 6;

/// The cells of a box: [c[0], c[4]] x [c[1], c[5]] x [c[2], c[6]] (c holds 8); false if it spans too many to
/// bin. floor() is a library call in a portable (pre-SSE4.1) build: truncate and correct instead.
inline bool cellsOf(float invCell, float lx, float ly, float lz, float hx, float hy, float hz, int* c) {
#if defined(__SSE2__)
  const __m128 scale = _mm_set1_ps(invCell);
  const auto floorCells = [scale](__m128 v, int* out) {
    const __m128 f = _mm_mul_ps(v, scale);
    const __m128i i = _mm_cvttps_epi32(f);
    // All ones (-1) where truncation went up, i.e. below zero.
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out),
                     _mm_add_epi32(i, _mm_castps_si128(_mm_cmplt_ps(f, _mm_cvtepi32_ps(i)))));
  };
  floorCells(_mm_setr_ps(lx, ly, lz, lz), c);
  floorCells(_mm_setr_ps(hx, hy, hz, hz), c + 4);
#else
  const float v[6] = {lx, ly, lz, hx, hy, hz};
  for (int k = 0; k < 6; ++k) {
    // Clamped as cvttps does (far or NaN: the most negative int), so the cast is defined.
    const float f = v[k] * invCell;
    const int i = f >= -2147483648.0f && f < 2147483648.0f ? static_cast<int>(f) : INT_MIN;
    c[k < 3 ? k : k + 1] = i - (f < static_cast<float>(i) ? 1 : 0);
  }
#endif
  // A box far out (or not finite: cells at the ints' ends, where the floor correction wraps) is not binned,
  // so neither its span nor the loops over its cells can overflow.
  constexpr std::int64_t kFar = std::int64_t(1) << 30;
  for (int k = 0; k < 3; ++k) {
    const std::int64_t lo = c[k], hi = c[k + 4];
    if (lo < -kFar || hi > kFar || hi < lo || hi - lo > kMaxSpan) return false;
  }
  return true;
}

/// Whether particle q is local to a triangle (its corners and the far corners across its edges): it reaches
/// such a triangle only by folding that edge's hinge flat, which the spring between the two far corners (a
/// shear or bend spring) resists, and the two triangles share an edge, so the hinge cannot make a
/// self-intersecting pair. At rest the other half of a grid cell is 0.71 spacings away, within the search's
/// reach: these were most of the exact tests.
inline bool isLocal(const TriangleLocalSet& set, std::uint32_t q) {
  const std::uint32_t* v = set.v;
#if defined(__SSE2__)
  const __m128i key = _mm_set1_epi32(static_cast<int>(q));
  const __m128i lo = _mm_cmpeq_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(v)), key);
  const __m128i hi = _mm_cmpeq_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(v + 4)), key);
  return _mm_movemask_epi8(_mm_or_si128(lo, hi)) != 0;
#else
  return (q == v[0]) | (q == v[1]) | (q == v[2]) | (q == v[3]) | (q == v[4]) | (q == v[5]);
#endif
}

inline bool boxesOverlap(const float* qlo, const float* qhi, const float* lo, const float* hi) {
  return (qhi[0] >= lo[0]) & (qhi[1] >= lo[1]) & (qhi[2] >= lo[2]) & (qlo[0] <= hi[0]) & (qlo[1] <= hi[1]) &
         (qlo[2] <= hi[2]);
}

/// The empty box's corners (any finite box's union with it is itself).
constexpr float kHuge = std::numeric_limits<float>::max();

/// How far segment p0-p1's projection onto unit axis u lies above q0-q1's (negative where they overlap): at
/// most the segments' distance, for any unit u.
inline float separationAlong(const Vec3& u, const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  return std::min(u.dot(p0), u.dot(p1)) - std::max(u.dot(q0), u.dot(q1));
}

}  // namespace

bool planeBarycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, float& wa, float& wb,
                      float& wc) {
  const Vec3 v0 = b - a, v1 = c - a, v2 = p - a;
  const float d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const float den = d00 * d11 - d01 * d01;
  if (!(den > 1e-20f)) return false;
  wb = (d11 * d20 - d01 * d21) / den;
  wc = (d00 * d21 - d01 * d20) / den;
  wa = 1.0f - wb - wc;
  return true;
}

// besideAndApart's bound on the most negative weight, kFaceMargin's -0.25 and room for rounding (apartLanes
// reads it too).
constexpr float kBesideBeyond = -0.27f;

// With planeBarycentric's weights times its denominator (den = |n|^2, no division): a weight w_k below
// -0.27 puts p's projection beyond the grown face (kFaceMargin, -0.25, with room for the rounding of both
// computations), and beyond the line of the edge opposite corner k by -w_k times the altitude from k,
// |n| / |edge|; p's distance from the triangle is at least that and its distance from the plane together.
// Only for triangles whose corner a has an angle of 6 degrees or more (|n|^2 >= 0.01 |ab|^2 |ac|^2), where
// the weights are well conditioned. Most self-contacts are such pairs at every substep: a fast cape's search
// reaches the 2-ring of a particle in its own sheet, more than a spacing away and never within the thickness
// (99.5 % of the solve's visits in the 20 x 20 sprint-turn).
bool besideAndApart(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, float thickness) {
  static_assert(kFaceMargin == 0.25f, "the bound below is for a margin of 1/4");
  const Vec3 v0 = b - a, v1 = c - a, v2 = p - a;
  const float d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const float den = d00 * d11 - d01 * d01;
  if (!(den >= 0.01f * d00 * d11 && den > 1e-20f)) return false;
  // den w_b, den w_c, den w_a; the most negative one and its opposite edge's squared length.
  const float db = d11 * d20 - d01 * d21, dc = d00 * d21 - d01 * d20, da = den - db - dc;
  // Weights within +-100: p no farther than a hundred times the triangle's size, where the weights' rounding
  // stays far below the margin.
  if (!(std::abs(db) <= 100.0f * den && std::abs(dc) <= 100.0f * den)) return false;
  float dk = db, edge2 = d11;         // w_b's opposite edge: ac
  if (dc < dk) dk = dc, edge2 = d00;  // w_c's: ab
  if (da < dk) dk = da, edge2 = (c - b).squaredNorm();
  if (!(dk < kBesideBeyond * den)) return false;
  // Squared distance from the edge's line in the plane, (w_k |n| / |edge|)^2 = dk^2 / (den edge2), plus the
  // squared distance from the plane, (n . v2)^2 / den; against thickness^2 (and 0.2 % for rounding), all
  // times den edge2.
  const float normal = v0.cross(v1).dot(v2);
  const float reach2 = thickness * thickness * 1.002f;
  return dk * dk + normal * normal * edge2 >= reach2 * den * edge2;
}

bool contactApart(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, float side, float thickness) {
  if (side != 0.0f) {
    // On its side of the plane and at least the thickness from it, so farther than that from the triangle
    // too: told without the nearest point.
    const Vec3 n = (b - a).cross(c - a);
    const float d = side * n.dot(p - a);
    if (d >= 0.0f && d * d >= thickness * thickness * n.squaredNorm()) return true;
  }
  return besideAndApart(p, a, b, c, thickness);
}

bool closestOnSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, float& s, float& t,
                       bool& interior) {
  // Minimise |r + s d1 - t d2|^2 (r = p0 - q0) over the square: the unconstrained minimum's s, clamped, then
  // the best t for it, clamped, and if that clamp bit, the best s for that end of q.
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const float a = d1.dot(d1), e = d2.dot(d2), b = d1.dot(d2), c = d1.dot(r), f = d2.dot(r);
  interior = false;
  if (!(a > 1e-20f && e > 1e-20f)) return false;
  const float den = a * e - b * b;  // |d1 x d2|^2
  // Parallel within about 0.06 degrees: any s will do (the closest points are not unique).
  const bool parallel = !(den > 1e-6f * a * e);
  const float free = parallel ? 0.0f : (b * f - c * e) / den;
  s = std::clamp(free, 0.0f, 1.0f);
  t = (b * s + f) / e;
  if (t < 0.0f) {
    t = 0.0f;
    s = std::clamp(-c / a, 0.0f, 1.0f);
  } else if (t > 1.0f) {
    t = 1.0f;
    s = std::clamp((b - c) / a, 0.0f, 1.0f);
  } else {
    interior = !parallel && free > 0.0f && free < 1.0f && t > 0.0f && t < 1.0f;
  }
  return true;
}

SelfCollision::SelfCollision(const Fabric& fabric) : fabric_(fabric) {}

void SelfCollision::allocate() {
  // The search's scratch, sized once, when the cape turns self-collision on (or at the first search): a cape
  // that never does keeps none of it (a 20 x 20 cape's is about 270 kB, most of it the contacts' reserve).
  if (!hashStart_.empty()) return;  // sized already (the hash's offsets are never empty once sized)
  const std::size_t n = fabric_.particleCount(), triangles = fabric_.triangleCount();
  // A hash of at least twice as many buckets as particles (a power of two).
  std::uint32_t buckets = 1;
  while (buckets < 2 * static_cast<std::uint32_t>(n)) buckets <<= 1;
  hashStart_.assign(buckets + 1, 0u);
  bucketCluster_.assign(buckets, ~0u);
  hashEntries_.assign(8 * triangles, HashEntry{});
  bucketHits_.assign(hashEntries_.size(), 0u);
  triangleMotion_.assign(triangles, 0.0f);
  triangleStamp_.assign(triangles, 0u);
  largeTriangles_.reserve(triangles);
  clusterBuckets_.reserve(8 * triangles);
  clusterBoxes_.assign(6 * fabric_.clusterCount(), 0.0f);
  clusterBucketStart_.assign(fabric_.clusterCount() + 1, 0u);
  stepMotion_ = Points::Zero(static_cast<Eigen::Index>(n), 3);
  sweptLo_ = Points::Zero(static_cast<Eigen::Index>(n), 3);
  sweptHi_ = Points::Zero(static_cast<Eigen::Index>(n), 3);
  stepMotionNorm_ = Eigen::VectorXf::Zero(static_cast<Eigen::Index>(n));
  contacts_.reserve(32 * n);
  buildEdgePairs();
}

std::size_t SelfCollision::scratchBytes() const {
  const auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  const auto points = [](const auto& m) { return static_cast<std::size_t>(m.size()) * sizeof(float); };
  return bytes(contacts_) + bytes(edgePairs_) + bytes(edgeAxis_) + bytes(edgeContacts_) + bytes(hashStart_) +
         bytes(hashEntries_) + bytes(bucketHits_) + bytes(triangleMotion_) + bytes(triangleStamp_) +
         bytes(largeTriangles_) + bytes(clusterBoxes_) + bytes(clusterBuckets_) + bytes(clusterBucketStart_) +
         bytes(bucketCluster_) + points(stepMotion_) + points(stepMotionNorm_) + points(sweptLo_) +
         points(sweptHi_);
}

float SelfCollision::thickness(const CapeSettings& settings) const {
  // As set, or 0.35 of the mean spacing (CapeSettings::selfCollisionThickness explains the choice).
  constexpr float kAutoThickness = 0.35f;
  return settings.selfCollisionThickness > 0.0f ? settings.selfCollisionThickness
                                                : kAutoThickness * fabric_.meanSpacing();
}

int SelfCollision::schedule(const CapeState& state, const Eigen::VectorXf& freeMask,
                            const CapeSettings& settings, float dt, int substeps) {
  // Self-contacts are found from where the cape is now and kept through the substeps. One search covers at
  // most three quarters of a spacing of motion (relative to the cape's rigid motion) and at most one
  // settings.timeStep: the motion is predicted from the velocities, and the springs change it within the
  // window (with a whole spacing, and the pins' velocities right, the sprint-turn let two pairs through).
  // A calm cape (no particle faster than that per timeStep) searches once per timeStep: a world stepping
  // at 1/240 s then searches once per 1/60 s, with that 1/60 s's motion bound. A faster one searches again
  // every few substeps: a search over a whole fast frame would pair every particle with every triangle it
  // might sweep past, and the substeps would carry thousands of contacts.
  if (!(state.time + static_cast<double>(dt) > validUntil_ + 1e-9)) return 0;  // still covered
  allocate();
  const float spacing = fabric_.meanSpacing();
  // The fastest particle relative to the cape's rigid motion (predictMotion), m/s.
  const float fastest = predictMotion(state, freeMask, settings.gravity, dt) / dt;
  constexpr float kSearchMotion = 0.75f;  // spacings of motion one search may cover
  if (std::isfinite(fastest) && fastest * settings.timeStep < kSearchMotion * spacing) {
    const float window = std::max(dt, settings.timeStep);
    if (window != dt) predictMotion(state, freeMask, settings.gravity, window);
    find(state.positions, state.velocities, thickness(settings));
    ++searches_;
    validUntil_ = state.time + static_cast<double>(window);
    return 0;
  }
  // Enough searches that none covers more than kSearchMotion spacings; every substep at most (and for a
  // non-finite motion, whose search finds nothing: find() leaves a blown-up cape alone).
  const float wanted = fastest * dt / (kSearchMotion * spacing);
  const int searches =
      std::isfinite(wanted)
          ? static_cast<int>(std::clamp(std::ceil(wanted), 1.0f, static_cast<float>(substeps)))
          : substeps;
  validUntil_ = state.time + static_cast<double>(dt);
  return (substeps + searches - 1) / searches;
}

void SelfCollision::searchFor(const CapeState& state, const Eigen::VectorXf& freeMask,
                              const CapeSettings& settings, float window) {
  allocate();
  predictMotion(state, freeMask, settings.gravity, window);
  find(state.positions, state.velocities, thickness(settings));
  ++searches_;
}

float SelfCollision::predictMotion(const CapeState& state, const Eigen::VectorXf& freeMask,
                                   const Vec3& gravity, float dt) {
  // How far each particle may move in dt, v dt + g dt^2 / 2 (pinned particles move at the velocity their
  // pin gave them), less a rigid motion of the whole cape: a rigid motion changes no distance, so only what
  // is left can bring a particle closer to a triangle. The rigid motion is the least-squares fit of a
  // translation and a small rotation (the mean displacement, and theta from I theta = sum r x m with I the
  // points' inertia about their centroid), applied exactly. Walking carries every particle 2 cm per frame
  // and a sprinter's turn swings the whole cape round: neither brings two of its particles together.
  const Points& x = state.positions;
  const Eigen::Index n = x.rows();
  stepMotion_ = state.velocities * dt;
  for (int c = 0; c < 3; ++c) stepMotion_.col(c) += (0.5f * dt * dt * gravity[c]) * freeMask;
  const Vec3 translation = stepMotion_.colwise().mean().transpose();
  const Vec3 centroid = x.colwise().mean().transpose();
  // Plain loops over the columns: this runs before every search.
  const float *px = x.col(0).data(), *py = x.col(1).data(), *pz = x.col(2).data();
  float *mx = stepMotion_.col(0).data(), *my = stepMotion_.col(1).data(), *mz = stepMotion_.col(2).data();
  float sxx = 0, syy = 0, szz = 0, sxy = 0, sxz = 0, syz = 0;
  Vec3 moment = Vec3::Zero();
  for (Eigen::Index i = 0; i < n; ++i) {
    const float rx = px[i] - centroid.x(), ry = py[i] - centroid.y(), rz = pz[i] - centroid.z();
    const float ux = mx[i] - translation.x(), uy = my[i] - translation.y(), uz = mz[i] - translation.z();
    sxx += rx * rx;
    syy += ry * ry;
    szz += rz * rz;
    sxy += rx * ry;
    sxz += rx * rz;
    syz += ry * rz;
    moment += Vec3(ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux);
  }
  Eigen::Matrix3f inertia;
  inertia << syy + szz, -sxy, -sxz, -sxy, sxx + szz, -syz, -sxz, -syz, sxx + syy;
  Eigen::Matrix3f rotationMinusIdentity = Eigen::Matrix3f::Zero();
  const Eigen::LDLT<Eigen::Matrix3f> ldlt(inertia);
  if (ldlt.info() == Eigen::Success && ldlt.isPositive() && inertia.trace() > 0.0f) {
    const Vec3 theta = ldlt.solve(moment);
    const float angle = theta.norm();
    // Any rigid motion keeps the bound exact; a poor fit (or none) only makes it looser.
    if (std::isfinite(angle) && angle > 0.0f && angle < 1.0f)
      rotationMinusIdentity =
          Eigen::AngleAxisf(angle, theta / angle).toRotationMatrix() - Eigen::Matrix3f::Identity();
  }
  const Eigen::Matrix3f& k = rotationMinusIdentity;
  for (Eigen::Index i = 0; i < n; ++i) {
    const float rx = px[i] - centroid.x(), ry = py[i] - centroid.y(), rz = pz[i] - centroid.z();
    mx[i] -= translation.x() + k(0, 0) * rx + k(0, 1) * ry + k(0, 2) * rz;
    my[i] -= translation.y() + k(1, 0) * rx + k(1, 1) * ry + k(1, 2) * rz;
    mz[i] -= translation.z() + k(2, 0) * rx + k(2, 1) * ry + k(2, 2) * rz;
  }
  stepMotionNorm_ = stepMotion_.rowwise().norm();  // same size every step: no allocation
  largestMotion_ = stepMotionNorm_.maxCoeff();
  return largestMotion_;
}

bool SelfCollision::provenApart(const Points& x) {
  // The flat proof (Fabric::keepsApart): a grid cape stretched and bent by little keeps every two of its
  // points at least kappa times their rest distance apart. A particle and a triangle it is not local to are
  // at least the fabric's FlatProof::particleTriangle apart at rest, a hinge's opposite edges
  // FlatProof::edgeEdge; a search keeps a pair only within the thickness, the slack and their relative
  // predicted motion (at most twice the largest motion) of each other. So where kappa times each rest gap
  // exceeds that reach, the search would find nothing, and is passed over. The 20 x 20 walking cape is
  // proven apart this way in about half its searches (docs/PERFORMANCE.md); a folding or a larger one seldom
  // is, and is searched as before.
  const Fabric::FlatProof* proof = fabric_.flatProof();
  if (proof == nullptr) return false;
  // How much closer two particles h king's moves apart may come over the window: at most h times the most
  // that two neighbours (a structural or shear spring apart) may, along a path of h neighbours, and at most
  // twice the largest motion.
  const int columns = fabric_.gridColumns(), rows = fabric_.gridRows();
  const float *mx = stepMotion_.col(0).data(), *my = stepMotion_.col(1).data(),
              *mz = stepMotion_.col(2).data();
  // Row by row, each particle against its right, lower-left, lower and lower-right neighbours: contiguous
  // runs of the motion's columns.
  const auto run = [mx, my, mz](int from, int to, int offset) {
    float most = 0.0f;
    int i = from;
#if defined(__SSE2__)
    // Four at a time (a compiler keeps a float maximum scalar, for its NaN rules).
    __m128 most4 = _mm_setzero_ps();
    for (; i + 4 <= to; i += 4) {
      const __m128 dx = _mm_sub_ps(_mm_loadu_ps(mx + i + offset), _mm_loadu_ps(mx + i));
      const __m128 dy = _mm_sub_ps(_mm_loadu_ps(my + i + offset), _mm_loadu_ps(my + i));
      const __m128 dz = _mm_sub_ps(_mm_loadu_ps(mz + i + offset), _mm_loadu_ps(mz + i));
      most4 = _mm_max_ps(most4,
                         _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz)));
    }
    alignas(16) float lanes[4];
    _mm_store_ps(lanes, most4);
    most = std::max(std::max(lanes[0], lanes[1]), std::max(lanes[2], lanes[3]));
#endif
    for (; i < to; ++i) {
      const float dx = mx[i + offset] - mx[i], dy = my[i + offset] - my[i], dz = mz[i + offset] - mz[i];
      const float d2 = dx * dx + dy * dy + dz * dz;
      most = most < d2 ? d2 : most;
    }
    return most;
  };
  float neighbour2 = 0.0f;
  for (int r = 0; r < rows; ++r) {
    const int start = r * columns;
    neighbour2 = std::max(neighbour2, run(start, start + columns - 1, 1));
    if (r + 1 == rows) break;
    neighbour2 = std::max({neighbour2, run(start, start + columns, columns),
                           run(start, start + columns - 1, columns + 1),
                           run(start + 1, start + columns, columns - 1)});
  }
  const float neighbour = std::sqrt(neighbour2), largest = 2.0f * largestMotion_;
  const float edgeThickness = kEdgeThicknessFraction * thickness_;
  // The least kappa that keeps every pair out of reach: each kind of pair's reach over its rest gap.
  float wanted = (thickness_ + slack_ + largest) / proof->beyond;
  float closest = proof->beyond;
  for (std::size_t h = 0; h < proof->particleTriangle.size(); ++h) {
    const float gap = proof->particleTriangle[h];
    if (gap == std::numeric_limits<float>::infinity()) continue;
    if (!(gap > 0.0f)) return false;  // touching at rest: nothing to prove with
    wanted =
        std::max(wanted, (thickness_ + slack_ + std::min(largest, static_cast<float>(h) * neighbour)) / gap);
    closest = std::min(closest, gap);
  }
  for (std::size_t h = 0; h < proof->edgeEdge.size(); ++h) {
    const float gap = proof->edgeEdge[h];
    if (gap == std::numeric_limits<float>::infinity()) continue;
    if (!(gap > 0.0f)) return false;  // touching at rest: nothing to prove with
    wanted = std::max(wanted,
                      (edgeThickness + slack_ + std::min(largest, static_cast<float>(h) * neighbour)) / gap);
    closest = std::min(closest, gap);
  }
  // Room for rounding: 1 %, and for coordinates far from the origin, whose differences keep fewer digits.
  const float far = x.cwiseAbs().maxCoeff();
  wanted = 1.01f * wanted + 64.0f * std::numeric_limits<float>::epsilon() * far / closest;
  if (!(wanted < 2.0f)) return false;  // not finite, or more than any cape stretched within bounds gives
  return fabric_.keepsApart(x, wanted, lastFailed_);
}

CAPE_ALWAYS_INLINE inline bool SelfCollision::particleFull() const {
  return contacts_.size() - particleFirst_ >= kMaxContactsPerParticle;
}

CAPE_ALWAYS_INLINE inline void SelfCollision::growCornerBox(std::uint32_t t, float* lo, float* hi) const {
  const std::vector<std::uint32_t>& tri = fabric_.triangles();
  const std::uint32_t ia = tri[3 * t], ib = tri[3 * t + 1], ic = tri[3 * t + 2];
  for (int k = 0; k < 3; ++k) {
    const float* l = sweptLo_.col(k).data();
    const float* h = sweptHi_.col(k).data();
    lo[k] = std::min(lo[k], std::min(std::min(l[ia], l[ib]), l[ic]));
    hi[k] = std::max(hi[k], std::max(std::max(h[ia], h[ib]), h[ic]));
  }
}

void SelfCollision::grownBox(std::uint32_t t, Vec3& lo, Vec3& hi) const {
  // The box a triangle sweeps over the search's window, its corners moving by their predicted motion (less
  // the cape's rigid motion), grown by the thickness and the slack: a particle that comes within the
  // thickness of it at some moment of the window is then in this box, and the particle's own swept box
  // overlaps it. As binned (bin() grows a cluster's union once: a rounded subtraction of one amount keeps
  // the order, so the same bits), and for the rare unbinned paths.
  float l[3] = {kHuge, kHuge, kHuge}, h[3] = {-kHuge, -kHuge, -kHuge};
  growCornerBox(t, l, h);
  const float grow = thickness_ + slack_;
  for (int k = 0; k < 3; ++k) {
    lo[k] = l[k] - grow;
    hi[k] = h[k] + grow;
  }
}

CAPE_ALWAYS_INLINE inline void SelfCollision::consider(std::uint32_t q, const Vec3& p, std::uint32_t t,
                                                       bool stamp) {
  // One particle against one triangle whose grown swept box its own swept box overlaps: the exact filter, and
  // the contact with the side it is on.
  if (isLocal(fabric_.triangleLocal()[t], q)) return;
  if (particleFull()) return;
  if (stamp) {
    if (triangleStamp_[t] == q) return;  // met already through another cell
    triangleStamp_[t] = q;
  }
  // The bounding sphere first (about the centroid, out to the farthest corner), with the two motions
  // added: it rejects most of what overlapping boxes let through. Computed here, not when binning: most
  // triangles meet no particle but their own corners, which the scan passes over.
  const std::vector<std::uint32_t>& tri = fabric_.triangles();
  const Points& x = *x_;
  const std::uint32_t ia = tri[3 * t], ib = tri[3 * t + 1], ic = tri[3 * t + 2];
  const Vec3 a = at(x, ia), b = at(x, ib), c = at(x, ic);
  const Vec3 centroid = (a + b + c) / 3.0f;
  const float radius = std::sqrt(
      std::max({(a - centroid).squaredNorm(), (b - centroid).squaredNorm(), (c - centroid).squaredNorm()}));
  const float d2 = (p - centroid).squaredNorm();
  const float loose = thickness_ + slack_ + stepMotionNorm_[q] + triangleMotion_[t] + radius;
  if (d2 > loose * loose) return;
  // How much closer the two may come: the particle's motion relative to the triangle's corners.
  const Vec3 mqv = stepMotion_.row(q).transpose();
  const float closing = std::sqrt(std::max({(mqv - stepMotion_.row(ia).transpose()).squaredNorm(),
                                            (mqv - stepMotion_.row(ib).transpose()).squaredNorm(),
                                            (mqv - stepMotion_.row(ic).transpose()).squaredNorm()}));
  const float within = thickness_ + slack_ + closing;
  // The sphere again with the relative motion, then the triangle itself.
  const float reach = within + radius;
  if (d2 > reach * reach) return;
  const TriangleNearest w = nearestOnTriangle(p, a, b, c);
  const Vec3 nearest = w.wa * a + w.wb * b + w.wc * c;
  if ((p - nearest).squaredNorm() > within * within) return;
  float side = 0.0f, wa, wb, wc;
  if (planeBarycentric(p, a, b, c, wa, wb, wc) && overFace(wa, wb, wc))
    side = (b - a).cross(c - a).dot(p - a) >= 0.0f ? 1.0f : -1.0f;
  contacts_.push_back({q, t, side});
}

void SelfCollision::find(const Points& x, const Points& v, float thickness) {
  contacts_.clear();
  edgeContacts_.clear();
  // A cape that is no longer finite has blown up (the metrics report it); there is nothing to keep apart.
  if (!x.allFinite() || !v.allFinite()) return;
  // A pair can close in by at most their relative motion; the solver's own corrections (springs, collisions)
  // add some more, which a quarter of the spacing allows for. Cells twice the spacing: a triangle spans one
  // or two per axis.
  x_ = &x;
  thickness_ = thickness;
  slack_ = 0.25f * fabric_.meanSpacing();
  if (flatProof_ && provenApart(x)) {
    ++provenApart_;
    return;
  }
  invCell_ = 1.0f / (2.0f * fabric_.meanSpacing());
  mask_ = static_cast<std::uint32_t>(hashStart_.size() - 1) - 1;
  // Each particle's swept box: from where it is to where its predicted motion takes it (the same size every
  // search: no allocation).
  sweptLo_ = x.cwiseMin(x + stepMotion_);
  sweptHi_ = x.cwiseMax(x + stepMotion_);
  bin();
  // Each particle visits the cells of its own swept box. A pair that comes within reach at some moment of
  // the window (each moving by its predicted motion; the slack for what the prediction misses) is in both
  // boxes then, so the boxes overlap: swept boxes keep every such pair, and drop the pairs that only a box of
  // the motion's length in every direction kept (those slide past each other or part: in the 64 x 64
  // sprint-turn such boxes met 18 clusters per particle where swept boxes meet 4.5, its own mostly).
  std::fill(triangleStamp_.begin(), triangleStamp_.end(), ~0u);
  const std::size_t triangles = fabric_.triangleCount();
  for (Eigen::Index qi = 0; qi < x.rows(); ++qi) {
    const std::uint32_t q = static_cast<std::uint32_t>(qi);
    particleFirst_ = contacts_.size();
    const Vec3 p = at(x, q);
    const float qlo[3] = {sweptLo_(qi, 0), sweptLo_(qi, 1), sweptLo_(qi, 2)},
                qhi[3] = {sweptHi_(qi, 0), sweptHi_(qi, 1), sweptHi_(qi, 2)};
    int range[8];
    if (!cellsOf(invCell_, qlo[0], qlo[1], qlo[2], qhi[0], qhi[1], qhi[2], range)) {
      for (std::size_t t = 0; t < triangles && !particleFull(); ++t) {
        Vec3 tlo, thi;
        grownBox(static_cast<std::uint32_t>(t), tlo, thi);
        if (boxesOverlap(qlo, qhi, tlo.data(), thi.data()))
          consider(q, p, static_cast<std::uint32_t>(t), false);
      }
      continue;
    }
    // Only a particle whose box spans several cells can meet a triangle twice.
    const bool stamp = range[4] > range[0] || range[5] > range[1] || range[6] > range[2];
    for (int ix = range[0]; ix <= range[4]; ++ix)
      for (int iy = range[1]; iy <= range[5]; ++iy)
        for (int iz = range[2]; iz <= range[6]; ++iz)
          scanBucket(q, p, qlo, qhi, bucketOf(ix, iy, iz, mask_), stamp);
    for (const std::uint32_t t : largeTriangles_) {
      if (particleFull()) break;
      Vec3 tlo, thi;
      grownBox(t, tlo, thi);
      if (boxesOverlap(qlo, qhi, tlo.data(), thi.data())) consider(q, p, t, false);
    }
  }
  findEdges(x);
}

void SelfCollision::buildEdgePairs() {
  // Every edge of two triangles (a, b, c) and (b, a, d) is a hinge, and its quad a-c-b-d has two pairs of
  // opposite edges, (a c, b d) and (b c, a d). Visited from both triangles: kept from the one whose own
  // corner is the lower index.
  const std::vector<std::uint32_t>& tri = fabric_.triangles();
  const std::vector<TriangleLocalSet>& local = fabric_.triangleLocal();
  for (std::size_t t = 0; t < fabric_.triangleCount(); ++t)
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3], c = tri[3 * t + (k + 2) % 3];
      const std::uint32_t d = local[t].v[3 + k];
      if (d == ~0u || !(c < d) || d == a || d == b) continue;
      edgePairs_.push_back({a, c, b, d});
      edgePairs_.push_back({b, c, a, d});
    }
  edgeAxis_.assign(3 * edgePairs_.size(), 0.0f);  // none yet: every pair's first search is exact
}

void SelfCollision::findEdges(const Points& x) {
  // The particle-triangle contacts leave out a triangle's own hinge: a particle is local to the triangles
  // across its triangle's edges (isLocal), and a hinge folded flat has no vertex near the other triangle's
  // face. Folded further, its triangles cross edge through edge: the hinge quad's opposite edges make an X
  // (two grid cells folded over their shared side cross their diagonals; a cell folded over its diagonal,
  // its opposite sides), each vertex still 0.6 spacings or more from the other triangle. Such a pair is
  // kept apart by an edge-edge contact, found as the particle-triangle ones are: within the thickness plus
  // the slack plus their relative predicted motion. The edge thickness is a fifth of the particle one
  // (kEdgeThicknessFraction): a clean fold's opposite edges lie about half as far apart as its layers, and
  // a gathered collar's pleats closer still, which twice that held open (docs/SOLVER.md).
  const float edgeThickness = kEdgeThicknessFraction * thickness_;
  const float* norm = stepMotionNorm_.data();
  const float *px = x.col(0).data(), *py = x.col(1).data(), *pz = x.col(2).data();
  // A hinge's two pairs (buildEdgePairs: consecutive) have the same four particles, read once for both.
  for (std::size_t i = 0; i + 1 < edgePairs_.size(); i += 2) {
    const EdgePair& h = edgePairs_[i];  // a = p0, c = p1, b = q0, d = q1
    const Vec3 a(px[h.p0], py[h.p0], pz[h.p0]), c(px[h.p1], py[h.p1], pz[h.p1]),
        b(px[h.q0], py[h.q0], pz[h.q0]), d(px[h.q1], py[h.q1], pz[h.q1]);
    const float reachA = norm[h.p0], reachC = norm[h.p1], reachB = norm[h.q0], reachD = norm[h.q1];
    // Most hinges are open: their opposite edges a spacing or so apart, out of reach of any motion the
    // search allows. The gap between the edges' projections onto any unit axis is at most their distance:
    // onto the direction that separated them at their last exact test, a hinge that has not turned much
    // since is passed over without its closest points (most hinges at every search), first with each end's
    // whole motion, then with its motion along the axis.
    const float* axisAC = &edgeAxis_[3 * i];
    const float* axisBC = &edgeAxis_[3 * i + 3];
    const Vec3 uAC(axisAC[0], axisAC[1], axisAC[2]), uBC(axisBC[0], axisBC[1], axisBC[2]);
    const float nearAC = edgeThickness + slack_ + std::max(reachA, reachC) + std::max(reachB, reachD);
    const float nearBC = edgeThickness + slack_ + std::max(reachB, reachC) + std::max(reachA, reachD);
    const bool openAC = separationAlong(uAC, a, c, b, d) > nearAC;
    const bool openBC = separationAlong(uBC, b, c, a, d) > nearBC;
    if (openAC && openBC) continue;
    if (!openAC) considerEdgePair(i, x);
    if (!openBC) considerEdgePair(i + 1, x);
  }
}

void SelfCollision::considerEdgePair(std::size_t i, const Points& x) {
  const EdgePair& e = edgePairs_[i];
  const float edgeThickness = kEdgeThicknessFraction * thickness_;
  const float* norm = stepMotionNorm_.data();
  const float *mx = stepMotion_.col(0).data(), *my = stepMotion_.col(1).data(),
              *mz = stepMotion_.col(2).data();
  const Vec3 p0 = at(x, e.p0), p1 = at(x, e.p1), q0 = at(x, e.q0), q1 = at(x, e.q1);
  float* axis = &edgeAxis_[3 * i];
  {
    const Vec3 u(axis[0], axis[1], axis[2]);
    const auto along = [&u, mx, my, mz](std::uint32_t k) {
      return u.x() * mx[k] + u.y() * my[k] + u.z() * mz[k];
    };
    const float lowest = std::min(u.dot(p0), u.dot(p1)) + std::min({0.0f, along(e.p0), along(e.p1)});
    const float highest = std::max(u.dot(q0), u.dot(q1)) + std::max({0.0f, along(e.q0), along(e.q1)});
    if (lowest - highest > edgeThickness + slack_) return;
  }
  float s, t;
  bool interior;
  if (!closestOnSegments(p0, p1, q0, q1, s, t, interior)) return;
  const Vec3 gap = (p0 + s * (p1 - p0)) - (q0 + t * (q1 - q0));
  const float gap2 = gap.squaredNorm();
  if (gap2 > 0.0f && std::isfinite(gap2)) {
    const Vec3 unit = gap / std::sqrt(gap2);  // from q's edge to p's: p's projection is the higher
    axis[0] = unit.x();
    axis[1] = unit.y();
    axis[2] = unit.z();
  }
  const float loose =
      edgeThickness + slack_ + std::max(norm[e.p0], norm[e.p1]) + std::max(norm[e.q0], norm[e.q1]);
  if (gap2 > loose * loose) return;
  // The relative motion of any two points of the edges is a weighted mean of their ends' relative motions.
  const Vec3 m0 = stepMotion_.row(e.p0).transpose(), m1 = stepMotion_.row(e.p1).transpose();
  const Vec3 n0 = stepMotion_.row(e.q0).transpose(), n1 = stepMotion_.row(e.q1).transpose();
  const float closing = std::sqrt(std::max(
      {(m0 - n0).squaredNorm(), (m0 - n1).squaredNorm(), (m1 - n0).squaredNorm(), (m1 - n1).squaredNorm()}));
  const float within = edgeThickness + slack_ + closing;
  if (gap2 > within * within) return;
  float side = 0.0f;
  if (interior) {
    const float g = (p1 - p0).cross(q1 - q0).dot(gap);
    side = g > 0.0f ? 1.0f : (g < 0.0f ? -1.0f : 0.0f);
  }
  edgeContacts_.push_back({static_cast<std::uint32_t>(i), side});
}

void SelfCollision::solveEdges(Points& x, const float* w, float thickness, float maxCrossing) {
  const float edgeThickness = kEdgeThicknessFraction * thickness;
  for (EdgeContact& k : edgeContacts_) {
    const EdgePair& e = edgePairs_[k.pair];
    const Vec3 p0 = at(x, e.p0), p1 = at(x, e.p1), q0 = at(x, e.q0), q1 = at(x, e.q1);
    // Apart along the search's separating direction by the thickness: apart, and on the side they were on.
    const Vec3 axis(edgeAxis_[3 * k.pair], edgeAxis_[3 * k.pair + 1], edgeAxis_[3 * k.pair + 2]);
    if (separationAlong(axis, p0, p1, q0, q1) >= edgeThickness) continue;
    float s, t;
    bool interior;
    if (!closestOnSegments(p0, p1, q0, q1, s, t, interior)) continue;
    const Vec3 gap = (p0 + s * (p1 - p0)) - (q0 + t * (q1 - q0));
    Vec3 normal;
    float distance;
    if (interior) {
      // The closest points inside both edges: keep p's edge on the side of q's it started on (or first came
      // to lie across from), along the edges' common normal.
      Vec3 n = (p1 - p0).cross(q1 - q0);
      const float len = n.norm();
      if (!(len > 0.0f)) continue;
      n /= len;
      if (k.side == 0.0f) k.side = n.dot(gap) >= 0.0f ? 1.0f : -1.0f;
      normal = k.side * n;
      distance = normal.dot(gap);             // negative: they have crossed, and are brought back
      if (distance < -maxCrossing) continue;  // not a crossing within this step (as for a particle)
    } else {
      // At an end of either edge: a plain distance, no side to keep.
      distance = gap.norm();
      if (!(distance > 1e-9f)) continue;
      normal = gap / distance;
    }
    if (!(distance < edgeThickness)) continue;
    // PBD edge-edge constraint C = n . (p(s) - q(t)) - thickness >= 0: gradients (1 - s) n, s n for p's ends,
    // -(1 - t) n, -t n for q's. The denominator is bounded below as the particle-triangle one is.
    const float wp0 = w[e.p0] * (1.0f - s), wp1 = w[e.p1] * s, wq0 = w[e.q0] * (1.0f - t), wq1 = w[e.q1] * t;
    const float denominator = std::max(wp0 * (1.0f - s) + wp1 * s + wq0 * (1.0f - t) + wq1 * t,
                                       std::max({wp0, wp1, wq0, wq1}) / kMaxCornerAmplification);
    if (!(denominator > 0.0f)) continue;
    const Vec3 step = ((edgeThickness - distance) / denominator) * normal;
    x.row(e.p0) += wp0 * step.transpose();
    x.row(e.p1) += wp1 * step.transpose();
    x.row(e.q0) -= wq0 * step.transpose();
    x.row(e.q1) -= wq1 * step.transpose();
  }
}

void SelfCollision::bin() {
  // Bin the triangles' swept boxes (grownBox), into the cells of a hashed grid. Binned by cluster (the two
  // triangles of a grid cell share its box): half the entries of binning each.
  const std::vector<std::uint32_t>& tri = fabric_.triangles();
  const std::vector<std::uint32_t>& clusterStart = fabric_.clusterStart();
  const std::uint32_t buckets = static_cast<std::uint32_t>(hashStart_.size() - 1);
  largeTriangles_.clear();
  clusterBuckets_.clear();
  std::fill(hashStart_.begin(), hashStart_.end(), 0u);
  std::fill(bucketCluster_.begin(), bucketCluster_.end(), ~0u);
  const std::size_t clusters = fabric_.clusterCount();
  // A cluster's box: the union of its triangles' grown boxes (grownBox), grown once.
  const float grow = thickness_ + slack_;
  const float* norm = stepMotionNorm_.data();
  for (std::size_t g = 0; g < clusters; ++g) {
    clusterBucketStart_[g] = static_cast<std::uint32_t>(clusterBuckets_.size());
    float lo[3] = {kHuge, kHuge, kHuge}, hi[3] = {-kHuge, -kHuge, -kHuge};
    for (std::uint32_t t = clusterStart[g]; t < clusterStart[g + 1]; ++t) {
      triangleMotion_[t] = std::max(std::max(norm[tri[3 * t]], norm[tri[3 * t + 1]]), norm[tri[3 * t + 2]]);
      growCornerBox(t, lo, hi);
    }
    for (int k = 0; k < 3; ++k) {
      lo[k] -= grow;
      hi[k] += grow;
    }
    float* clusterBox = &clusterBoxes_[6 * g];
    for (int k = 0; k < 3; ++k) {
      clusterBox[k] = lo[k];
      clusterBox[3 + k] = hi[k];
    }
    int range[8];
    if (!cellsOf(invCell_, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], range)) {
      for (std::uint32_t t = clusterStart[g]; t < clusterStart[g + 1]; ++t) largeTriangles_.push_back(t);
      continue;
    }
    // The buckets of its cells, kept for the fill below (at most (kMaxSpan + 1)^3; usually 1 to 8).
    for (int ix = range[0]; ix <= range[4]; ++ix)
      for (int iy = range[1]; iy <= range[5]; ++iy)
        for (int iz = range[2]; iz <= range[6]; ++iz) {
          const std::uint32_t bucket = bucketOf(ix, iy, iz, mask_);
          // Once per bucket, even if two of its cells hash to the same one: a particle that visits a single
          // cell then meets each triangle at most once, and needs no stamps.
          if (bucketCluster_[bucket] == g) continue;
          bucketCluster_[bucket] = static_cast<std::uint32_t>(g);
          ++hashStart_[bucket + 1];
          clusterBuckets_.push_back(bucket);  // grows rarely: capacity kept between steps
        }
  }
  clusterBucketStart_[clusters] = static_cast<std::uint32_t>(clusterBuckets_.size());
  for (std::uint32_t b = 0; b < buckets; ++b) hashStart_[b + 1] += hashStart_[b];  // [b] = start of bucket b
  if (hashEntries_.size() < hashStart_[buckets]) {                                 // grows rarely
    hashEntries_.resize(hashStart_[buckets]);
    bucketHits_.resize(hashStart_[buckets]);
  }
  // Fill in cluster order (deterministic), each bucket's start serving as its cursor...
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (std::size_t g = 0; g < clusters; ++g) {
    const float* box = &clusterBoxes_[6 * g];
    const HashEntry entry{{box[0], box[1], box[2], indexBits(static_cast<std::uint32_t>(g))},
                          {box[3], box[4], box[5], kInf}};
    for (std::uint32_t k = clusterBucketStart_[g]; k < clusterBucketStart_[g + 1]; ++k)
      hashEntries_[hashStart_[clusterBuckets_[k]]++] = entry;
  }
  // ...which leaves [b] at the end of bucket b: shift back so bucket b is [hashStart_[b], hashStart_[b + 1]).
  for (std::uint32_t b = buckets; b > 0; --b) hashStart_[b] = hashStart_[b - 1];
  hashStart_[0] = 0;
}

void SelfCollision::scanBucket(std::uint32_t q, const Vec3& p, const float* qlo, const float* qhi,
                               std::uint32_t bucket, bool stamp) {
  // The bucket's overlapping entries first, without a branch per entry (about one in four overlaps: too many
  // for branches to predict), then the exact tests. The clusters the particle is a corner of overlap it but
  // hold nothing for it (95 % of what overlaps, on a walking cape): one compare passes each over.
  if (particleFull()) return;
  const HashEntry* entry = hashEntries_.data() + hashStart_[bucket];
  const std::uint32_t count = hashStart_[bucket + 1] - hashStart_[bucket];
  std::uint32_t* found = bucketHits_.data();
  std::uint32_t hits = 0;
#if defined(__SSE2__)
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const __m128 queryLo = _mm_setr_ps(qlo[0], qlo[1], qlo[2], -kInf),
               queryHi = _mm_setr_ps(qhi[0], qhi[1], qhi[2], kInf);
  const __m128i self = _mm_set1_epi32(static_cast<int>(q));
#endif
  for (std::uint32_t e = 0; e < count; ++e) {
    found[hits] = e;
#if defined(__SSE2__)
    const __m128 inside = _mm_and_ps(_mm_cmpge_ps(queryHi, _mm_load_ps(entry[e].lo)),
                                     _mm_cmple_ps(queryLo, _mm_load_ps(entry[e].hi)));
    hits += _mm_movemask_ps(inside) == 0xF ? 1u : 0u;
#else
    hits += boxesOverlap(qlo, qhi, entry[e].lo, entry[e].hi) ? 1u : 0u;
#endif
  }
  const std::vector<std::uint32_t>& clusterStart = fabric_.clusterStart();
  for (std::uint32_t k = 0; k < hits && !particleFull(); ++k) {
    const std::uint32_t g = bitsIndex(entry[found[k]].lo[3]);
    const std::uint32_t* l = fabric_.clusterLocal()[g].v;
#if defined(__SSE2__)
    if (_mm_movemask_epi8(_mm_cmpeq_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(l)), self)) != 0)
      continue;
#else
    if ((q == l[0]) | (q == l[1]) | (q == l[2]) | (q == l[3])) continue;
#endif
    for (std::uint32_t t = clusterStart[g]; t < clusterStart[g + 1]; ++t) consider(q, p, t, stamp);
  }
}

#if defined(__SSE2__)

namespace {

// Four 3-vectors, one per lane, and the operations of Eigen's fixed-size ones in the same order (its dot
// product is a0 b0 + (a1 b1 + a2 b2), its squared norm likewise; the core is built without contraction into
// fused multiply-adds), so that each lane's figures are the scalar ones bit for bit.
struct Lanes3 {
  __m128 x, y, z;
};
inline Lanes3 minus(const Lanes3& a, const Lanes3& b) {
  return {_mm_sub_ps(a.x, b.x), _mm_sub_ps(a.y, b.y), _mm_sub_ps(a.z, b.z)};
}
inline __m128 dot(const Lanes3& a, const Lanes3& b) {
  return _mm_add_ps(_mm_mul_ps(a.x, b.x), _mm_add_ps(_mm_mul_ps(a.y, b.y), _mm_mul_ps(a.z, b.z)));
}
inline Lanes3 cross(const Lanes3& a, const Lanes3& b) {
  return {_mm_sub_ps(_mm_mul_ps(a.y, b.z), _mm_mul_ps(a.z, b.y)),
          _mm_sub_ps(_mm_mul_ps(a.z, b.x), _mm_mul_ps(a.x, b.z)),
          _mm_sub_ps(_mm_mul_ps(a.x, b.y), _mm_mul_ps(a.y, b.x))};
}
inline __m128 select(__m128 mask, __m128 yes, __m128 no) {
  return _mm_or_ps(_mm_and_ps(mask, yes), _mm_andnot_ps(mask, no));
}

}  // namespace

int apartLanes(const Points& x, const std::vector<std::uint32_t>& tri, const Cape::SelfContact* k,
               float thickness) {
  // contactApart four contacts at a time, line for line.
  const float *px = x.col(0).data(), *py = x.col(1).data(), *pz = x.col(2).data();
  const auto gather = [&](std::uint32_t i0, std::uint32_t i1, std::uint32_t i2, std::uint32_t i3) {
    return Lanes3{_mm_setr_ps(px[i0], px[i1], px[i2], px[i3]), _mm_setr_ps(py[i0], py[i1], py[i2], py[i3]),
                  _mm_setr_ps(pz[i0], pz[i1], pz[i2], pz[i3])};
  };
  const auto corner = [&](int c) {
    return gather(tri[3 * k[0].triangle + c], tri[3 * k[1].triangle + c], tri[3 * k[2].triangle + c],
                  tri[3 * k[3].triangle + c]);
  };
  const Lanes3 p = gather(k[0].particle, k[1].particle, k[2].particle, k[3].particle);
  const Lanes3 a = corner(0), b = corner(1), c = corner(2);
  const __m128 side = _mm_setr_ps(k[0].side, k[1].side, k[2].side, k[3].side);
  const __m128 zero = _mm_setzero_ps();
  const __m128 t2 = _mm_set1_ps(thickness * thickness);
  const Lanes3 v0 = minus(b, a), v1 = minus(c, a), v2 = minus(p, a);
  const Lanes3 n = cross(v0, v1);
  // On its side, beyond the thickness (only for a contact with a side).
  const __m128 d = _mm_mul_ps(side, dot(n, v2));
  const __m128 onSide = _mm_and_ps(
      _mm_cmpneq_ps(side, zero),
      _mm_and_ps(_mm_cmpge_ps(d, zero), _mm_cmpge_ps(_mm_mul_ps(d, d), _mm_mul_ps(t2, dot(n, n)))));
  // Beside and apart.
  const __m128 d00 = dot(v0, v0), d01 = dot(v0, v1), d11 = dot(v1, v1), d20 = dot(v2, v0), d21 = dot(v2, v1);
  const __m128 den = _mm_sub_ps(_mm_mul_ps(d00, d11), _mm_mul_ps(d01, d01));
  __m128 beside = _mm_and_ps(_mm_cmpge_ps(den, _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(0.01f), d00), d11)),
                             _mm_cmpgt_ps(den, _mm_set1_ps(1e-20f)));
  const __m128 db = _mm_sub_ps(_mm_mul_ps(d11, d20), _mm_mul_ps(d01, d21));
  const __m128 dc = _mm_sub_ps(_mm_mul_ps(d00, d21), _mm_mul_ps(d01, d20));
  const __m128 da = _mm_sub_ps(_mm_sub_ps(den, db), dc);
  const __m128 absMask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  const __m128 bound = _mm_mul_ps(_mm_set1_ps(100.0f), den);
  beside = _mm_and_ps(beside, _mm_and_ps(_mm_cmple_ps(_mm_and_ps(db, absMask), bound),
                                         _mm_cmple_ps(_mm_and_ps(dc, absMask), bound)));
  __m128 dk = db, edge2 = d11;
  const __m128 takeC = _mm_cmplt_ps(dc, dk);
  dk = select(takeC, dc, dk);
  edge2 = select(takeC, d00, edge2);
  const Lanes3 cb = minus(c, b);
  const __m128 takeA = _mm_cmplt_ps(da, dk);
  dk = select(takeA, da, dk);
  edge2 = select(takeA, dot(cb, cb), edge2);
  beside = _mm_and_ps(beside, _mm_cmplt_ps(dk, _mm_mul_ps(_mm_set1_ps(kBesideBeyond), den)));
  const __m128 normal = dot(n, v2);
  const __m128 reach2 = _mm_set1_ps(thickness * thickness * 1.002f);
  beside = _mm_and_ps(
      beside, _mm_cmpge_ps(_mm_add_ps(_mm_mul_ps(dk, dk), _mm_mul_ps(_mm_mul_ps(normal, normal), edge2)),
                           _mm_mul_ps(_mm_mul_ps(reach2, den), edge2)));
  return _mm_movemask_ps(_mm_or_ps(onSide, beside));
}

#endif

CAPE_ALWAYS_INLINE inline void SelfCollision::solveContact(Points& x, const float* w, float thickness,
                                                           float maxCrossing, Cape::SelfContact& k) {
  const std::vector<std::uint32_t>& tri = fabric_.triangles();
  const std::uint32_t ia = tri[3 * k.triangle], ib = tri[3 * k.triangle + 1], ic = tri[3 * k.triangle + 2];
  const Vec3 p = at(x, k.particle), a = at(x, ia), b = at(x, ib), c = at(x, ic);
  if (contactApart(p, a, b, c, k.side, thickness)) return;  // most listed pairs are apart
  const TriangleNearest bary = nearestOnTriangle(p, a, b, c);
  Vec3 normal;
  float distance;
  float wa, wb, wc;
  if (planeBarycentric(p, a, b, c, wa, wb, wc) && overFace(wa, wb, wc)) {
    // Over the (grown) face: keep to the side the particle started the step on, or first came over it from.
    Vec3 faceNormal = (b - a).cross(c - a);
    const float len = faceNormal.norm();
    if (!(len > 0.0f)) return;
    faceNormal /= len;
    if (k.side == 0.0f) k.side = faceNormal.dot(p - a) >= 0.0f ? 1.0f : -1.0f;
    normal = k.side * faceNormal;
    distance = normal.dot(p - a);  // negative: it has crossed, and is brought back
    // Far on the other side is not a crossing within this step (the region over a face reaches out along
    // its normal without end, and a triangle that turns over carries its side with it): pulling such a
    // particle back through the cloth would throw it across the cape, so the pair is let go.
    if (distance < -maxCrossing) return;
    // The correction goes to the corners by the weights of the nearest point of the real triangle.
  } else {
    // Beside an edge or a corner: a plain distance, no side to keep.
    const Vec3 d = p - (bary.wa * a + bary.wb * b + bary.wc * c);
    distance = d.norm();
    if (!(distance > 1e-9f)) return;
    normal = d / distance;
  }
  if (distance >= thickness) return;
  // PBD point-triangle constraint C = n . (p - sum w_k x_k) - thickness >= 0, gradients n and -w_k n.
  const float invP = w[k.particle], invA = w[ia], invB = w[ib], invC = w[ic];
  // A corner k moves by invK w_k violation / denominator: the denominator is kept at least invK w_k /
  // kMaxCornerAmplification for every corner (kMaxCornerAmplification's comment); with equal masses (the
  // grid's) it is left as it is whenever the particle or all three corners can move.
  const float denominator =
      std::max(invP + bary.wa * bary.wa * invA + bary.wb * bary.wb * invB + bary.wc * bary.wc * invC,
               std::max({invA * bary.wa, invB * bary.wb, invC * bary.wc}) / kMaxCornerAmplification);
  if (!(denominator > 0.0f)) return;
  const Vec3 step = ((thickness - distance) / denominator) * normal;
  x.row(k.particle) += invP * step.transpose();
  x.row(ia) -= (invA * bary.wa) * step.transpose();
  x.row(ib) -= (invB * bary.wb) * step.transpose();
  x.row(ic) -= (invC * bary.wc) * step.transpose();
}

void SelfCollision::solve(Points& x, const float* w, float thickness) {
  // The deepest a particle can have crossed within one step and still be brought back: half the spacing.
  const float maxCrossing = 0.5f * fabric_.meanSpacing();
  // In order (Gauss-Seidel). Most listed pairs are apart, and solveContact passes them over: four at a time
  // their tests say so (apartLanes, the same figures), and the first of the four that is not apart is solved
  // on its own, the next four starting after it, so that each contact's tests read the positions every
  // contact before it left, as in a loop over them one by one.
  std::size_t next = 0;
#if defined(__SSE2__)
  while (next + 4 <= contacts_.size()) {
    const int apart = apartLanes(x, fabric_.triangles(), &contacts_[next], thickness);
    if (apart == 0xF) {
      next += 4;
      continue;
    }
    next += static_cast<std::size_t>(__builtin_ctz(static_cast<unsigned>(~apart)));
    solveContact(x, w, thickness, maxCrossing, contacts_[next]);
    ++next;
  }
#endif
  for (; next < contacts_.size(); ++next) solveContact(x, w, thickness, maxCrossing, contacts_[next]);
  if (!edgeContacts_.empty()) solveEdges(x, w, thickness, maxCrossing);
}

}  // namespace cape::detail
