// Cape's coarse level of detail (Cape::setCoarseLevel): a cape of Fabric::coarseLevel() steps in the fine
// cape's place, and the fine particles follow it by bilinear interpolation over the grid.
#include "cape/core/Cape.h"

#include "CapeScratch.h"
#include "CoarseLevel.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace cape {

namespace {

using detail::GridTap;

// Where each of `count` grid lines falls on a grid of `other` lines over the same span.
std::vector<GridTap> taps(int count, int other) {
  std::vector<GridTap> t(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    const double x = static_cast<double>(i) * (other - 1) / (count - 1);
    const int first = std::min(static_cast<int>(std::floor(x)), other - 2);
    t[static_cast<std::size_t>(i)] = {first, static_cast<float>(x - first)};
  }
  return t;
}

// to(r, c) = the bilinear interpolation of `from` (a grid of fromColumns columns) at rows[r], columns[c],
// for each of the three coordinates; `to` has rows.size() * columns.size() rows. In two passes: every row of
// `from` along the columns into `along` (fromRows x columns.size(), sized by the caller), then between
// those rows, a plain blend of two contiguous rows.
void interpolate(const Points& from, int fromColumns, const std::vector<GridTap>& rows,
                 const std::vector<GridTap>& columns, Eigen::VectorXf& along, Points& to) {
  const std::size_t toColumns = columns.size();
  const std::size_t fromRows = static_cast<std::size_t>(from.rows()) / static_cast<std::size_t>(fromColumns);
  for (int k = 0; k < 3; ++k) {
    const float* v = from.col(k).data();
    float* a = along.data();
    for (std::size_t r = 0; r < fromRows; ++r, v += fromColumns, a += toColumns)
      for (std::size_t c = 0; c < toColumns; ++c) {
        const int i = columns[c].first;
        const float w = columns[c].weight;
        a[c] = (1.0f - w) * v[i] + w * v[i + 1];
      }
    float* out = to.col(k).data();
    for (std::size_t r = 0; r < rows.size(); ++r, out += toColumns) {
      const float w = rows[r].weight, u = 1.0f - w;
      const float* top = along.data() + static_cast<std::size_t>(rows[r].first) * toColumns;
      const float* bottom = top + toColumns;
      for (std::size_t c = 0; c < toColumns; ++c) out[c] = u * top[c] + w * bottom[c];
    }
  }
}

}  // namespace

Cape::CoarseLevel::CoarseLevel(FabricPtr coarseFabric, const Cape& fine)
    : cape(std::move(coarseFabric), fine.settings(), fine.referencePose()) {
  if (!cape.ok()) return;
  const int fr = fine.fabric().gridRows(), fc = fine.fabric().gridColumns();
  const int cr = cape.fabric().gridRows(), cc = cape.fabric().gridColumns();
  fineRows = taps(fr, cr);
  fineColumns = taps(fc, cc);
  coarseRows = taps(cr, fr);
  coarseColumns = taps(cc, fc);
  finePinOf.assign(fine.fabric().particleCount(), -1);
  nodePin.assign(cape.fabric().particleCount(), -1);
  nodeShare.assign(cape.fabric().particleCount(), 0.0f);
  offset = Points::Zero(static_cast<Eigen::Index>(fine.fabric().particleCount()), 3);
  // The larger of the two passes' buffers: fine rows x coarse columns, coarse rows x fine columns.
  along.resize(std::max(fr * cc, cr * fc));
  cape.setSubstepOverride(fine.substepOverride());
}

Status Cape::setCoarseLevel(bool on) {
  if (!ok()) return status_;
  if (on && !coarse_) {
    FabricPtr coarse = fabric_->coarseLevel();
    if (!coarse)
      return Status::error(
          "Cape::setCoarseLevel: the fabric has no coarse level (a grid fabric of at least 3 x 3 particles "
          "has one; a mesh fabric has none)");
    auto level = std::make_unique<CoarseLevel>(std::move(coarse), *this);
    if (!level->cape.ok()) return level->cape.status();
    coarse_ = std::move(level);
  }
  if (on && !coarseOn_) coarse_->stale = true;
  coarseOn_ = on;
  return Status::success();
}

