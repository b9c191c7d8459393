/// \file
/// The quality metrics of docs/SCENES.md as library code, so that tests, demos, benchmarks and
/// comparisons measure exactly the same thing.
#pragma once

#include "cape/core/Cape.h"
#include "cape/core/ColliderRecord.h"
#include "cape/scenes/Export.h"

#include <cstdint>
#include <vector>

namespace cape {

/// Strain as docs/SCENES.md defines it, signed: a stretched spring's strain is positive, a compressed one's
/// negative. The one measure of strain outside the solver (tests, demos and the comparison all use it).
struct StrainStats {
  float max =
      0.0f;  ///< max over structural springs of (|xi - xj| - L0) / L0 (negative if all are compressed)
  float mean = 0.0f;  ///< mean of the same (signed)
};
/// Strain of the structural springs at the given positions; 0 and 0 for a fabric with none.
CAPE_SCENES_API StrainStats structuralStrain(const Fabric& fabric, const Points& positions);

/// Penetration: max over particles and colliders of max(0, -signed distance to the true surface) at each
/// collider's current pose, m. Invalid colliders are skipped.
CAPE_SCENES_API float maxPenetration(const Points& positions, ColliderSpan colliders);

/// Pin error: the largest distance of a pinned particle from its current target (`Pin::target`), m.
CAPE_SCENES_API float maxPinError(const Points& positions, const std::vector<Pin>& pins);
/// The same over a cape's state and its pins.
CAPE_SCENES_API float maxPinError(const CapeState& state);

/// Blow-up: a non-finite coordinate, or a particle farther than `radius` from `centre`.
CAPE_SCENES_API bool isBlownUp(const Points& positions, const Vec3& centre, float radius = 10.0f);

/// Exact triangle-triangle intersection test (Möller 1997 interval test, evaluated in double precision with
/// no tolerance; touching counts as intersecting; coplanar triangles are tested in 2D). Triangles whose
/// bounding boxes are apart never intersect: tested first, as the interval test alone reports such pairs as
/// crossing when a triangle is degenerate (its corners on a line) or the two normals are parallel in double
/// while rounding puts each triangle across the other's plane.
CAPE_SCENES_API bool trianglesIntersect(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0,
                                        const Vec3& q1, const Vec3& q2);

/// Counts pairs of triangles that share no vertex and intersect: the pairs whose bounding boxes overlap
/// (closed boxes, as `trianglesIntersect` counts touching), each tested once with the exact test, so the
/// count is the brute-force count over all pairs. The pairs are found through a uniform grid of cells at
/// least as large as the triangles' boxes, each triangle in the one cell of its box's least corner: two
/// boxes that overlap then lie in the same or in neighbouring cells. The triangles are sorted by cell, so
/// that a cell's 13 forward neighbours (one of each opposite pair of the 26) lie in five runs of the order,
/// and each triangle is tested against those runs four at a time. A triangle larger than the cells (or not
/// finite) is tested against every other. Reuses its scratch between calls (one counter per cape: no
/// allocation once it has seen the cape's size).
///
/// Before any of that, a grid fabric's count tries the flat proof (Fabric::keepsApart): a cape that keeps
/// every two of its points at least kFlatProofKappa times their rest distance apart keeps two triangles that
/// share no corner at least that times Fabric::FlatProof::disjointTriangles apart (a quarter of a millimetre
/// on the canonical cape), so none meets another and the count is 0 without a box. That is the geometric
/// truth of the float positions; the interval test in double agrees with it wherever its rounding (about
/// 1e-16 of the coordinates, divided by the sine of the angle between two triangles' planes) is under that
/// distance, which the tests check on every frame of the canonical scenes against the count without the proof
/// (itself tested against the brute-force count), and on a sample of them against the brute force.
class CAPE_SCENES_API SelfIntersectionCounter {
 public:
  /// The least stretch (kappa) the count's flat proof asks for: a hundredth.
  static constexpr float kFlatProofKappa = 0.01f;

  /// The number of intersecting pairs of the fabric's triangles at `positions` (m, one row per particle).
  int count(const Fabric& fabric, const Points& positions);
  /// Counts proven to be 0 by the flat proof so far.
  std::int64_t countsProvenApart() const { return provenApart_; }
  /// Whether count() tries the flat proof first (it does unless told not to; tests compare both ways).
  void setFlatProof(bool on) { flatProof_ = on; }

