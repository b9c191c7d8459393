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

/// Whether SelfCollision::solve passes over the contact of particle p with triangle (a, b, c), noted on
/// `side` (+1, -1, or 0 for none yet): on that side of the plane and at least the thickness from it, or
/// besideAndApart.
bool contactApart(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, float side, float thickness);

#if defined(__SSE2__)
/// contactApart for four contacts k[0..3] at once, at positions x (`triangles`: Fabric::triangles()): bit i
/// set if contact k[i] is apart. The same operations in the same order in every lane, so the same answer.
int apartLanes(const Points& x, const std::vector<std::uint32_t>& triangles, const Cape::SelfContact* k,
               float thickness);
#endif

/// The closest points of segments p0-p1 and q0-q1: p0 + s (p1 - p0) and q0 + t (q1 - q0), s and t in [0, 1].
/// `interior` when both lie strictly inside their segments and the segments are not parallel: the points are
/// then unique and their difference is along (p1 - p0) x (q1 - q0). false if either segment is degenerate.
bool closestOnSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, float& s, float& t,
                       bool& interior);

/// The edge-edge self-contacts' thickness, as a fraction of the particle-triangle one (SelfCollision.cpp
/// explains the choice).
inline constexpr float kEdgeThicknessFraction = 0.2f;

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

  /// A pair of opposite edges of a hinge (two triangles sharing an edge, seen as a quad): p0-p1 and q0-q1.
  struct EdgePair {
    std::uint32_t p0, p1, q0, q1;
  };
  /// An edge-edge contact: a pair within reach at the search, and the side of q's edge p's was on (+1, -1,
  /// or 0 while their closest points are not both inside the edges).
  struct EdgeContact {
    std::uint32_t pair;  ///< Index into edgePairs().
    float side;
  };

  /// Drops the contacts: the next step searches afresh (the cape was put somewhere else).
  void forget() {
    contacts_.clear();
    edgeContacts_.clear();
    validUntil_ = -std::numeric_limits<double>::infinity();
  }

  const std::vector<Cape::SelfContact>& contacts() const { return contacts_; }
  /// Every hinge's two pairs of opposite edges (built with the scratch, allocate(); empty before).
  const std::vector<EdgePair>& edgePairs() const { return edgePairs_; }
  const std::vector<EdgeContact>& edgeContacts() const { return edgeContacts_; }
  std::uint64_t searches() const { return searches_; }
  /// Searches that the flat proof passed over (provenApart()): no contact was possible, none was looked for.
  std::uint64_t searchesProvenApart() const { return provenApart_; }
  /// Whether searches may try the flat proof first (on by default; tests turn it off to compare).
  void setFlatProof(bool on) { flatProof_ = on; }
  /// Bytes held by the search's scratch: none until allocate() or the first search.
  std::size_t scratchBytes() const;
  /// Sizes the search's scratch (once; a search does it if nothing has): Cape calls it when self-collision
  /// is turned on, so that its steps never allocate.
  void allocate();

 private:
  float predictMotion(const CapeState& state, const Eigen::VectorXf& freeMask, const Vec3& gravity, float dt);
  /// Whether no particle-triangle or edge-edge pair of the cape at x can be within a search's reach: the
  /// flat proof (see the definition). Reads the thickness, slack and predicted motion of the search that
  /// find() is running. false where it cannot tell (and for a fabric that is not a grid).
  bool provenApart(const Points& x);
  void find(const Points& x, const Points& v, float thickness);
  /// Bins every cluster's grown box into the hash (find's first half).
  void bin();
  /// Particle q (at p, its swept box qlo..qhi) against one bucket's clusters.
  void scanBucket(std::uint32_t q, const Vec3& p, const float* qlo, const float* qhi, std::uint32_t bucket,
                  bool stamp);
  /// Particle q against triangle t: the exact filter, and the contact if within reach.
  void consider(std::uint32_t q, const Vec3& p, std::uint32_t t, bool stamp);
  void grownBox(std::uint32_t t, Vec3& lo, Vec3& hi) const;
  /// Grows lo..hi (3 floats each) to take in triangle t's corners' swept boxes.
  void growCornerBox(std::uint32_t t, float* lo, float* hi) const;
  /// Whether the particle being scanned has as many contacts as a search keeps for one.
  bool particleFull() const;
  /// The hinges' opposite edges within reach (find's last part).
  void findEdges(const Points& x);
  void buildEdgePairs();
  /// Edge pair i that the cheap test could not pass over: the exact test, and the contact if within reach.
  void considerEdgePair(std::size_t i, const Points& x);
  void solveEdges(Points& x, const float* w, float thickness, float maxCrossing);
  /// One particle-triangle contact of solve(): passed over if apart, else kept to its side, the thickness
  /// away.
  void solveContact(Points& x, const float* w, float thickness, float maxCrossing, Cape::SelfContact& k);

  const Fabric& fabric_;
  std::vector<Cape::SelfContact> contacts_;
  std::vector<EdgePair> edgePairs_;
  std::vector<float> edgeAxis_;  ///< Per edge pair: the unit direction that last separated its edges.
  std::vector<EdgeContact> edgeContacts_;
  double validUntil_ = -1.0;       ///< s: the contacts cover the motion until this time.
  std::uint64_t searches_ = 0;     ///< Searches so far (diagnostics).
  std::uint64_t provenApart_ = 0;  ///< Searches passed over by the flat proof (diagnostics).
  bool flatProof_ = true;
  float largestMotion_ = 0.0f;  ///< The largest |stepMotion_|, m (predictMotion).
  std::size_t lastFailed_ = 0;  ///< The triangle that failed the last flat proof (where the next starts).

  // The search's scratch, sized once (allocate()).
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
