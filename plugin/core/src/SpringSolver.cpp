#include "SpringSolver.h"

#include "SimdDispatch.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if CAPE_HAVE_AVX2_KERNELS
#include <immintrin.h>
#endif

namespace cape::detail {

// The largest squared length a spring is solved at: beyond it the square has overflowed (or nearly).
constexpr float kMaxLength2 = std::numeric_limits<float>::max();

namespace {

// solveSpringsScalar's loop; without multipliers (kLambda false) every lambda is zero and none is stored.
template <bool kLambda, bool kScaled>
void scalarSprings(const SpringSolveArrays& a, std::uint32_t begin, std::uint32_t end, float alphaBase) {
  float* __restrict px = a.px;
  float* __restrict py = a.py;
  float* __restrict pz = a.pz;
  const float* __restrict w = a.inverseMass;
  float* __restrict lambda = a.lambda;
  // Springs of one colour share no particle, so consecutive iterations do not wait on each other's stores
  // and the processor overlaps their square roots and divisions.
  for (std::uint32_t s = begin; s < end; ++s) {
    const std::uint32_t i = a.first[s], j = a.second[s];
    const float wi = w[i], wj = w[j];
    const float dx = px[j] - px[i], dy = py[j] - py[i], dz = pz[j] - pz[i];
    const float len2 = dx * dx + dy * dy + dz * dz;
    // A zero length has no direction, and a length whose square overflows (a runaway particle, restored by
    // the cape's guard after the step) no finite one.
    if (!(len2 > 1e-18f && len2 <= kMaxLength2)) continue;
    float alphaTilde = alphaBase;
    if constexpr (kScaled) alphaTilde = alphaBase * a.complianceScale[s];
    const float wsum = wi + wj;
    const float invDenominator = wsum > 0.0f ? 1.0f / (wsum + alphaTilde) : 0.0f;  // 0: both ends pinned
    const float len = std::sqrt(len2);
    float dl;
    if constexpr (kLambda) {
      dl = (a.restLength[s] - len - alphaTilde * lambda[s]) * invDenominator;
      lambda[s] += dl;
    } else {
      dl = (a.restLength[s] - len) * invDenominator;
    }
    const float k = dl / len;
    const float cx = k * dx, cy = k * dy, cz = k * dz;
    px[i] -= wi * cx;
    py[i] -= wi * cy;
    pz[i] -= wi * cz;
    px[j] += wj * cx;
    py[j] += wj * cy;
    pz[j] += wj * cz;
  }
}

}  // namespace

void solveSpringsScalar(const SpringSolveArrays& a, std::uint32_t begin, std::uint32_t end,
                        float alphaTilde) {
  if (a.complianceScale != nullptr) {
    if (a.lambda != nullptr)
      scalarSprings<true, true>(a, begin, end, alphaTilde);
    else
      scalarSprings<false, true>(a, begin, end, alphaTilde);
  } else if (a.lambda != nullptr) {
    scalarSprings<true, false>(a, begin, end, alphaTilde);
  } else {
    scalarSprings<false, false>(a, begin, end, alphaTilde);
  }
}

void solveTethersScalar(float* px, float* py, float* pz, const float* inverseMass, const TetherSet& tethers,
                        std::size_t begin, std::size_t end) {
  // The update is a select rather than a branch: whether a tether is taut is close to random from one to the
  // next, and mispredicted branches cost more than the square root.
  const float* __restrict w = inverseMass;
  for (std::size_t k = begin; k < end; ++k) {
    const std::uint32_t a = tethers.anchor[k], p = tethers.particle[k];
    const float dx = px[p] - px[a], dy = py[p] - py[a], dz = pz[p] - pz[a];
    const float len2 = dx * dx + dy * dy + dz * dz;
    const float maxLen = tethers.maxLength[k];
    const bool taut = w[a] == 0.0f && w[p] != 0.0f && len2 > maxLen * maxLen;
    const float scale = maxLen / std::sqrt(std::max(len2, 1e-30f));
    px[p] = taut ? px[a] + dx * scale : px[p];
    py[p] = taut ? py[a] + dy * scale : py[p];
    pz[p] = taut ? pz[a] + dz * scale : pz[p];
  }
}

void limitStretchScalar(float* px, float* py, float* pz, const float* inverseMass, const SpringSet& set,
                        std::size_t begin, std::size_t end, float stretch) {
  // A branch, not a select: under ordinary motion few springs are over the ceiling, and the branch skips
  // the square root and the division for the rest.
  const float* __restrict w = inverseMass;
  const std::uint32_t* __restrict first = set.first.data();
  const std::uint32_t* __restrict second = set.second.data();
  const float* __restrict rest = set.restLength.data();
  for (std::size_t s = begin; s < end; ++s) {
    const std::uint32_t i = first[s], j = second[s];
    const float dx = px[j] - px[i], dy = py[j] - py[i], dz = pz[j] - pz[i];
    const float len2 = dx * dx + dy * dy + dz * dz;
    const float maxLen = stretch * rest[s];
    const float wsum = w[i] + w[j];
    if (!(len2 > maxLen * maxLen) || !(wsum > 0.0f)) continue;
    const float len = std::sqrt(len2);
    // The length to remove per unit of d = xj - xi, shared as wi : wj.
    const float k = (len - maxLen) / (len * wsum);
    const float ki = w[i] * k, kj = w[j] * k;
    px[i] += ki * dx;
    py[i] += ki * dy;
    pz[i] += ki * dz;
    px[j] -= kj * dx;
    py[j] -= kj * dy;
    pz[j] -= kj * dz;
  }
}

float maxSquaredStretchScalar(const float* px, const float* py, const float* pz, const SpringSet& set,
                              std::size_t begin, std::size_t end, float worst) {
  for (std::size_t s = begin; s < end; ++s) {
    const std::uint32_t i = set.first[s], j = set.second[s];
    const float dx = px[j] - px[i], dy = py[j] - py[i], dz = pz[j] - pz[i];
    const float rest = set.restLength[s];
    worst = std::max(worst, (dx * dx + dy * dy + dz * dz) / (rest * rest));
  }
  return worst;
}

#if defined(__SSE2__)

namespace {

// Loads the values of a block's first ends (vi) and second ends (vj) from one array, and stores them back,
// for each vector layout; i and j point at the block's first and second indices. `p` is the block's first
// particle, `q` its second (SpringLayout's notation).
template <SpringLayout L>
struct Lanes;

template <>
struct Lanes<SpringLayout::Contiguous> {
  static void load(const float* x, const std::uint32_t* i, const std::uint32_t* j, __m128& vi, __m128& vj) {
    const std::uint32_t p = i[0], q = j[0];
    vi = _mm_loadu_ps(x + p);
    vj = _mm_loadu_ps(x + q);
  }
  static void store(float* x, const std::uint32_t* i, const std::uint32_t* j, __m128 vi, __m128 vj) {
    const std::uint32_t p = i[0], q = j[0];
    _mm_storeu_ps(x + p, vi);
    _mm_storeu_ps(x + q, vj);
  }
};

template <>
struct Lanes<SpringLayout::PairSwapped> {
  // q is the second end of the block's first spring; its four second ends occupy [q - 1, q + 3).
  static void load(const float* x, const std::uint32_t* i, const std::uint32_t* j, __m128& vi, __m128& vj) {
    const std::uint32_t p = i[0], q = j[0];
    vi = _mm_loadu_ps(x + p);
    const __m128 t = _mm_loadu_ps(x + q - 1);            // x[q-1], x[q], x[q+1], x[q+2]
    vj = _mm_shuffle_ps(t, t, _MM_SHUFFLE(2, 3, 0, 1));  // x[q], x[q-1], x[q+2], x[q+1]
  }
  static void store(float* x, const std::uint32_t* i, const std::uint32_t* j, __m128 vi, __m128 vj) {
    const std::uint32_t p = i[0], q = j[0];
    _mm_storeu_ps(x + p, vi);
    _mm_storeu_ps(x + q - 1, _mm_shuffle_ps(vj, vj, _MM_SHUFFLE(2, 3, 0, 1)));
  }
};

template <>
struct Lanes<SpringLayout::Interleaved> {
  // [p, p + 8) holds first, second, first, second...
  static void load(const float* x, const std::uint32_t* i, const std::uint32_t*, __m128& vi, __m128& vj) {
    const std::uint32_t p = i[0];
    const __m128 lo = _mm_loadu_ps(x + p), hi = _mm_loadu_ps(x + p + 4);
    vi = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));
    vj = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1));
  }
  static void store(float* x, const std::uint32_t* i, const std::uint32_t*, __m128 vi, __m128 vj) {
    const std::uint32_t p = i[0];
    _mm_storeu_ps(x + p, _mm_unpacklo_ps(vi, vj));
    _mm_storeu_ps(x + p + 4, _mm_unpackhi_ps(vi, vj));
  }
};