 private:
  /// A triangle's bounding box.
  struct Box {
    float lo[3], hi[3];
  };
  /// A run [begin, end) of the cell order.
  struct Run {
    std::uint32_t begin, end;
  };
  /// Sorts the hashed triangles by cell (stable) into the structure of arrays below.
  void sortByCell(const std::vector<std::uint32_t>& triangles, std::uint64_t largestKey);
  /// Tests triangle `a` (an index into the cell order) against the triangles of `runs`.
  void testAgainst(const Points& positions, std::uint32_t a, const Run* runs, int runCount);

  std::vector<Box> boxes_;
  std::vector<std::int32_t> cells_;      ///< per triangle: its cell's three indices (hashed ones)
  std::vector<std::uint64_t> keys_[2];   ///< the hashed triangles' cells, in radix-sort passes
  std::vector<std::uint32_t> order_[2];  ///< the hashed triangles, in radix-sort passes
  std::vector<std::uint32_t> histogram_;
  // The hashed triangles in the cell order, as structure of arrays (padded for four-wide loads): their
  // boxes, corners, indices and cells.
  std::vector<float> lo_[3], hi_[3];
  std::vector<std::uint32_t> vertex_[3], triangle_;
  std::vector<std::uint64_t> key_;
  std::vector<std::uint32_t> loose_;   ///< triangles left out of the grid (too large, or not finite)
  std::vector<std::uint8_t> isLoose_;  ///< per triangle: hashed, loose as too large, loose as not finite
  int found_ = 0;                      ///< intersecting pairs found so far in this count
  bool flatProof_ = true;              ///< try the flat proof first
  std::size_t proofStart_ = 0;         ///< the triangle the last failed proof failed at
  std::int64_t provenApart_ = 0;       ///< counts the flat proof settled
};

/// Per-frame values and run summary of every metric, as the demos report them.
struct FrameMetrics {
  float maxStrain = 0.0f;       ///< The largest structural strain (StrainStats::max), dimensionless
  float meanStrain = 0.0f;      ///< The mean structural strain (StrainStats::mean), dimensionless
  float maxPenetration = 0.0f;  ///< m, maxPenetration() over the body colliders
  int selfIntersections = 0;    ///< Intersecting triangle pairs (0 when not counted)
  float pinError = 0.0f;        ///< m, maxPinError()
  float meanSpeed = 0.0f;       ///< m/s, over particles
  /// Particles the cape's numerical guard restored in the frame's steps (Cape::guard(): not finite, or run
  /// away from the pins). The guard keeps the NaN from lasting; the frame counts as blown up all the same.
  std::uint32_t guardRestored = 0;
  bool blowUp = false;  ///< A coordinate not finite, or a particle beyond isBlownUp()'s radius
  /// How the cape folds (FoldMeter; 0 unless the caller measures it: measureFrame does not, it has no
  /// memory of the last frame): the mean dihedral angle over interior edges, rad.
  float meanDihedral = 0.0f;
  /// The mean change of those angles since the last frame, rad (FoldMeter; 0 unless measured).
  float dihedralChange = 0.0f;
};

/// How a cape folds. For every interior edge (two triangles sharing it) the dihedral angle: the angle
/// between the two triangles' normals, 0 where the sheet is flat there, pi where it is folded flat onto
/// itself. And how much each of those angles changed since the last measure: a cape that sways and folds
/// changes shape from frame to frame; a board only moves. Degenerate or non-finite triangles are left out.
struct FoldStats {
  float meanDihedral = 0.0f;  ///< rad, mean over the interior edges measured (each once)
  float meanChange = 0.0f;    ///< rad, mean over edges measured both times of |angle - last angle| (first: 0)
  std::size_t edges = 0;      ///< interior edges measured
};
/// Measures FoldStats frame after frame, keeping each edge's last angle (sized on the first measure).
class CAPE_SCENES_API FoldMeter {
 public:
  /// The fold statistics of `positions` (one row per particle of `fabric`), against the last call's.
  FoldStats measure(const Fabric& fabric, const Points& positions);

 private:
  /// The interior edges of `fabric` as pairs of triangles (once per fabric).
  void findEdges(const Fabric& fabric);

