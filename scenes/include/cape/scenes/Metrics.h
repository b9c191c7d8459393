// The quality metrics of docs/SCENES.md as library code, so that tests, demos, benchmarks and
// comparisons measure exactly the same thing.
#pragma once

#include "cape/core/Cape.h"

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
StrainStats structuralStrain(const Fabric& fabric, const Points& positions);

/// Penetration: max over particles and colliders of max(0, -signed distance to the true surface) at each
/// collider's current pose, m. Invalid colliders are skipped.
float maxPenetration(const Points& positions, ColliderSpan colliders);

/// Pin error: the largest distance of a pinned particle from its current target (`Pin::target`), m.
float maxPinError(const Points& positions, const std::vector<Pin>& pins);
/// The same over a cape's state and its pins.
float maxPinError(const CapeState& state);

/// Blow-up: a non-finite coordinate, or a particle farther than `radius` from `centre`.
bool isBlownUp(const Points& positions, const Vec3& centre, float radius = 10.0f);

/// Exact triangle-triangle intersection test (Möller 1997 interval test, evaluated in double precision with
/// no tolerance; touching counts as intersecting; coplanar triangles are tested in 2D).
bool trianglesIntersect(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& q0, const Vec3& q1,
                        const Vec3& q2);

/// Counts pairs of triangles that share no vertex and intersect. Reuses its scratch between calls.
class SelfIntersectionCounter {
 public:
  int count(const Fabric& fabric, const Points& positions);

 private:
  struct Box {
    Eigen::Vector3f lo, hi;
    std::uint32_t triangle;
  };
  std::vector<Box> boxes_;
};

/// Per-frame values and run summary of every metric, as the demos report them.
struct FrameMetrics {
  float maxStrain = 0.0f;
  float meanStrain = 0.0f;
  float maxPenetration = 0.0f;
  int selfIntersections = 0;
  float pinError = 0.0f;
  float meanSpeed = 0.0f;  ///< m/s, over particles
  bool blowUp = false;
};

/// Measures a frame of any solver's cloth on `fabric` (ours, or a Bullet twin copied into these arrays), so
/// that every solver compared is measured by the same code: `positions` and `velocities` have one row per
/// fabric particle (m, m/s); `pins` are the pinned particles with where each should be now (`target`; the
/// previous target is not read); `bodyColliders` are at this frame's poses; `torsoCentre` is where the
/// blow-up radius is measured from. A blown-up frame only says so (`blowUp`; every other figure left 0, as
/// they would be NaN or meaningless). Self-intersections are only counted when a counter is given.
FrameMetrics measureFrame(const Fabric& fabric, const Points& positions, const Points& velocities,
                          const std::vector<Pin>& pins, ColliderSpan bodyColliders, const Vec3& torsoCentre,
                          SelfIntersectionCounter* selfIntersections);
/// Our cape's frame: the function above on its fabric, its state and its pins.
FrameMetrics measureFrame(const Cape& cape, ColliderSpan bodyColliders, const Vec3& torsoCentre,
                          SelfIntersectionCounter* selfIntersections);

/// The worst of two frames, metric by metric (the larger strain, penetration, count, pin error and speed;
/// blown up if either is): a crowd's row holds the worst of its characters.
FrameMetrics worstOf(const FrameMetrics& a, const FrameMetrics& b);

struct RunSummary {
  int frames = 0;
  float maxStrain = 0.0f;             ///< max over frames of the per-frame max strain (signed)
  double meanStrain = 0.0;            ///< mean over frames of the per-frame mean strain
  float medianFrameMaxStrain = 0.0f;  ///< median over frames of the per-frame max strain
  float p95FrameMaxStrain = 0.0f;     ///< 95th percentile over frames of the per-frame max strain
  float maxPenetration = 0.0f;
  int framesPenetrationOver1mm = 0;
  int selfIntersectionsMax = 0;
  int framesWithSelfIntersections = 0;
  float pinErrorMax = 0.0f;
  bool blowUp = false;
  float restJitter = 0.0f;  ///< mean particle speed over the last second, m/s
};

/// Accumulates frames into a summary.
class MetricsRecorder {
 public:
  explicit MetricsRecorder(double frameTime = 1.0 / 60.0) : frameTime_(frameTime) {}
  void add(const FrameMetrics& m);
  RunSummary summary() const;
  const std::vector<FrameMetrics>& frames() const { return frames_; }

 private:
  double frameTime_;
  std::vector<FrameMetrics> frames_;
};

/// Median and p-th percentile (nearest rank) of a list of values; 0 for an empty list.
double percentile(std::vector<double> values, double p);

}  // namespace cape