template <>
struct Lanes<SpringLayout::Pairs> {
  // [p, p + 8) holds first, first, second, second, first, first, second, second.
  static void load(const float* x, const std::uint32_t* i, const std::uint32_t*, __m128& vi, __m128& vj) {
    const std::uint32_t p = i[0];
    const __m128 lo = _mm_loadu_ps(x + p), hi = _mm_loadu_ps(x + p + 4);
    vi = _mm_movelh_ps(lo, hi);
    vj = _mm_movehl_ps(hi, lo);
  }
  static void store(float* x, const std::uint32_t* i, const std::uint32_t*, __m128 vi, __m128 vj) {
    const std::uint32_t p = i[0];
    _mm_storeu_ps(x + p, _mm_movelh_ps(vi, vj));
    _mm_storeu_ps(x + p + 4, _mm_movehl_ps(vj, vi));
  }
};

template <>
struct Lanes<SpringLayout::Gathered> {
  static void load(const float* x, const std::uint32_t* i, const std::uint32_t* j, __m128& vi, __m128& vj) {
    vi = _mm_setr_ps(x[i[0]], x[i[1]], x[i[2]], x[i[3]]);
    vj = _mm_setr_ps(x[j[0]], x[j[1]], x[j[2]], x[j[3]]);
  }
  static void store(float* x, const std::uint32_t* i, const std::uint32_t* j, __m128 vi, __m128 vj) {
    alignas(16) float a[4], b[4];
    _mm_store_ps(a, vi);
    _mm_store_ps(b, vj);
    for (int k = 0; k < 4; ++k) {
      x[i[k]] = a[k];
      x[j[k]] = b[k];
    }
  }
};

inline __m128 select(__m128 mask, __m128 ifTrue, __m128 ifFalse) {
  return _mm_or_ps(_mm_and_ps(mask, ifTrue), _mm_andnot_ps(mask, ifFalse));
}