  const Fabric* fabric_ = nullptr;       ///< the fabric edges_ were found on
  std::vector<std::uint32_t> edges_[2];  ///< per interior edge: its two triangles
  std::vector<float> normal_[3];         ///< per triangle: its unit normal, 0 if degenerate or not finite
  std::vector<float> last_;              ///< per interior edge: the last angle, NaN if not measured
};

/// Measures a frame of any solver's cloth on `fabric` (ours, or a Bullet twin copied into these arrays), so
/// that every solver compared is measured by the same code: `positions` and `velocities` have one row per
/// fabric particle (m, m/s); `pins` are the pinned particles with where each should be now (`target`; the
/// previous target is not read); `bodyColliders` are at this frame's poses; `torsoCentre` is where the
/// blow-up radius is measured from. A blown-up frame only says so (`blowUp`; every other figure left 0, as
/// they would be NaN or meaningless). Self-intersections are only counted when a counter is given.
CAPE_SCENES_API FrameMetrics measureFrame(const Fabric& fabric, const Points& positions,
                                          const Points& velocities, const std::vector<Pin>& pins,
                                          ColliderSpan bodyColliders, const Vec3& torsoCentre,
                                          SelfIntersectionCounter* selfIntersections);
/// Our cape's frame: the function above on its fabric, its state and its pins.
CAPE_SCENES_API FrameMetrics measureFrame(const Cape& cape, ColliderSpan bodyColliders,
                                          const Vec3& torsoCentre,
                                          SelfIntersectionCounter* selfIntersections);

/// Measures one cloth frame after frame as the demos do: measureFrame with a SelfIntersectionCounter of its
/// own, and (when asked) the fold statistics of a FoldMeter. A frame whose inputs are bit for bit the last
/// frame's (positions, velocities, pins, the body colliders as a ColliderRecord sees them, the blow-up
/// centre) has the last frame's figures, its fold change 0, which is what measuring it again would give: a
/// cape asleep among still bodies then costs a comparison of its inputs, not the metrics. One meter per cape
/// (it keeps a copy of the last inputs; no allocation once it has seen the cape's size and colliders).
class CAPE_SCENES_API FrameMeter {
 public:
  /// `folds`: also measure FrameMetrics::meanDihedral and dihedralChange (FoldMeter).
  explicit FrameMeter(bool folds = false) : measureFolds_(folds) {}
  /// The metrics of a frame, as measureFrame with this meter's counter, and the fold statistics when the
  /// meter measures them and the frame did not blow up. `guardRestored` (Cape::guard() over the frame)
  /// goes into FrameMetrics::guardRestored and makes the frame a blow-up; such a frame is always measured.
  FrameMetrics measure(const Fabric& fabric, const Points& positions, const Points& velocities,
                       const std::vector<Pin>& pins, ColliderSpan bodyColliders, const Vec3& torsoCentre,
                       std::uint32_t guardRestored = 0);
  /// Our cape's frame: the function above on its fabric, its state and its pins.
  FrameMetrics measure(const Cape& cape, ColliderSpan bodyColliders, const Vec3& torsoCentre,
                       std::uint32_t guardRestored = 0);
  /// True when the last measure() reused the frame before's figures.
  bool lastReused() const { return lastReused_; }
  /// Frames measured so far that reused the frame before's figures.
  std::int64_t reusedFrames() const { return reused_; }

