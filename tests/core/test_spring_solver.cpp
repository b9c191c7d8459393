// The constraint kernels alone (plugin/core/src/SpringSolver.h): the fabric's spring runs are a valid plan
// (every spring once, in order; every block of four inside one colour, its indices following its layout),
// and the vector paths give the scalar loops' bits, springs, tethers and bending hinges (whose levels keep
// the build's order), with pinned, coincident and non-finite particles among them.
#include "SpringSolver.h"

#include "cape/core/Simd.h"

#include "CapeTestFixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <vector>

namespace cape::test {
namespace {

FabricPtr meshFabric() {
  // A 9 x 7 grid's triangles through the mesh builder (its own spring order, no shear family).
  MeshDesc d;
  const int nc = 9, nr = 7;
  for (int r = 0; r < nr; ++r)
    for (int c = 0; c < nc; ++c)
      d.positions.emplace_back(0.1f * static_cast<float>(c), -0.1f * static_cast<float>(r), 0.0f);
  for (int r = 0; r + 1 < nr; ++r) {
    for (int c = 0; c + 1 < nc; ++c) {
      const auto id = [nc](int rr, int cc) { return static_cast<std::uint32_t>(rr * nc + cc); };
      d.triangles.insert(d.triangles.end(), {id(r + 1, c), id(r + 1, c + 1), id(r, c + 1), id(r + 1, c),
                                             id(r, c + 1), id(r, c)});
    }
  }
  d.tetherAnchors = {0, static_cast<std::uint32_t>(nc - 1)};
  FabricResult result = Fabric::fromMesh(d);
  EXPECT_TRUE(result.status.ok()) << result.status.message();
  return result.fabric;
}

std::vector<FabricPtr> fabrics() {
  return {makeGrid(20, 20, 0.6f, 1.0f, 0.4f, true, {0, 19}), makeGrid(7, 5, 0.6f, 1.0f, 0.4f, true, {0, 6}),
          makeGrid(33, 17, 0.6f, 1.0f, 0.4f, false, {0, 32}), meshFabric()};
}

// Every instruction set of the kernels this processor has (Simd.h), each set in turn for `body` and the one
// in use put back after: the vector paths are checked at every level, four lanes and eight.
template <class Body>
void forEachSimdLevel(Body body) {
  const SimdLevel before = simdLevel();
  for (const SimdLevel level : {SimdLevel::Portable, SimdLevel::Avx2}) {
    if (!setSimdLevel(level).ok()) continue;  // no AVX2 on this processor
    SCOPED_TRACE(simdLevelName(level));
    body();
  }
  ASSERT_TRUE(setSimdLevel(before).ok());
}

// The particles of block [s, s + 4) as the layout reads them, in lane order (first ends, then second ends).
bool followsLayout(const SpringSet& set, std::size_t s, SpringLayout layout) {
  const auto f = [&](std::size_t k) { return static_cast<long>(set.first[s + k]); };
  const auto g = [&](std::size_t k) { return static_cast<long>(set.second[s + k]); };
  const long p = f(0), q = g(0);
  const long pairOffset[4] = {0, 1, 4, 5};
  for (std::size_t k = 0; k < 4; ++k) {
    const long kk = static_cast<long>(k);
    switch (layout) {
      case SpringLayout::Contiguous:
        if (f(k) != p + kk || g(k) != q + kk) return false;
        break;
      case SpringLayout::PairSwapped:
        if (f(k) != p + kk || g(k) != q + (k % 2 == 0 ? kk : kk - 2)) return false;
        break;
      case SpringLayout::Interleaved:
        if (f(k) != p + 2 * kk || g(k) != f(k) + 1) return false;
        break;
      case SpringLayout::Pairs:
        if (f(k) != p + pairOffset[k] || g(k) != f(k) + 2) return false;
        break;
      case SpringLayout::Gathered:
        break;
      case SpringLayout::Scalar:
        return false;
    }
  }
  return true;
}

TEST(SpringRuns, CoverEverySpringOnceInOrderWithEveryVectorRunInsideOneColourAndItsLayout) {
  for (const FabricPtr& fabric : fabrics()) {
    ASSERT_TRUE(fabric);
    for (int family = 0; family < kSpringFamilyCount; ++family) {
      const SpringSet& set = fabric->springs(static_cast<SpringFamily>(family));
      std::uint32_t next = 0;
      for (const SpringRun& run : set.runs) {
        ASSERT_EQ(run.begin, next) << "family " << family;
        ASSERT_LT(run.begin, run.end);
        next = run.end;
        if (run.layout == SpringLayout::Scalar) continue;
        ASSERT_EQ((run.end - run.begin) % 4, 0u);
        // A vector run lies inside one colour: the eight-wide kernels solve two of its blocks together.
        const auto colourOf = [&](std::uint32_t spring) {
          return std::upper_bound(set.colourStart.begin(), set.colourStart.end(), spring) -
                 set.colourStart.begin();
        };
        EXPECT_EQ(colourOf(run.begin), colourOf(run.end - 1)) << "run at " << run.begin << " spans colours";
        for (std::uint32_t s = run.begin; s < run.end; s += 4) {
          // Inside one colour, and so four distinct particles at each end and none shared.
          const auto colour =
              std::upper_bound(set.colourStart.begin(), set.colourStart.end(), s) - set.colourStart.begin();
          EXPECT_LE(s + 4, set.colourStart[static_cast<std::size_t>(colour)])
              << "block at " << s << " straddles colours";
          std::set<std::uint32_t> particles;
          for (std::uint32_t k = 0; k < 4; ++k) particles.insert({set.first[s + k], set.second[s + k]});
          EXPECT_EQ(particles.size(), 8u) << "block at " << s;
          EXPECT_TRUE(followsLayout(set, s, run.layout)) << "family " << family << " block at " << s;
        }
      }
      EXPECT_EQ(next, set.size()) << "family " << family;
    }
  }
}

TEST(SpringRuns, MostOfTheSeedGridsSpringsAreReadWithContiguousLoads) {
  // The 20 x 20 cape: rows, columns and diagonals fall into the structured layouts, which load whole
  // neighbourhoods; only what the greedy colouring scatters is gathered: within a colour the springs are
  // ordered into patterned blocks where they can be (81 % of them; 75 % in the colouring's own order).
  const FabricPtr fabric = makeGrid(20, 20);
  std::size_t structured = 0, total = 0;
  for (int family = 0; family < kSpringFamilyCount; ++family) {
    const SpringSet& set = fabric->springs(static_cast<SpringFamily>(family));
    total += set.size();
    for (const SpringRun& run : set.runs)
      if (run.layout != SpringLayout::Scalar && run.layout != SpringLayout::Gathered)
        structured += run.end - run.begin;
  }
  EXPECT_GE(static_cast<double>(structured), 0.8 * static_cast<double>(total))
      << structured << " of " << total;
}

// A cape's worth of state: the rest positions jittered, a few particles pinned, two made to coincide with a
// neighbour (a spring of zero length) and one not finite.
struct KernelState {
  std::vector<float> x, y, z, w, lambda;
};

KernelState jittered(const Fabric& fabric, unsigned seed) {
  KernelState st;
  const std::size_t n = fabric.particleCount();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Index r = static_cast<Eigen::Index>(i);
    st.x.push_back(fabric.restPositions()(r, 0) * 1.05f + jitter(rng));
    st.y.push_back(fabric.restPositions()(r, 1) * 1.05f + jitter(rng));
    st.z.push_back(fabric.restPositions()(r, 2) + jitter(rng));
    st.w.push_back(1.0f / fabric.masses()[r]);
  }
  st.w[0] = 0.0f;
  st.w[n - 1] = 0.0f;
  st.x[5] = st.x[4];
  st.y[5] = st.y[4];
  st.z[5] = st.z[4];
  st.x[n / 2] = std::numeric_limits<float>::quiet_NaN();
  st.lambda.assign(fabric.springCount(), 0.0f);
  return st;
}

void solveAll(const Fabric& fabric, KernelState& st, bool vector, bool keepLambda = true,
              const std::vector<float>* complianceScale = nullptr) {
  std::size_t offset = 0;
  for (int family = 0; family < kSpringFamilyCount; ++family) {
    const SpringSet& set = fabric.springs(static_cast<SpringFamily>(family));
    detail::SpringSolveArrays a;
    a.px = st.x.data();
    a.py = st.y.data();
    a.pz = st.z.data();
    a.inverseMass = st.w.data();
    a.first = set.first.data();
    a.second = set.second.data();
    a.restLength = set.restLength.data();
    a.lambda = keepLambda ? st.lambda.data() + offset : nullptr;
    a.complianceScale = complianceScale != nullptr ? complianceScale->data() + offset : nullptr;
    const float alphaTilde = 0.01f * static_cast<float>(family + 1);
    if (vector) {
      for (const SpringRun& run : set.runs) detail::solveSpringRun(a, run, alphaTilde);
    } else {
      detail::solveSpringsScalar(a, 0, static_cast<std::uint32_t>(set.size()), alphaTilde);
    }
    offset += set.size();
  }
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(SpringSolver, WithoutMultipliersOneIterationGivesTheSameBits) {
  forEachSimdLevel([&] {
    // One iteration per substep starts every multiplier at zero and never reads it again: the kernels without
    // the multiplier array (lambda null) must move the particles exactly as the kernels with a zeroed one.
    for (const FabricPtr& fabric : fabrics()) {
      ASSERT_TRUE(fabric);
      for (const bool vector : {false, true}) {
        KernelState with = jittered(*fabric, 11), without = with;
        for (int substep = 0; substep < 4; ++substep) {
          std::fill(with.lambda.begin(), with.lambda.end(), 0.0f);
          solveAll(*fabric, with, vector, true);
          solveAll(*fabric, without, vector, false);
        }
        EXPECT_TRUE(sameBits(with.x, without.x)) << vector;
        EXPECT_TRUE(sameBits(with.y, without.y)) << vector;
        EXPECT_TRUE(sameBits(with.z, without.z)) << vector;
        EXPECT_TRUE(
            std::all_of(without.lambda.begin(), without.lambda.end(), [](float l) { return l == 0.0f; }));
      }
    }
  });
}

TEST(SpringSolver, VectorRunsGiveTheScalarLoopsBits) {
  forEachSimdLevel([&] {
    for (const FabricPtr& fabric : fabrics()) {
      ASSERT_TRUE(fabric);
      KernelState vector = jittered(*fabric, 7), scalar = vector;
      for (int iteration = 0; iteration < 5; ++iteration) {
        solveAll(*fabric, vector, true);
        solveAll(*fabric, scalar, false);
      }
      EXPECT_TRUE(sameBits(vector.x, scalar.x));
      EXPECT_TRUE(sameBits(vector.y, scalar.y));
      EXPECT_TRUE(sameBits(vector.z, scalar.z));
      EXPECT_TRUE(sameBits(vector.lambda, scalar.lambda));
      // And the springs did work: the jittered cape moved.
      const KernelState start = jittered(*fabric, 7);
      EXPECT_FALSE(sameBits(vector.y, start.y));
    }
  });
}

TEST(SpringSolver, ScaledComplianceGivesTheScalarLoopsBitsAndOneChangesNoBit) {
  forEachSimdLevel([&] {
    // Per-spring compliance scales (Cape::setStiffnessScale): the vector runs still give the scalar loop's
    // bits, with and without multipliers; a scale of exactly 1 everywhere gives the unscaled kernels' bits;
    // and a real scale moves the particles elsewhere.
    for (const FabricPtr& fabric : fabrics()) {
      ASSERT_TRUE(fabric);
      std::vector<float> scale(fabric->springCount()), ones(fabric->springCount(), 1.0f);
      std::mt19937 rng(3);
      std::uniform_real_distribution<float> u(0.05f, 20.0f);
      for (float& v : scale) v = u(rng);
      for (const bool keep : {true, false}) {
        KernelState vector = jittered(*fabric, 5), scalar = vector, unit = vector, plain = vector;
        for (int iteration = 0; iteration < 5; ++iteration) {
          solveAll(*fabric, vector, true, keep, &scale);
          solveAll(*fabric, scalar, false, keep, &scale);
          solveAll(*fabric, unit, true, keep, &ones);
          solveAll(*fabric, plain, true, keep, nullptr);
        }
        EXPECT_TRUE(sameBits(vector.x, scalar.x) && sameBits(vector.y, scalar.y) &&
                    sameBits(vector.z, scalar.z));
        EXPECT_TRUE(sameBits(vector.lambda, scalar.lambda));
        EXPECT_TRUE(sameBits(unit.x, plain.x) && sameBits(unit.y, plain.y) && sameBits(unit.z, plain.z));
        EXPECT_FALSE(sameBits(vector.y, plain.y));
      }
    }
  });
}

TEST(SpringSolver, TheLargestStretchReadRunByRunIsTheScalarLoops) {
  // The strain check of the adaptive substeps (Cape::adaptRefinement) over every family's runs: the same
  // value as one spring after another, with coincident, non-finite and overflowing particles among them.
  for (const FabricPtr& fabric : fabrics()) {
    ASSERT_TRUE(fabric);
    for (const int variant : {0, 1, 2}) {
      KernelState st = jittered(*fabric, 13);
      if (variant == 1) st.y[3] = 3e19f;  // a square that overflows to inf
      if (variant == 2) std::fill(st.x.begin(), st.x.end(), std::numeric_limits<float>::quiet_NaN());
      for (int family = 0; family < kSpringFamilyCount; ++family) {
        const SpringSet& set = fabric->springs(static_cast<SpringFamily>(family));
        const float vector = detail::maxSquaredStretch(st.x.data(), st.y.data(), st.z.data(), set);
        const float scalar =
            detail::maxSquaredStretchScalar(st.x.data(), st.y.data(), st.z.data(), set, 0, set.size());
        EXPECT_EQ(std::memcmp(&vector, &scalar, sizeof(float)), 0)
            << "family " << family << ", variant " << variant << ": " << vector << " against " << scalar;
        if (variant == 0 && set.size() > 0) {
          EXPECT_GT(vector, 1.0f);  // the jittered cape is stretched
        }
        if (variant == 2) {
          EXPECT_EQ(vector, 0.0f);  // every value NaN: passed over
        }
      }
    }
  }
}

TEST(SpringSolver, TheStrainCeilingCheckedRunByRunGivesTheScalarLoopsBits) {
  // Strain limiting (CapeSettings::strainCeiling) over every family's runs, blocks checked four at a time:
  // the same bits as the scalar loop over the whole set, with pinned, coincident and non-finite particles
  // among them, at a ceiling most springs are under (5 % stretched by the jitter's 1.05: a few blocks to
  // correct) and one every spring is over (0: every block).
  for (const FabricPtr& fabric : fabrics()) {
    ASSERT_TRUE(fabric);
    for (const float ceiling : {0.08f, 0.0f}) {
      for (int family = 0; family < kSpringFamilyCount; ++family) {
        const SpringSet& set = fabric->springs(static_cast<SpringFamily>(family));
        KernelState vector = jittered(*fabric, 17), scalar = vector;
        const KernelState start = vector;
        for (int pass = 0; pass < 3; ++pass) {
          detail::limitStretch(vector.x.data(), vector.y.data(), vector.z.data(), vector.w.data(), set,
                               1.0f + ceiling);
          detail::limitStretchScalar(scalar.x.data(), scalar.y.data(), scalar.z.data(), scalar.w.data(), set,
                                     0, set.size(), 1.0f + ceiling);
        }
        EXPECT_TRUE(sameBits(vector.x, scalar.x) && sameBits(vector.y, scalar.y) &&
                    sameBits(vector.z, scalar.z))
            << "family " << family << ", ceiling " << ceiling;
        if (set.size() > 0) {
          EXPECT_FALSE(sameBits(vector.x, start.x) && sameBits(vector.y, start.y)) << "nothing was corrected";
        }
      }
    }
  }
}

TEST(SimdLevels, TheWidestIsTheDefaultAndALevelTheProcessorLacksIsRefused) {
  const SimdLevel before = simdLevel();
  EXPECT_TRUE(setSimdLevel(SimdLevel::Portable).ok());  // every processor runs the portable kernels
  EXPECT_EQ(simdLevel(), SimdLevel::Portable);
  const Status avx2 = setSimdLevel(SimdLevel::Avx2);
  EXPECT_EQ(avx2.ok(), simdAvailable() == SimdLevel::Avx2);
  EXPECT_EQ(simdLevel(), avx2.ok() ? SimdLevel::Avx2 : SimdLevel::Portable);  // a refusal keeps the level
  if (!avx2.ok()) {
    EXPECT_NE(avx2.message().find("AVX2"), std::string::npos) << avx2.message();
  }
  const Status bad = setSimdLevel(static_cast<SimdLevel>(7));
  EXPECT_FALSE(bad.ok());
  EXPECT_FALSE(bad.message().empty());
  EXPECT_STREQ(simdLevelName(SimdLevel::Portable), "portable");
  EXPECT_STREQ(simdLevelName(SimdLevel::Avx2), "avx2");
  ASSERT_TRUE(setSimdLevel(before).ok());
  RecordProperty("available", simdLevelName(simdAvailable()));
}

TEST(Tethers, VectorPathGivesTheScalarLoopsBits) {
  forEachSimdLevel([&] {
    for (const FabricPtr& fabric : fabrics()) {
      ASSERT_TRUE(fabric);
      const TetherSet& tethers = fabric->tethers();
      ASSERT_GT(tethers.size(), 0u);
      KernelState vector = jittered(*fabric, 11);
      // Pin the anchors (one of them left free on the second fabric: its tethers must not act), and stretch
      // the cape downwards so that the lower half is taut.
      for (std::uint32_t a : tethers.anchor) vector.w[a] = 0.0f;
      if (fabric->gridColumns() == 7) vector.w[tethers.anchor.back()] = 1.0f;
      for (float& y : vector.y) y *= 1.3f;
      const KernelState before = vector;
      KernelState scalar = vector;
      detail::solveTethers(vector.x.data(), vector.y.data(), vector.z.data(), vector.w.data(), tethers);
      detail::solveTethersScalar(scalar.x.data(), scalar.y.data(), scalar.z.data(), scalar.w.data(), tethers,
                                 0, tethers.size());
      EXPECT_TRUE(sameBits(vector.x, scalar.x));
      EXPECT_TRUE(sameBits(vector.y, scalar.y));
      EXPECT_TRUE(sameBits(vector.z, scalar.z));
      // The last tether of every particle holds it within its length of a pinned anchor (an earlier one may
      // be loosened again by a later one); the taut ones moved their particles.
      std::vector<std::size_t> last(fabric->particleCount(), tethers.size());
      for (std::size_t k = 0; k < tethers.size(); ++k) last[tethers.particle[k]] = k;
      std::size_t moved = 0;
      for (std::size_t p = 0; p < last.size(); ++p) {
        if (last[p] == tethers.size() || !std::isfinite(vector.x[p])) continue;
        moved += vector.y[p] != before.y[p];
        const std::uint32_t a = tethers.anchor[last[p]];
        if (vector.w[a] != 0.0f || vector.w[p] == 0.0f) continue;
        const float d = std::sqrt((vector.x[p] - vector.x[a]) * (vector.x[p] - vector.x[a]) +
                                  (vector.y[p] - vector.y[a]) * (vector.y[p] - vector.y[a]) +
                                  (vector.z[p] - vector.z[a]) * (vector.z[p] - vector.z[a]));
        EXPECT_LE(d, tethers.maxLength[last[p]] * 1.00001f) << "particle " << p;
      }
      EXPECT_GT(moved, 0u);
    }
  });
}

TEST(Hinges, LevelsShareNoParticleAndKeepTheBuildOrderAtEveryParticle) {
  for (const FabricPtr& fabric : fabrics()) {
    ASSERT_TRUE(fabric);
    const HingeSet& h = fabric->hinges();
    ASSERT_GT(h.size(), 0u);
    ASSERT_GE(h.levelStart.size(), 2u);
    EXPECT_EQ(h.levelStart.front(), 0u);
    EXPECT_EQ(h.levelStart.back(), h.size());
    std::vector<std::size_t> seenInLevel(fabric->particleCount(), h.size());
    for (std::size_t c = 0; c + 1 < h.levelStart.size(); ++c) {
      ASSERT_LT(h.levelStart[c], h.levelStart[c + 1]) << "empty level " << c;
      for (std::size_t k = h.levelStart[c]; k < h.levelStart[c + 1]; ++k) {
        for (const std::uint32_t p : {h.first[k], h.middle[k], h.second[k]}) {
          EXPECT_NE(seenInLevel[p], c) << "particle " << p << " twice in level " << c;
          seenInLevel[p] = c;
        }
      }
    }
    // The build goes particle after particle (the hinges through each middle in turn), so every two hinges
    // that share a particle are in the order of their middles, as the build made them.
    std::vector<std::uint32_t> lastMiddle(fabric->particleCount(), 0);
    for (std::size_t k = 0; k < h.size(); ++k) {
      for (const std::uint32_t p : {h.first[k], h.middle[k], h.second[k]}) {
        EXPECT_LE(lastMiddle[p], h.middle[k]) << "hinge " << k << " at particle " << p;
        lastMiddle[p] = h.middle[k];
      }
    }
  }
  // The seed's 20 x 20 grid: levels wide enough that most hinges go four at a time.
  const FabricPtr grid = makeGrid(20, 20);
  const HingeSet& h = grid->hinges();
  std::size_t inBlocks = 0;
  for (std::size_t c = 0; c + 1 < h.levelStart.size(); ++c)
    inBlocks += (h.levelStart[c + 1] - h.levelStart[c]) / 4 * 4;
  EXPECT_GT(inBlocks, h.size() * 3 / 4) << inBlocks << " of " << h.size();
}

TEST(Hinges, FourAtATimeGiveTheScalarLoopsBits) {
  for (const FabricPtr& fabric : fabrics()) {
    ASSERT_TRUE(fabric);
    const HingeSet& h = fabric->hinges();
    for (const bool keepLambda : {false, true}) {
      for (const bool scaled : {false, true}) {
        SCOPED_TRACE(::testing::Message() << "lambda " << keepLambda << ", scaled " << scaled);
        KernelState vector = jittered(*fabric, 23);
        vector.w[1] = 0.0f;  // with particle 0: a clamp at every hinge with middle 1 and one arm on 0
        std::vector<float> lambda(h.size(), 0.0f), scale(h.size(), 1.0f);
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> u(0.5f, 2.0f);
        for (std::size_t k = 0; k < h.size(); ++k) {
          lambda[k] = keepLambda ? 1e-3f * u(rng) : 0.0f;
          scale[k] = u(rng);
        }
        const KernelState before = vector;
        KernelState scalar = vector;
        std::vector<float> lambdaScalar = lambda;
        const float* s = scaled ? scale.data() : nullptr;
        const float rigidity = 2e-4f, invH2 = 240.0f * 240.0f;
        for (int pass = 0; pass < 3; ++pass) {
          detail::solveHinges(vector.x.data(), vector.y.data(), vector.z.data(), vector.w.data(), h, rigidity,
                              invH2, keepLambda ? lambda.data() : nullptr, s);
          detail::solveHingesScalar(scalar.x.data(), scalar.y.data(), scalar.z.data(), scalar.w.data(), h,
                                    rigidity, invH2, keepLambda ? lambdaScalar.data() : nullptr, s, 0,
                                    h.size());
        }
        EXPECT_TRUE(sameBits(vector.x, scalar.x));
        EXPECT_TRUE(sameBits(vector.y, scalar.y));
        EXPECT_TRUE(sameBits(vector.z, scalar.z));
        EXPECT_TRUE(sameBits(lambda, lambdaScalar));
        EXPECT_FALSE(sameBits(vector.z, before.z));  // the hinges did bend the jittered cloth back
        EXPECT_EQ(vector.x[0], before.x[0]);         // pinned particles stay
        EXPECT_EQ(vector.x[1], before.x[1]);
      }
    }
  }
}

}  // namespace
}  // namespace cape::test
