#include "cape/scenes/Metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

float maxPenetration(const Points& x, ColliderSpan colliders) {
  float worst = 0.0f;
  for (const Collider& c : colliders) {
    if (!c.validate().ok()) continue;
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      worst = std::max(worst, -signedDistance(c, x.row(i).transpose()));
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

}  // namespace

bool trianglesIntersect(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0, const Vec3& q1,
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

int SelfIntersectionCounter::count(const Fabric& fabric, const Points& x) {
  const std::vector<std::uint32_t>& tri = fabric.triangles();
  const std::size_t nt = tri.size() / 3;
  boxes_.resize(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const Vec3 a = x.row(tri[3 * t]), b = x.row(tri[3 * t + 1]), c = x.row(tri[3 * t + 2]);
    boxes_[t] = {a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c), static_cast<std::uint32_t>(t)};
  }
  // Sweep and prune along x.
  std::sort(boxes_.begin(), boxes_.end(), [](const Box& l, const Box& r) {
    return l.lo.x() < r.lo.x() || (l.lo.x() == r.lo.x() && l.triangle < r.triangle);
  });
  int found = 0;
  for (std::size_t i = 0; i < nt; ++i) {
    const Box& bi = boxes_[i];
    const std::uint32_t* ti = &tri[3 * bi.triangle];
    for (std::size_t j = i + 1; j < nt && boxes_[j].lo.x() <= bi.hi.x(); ++j) {
      const Box& bj = boxes_[j];
      if (bj.lo.y() > bi.hi.y() || bj.hi.y() < bi.lo.y() || bj.lo.z() > bi.hi.z() || bj.hi.z() < bi.lo.z())
        continue;
      const std::uint32_t* tj = &tri[3 * bj.triangle];
      bool shares = false;
      for (int a = 0; a < 3 && !shares; ++a)
        for (int b = 0; b < 3; ++b) shares = shares || ti[a] == tj[b];
      if (shares) continue;
      if (trianglesIntersect(x.row(ti[0]), x.row(ti[1]), x.row(ti[2]), x.row(tj[0]), x.row(tj[1]),
                             x.row(tj[2])))
        ++found;
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
  return m;
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
  if (r.frames > 0) r.meanStrain = meanStrainSum_ / static_cast<double>(r.frames);
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