// Calls f(std::integral_constant<SpringLayout, L>()) with a vector layout L as a compile-time constant, and
// returns true; false, calling nothing, for SpringLayout::Scalar.
template <class F>
bool withVectorLayout(SpringLayout layout, F&& f) {
  switch (layout) {
    case SpringLayout::Contiguous:
      f(std::integral_constant<SpringLayout, SpringLayout::Contiguous>());
      return true;
    case SpringLayout::PairSwapped:
      f(std::integral_constant<SpringLayout, SpringLayout::PairSwapped>());
      return true;
    case SpringLayout::Interleaved:
      f(std::integral_constant<SpringLayout, SpringLayout::Interleaved>());
      return true;
    case SpringLayout::Pairs:
      f(std::integral_constant<SpringLayout, SpringLayout::Pairs>());
      return true;
    case SpringLayout::Gathered:
      f(std::integral_constant<SpringLayout, SpringLayout::Gathered>());
      return true;
    case SpringLayout::Scalar:
      break;
  }
  return false;
}

// solveSpringsScalar's body in four lanes. A lane whose spring has no direction keeps its old values (a
// select, not a multiplication by zero, so not even the sign of a zero changes).
template <SpringLayout L, bool kLambda, bool kScaled>
void solveBlocks(const SpringSolveArrays& a, std::uint32_t begin, std::uint32_t end, float alphaTilde) {
  using In = Lanes<L>;
  const __m128 alphaBase = _mm_set1_ps(alphaTilde);
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  const __m128 minLen2 = _mm_set1_ps(1e-18f);
  const __m128 maxLen2 = _mm_set1_ps(kMaxLength2);
  for (std::uint32_t s = begin; s < end; s += 4) {
    const std::uint32_t* p = a.first + s;
    const std::uint32_t* q = a.second + s;
    __m128 alpha = alphaBase;
    if constexpr (kScaled) alpha = _mm_mul_ps(alphaBase, _mm_loadu_ps(a.complianceScale + s));
    __m128 xi, xj, yi, yj, zi, zj, wi, wj;
    In::load(a.px, p, q, xi, xj);
    In::load(a.py, p, q, yi, yj);
    In::load(a.pz, p, q, zi, zj);
    In::load(a.inverseMass, p, q, wi, wj);
    const __m128 dx = _mm_sub_ps(xj, xi), dy = _mm_sub_ps(yj, yi), dz = _mm_sub_ps(zj, zi);
    const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 active =  // false for NaN and for an overflowed square too
        _mm_and_ps(_mm_cmpgt_ps(len2, minLen2), _mm_cmple_ps(len2, maxLen2));
    const __m128 wsum = _mm_add_ps(wi, wj);
    const __m128 invDenominator =
        _mm_and_ps(_mm_cmpgt_ps(wsum, zero), _mm_div_ps(one, _mm_add_ps(wsum, alpha)));
    const __m128 len = _mm_sqrt_ps(len2);
    __m128 dl;
    if constexpr (kLambda) {
      const __m128 lambda = _mm_loadu_ps(a.lambda + s);
      dl = _mm_mul_ps(_mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(a.restLength + s), len), _mm_mul_ps(alpha, lambda)),
                      invDenominator);
      _mm_storeu_ps(a.lambda + s, select(active, _mm_add_ps(lambda, dl), lambda));
    } else {
      dl = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(a.restLength + s), len), invDenominator);
    }
    const __m128 k = _mm_div_ps(dl, len);
    const __m128 cx = _mm_mul_ps(k, dx), cy = _mm_mul_ps(k, dy), cz = _mm_mul_ps(k, dz);
    In::store(a.px, p, q, select(active, _mm_sub_ps(xi, _mm_mul_ps(wi, cx)), xi),
              select(active, _mm_add_ps(xj, _mm_mul_ps(wj, cx)), xj));
    In::store(a.py, p, q, select(active, _mm_sub_ps(yi, _mm_mul_ps(wi, cy)), yi),
              select(active, _mm_add_ps(yj, _mm_mul_ps(wj, cy)), yj));
    In::store(a.pz, p, q, select(active, _mm_sub_ps(zi, _mm_mul_ps(wi, cz)), zi),
              select(active, _mm_add_ps(zj, _mm_mul_ps(wj, cz)), zj));
  }
}

#if CAPE_HAVE_AVX2_KERNELS

#define CAPE_AVX2 __attribute__((target("avx2")))

// solveBlocks two blocks at a time: eight lanes, each doing its four-lane kernel's operations in the same
// order (and so the same bits; no fused multiply-add). The two blocks of a run share no particle (a vector
// run lies inside one colour), so loading the second before the first is stored changes nothing. An odd last
// block goes through solveBlocks.
CAPE_AVX2 inline __m256 join(__m128 low, __m128 high) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(low), high, 1);
}

template <SpringLayout L>
CAPE_AVX2 inline void load8(const float* x, const std::uint32_t* i, const std::uint32_t* j, __m256& vi,
                            __m256& vj) {
  __m128 i0, j0, i1, j1;
  Lanes<L>::load(x, i, j, i0, j0);
  Lanes<L>::load(x, i + 4, j + 4, i1, j1);
  vi = join(i0, i1);
  vj = join(j0, j1);
}

template <SpringLayout L>
CAPE_AVX2 inline void store8(float* x, const std::uint32_t* i, const std::uint32_t* j, __m256 vi, __m256 vj) {
  Lanes<L>::store(x, i, j, _mm256_castps256_ps128(vi), _mm256_castps256_ps128(vj));
  Lanes<L>::store(x, i + 4, j + 4, _mm256_extractf128_ps(vi, 1), _mm256_extractf128_ps(vj, 1));
}

CAPE_AVX2 inline __m256 select8(__m256 mask, __m256 ifTrue, __m256 ifFalse) {
  return _mm256_blendv_ps(ifFalse, ifTrue, mask);  // the masks are whole lanes, as select's
}

