// The measurement behind the choice of integrator (README, "Choosing the integrator"): XPBD with small
// substeps and tethers (the core's default) against the implicit mass-spring of Liu, Bargteil, O'Brien and
// Kavan 2013, "Fast Simulation of Mass-Spring Systems" (local/global iterations with a prefactored sparse
// Cholesky factorisation), implemented here only for this comparison.
//
// Scene: the canonical 20 x 20 cape pinned by its top corners to the walking character's shoulders (the pins
// bob and move at 1.4 m/s), no colliders, 1/60 s frames, same stiffness, mass and damping. Reported per
// configuration: time per frame and the strain of docs/SCENES.md (median and p95 over frames of the per-frame
// maximum structural strain).
#include "cape/scenes/Metrics.h"
#include "cape/scenes/Scene.h"

#include <benchmark/benchmark.h>
#include <Eigen/SparseCholesky>

#include <vector>

namespace {

using namespace cape;

constexpr float kFrame = 1.0f / 60.0f;
constexpr int kFrames = 600;

std::vector<Vec3> pinTargets(const CapeRig& rig, const MotionDesc& motion, double t) {
  const Pose frame = motionAt(motion, t).frame();
  std::vector<Vec3> out;
  for (const Vec3& p : rig.pinLocalPoints) out.push_back(frame.apply(p));
  return out;
}

/// Liu et al. 2013 for one cape: minimise 1/(2h^2) |x - y|_M^2 + sum_s k/2 |x_i - x_j - d_s|^2 by alternating
/// the local step (d_s = L0 (x_i - x_j) / |x_i - x_j|) and the global step ((M + h^2 L) x = M y + h^2 J d),
/// with the pinned particles eliminated (known values moved to the right-hand side).
class LiuMassSpring {
 public:
  LiuMassSpring(const Fabric& fabric, const CapeSettings& s, const Points& start,
                const std::vector<std::uint32_t>& pinned)
      : fabric_(fabric), settings_(s), x_(start.cast<double>()), v_(Eigen::MatrixX3d::Zero(start.rows(), 3)) {
    const Eigen::Index n = start.rows();
    isPinned_.assign(static_cast<std::size_t>(n), false);
    for (std::uint32_t p : pinned) isPinned_[p] = true;
    freeIndex_.assign(static_cast<std::size_t>(n), -1);
    for (Eigen::Index i = 0; i < n; ++i)
      if (!isPinned_[static_cast<std::size_t>(i)]) freeIndex_[static_cast<std::size_t>(i)] = nFree_++;
    for (int f = 0; f < kSpringFamilyCount; ++f) {
      const double k = f == 0 ? s.structuralStiffness : f == 1 ? s.shearStiffness : s.bendStiffness;
      if (k <= 0.0) continue;
      const SpringSet& set = fabric.springs(static_cast<SpringFamily>(f));
      for (std::size_t q = 0; q < set.size(); ++q)
        springs_.push_back({set.first[q], set.second[q], set.restLength[q], k});
    }
    const double h = kFrame;
    std::vector<Eigen::Triplet<double>> t;
    for (Eigen::Index i = 0; i < n; ++i)
      if (freeIndex_[static_cast<std::size_t>(i)] >= 0)
        t.emplace_back(freeIndex_[static_cast<std::size_t>(i)], freeIndex_[static_cast<std::size_t>(i)],
                       fabric.masses()[i]);
    for (const Spring& sp : springs_) {
      const int a = freeIndex_[sp.i], b = freeIndex_[sp.j];
      const double w = h * h * sp.k;
      if (a >= 0) t.emplace_back(a, a, w);
      if (b >= 0) t.emplace_back(b, b, w);
      if (a >= 0 && b >= 0) {
        t.emplace_back(a, b, -w);
        t.emplace_back(b, a, -w);
      }
    }
    Eigen::SparseMatrix<double> A(nFree_, nFree_);
    A.setFromTriplets(t.begin(), t.end());
    solver_.compute(A);  // prefactored once: the matrix does not change while the pins stay pinned
    rhs_.resize(nFree_, 3);
    xFree_.resize(nFree_, 3);
    d_.resize(static_cast<Eigen::Index>(springs_.size()), 3);
  }

  void setPin(std::uint32_t particle, const Vec3& target) {
    x_.row(particle) = target.cast<double>().transpose();
  }

