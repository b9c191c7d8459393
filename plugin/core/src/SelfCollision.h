// SelfCollision: predictive particle-triangle contacts (Lewin 2018, "Cloth Self Collision with Predictive
// Contacts", GDC) and the scratch memory of their search, one per cape. The fabric's triangle tables
// (Fabric::triangleLocal, clusters) are shared; everything here is this cape's.
#pragma once

#include "cape/core/Cape.h"

#include <limits>
#include <vector>

namespace cape::detail {

/// Barycentric weights of p's projection onto the plane of (a, b, c), unclamped; false if degenerate.
bool planeBarycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, float& wa, float& wb,
                      float& wc);
/// A particle over a triangle grown by this fraction of itself (in barycentric terms) keeps its side: the
/// grown triangles of a vertex's ring overlap, so a particle heading straight for a vertex or an edge of the
/// other layer (two halves of a folded grid line up exactly) is caught as surely as one heading for a face.
inline constexpr float kFaceMargin = 0.25f;

/// Whether p is beside triangle (a, b, c) and at least `thickness` from it, told without its nearest point:
/// then SelfCollision::solve leaves the pair as it is (p neither over the face grown by kFaceMargin, where
/// the solve would note its side, nor within the thickness). false where it cannot tell, and the full test
/// decides.
bool besideAndApart(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, float thickness);

class SelfCollision {
 public:
  explicit SelfCollision(const Fabric& fabric);

  /// The thickness in use, m: the setting, or 0.35 of the fabric's mean spacing.
  float thickness(const CapeSettings& settings) const;

  /// Plans this step's searches (see the definition for the rule). Returns the substeps between searches,
  /// or 0 when no search runs inside the substep loop (one ran here, or the earlier contacts still cover
  /// the step).
  int schedule(const CapeState& state, const Eigen::VectorXf& freeMask, const CapeSettings& settings,
               float dt, int substeps);
  /// A search inside the substep loop covering `window` seconds of motion.
  void searchFor(const CapeState& state, const Eigen::VectorXf& freeMask, const CapeSettings& settings,
                 float window);

  /// Keeps every contact's particle on its side of its triangle, at least the thickness away (a PBD pass
  /// with inverse masses `w`).
  void solve(Points& positions, const float* w, float thickness);

  /// Drops the contacts: the next step searches afresh (the cape was put somewhere else).
  void forget() {
    contacts_.clear();
    validUntil_ = -std::numeric_limits<double>::infinity();
  }

  const std::vector<Cape::SelfContact>& contacts() const { return contacts_; }
  std::uint64_t searches() const { return searches_; }

 private:
  float predictMotion(const CapeState& state, const Eigen::VectorXf& freeMask, const Vec3& gravity, float dt);
  void find(const Points& x, const Points& v, float thickness);
  /// Bins every cluster's grown box into the hash (find's first half).
  void bin();
  /// Particle q (at p, its swept box qlo..qhi) against one bucket's clusters.
  void scanBucket(std::uint32_t q, const Vec3& p, const float* qlo, const float* qhi, std::uint32_t bucket,
                  bool stamp);
  /// Particle q against triangle t: the exact filter, and the contact if within reach.
  void consider(std::uint32_t q, const Vec3& p, std::uint32_t t, bool stamp);
  void grownBox(std::uint32_t t, Vec3& lo, Vec3& hi) const;
  /// Whether the particle being scanned has as many contacts as a search keeps for one.
  bool particleFull() const;

  const Fabric& fabric_;
  std::vector<Cape::SelfContact> contacts_;
  double validUntil_ = -1.0;    ///< s: the contacts cover the motion until this time.
  std::uint64_t searches_ = 0;  ///< Searches so far (diagnostics).

  // The search's scratch, sized once.
  std::vector<std::uint32_t> hashStart_;  ///< Spatial hash: bucket offsets (buckets + 1).
  /// A cluster of triangles in a bucket of the spatial hash, with its grown box inline: the search reads
  /// entries in order and rejects most by the box without touching the triangles.
  struct alignas(16) HashEntry {
    float lo[4];  ///< [3]: the cluster's index, as float bits
    float hi[4];  ///< [3]: +inf
  };
  std::vector<HashEntry> hashEntries_;             ///< Spatial hash: clusters of triangles sorted by bucket.
  std::vector<std::uint32_t> bucketHits_;          ///< One bucket's entries that overlap (hashEntries_ size).
  std::vector<float> triangleMotion_;              ///< Per triangle: the largest motion of its corners, m.
  std::vector<std::uint32_t> triangleStamp_;       ///< Last particle that met each triangle in the search.
  std::vector<std::uint32_t> largeTriangles_;      ///< Triangles whose grown box is too big to bin.
  std::vector<float> clusterBoxes_;                ///< Per cluster: the union of its grown boxes, m.
  std::vector<std::uint32_t> clusterBuckets_;      ///< The buckets each binned cluster went into...
  std::vector<std::uint32_t> clusterBucketStart_;  ///< ...from this offset per cluster (clusters + 1).
  std::vector<std::uint32_t> bucketCluster_;       ///< The last cluster binned into each bucket.
  Points stepMotion_;  ///< Predicted displacement over the search's window, less a rigid motion, m.
  Eigen::VectorXf stepMotionNorm_;  ///< |stepMotion_| per particle, m.
  Points sweptLo_, sweptHi_;        ///< Per particle: the box from its position to its predicted one, m.

  // Per search: what every particle's scan reads.
  const Points* x_ = nullptr;
  float thickness_ = 0.0f;
  float slack_ = 0.0f;
  float invCell_ = 0.0f;
  std::uint32_t mask_ = 0;
  std::size_t particleFirst_ = 0;  ///< The scanned particle's first contact in contacts_.
};

}  // namespace cape::detail