bool Cape::coarseUsable() const {
  return coarse_ && massScale_.size() == 0 && stiffnessScale_.size() == 0 && !motionActive_ && !userAnimated_;
}

void Cape::markCoarseStale() {
  if (coarse_) coarse_->stale = true;
}

void Cape::leaveCoarse() {
  // The fine cape steps on from the interpolated state it shows; its own self-contacts are stale.
  steppedCoarse_ = false;
  asleep_ = false;
  stillTime_ = 0.0f;
  work_->self.forget();
  work_->startPositions = state_.positions;
  if (coarse_) coarse_->stale = true;
}

void Cape::restrictToCoarse() {
  CoarseLevel& level = *coarse_;
  Cape& c = level.cape;
  level.stale = false;
  level.pinsStale = true;
  c.origin_ = origin_;
  c.reference_ = reference_;  // the two rest shapes are one rectangle: one pose places both
  c.state_.time = state_.time;
  const int fineColumns = fabric_->gridColumns();
  interpolate(state_.positions, fineColumns, level.coarseRows, level.coarseColumns, level.along,
              c.state_.positions);
  interpolate(state_.velocities, fineColumns, level.coarseRows, level.coarseColumns, level.along,
              c.state_.velocities);
  c.work_->startPositions = c.state_.positions;
  c.work_->self.forget();
  c.wake();
  // What the coarse grid does not hold fades out over kCoarseBlendTime instead of vanishing at once.
  interpolate(c.state_.positions, c.fabric_->gridColumns(), level.fineRows, level.fineColumns, level.along,
              level.offset);
  level.offset = state_.positions - level.offset;
  level.blend = 1.0f;
  // A particle lost before the switch (not finite, or farther from the coarse cape than the fabric is
  // wide: no fold of it) is no detail to keep: it takes the coarse cape's place at once, and the numerical
  // guard's report counts it (the coarse cape's guard restores what was sampled from it).
  const float limit2 = fabric_->restDiameter() * fabric_->restDiameter();
  for (Eigen::Index i = 0; i < level.offset.rows(); ++i) {
    if (level.offset.row(i).squaredNorm() <= limit2) continue;  // false for NaN
    level.offset.row(i).setZero();
    ++level.restored;
  }
}