template <SpringLayout L, bool kLambda, bool kScaled>
CAPE_AVX2 void solveBlocks8(const SpringSolveArrays& a, std::uint32_t begin, std::uint32_t end,
                            float alphaTilde) {
  const __m256 alphaBase = _mm256_set1_ps(alphaTilde);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 minLen2 = _mm256_set1_ps(1e-18f);
  const __m256 maxLen2 = _mm256_set1_ps(kMaxLength2);
  std::uint32_t s = begin;
  for (; s + 8 <= end; s += 8) {
    const std::uint32_t* p = a.first + s;
    const std::uint32_t* q = a.second + s;
    __m256 alpha = alphaBase;
    if constexpr (kScaled) alpha = _mm256_mul_ps(alphaBase, _mm256_loadu_ps(a.complianceScale + s));
    __m256 xi, xj, yi, yj, zi, zj, wi, wj;
    load8<L>(a.px, p, q, xi, xj);
    load8<L>(a.py, p, q, yi, yj);
    load8<L>(a.pz, p, q, zi, zj);
    load8<L>(a.inverseMass, p, q, wi, wj);
    const __m256 dx = _mm256_sub_ps(xj, xi), dy = _mm256_sub_ps(yj, yi), dz = _mm256_sub_ps(zj, zi);
    const __m256 len2 =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    const __m256 active =
        _mm256_and_ps(_mm256_cmp_ps(len2, minLen2, _CMP_GT_OS), _mm256_cmp_ps(len2, maxLen2, _CMP_LE_OS));
    const __m256 wsum = _mm256_add_ps(wi, wj);
    const __m256 invDenominator =
        _mm256_and_ps(_mm256_cmp_ps(wsum, zero, _CMP_GT_OS), _mm256_div_ps(one, _mm256_add_ps(wsum, alpha)));
    const __m256 len = _mm256_sqrt_ps(len2);
    __m256 dl;
    if constexpr (kLambda) {
      const __m256 lambda = _mm256_loadu_ps(a.lambda + s);
      dl = _mm256_mul_ps(
          _mm256_sub_ps(_mm256_sub_ps(_mm256_loadu_ps(a.restLength + s), len), _mm256_mul_ps(alpha, lambda)),
          invDenominator);
      _mm256_storeu_ps(a.lambda + s, select8(active, _mm256_add_ps(lambda, dl), lambda));
    } else {
      dl = _mm256_mul_ps(_mm256_sub_ps(_mm256_loadu_ps(a.restLength + s), len), invDenominator);
    }
    const __m256 k = _mm256_div_ps(dl, len);
    const __m256 cx = _mm256_mul_ps(k, dx), cy = _mm256_mul_ps(k, dy), cz = _mm256_mul_ps(k, dz);
    store8<L>(a.px, p, q, select8(active, _mm256_sub_ps(xi, _mm256_mul_ps(wi, cx)), xi),
              select8(active, _mm256_add_ps(xj, _mm256_mul_ps(wj, cx)), xj));
    store8<L>(a.py, p, q, select8(active, _mm256_sub_ps(yi, _mm256_mul_ps(wi, cy)), yi),
              select8(active, _mm256_add_ps(yj, _mm256_mul_ps(wj, cy)), yj));
    store8<L>(a.pz, p, q, select8(active, _mm256_sub_ps(zi, _mm256_mul_ps(wi, cz)), zi),
              select8(active, _mm256_add_ps(zj, _mm256_mul_ps(wj, cz)), zj));
  }
  if (s < end) solveBlocks<L, kLambda, kScaled>(a, s, end, alphaTilde);
}

template <bool kLambda, bool kScaled>
bool solveRun8(const SpringSolveArrays& a, const SpringRun& run, float alphaTilde) {
  return withVectorLayout(run.layout, [&](auto layout) {
    solveBlocks8<decltype(layout)::value, kLambda, kScaled>(a, run.begin, run.end, alphaTilde);
  });
}

#endif  // CAPE_HAVE_AVX2_KERNELS

template <bool kLambda, bool kScaled>
void solveRun(const SpringSolveArrays& a, const SpringRun& run, float alphaTilde) {
#if CAPE_HAVE_AVX2_KERNELS
  if (useAvx2Kernels() && solveRun8<kLambda, kScaled>(a, run, alphaTilde)) return;
#endif
  const bool vector = withVectorLayout(run.layout, [&](auto layout) {
    solveBlocks<decltype(layout)::value, kLambda, kScaled>(a, run.begin, run.end, alphaTilde);
  });
  if (!vector) scalarSprings<kLambda, kScaled>(a, run.begin, run.end, alphaTilde);
}

}  // namespace