 private:
  SelfIntersectionCounter counter_;
  FoldMeter folds_;
  bool measureFolds_ = false;
  bool have_ = false;  ///< the members below hold the last measured frame
  bool lastReused_ = false;
  std::int64_t reused_ = 0;
  const Fabric* fabric_ = nullptr;
  Points positions_, velocities_;
  std::vector<Pin> pins_;
  Vec3 centre_ = Vec3::Zero();
  ColliderRecord colliders_;
  FrameMetrics last_;
};

/// The worst of two frames, metric by metric (the larger strain, penetration, count, pin error and speed;
/// blown up if either is): a crowd's row holds the worst of its characters.
CAPE_SCENES_API FrameMetrics worstOf(const FrameMetrics& a, const FrameMetrics& b);

/// The summary of a run, frame by frame metrics accumulated by MetricsRecorder.
struct RunSummary {
  std::int64_t frames = 0;  ///< Frames measured
  float maxStrain = 0.0f;   ///< max over frames of the per-frame max strain (signed)
  double meanStrain = 0.0;  ///< mean over frames of the per-frame mean strain
  float medianFrameMaxStrain =
      0.0f;                        ///< median over frames of the per-frame max strain (PercentileEstimator)
  float p95FrameMaxStrain = 0.0f;  ///< 95th percentile over frames of the per-frame max strain (the same)
  float maxPenetration = 0.0f;     ///< m, the largest over frames
  std::int64_t framesPenetrationOver1mm = 0;     ///< Frames whose penetration exceeds 1 mm
  int selfIntersectionsMax = 0;                  ///< The most intersecting triangle pairs in a frame
  std::int64_t framesWithSelfIntersections = 0;  ///< Frames with at least one
  float pinErrorMax = 0.0f;                      ///< m, the largest over frames
  std::int64_t guardRestored = 0;                ///< particles the numerical guard restored, over the run
  std::int64_t framesGuardRestored = 0;          ///< frames in which it restored any
  bool blowUp = false;                           ///< Any frame blew up
  float restJitter = 0.0f;                       ///< mean particle speed over the last second, m/s
  double meanDihedral = 0.0;                     ///< rad, mean over frames of FrameMetrics::meanDihedral
  double meanDihedralChange = 0.0;  ///< rad per frame, mean over frames of FrameMetrics::dihedralChange
};

/// Nearest-rank percentiles of a stream of values in bounded memory (about 110 KB, allocated up front,
/// however many values come). The first kExactValues values are kept and the percentile is exact (what
/// `percentile` gives). From then on the values are counted in a fixed histogram of logarithmic buckets, one
/// set for each sign: a bucket holds the magnitudes in (s g^(k-1), s g^k] with s = kSmallest and g = (1 + a)
/// / (1 - a), a = kRelativeError, and stands for 2 s g^k / (g + 1). The rank is found exactly among the
/// counts, so the estimate differs from the exact percentile q by at most a |q| (plus rounding) for kSmallest
/// <= |q| <= kLargest, by at most kSmallest when |q| < kSmallest (such values count as 0), and always lies
/// between the smallest and the largest value seen, which are kept exactly (the 0th and 100th percentiles are
/// exact). NaN values are not counted.
class CAPE_SCENES_API PercentileEstimator {
 public:
  static constexpr std::size_t kExactValues = 4096;  ///< Values kept exactly before the histogram takes over
  static constexpr double kRelativeError = 0.005;    ///< a: the histogram's relative error bound
  static constexpr double kSmallest = 1e-9;          ///< s: magnitudes below it count as 0
  static constexpr double kLargest = 1e12;           ///< Magnitudes above it share the last bucket

  /// No values yet; all the memory allocated.
  PercentileEstimator();
  /// Counts a value (NaN is ignored).
  void add(double value);
  /// The p-th percentile (nearest rank), p in [0, 100]; 0 when no value came.
  double percentile(double p) const;
  /// The number of values counted.
  std::int64_t count() const { return count_; }
  /// True while every value is kept (the percentiles are exact).
  bool exact() const { return count_ <= static_cast<std::int64_t>(kExactValues); }

 private:
  std::size_t bucket(double value) const;
  double bucketValue(std::size_t bucket) const;

  std::vector<double> values_;          ///< the first kExactValues values, then empty
  std::vector<std::uint64_t> buckets_;  ///< negative magnitudes high to low, zero, positive low to high
  std::int64_t count_ = 0;
  double min_ = 0.0, max_ = 0.0;
};

/// Accumulates frames into a summary, in constant memory: running extrema, counts and sums, the per-frame max
/// strain in a PercentileEstimator, and the mean speeds of the last second.
class CAPE_SCENES_API MetricsRecorder {
 public:
  /// A recorder for frames `frameTime` s apart (sizes the last second's ring).
  explicit MetricsRecorder(double frameTime = 1.0 / 60.0);
  /// Adds one frame.
  void add(const FrameMetrics& m);
  /// The summary of every frame added so far.
  RunSummary summary() const;

 private:
  RunSummary running_;  ///< the extrema and counts so far
  double meanStrainSum_ = 0.0;
  double dihedralSum_ = 0.0, dihedralChangeSum_ = 0.0;
  PercentileEstimator frameMaxStrain_;
  std::vector<float> lastSpeeds_;  ///< ring of the last second's frames' mean speeds
  std::size_t nextSpeed_ = 0;      ///< where the next one goes (the oldest once the ring is full)
};

/// Median and p-th percentile (nearest rank) of a list of values; 0 for an empty list.
CAPE_SCENES_API double percentile(std::vector<double> values, double p);

}  // namespace cape