void Cape::rebuildCoarsePins() {
  CoarseLevel& level = *coarse_;
  Cape& c = level.cape;
  level.pinsStale = false;
  c.state_.pins.clear();
  c.state_.inverseMasses = c.fabric_->masses().cwiseInverse();
  level.pinSources.clear();
  std::fill(level.finePinOf.begin(), level.finePinOf.end(), -1);
  std::fill(level.nodePin.begin(), level.nodePin.end(), -1);
  std::fill(level.nodeShare.begin(), level.nodeShare.end(), 0.0f);
  for (std::size_t k = 0; k < state_.pins.size(); ++k)
    level.finePinOf[state_.pins[k].particle] = static_cast<std::int32_t>(k);
  const int fineColumns = fabric_->gridColumns(), fineRows = fabric_->gridRows();
  const int columns = c.fabric_->gridColumns(), rows = c.fabric_->gridRows();
  const auto addPin = [&](std::uint32_t node) {
    level.nodePin[node] = static_cast<std::int32_t>(c.state_.pins.size());
    c.state_.pins.push_back({node, Vec3::Zero(), Vec3::Zero()});
    c.state_.inverseMasses[node] = 0.0f;
  };
  // A coarse particle whose every fine neighbour (of non-zero weight) is pinned: pinned where they are.
  for (int r = 0; r < rows; ++r) {
    for (int col = 0; col < columns; ++col) {
      const GridTap tr = level.coarseRows[static_cast<std::size_t>(r)];
      const GridTap tc = level.coarseColumns[static_cast<std::size_t>(col)];
      const std::pair<int, float> rowTaps[2] = {{tr.first, 1.0f - tr.weight}, {tr.first + 1, tr.weight}};
      const std::pair<int, float> columnTaps[2] = {{tc.first, 1.0f - tc.weight}, {tc.first + 1, tc.weight}};
      bool all = true;
      for (const auto& [fr, wr] : rowTaps)
        for (const auto& [fc, wc] : columnTaps)
          if (wr * wc > 0.0f && level.finePinOf[static_cast<std::size_t>(fr * fineColumns + fc)] < 0)
            all = false;
      if (!all) continue;
      const auto node = static_cast<std::uint32_t>(r * columns + col);
      addPin(node);
      for (const auto& [fr, wr] : rowTaps)
        for (const auto& [fc, wc] : columnTaps)
          if (wr * wc > 0.0f)
            level.pinSources.push_back(
                {static_cast<std::uint32_t>(level.nodePin[node]),
                 static_cast<std::uint32_t>(level.finePinOf[static_cast<std::size_t>(fr * fineColumns + fc)]),
                 wr * wc});
    }
  }
  // Every other fine pin holds the coarse particle nearest it (the mean of their targets where several do).
  const std::size_t firstNearest = level.pinSources.size();
  for (std::size_t k = 0; k < state_.pins.size(); ++k) {
    const int p = static_cast<int>(state_.pins[k].particle);
    const auto nearest = [](int i, int fine, int coarse) {
      return static_cast<int>(std::lround(static_cast<double>(i) * (coarse - 1) / (fine - 1)));
    };
    const auto node = static_cast<std::uint32_t>(nearest(p / fineColumns, fineRows, rows) * columns +
                                                 nearest(p % fineColumns, fineColumns, columns));
    if (level.nodePin[node] >= 0 && level.nodeShare[node] == 0.0f) continue;  // pinned by its neighbours
    if (level.nodePin[node] < 0) addPin(node);
    level.nodeShare[node] += 1.0f;
    level.pinSources.push_back(
        {static_cast<std::uint32_t>(level.nodePin[node]), static_cast<std::uint32_t>(k), 1.0f});
  }
  for (std::size_t s = firstNearest; s < level.pinSources.size(); ++s) {
    CoarseLevel::PinSource& source = level.pinSources[s];
    source.weight = 1.0f / level.nodeShare[c.state_.pins[source.coarsePin].particle];
  }
  c.markPinnedComponents();
  c.wake();
}

void Cape::stepCoarse(float dt, ColliderSpan colliders) {
  CoarseLevel& level = *coarse_;
  Cape& c = level.cape;
  if (!steppedCoarse_ || level.stale) restrictToCoarse();
  if (level.pinsStale) rebuildCoarsePins();
  // The coarse pins sweep as the fine pins they stand for.
  for (Pin& p : c.state_.pins) p.previousTarget = p.target = Vec3::Zero();
  for (const CoarseLevel::PinSource& s : level.pinSources) {
    const Pin& from = state_.pins[s.finePin];
    Pin& to = c.state_.pins[s.coarsePin];
    to.previousTarget += s.weight * from.previousTarget;
    to.target += s.weight * from.target;
  }
  c.setGravity(settings_.gravity);
  const std::uint64_t slept = c.sleptSteps_;
  c.step(dt, colliders);
  const bool moved = c.sleptSteps_ == slept;
  steppedCoarse_ = true;
  level.blend = std::max(0.0f, level.blend - dt / kCoarseBlendTime);
  if (moved || level.blend > 0.0f) {
    interpolate(c.state_.positions, c.fabric_->gridColumns(), level.fineRows, level.fineColumns, level.along,
                state_.positions);
    interpolate(c.state_.velocities, c.fabric_->gridColumns(), level.fineRows, level.fineColumns, level.along,
                state_.velocities);
    if (level.blend > 0.0f) state_.positions += level.blend * level.offset;
  }
  for (Pin& p : state_.pins) {
    state_.positions.row(p.particle) = p.target.transpose();
    state_.velocities.row(p.particle) = ((p.target - p.previousTarget) / dt).transpose();
    p.previousTarget = p.target;
  }
  state_.time += static_cast<double>(dt);
  asleep_ = c.asleep_;
  if (!moved) ++sleptSteps_;
  guard_.lastStep = c.guard_.lastStep + level.restored;
  level.restored = 0;
  if (guard_.lastStep > 0) {
    guard_.total += guard_.lastStep;
    ++guard_.steps;
  }
  lastMaxStrain_ = c.lastMaxStrain_;
  reference_ = c.reference_;
}

}  // namespace cape