namespace {

// Whether tethers [k, k + count) move the consecutive particles particle[k], particle[k] + 1, ...
bool consecutive(const std::uint32_t* particle, std::size_t k, std::size_t count, std::size_t n) {
  if (k + count > n) return false;
  for (std::size_t i = 1; i < count; ++i)
    if (particle[k + i] != particle[k] + i) return false;
  return true;
}

// solveTethersScalar's body for the four tethers from k, which move consecutive particles.
inline void tetherBlock(float* px, float* py, float* pz, const float* w, const TetherSet& tethers,
                        std::size_t k) {
  const std::uint32_t p = tethers.particle[k];
  const std::uint32_t* anchor = tethers.anchor.data() + k;
  const __m128 zero = _mm_setzero_ps(), tiny = _mm_set1_ps(1e-30f);
  const auto gather = [anchor](const float* x) {
    return _mm_setr_ps(x[anchor[0]], x[anchor[1]], x[anchor[2]], x[anchor[3]]);
  };
  const __m128 xp = _mm_loadu_ps(px + p), yp = _mm_loadu_ps(py + p), zp = _mm_loadu_ps(pz + p);
  const __m128 xa = gather(px), ya = gather(py), za = gather(pz);
  const __m128 dx = _mm_sub_ps(xp, xa), dy = _mm_sub_ps(yp, ya), dz = _mm_sub_ps(zp, za);
  const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
  const __m128 maxLen = _mm_loadu_ps(tethers.maxLength.data() + k);
  const __m128 taut =
      _mm_and_ps(_mm_and_ps(_mm_cmpeq_ps(gather(w), zero), _mm_cmpneq_ps(_mm_loadu_ps(w + p), zero)),
                 _mm_cmpgt_ps(len2, _mm_mul_ps(maxLen, maxLen)));
  // max(tiny, len2) is len2 when len2 is NaN, as std::max(len2, tiny) is.
  const __m128 scale = _mm_div_ps(maxLen, _mm_sqrt_ps(_mm_max_ps(tiny, len2)));
  _mm_storeu_ps(px + p, select(taut, _mm_add_ps(xa, _mm_mul_ps(dx, scale)), xp));
  _mm_storeu_ps(py + p, select(taut, _mm_add_ps(ya, _mm_mul_ps(dy, scale)), yp));
  _mm_storeu_ps(pz + p, select(taut, _mm_add_ps(za, _mm_mul_ps(dz, scale)), zp));
}

#if CAPE_HAVE_AVX2_KERNELS

CAPE_AVX2 inline __m256 gather8(const float* x, const std::uint32_t* index) {
  return _mm256_setr_ps(x[index[0]], x[index[1]], x[index[2]], x[index[3]], x[index[4]], x[index[5]],
                        x[index[6]], x[index[7]]);
}

// tetherBlock for the eight tethers from k (consecutive particles), lane for lane the same operations.
CAPE_AVX2 void tetherBlock8(float* px, float* py, float* pz, const float* w, const TetherSet& tethers,
                            std::size_t k) {
  const std::uint32_t p = tethers.particle[k];
  const std::uint32_t* anchor = tethers.anchor.data() + k;
  const __m256 zero = _mm256_setzero_ps(), tiny = _mm256_set1_ps(1e-30f);
  const __m256 xp = _mm256_loadu_ps(px + p), yp = _mm256_loadu_ps(py + p), zp = _mm256_loadu_ps(pz + p);
  const __m256 xa = gather8(px, anchor), ya = gather8(py, anchor), za = gather8(pz, anchor);
  const __m256 dx = _mm256_sub_ps(xp, xa), dy = _mm256_sub_ps(yp, ya), dz = _mm256_sub_ps(zp, za);
  const __m256 len2 =
      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
  const __m256 maxLen = _mm256_loadu_ps(tethers.maxLength.data() + k);
  const __m256 taut = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(gather8(w, anchor), zero, _CMP_EQ_OQ),
                                                  _mm256_cmp_ps(_mm256_loadu_ps(w + p), zero, _CMP_NEQ_UQ)),
                                    _mm256_cmp_ps(len2, _mm256_mul_ps(maxLen, maxLen), _CMP_GT_OS));
  const __m256 scale = _mm256_div_ps(maxLen, _mm256_sqrt_ps(_mm256_max_ps(tiny, len2)));
  _mm256_storeu_ps(px + p, select8(taut, _mm256_add_ps(xa, _mm256_mul_ps(dx, scale)), xp));
  _mm256_storeu_ps(py + p, select8(taut, _mm256_add_ps(ya, _mm256_mul_ps(dy, scale)), yp));
  _mm256_storeu_ps(pz + p, select8(taut, _mm256_add_ps(za, _mm256_mul_ps(dz, scale)), zp));
}

#endif  // CAPE_HAVE_AVX2_KERNELS

}  // namespace

void solveTethers(float* px, float* py, float* pz, const float* inverseMass, const TetherSet& tethers) {
  const std::uint32_t* particle = tethers.particle.data();
  const std::size_t n = tethers.size();
#if CAPE_HAVE_AVX2_KERNELS
  const bool wide = useAvx2Kernels();
#endif
  std::size_t k = 0;
  while (k < n) {
#if CAPE_HAVE_AVX2_KERNELS
    if (wide && consecutive(particle, k, 8, n)) {
      tetherBlock8(px, py, pz, inverseMass, tethers, k);
      k += 8;
      continue;
    }
#endif
    if (consecutive(particle, k, 4, n)) {
      tetherBlock(px, py, pz, inverseMass, tethers, k);
      k += 4;
      continue;
    }
    solveTethersScalar(px, py, pz, inverseMass, tethers, k, k + 1);
    ++k;
  }
}