  void step(int iterations) {
    const double h = kFrame;
    const Eigen::Index n = x_.rows();
    const Eigen::RowVector3d g = settings_.gravity.cast<double>().transpose();
    // y = x + h v + h^2 g (inertial prediction), also the first guess.
    Eigen::MatrixX3d y = x_ + h * v_;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!isPinned_[static_cast<std::size_t>(i)]) y.row(i) += h * h * g;
    const Eigen::MatrixX3d xOld = x_;
    Eigen::MatrixX3d x = y;
    for (Eigen::Index i = 0; i < n; ++i)
      if (isPinned_[static_cast<std::size_t>(i)]) x.row(i) = x_.row(i);
    for (int it = 0; it < iterations; ++it) {
      for (std::size_t q = 0; q < springs_.size(); ++q) {
        const Eigen::RowVector3d e = x.row(springs_[q].i) - x.row(springs_[q].j);
        d_.row(static_cast<Eigen::Index>(q)) = springs_[q].rest * e / std::max(e.norm(), 1e-12);
      }
      for (Eigen::Index i = 0; i < n; ++i) {
        const int a = freeIndex_[static_cast<std::size_t>(i)];
        if (a >= 0) rhs_.row(a) = fabric_.masses()[i] * y.row(i);
      }
      for (std::size_t q = 0; q < springs_.size(); ++q) {
        const Spring& sp = springs_[q];
        const int a = freeIndex_[sp.i], b = freeIndex_[sp.j];
        const double w = h * h * sp.k;
        if (a >= 0) rhs_.row(a) += w * d_.row(static_cast<Eigen::Index>(q));
        if (b >= 0) rhs_.row(b) -= w * d_.row(static_cast<Eigen::Index>(q));
        if (a >= 0 && b < 0) rhs_.row(a) += w * x.row(sp.j);  // known pinned neighbour
        if (b >= 0 && a < 0) rhs_.row(b) += w * x.row(sp.i);
      }
      xFree_ = solver_.solve(rhs_);
      for (Eigen::Index i = 0; i < n; ++i) {
        const int a = freeIndex_[static_cast<std::size_t>(i)];
        if (a >= 0) x.row(i) = xFree_.row(a);
      }
    }
    v_ = (x - xOld) / h / (1.0 + settings_.damping * h);
    x_ = x;
  }

  Points positions() const { return x_.cast<float>(); }

 private:
  struct Spring {
    std::uint32_t i, j;
    double rest, k;
  };
  const Fabric& fabric_;
  CapeSettings settings_;
  Eigen::MatrixX3d x_, v_;
  std::vector<bool> isPinned_;
  std::vector<int> freeIndex_;
  int nFree_ = 0;
  std::vector<Spring> springs_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> solver_;
  Eigen::MatrixX3d rhs_, xFree_, d_;
};

void reportStrain(benchmark::State& state, const MetricsRecorder& rec) {
  const RunSummary r = rec.summary();
  state.counters["strain_median_pct"] = 100.0 * r.medianFrameMaxStrain;
  state.counters["strain_p95_pct"] = 100.0 * r.p95FrameMaxStrain;
}

// XPBD: the core as shipped; range(0) = substeps, range(1) = tethers on/off. Fixed substeps (no strain-
// adaptive refinement), so that each row measures the substep count it names.
void BM_WalkPinsXpbd(benchmark::State& state) {
  CapeSettings s;
  s.strainLimit = 0.0f;
  s.substeps = static_cast<int>(state.range(0));
  s.useTethers = state.range(1) != 0;
  const MotionDesc motion = MotionDesc::forScene(SceneKind::Walk);
  for (auto _ : state) {
    const CapeRig rig = makeCapeRig(20, PinLayout::Corners);
    Cape cape(rig.fabric, s, capeStartPlacement(SceneKind::Walk));
    std::vector<Vec3> targets = pinTargets(rig, motion, 0.0);
    for (std::size_t k = 0; k < targets.size(); ++k) cape.pin(rig.pinnedParticles[k], targets[k]);
    MetricsRecorder rec;
    for (int f = 1; f <= kFrames; ++f) {
      targets = pinTargets(rig, motion, f * kFrame);
      for (std::size_t k = 0; k < targets.size(); ++k) cape.movePin(k, targets[k]);
      cape.step(kFrame, ColliderSpan());
      state.PauseTiming();
      rec.add(measureFrame(cape, ColliderSpan(), cape.state().positions.row(0).transpose(), nullptr));
      state.ResumeTiming();
    }
    state.PauseTiming();
    reportStrain(state, rec);
    state.ResumeTiming();
  }
  state.counters["us_per_frame"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kFrames,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// Liu et al.: range(0) = local/global iterations per 1/60 s frame.
void BM_WalkPinsLiu(benchmark::State& state) {
  const CapeSettings s;
  const MotionDesc motion = MotionDesc::forScene(SceneKind::Walk);
  for (auto _ : state) {
    const CapeRig rig = makeCapeRig(20, PinLayout::Corners);
    const Cape placed(rig.fabric, s, capeStartPlacement(SceneKind::Walk));
    LiuMassSpring liu(*rig.fabric, s, placed.state().positions, rig.pinnedParticles);
    Cape probe(rig.fabric, s);  // holds positions and pins for the shared metric code
    MetricsRecorder rec;
    for (int f = 1; f <= kFrames; ++f) {
      const std::vector<Vec3> targets = pinTargets(rig, motion, f * kFrame);
      for (std::size_t k = 0; k < targets.size(); ++k) liu.setPin(rig.pinnedParticles[k], targets[k]);
      liu.step(static_cast<int>(state.range(0)));
      state.PauseTiming();
      probe.mutableState().positions = liu.positions();
      rec.add(measureFrame(probe, ColliderSpan(), probe.state().positions.row(0).transpose(), nullptr));
      state.ResumeTiming();
    }
    state.PauseTiming();
    reportStrain(state, rec);
    state.ResumeTiming();
  }
  state.counters["us_per_frame"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kFrames,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_WalkPinsXpbd)
    ->Args({3, 1})
    ->Args({3, 0})
    ->Args({8, 0})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK(BM_WalkPinsLiu)->Arg(5)->Arg(10)->Arg(20)->Arg(40)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_MAIN();