namespace {

// The squared lengths of block [s, s + 4) of a run of layout L, as the scalar loops compute them
// (dx dx + dy dy, plus dz dz).
template <SpringLayout L>
__m128 blockSquaredLengths(const float* px, const float* py, const float* pz, const SpringSet& set,
                           std::uint32_t s) {
  using In = Lanes<L>;
  const std::uint32_t* p = set.first.data() + s;
  const std::uint32_t* q = set.second.data() + s;
  __m128 xi, xj, yi, yj, zi, zj;
  In::load(px, p, q, xi, xj);
  In::load(py, p, q, yi, yj);
  In::load(pz, p, q, zi, zj);
  const __m128 dx = _mm_sub_ps(xj, xi), dy = _mm_sub_ps(yj, yi), dz = _mm_sub_ps(zj, zi);
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
}

// maxSquaredStretch over one vector run: four lanes of maxima (maxps(v, worst) keeps worst where v is NaN,
// as std::max(worst, v) does).
template <SpringLayout L>
__m128 stretchBlocks(const float* px, const float* py, const float* pz, const SpringSet& set,
                     const SpringRun& run, __m128 worst) {
  for (std::uint32_t s = run.begin; s < run.end; s += 4) {
    const __m128 len2 = blockSquaredLengths<L>(px, py, pz, set, s);
    const __m128 rest = _mm_loadu_ps(set.restLength.data() + s);
    worst = _mm_max_ps(_mm_div_ps(len2, _mm_mul_ps(rest, rest)), worst);
  }
  return worst;
}

}  // namespace

float maxSquaredStretch(const float* px, const float* py, const float* pz, const SpringSet& set) {
  __m128 lanes = _mm_setzero_ps();
  float worst = 0.0f;
  for (const SpringRun& run : set.runs) {
    const bool vector = withVectorLayout(run.layout, [&](auto layout) {
      lanes = stretchBlocks<decltype(layout)::value>(px, py, pz, set, run, lanes);
    });
    if (!vector) worst = maxSquaredStretchScalar(px, py, pz, set, run.begin, run.end, worst);
  }
  alignas(16) float l[4];
  _mm_store_ps(l, lanes);
  for (const float v : l) worst = std::max(worst, v);  // lanes hold no NaN: maxps kept the old value
  return worst;
}

namespace {

// limitStretch over one vector run: each block's four lengths against the ceiling as the scalar loop
// computes them (the same operations in the same order, so the same bits), and the scalar loop over the
// block only where a lane is beyond it. The block's springs share no particle, so the blocks in order are
// the springs in order.
template <SpringLayout L>
void limitBlocks(float* px, float* py, float* pz, const float* inverseMass, const SpringSet& set,
                 const SpringRun& run, float stretch) {
  const __m128 factor = _mm_set1_ps(stretch);
  for (std::uint32_t s = run.begin; s < run.end; s += 4) {
    const __m128 len2 = blockSquaredLengths<L>(px, py, pz, set, s);
    const __m128 maxLen = _mm_mul_ps(factor, _mm_loadu_ps(set.restLength.data() + s));
    if (_mm_movemask_ps(_mm_cmpgt_ps(len2, _mm_mul_ps(maxLen, maxLen))) != 0)
      limitStretchScalar(px, py, pz, inverseMass, set, s, s + 4, stretch);
  }
}

}  // namespace

void limitStretch(float* px, float* py, float* pz, const float* inverseMass, const SpringSet& set,
                  float stretch) {
  for (const SpringRun& run : set.runs) {
    const bool vector = withVectorLayout(run.layout, [&](auto layout) {
      limitBlocks<decltype(layout)::value>(px, py, pz, inverseMass, set, run, stretch);
    });
    if (!vector) limitStretchScalar(px, py, pz, inverseMass, set, run.begin, run.end, stretch);
  }
}

void solveSpringRun(const SpringSolveArrays& a, const SpringRun& run, float alphaTilde) {
  if (a.complianceScale != nullptr) {
    if (a.lambda != nullptr)
      solveRun<true, true>(a, run, alphaTilde);
    else
      solveRun<false, true>(a, run, alphaTilde);
  } else if (a.lambda != nullptr) {
    solveRun<true, false>(a, run, alphaTilde);
  } else {
    solveRun<false, false>(a, run, alphaTilde);
  }
}

#else

void solveTethers(float* px, float* py, float* pz, const float* inverseMass, const TetherSet& tethers) {
  solveTethersScalar(px, py, pz, inverseMass, tethers, 0, tethers.size());
}

float maxSquaredStretch(const float* px, const float* py, const float* pz, const SpringSet& set) {
  return maxSquaredStretchScalar(px, py, pz, set, 0, set.size());
}

void limitStretch(float* px, float* py, float* pz, const float* inverseMass, const SpringSet& set,
                  float stretch) {
  limitStretchScalar(px, py, pz, inverseMass, set, 0, set.size(), stretch);
}

void solveSpringRun(const SpringSolveArrays& a, const SpringRun& run, float alphaTilde) {
  solveSpringsScalar(a, run.begin, run.end, alphaTilde);
}

#endif

namespace {

// The hinge's curvature vector d, its length and C = |d| - restBend.
struct HingeGeometry {
  float dx, dy, dz, length, c;
};

inline HingeGeometry hingeGeometry(const float* px, const float* py, const float* pz, const HingeSet& h,
                                   std::size_t k) {
  const std::uint32_t i = h.first[k], j = h.middle[k], l = h.second[k];
  const float a = h.firstWeight[k], b = h.secondWeight[k];
  HingeGeometry g;
  g.dx = a * (px[i] - px[j]) + b * (px[l] - px[j]);
  g.dy = a * (py[i] - py[j]) + b * (py[l] - py[j]);
  g.dz = a * (pz[i] - pz[j]) + b * (pz[l] - pz[j]);
  g.length = std::sqrt(g.dx * g.dx + g.dy * g.dy + g.dz * g.dz);
  g.c = g.length - h.restBend[k];
  return g;
}

}  // namespace

void solveHingesScalar(float* px, float* py, float* pz, const float* inverseMass, const HingeSet& hinges,
                       float bendingRigidity, float invH2, float* lambda, const float* stiffnessScale,
                       std::size_t begin, std::size_t end) {
  for (std::size_t k = begin; k < end; ++k) {
    const HingeGeometry g = hingeGeometry(px, py, pz, hinges, k);
    if (!(g.length > 1e-12f) || !std::isfinite(g.length)) continue;
    const std::uint32_t i = hinges.first[k], j = hinges.middle[k], l = hinges.second[k];
    const float a = hinges.firstWeight[k], b = hinges.secondWeight[k], ab = a + b;
    const float wi = inverseMass[i], wj = inverseMass[j], wl = inverseMass[l];
    // A clamp (the middle and one arm pinned): the pinned half of the hinge's area lies on the support, held
    // straight, so the hinge bends over its free half only: twice the stiffness.
    const float clamp = wj == 0.0f && ((wi == 0.0f) != (wl == 0.0f)) ? 2.0f : 1.0f;
    const float scale = stiffnessScale != nullptr ? stiffnessScale[k] : 1.0f;
    const float alphaTilde = invH2 / (clamp * scale * bendingRigidity * hinges.areaOverLength2[k]);
    const float denominator = wi * a * a + wl * b * b + wj * ab * ab + alphaTilde;
    if (!(denominator > 0.0f)) continue;
    const float previous = lambda != nullptr ? lambda[k] : 0.0f;
    const float dLambda = (-g.c - alphaTilde * previous) / denominator;
    if (lambda != nullptr) lambda[k] = previous + dLambda;
    const float s = dLambda / g.length;  // along n = d / |d|
    const float nx = g.dx * s, ny = g.dy * s, nz = g.dz * s;
    px[i] += wi * a * nx;
    py[i] += wi * a * ny;
    pz[i] += wi * a * nz;
    px[l] += wl * b * nx;
    py[l] += wl * b * ny;
    pz[l] += wl * b * nz;
    px[j] -= wj * ab * nx;
    py[j] -= wj * ab * ny;
    pz[j] -= wj * ab * nz;
  }
}

#if defined(__SSE2__)

namespace {

// solveHingesScalar's body for hinges [k, k + 4) of one level (they share no particle), lane for lane the
// same operations in the same order; a lane the scalar loop would skip keeps its particles' values (selects).
inline void hingeBlock(float* px, float* py, float* pz, const float* w, const HingeSet& h,
                       __m128 bendingRigidity, __m128 invH2, float* lambda, const float* stiffnessScale,
                       std::size_t k) {
  const std::uint32_t* i = h.first.data() + k;
  const std::uint32_t* j = h.middle.data() + k;
  const std::uint32_t* l = h.second.data() + k;
  const auto gather = [](const float* x, const std::uint32_t* index) {
    return _mm_setr_ps(x[index[0]], x[index[1]], x[index[2]], x[index[3]]);
  };
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f), two = _mm_set1_ps(2.0f);
  const __m128 xi = gather(px, i), xj = gather(px, j), xl = gather(px, l);
  const __m128 yi = gather(py, i), yj = gather(py, j), yl = gather(py, l);
  const __m128 zi = gather(pz, i), zj = gather(pz, j), zl = gather(pz, l);
  const __m128 a = _mm_loadu_ps(h.firstWeight.data() + k), b = _mm_loadu_ps(h.secondWeight.data() + k);
  const __m128 ab = _mm_add_ps(a, b);
  const __m128 dx = _mm_add_ps(_mm_mul_ps(a, _mm_sub_ps(xi, xj)), _mm_mul_ps(b, _mm_sub_ps(xl, xj)));
  const __m128 dy = _mm_add_ps(_mm_mul_ps(a, _mm_sub_ps(yi, yj)), _mm_mul_ps(b, _mm_sub_ps(yl, yj)));
  const __m128 dz = _mm_add_ps(_mm_mul_ps(a, _mm_sub_ps(zi, zj)), _mm_mul_ps(b, _mm_sub_ps(zl, zj)));
  const __m128 length =
      _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz)));
  const __m128 c = _mm_sub_ps(length, _mm_loadu_ps(h.restBend.data() + k));
  const __m128 wi = gather(w, i), wj = gather(w, j), wl = gather(w, l);
  const __m128 clamped =
      _mm_and_ps(_mm_cmpeq_ps(wj, zero), _mm_xor_ps(_mm_cmpeq_ps(wi, zero), _mm_cmpeq_ps(wl, zero)));
  const __m128 clamp = select(clamped, two, one);
  const __m128 scale = stiffnessScale != nullptr ? _mm_loadu_ps(stiffnessScale + k) : one;
  const __m128 alphaTilde =
      _mm_div_ps(invH2, _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(clamp, scale), bendingRigidity),
                                   _mm_loadu_ps(h.areaOverLength2.data() + k)));
  const __m128 denominator =
      _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_mul_ps(wi, a), a), _mm_mul_ps(_mm_mul_ps(wl, b), b)),
                            _mm_mul_ps(_mm_mul_ps(wj, ab), ab)),
                 alphaTilde);
  // Solved where 1e-12 < |d| <= FLT_MAX (false for NaN) and the denominator is positive (false for NaN).
  const __m128 active =
      _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(length, _mm_set1_ps(1e-12f)),
                            _mm_cmple_ps(length, _mm_set1_ps(std::numeric_limits<float>::max()))),
                 _mm_cmpgt_ps(denominator, zero));
  const __m128 previous = lambda != nullptr ? _mm_loadu_ps(lambda + k) : zero;
  const __m128 dLambda = _mm_div_ps(
      _mm_sub_ps(_mm_xor_ps(c, _mm_set1_ps(-0.0f)), _mm_mul_ps(alphaTilde, previous)), denominator);
  if (lambda != nullptr) _mm_storeu_ps(lambda + k, select(active, _mm_add_ps(previous, dLambda), previous));
  const __m128 s = _mm_div_ps(dLambda, length);
  const __m128 nx = _mm_mul_ps(dx, s), ny = _mm_mul_ps(dy, s), nz = _mm_mul_ps(dz, s);
  const __m128 wia = _mm_mul_ps(wi, a), wlb = _mm_mul_ps(wl, b), wjab = _mm_mul_ps(wj, ab);
  alignas(16) float out[9][4];
  _mm_store_ps(out[0], select(active, _mm_add_ps(xi, _mm_mul_ps(wia, nx)), xi));
  _mm_store_ps(out[1], select(active, _mm_add_ps(yi, _mm_mul_ps(wia, ny)), yi));
  _mm_store_ps(out[2], select(active, _mm_add_ps(zi, _mm_mul_ps(wia, nz)), zi));
  _mm_store_ps(out[3], select(active, _mm_add_ps(xl, _mm_mul_ps(wlb, nx)), xl));
  _mm_store_ps(out[4], select(active, _mm_add_ps(yl, _mm_mul_ps(wlb, ny)), yl));
  _mm_store_ps(out[5], select(active, _mm_add_ps(zl, _mm_mul_ps(wlb, nz)), zl));
  _mm_store_ps(out[6], select(active, _mm_sub_ps(xj, _mm_mul_ps(wjab, nx)), xj));
  _mm_store_ps(out[7], select(active, _mm_sub_ps(yj, _mm_mul_ps(wjab, ny)), yj));
  _mm_store_ps(out[8], select(active, _mm_sub_ps(zj, _mm_mul_ps(wjab, nz)), zj));
  for (int q = 0; q < 4; ++q) {
    px[i[q]] = out[0][q];
    py[i[q]] = out[1][q];
    pz[i[q]] = out[2][q];
    px[l[q]] = out[3][q];
    py[l[q]] = out[4][q];
    pz[l[q]] = out[5][q];
    px[j[q]] = out[6][q];
    py[j[q]] = out[7][q];
    pz[j[q]] = out[8][q];
  }
}

}  // namespace

void solveHinges(float* px, float* py, float* pz, const float* inverseMass, const HingeSet& hinges,
                 float bendingRigidity, float invH2, float* lambda, const float* stiffnessScale) {
  const __m128 rigidity = _mm_set1_ps(bendingRigidity), inverseH2 = _mm_set1_ps(invH2);
  for (std::size_t c = 0; c + 1 < hinges.levelStart.size(); ++c) {
    std::size_t k = hinges.levelStart[c];
    const std::size_t end = hinges.levelStart[c + 1];
    for (; k + 4 <= end; k += 4)
      hingeBlock(px, py, pz, inverseMass, hinges, rigidity, inverseH2, lambda, stiffnessScale, k);
    solveHingesScalar(px, py, pz, inverseMass, hinges, bendingRigidity, invH2, lambda, stiffnessScale, k,
                      end);
  }
}

#else

void solveHinges(float* px, float* py, float* pz, const float* inverseMass, const HingeSet& hinges,
                 float bendingRigidity, float invH2, float* lambda, const float* stiffnessScale) {
  solveHingesScalar(px, py, pz, inverseMass, hinges, bendingRigidity, invH2, lambda, stiffnessScale, 0,
                    hinges.size());
}

#endif

void addHingeForces(const float* px, const float* py, const float* pz, const float* inverseMass,
                    const HingeSet& hinges, float bendingRigidity, float* ax, float* ay, float* az,
                    const float* stiffnessScale) {
  for (std::size_t k = 0; k < hinges.size(); ++k) {
    const HingeGeometry g = hingeGeometry(px, py, pz, hinges, k);
    if (!(g.length > 1e-12f) || !std::isfinite(g.length)) continue;
    const std::uint32_t i = hinges.first[k], j = hinges.middle[k], l = hinges.second[k];
    const float a = hinges.firstWeight[k], b = hinges.secondWeight[k], ab = a + b;
    const float scale = stiffnessScale != nullptr ? stiffnessScale[k] : 1.0f;
    const float s = -scale * bendingRigidity * hinges.areaOverLength2[k] * g.c / g.length;  // -k C along n
    const float fx = g.dx * s, fy = g.dy * s, fz = g.dz * s;
    ax[i] += inverseMass[i] * a * fx;
    ay[i] += inverseMass[i] * a * fy;
    az[i] += inverseMass[i] * a * fz;
    ax[l] += inverseMass[l] * b * fx;
    ay[l] += inverseMass[l] * b * fy;
    az[l] += inverseMass[l] * b * fz;
    ax[j] -= inverseMass[j] * ab * fx;
    ay[j] -= inverseMass[j] * ab * fy;
    az[j] -= inverseMass[j] * ab * fz;
  }
}

double hingeEnergy(const Points& positions, const HingeSet& hinges, float bendingRigidity,
                   const float* stiffnessScale) {
  double e = 0.0;
  const float *px = positions.col(0).data(), *py = positions.col(1).data(), *pz = positions.col(2).data();
  for (std::size_t k = 0; k < hinges.size(); ++k) {
    const HingeGeometry g = hingeGeometry(px, py, pz, hinges, k);
    const double scale = stiffnessScale != nullptr ? stiffnessScale[k] : 1.0;
    e += 0.5 * scale * static_cast<double>(bendingRigidity) * hinges.areaOverLength2[k] * g.c * g.c;
  }
  return e;
}

}  // namespace cape::detail
