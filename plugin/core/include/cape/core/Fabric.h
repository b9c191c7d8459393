/// \file
/// Fabric: the shared, immutable topology and rest state of a cape (NvCloth's Fabric, Jolt's
/// SoftBodySharedSettings). Many capes may share one Fabric; per-cape data lives in CapeState.
#pragma once

#include "cape/core/Export.h"
#include "cape/core/Types.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace cape {

/// The families of springs. Structural and shear together form the seed's King's graph for a grid.
enum class SpringFamily : int {
  Structural = 0,  ///< Along rows and columns (a mesh's edges): what holds the cloth's length.
  Shear = 1,       ///< Across each grid cell's diagonals.
  Bend = 2,        ///< Between every second particle (a mesh's far vertices across an edge).
};
/// The number of spring families (the size of per-family arrays).
constexpr int kSpringFamilyCount = 3;
/// The family's name: "structural", "shear" or "bend".
CAPE_CORE_API const char* toString(SpringFamily family);

/// How the solver reads the particles of a run of springs. Every block of four consecutive springs of one
/// colour is solved four at a time: with vector loads and stores of whole neighbourhoods where the indices
/// follow one of the patterns below (the grid's rows, columns and diagonals fall into them), gathered
/// otherwise; the last one to three springs of a colour one at a time. With p the first particle of the
/// block and q its second:
enum class SpringLayout : std::uint8_t {
  Scalar,       ///< Any indices, one spring at a time.
  Contiguous,   ///< first p, p+1, p+2, p+3; second q, q+1, q+2, q+3 (a grid's columns and diagonals).
  PairSwapped,  ///< first p, p+1, p+2, p+3; second q, q-1, q+2, q+1 (a grid's two diagonals of a cell).
  Interleaved,  ///< first p, p+2, p+4, p+6; second first + 1 (every other spring along a row).
  Pairs,        ///< first p, p+1, p+4, p+5; second first + 2 (bend springs along a row).
  Gathered,     ///< Any four springs of one colour: the particles read and written one by one, the
                ///< arithmetic four at a time.
};

/// Springs [begin, end) of a set, read with one layout. A vector run holds a whole number of blocks of four.
struct SpringRun {
  std::uint32_t begin = 0;                     ///< The run's first spring (index into the set).
  std::uint32_t end = 0;                       ///< One past its last spring.
  SpringLayout layout = SpringLayout::Scalar;  ///< How the solver reads the run's particles.
};

/// Springs of one family as parallel arrays (structure of arrays), solved in this order. The build sorts
/// them by colour: springs [colourStart[k], colourStart[k+1]) share no particle, so consecutive springs in
/// the solver loop do not wait on each other (and a colour could be solved in parallel).
struct SpringSet {
  std::vector<std::uint32_t> first;        ///< Particle index of one end.
  std::vector<std::uint32_t> second;       ///< Particle index of the other end.
  std::vector<float> restLength;           ///< |x_first - x_second| at rest, m (> 0).
  std::vector<std::uint32_t> colourStart;  ///< Offsets of each colour, plus the end.
  /// The set cut into runs, in order (built with the colouring); no block of four straddles two colours, and
  /// no vector run does either (any two blocks of one run share no particle).
  /// Solving the runs in order is solving the springs in order: the four springs of a block share no
  /// particle, so solving them together gives the same bits as one after another.
  std::vector<SpringRun> runs;
  /// The number of springs.
  std::size_t size() const { return first.size(); }
  /// The number of colours.
  std::size_t colourCount() const { return colourStart.empty() ? 0 : colourStart.size() - 1; }
};

/// Long-range attachments (Kim, Chentanez and Müller 2012, "Long Range Attachments - A Method to Simulate
/// Inextensible Clothing in Computer Games"): particle `particle` may not be farther than `maxLength` from
/// particle `anchor` while the anchor is pinned. A unilateral constraint, so it never pushes.
struct TetherSet {
  std::vector<std::uint32_t> particle;  ///< The tethered particle of each tether.
  std::vector<std::uint32_t> anchor;    ///< The anchor particle it may not drift from.
  std::vector<float> maxLength;         ///< m; the rest distance times the tether scale.
  /// The number of tethers.
  std::size_t size() const { return particle.size(); }
};

/// The hinges of the linear bending model (CapeSettings::bendingRigidity): three particles `first`, `middle`,
/// `second` in a straight line at rest, joined by structural springs (a grid's rows and columns, a mesh's
/// edges through a vertex to its most opposite neighbour). The hinge's curvature vector is
/// d = (x_first - x_middle) / L1 + (x_second - x_middle) / L2 (L1, L2 the arms' rest lengths): linear in the
/// positions, 0 on a straight line whatever the arms, |d| = 2 sin(theta / 2) for a hinge bent by theta. Its
/// energy, 1/2 B areaOverLength2 (|d| - restBend)^2, is the plate's 1/2 B kappa^2 over the hinge's area, so
/// a coarse and a fine grid of one fabric bend alike (docs/SOLVER.md, "Linear bending").
struct HingeSet {
  std::vector<std::uint32_t> first;   ///< One end of each hinge.
  std::vector<std::uint32_t> middle;  ///< The particle it bends at.
  std::vector<std::uint32_t> second;  ///< The other end.
  std::vector<float> firstWeight;     ///< 1 / L1, 1/m.
  std::vector<float> secondWeight;    ///< 1 / L2, 1/m.
  std::vector<float> restBend;        ///< |d| at rest (0 for a straight hinge).
  /// The hinge's area over its mean arm length squared (dimensionless): its stiffness is B times this (N·m).
  /// The area is the middle particle's share of the fabric (its mass over the fabric's mean mass per area):
  /// whole for each of one or two hinges (a grid's row and column, exact along them; on the bias a grid is
  /// half as stiff), 8 / (3 n) of it for each of n >= 3 (exact in every direction on an equilateral mesh).
  std::vector<float> areaOverLength2;
  /// Offsets of each level, plus the end. The build sorts the hinges into levels of its own order (a
  /// hinge's level is one past the highest of the earlier hinges it shares a particle with): the hinges of
  /// one level share no particle, so the solver takes four of them at a time, and solving level after level
  /// is solving the build's order (particle after particle) bit for bit.
  std::vector<std::uint32_t> levelStart;
  /// The number of hinges.
  std::size_t size() const { return first.size(); }
};

/// A vertex with more neighbours than this gets no hinges (its neighbours are paired in time quadratic in
/// their number; a real cloth mesh has 4 to 8).
constexpr std::size_t kMaxHingeNeighbours = 32;

/// How to build a rectangular grid fabric.
struct GridDesc {
  int columns = 20;        ///< Particles per row (>= 2).
  int rows = 20;           ///< Particles per column (>= 2).
  float width = 0.6f;      ///< m, along +X of the grid's local frame.
  float height = 1.0f;     ///< m, along -Y: row 0 is the top.
  float totalMass = 0.4f;  ///< kg, spread evenly over the particles (or by area: massByArea).
  /// Spread the mass in proportion to each particle's share of the area, as a cloth's own weight is (edge
  /// particles half, corners a quarter of an interior one), instead of evenly (the canonical cape's, which
  /// gives the grid's border a tile beyond it). What a textile test of a strip measures (FabricPresets.h).
  bool massByArea = false;
  bool bendSprings = true;  ///< Add bend springs: every second particle along rows and columns.
  /// Particles to which tethers are made (usually the particles that will be pinned). Empty: no tethers.
  std::vector<std::uint32_t> tetherAnchors;
  int tethersPerParticle = 2;  ///< Each particle tethers to this many nearest anchors.
  float tetherScale = 1.0f;    ///< Tether length = scale * rest distance (>= 1 allows that much stretch).
};

/// The largest rest coordinate a fabric may have, m: a fabric is metres; beyond this a float square (a
/// spring's squared length) overflows.
constexpr float kMaxFabricCoordinate = 1e6f;

/// How to build a fabric from any triangle mesh (an artist's cape).
struct MeshDesc {
  std::vector<Vec3> positions;  ///< Rest positions, m, each coordinate within +-kMaxFabricCoordinate.
  std::vector<std::uint32_t>
      triangles;                     ///< Three indices per triangle, counter-clockwise seen from the front.
  std::vector<Eigen::Vector2f> uvs;  ///< Optional, one per vertex.
  float totalMass = 0.4f;            ///< kg, spread over vertices in proportion to their triangle area.
  bool bendSprings = true;           ///< Far vertices of each pair of adjacent triangles.
  std::vector<std::uint32_t> tetherAnchors;  ///< Vertices tethers are made to (as GridDesc's); empty: none.
  int tethersPerParticle = 2;                ///< Each vertex tethers to this many nearest anchors.
  float tetherScale = 1.0f;  ///< Tether length = scale * rest distance (>= 1 allows that much stretch).
};

/// The particles a triangle never makes self-contacts with: its three corners and, for each edge k, the far
/// corner of the triangle across it in v[3 + k] (~0u on the border or a non-manifold edge); v[6], v[7] are
/// ~0u padding, so that membership is two 4-lane compares.
struct alignas(16) TriangleLocalSet {
  std::uint32_t v[8];  ///< Particle indices (corners, far corners, ~0u padding).
};

/// Triangles the self-collision search bins together: two consecutive triangles sharing an edge (a grid
/// cell's halves) or one alone. `local` holds the particles local to every triangle of the cluster (a grid
/// cell's four corners; ~0u padding), which meet nothing in it.
struct alignas(16) ClusterLocalSet {
  std::uint32_t v[4];  ///< Particle indices (~0u padding).
};

class Fabric;
/// A shared, immutable fabric: any number of capes may use one.
using FabricPtr = std::shared_ptr<const Fabric>;

/// The result of building a fabric: the fabric, or an error message.
struct FabricResult {
  FabricPtr fabric;                   ///< The fabric; null on error.
  Status status = Status::success();  ///< Why there is no fabric.
  /// True when a fabric was built.
  explicit operator bool() const { return fabric != nullptr; }
};

/// The shared, immutable topology and rest state of a cape: particles and masses, springs by family, tethers,
/// triangles and UVs, and the tables the solver derives from them. Built only by grid() or fromMesh(), which
/// run the derived-data pass, so an unfinished fabric cannot exist.
class CAPE_CORE_API Fabric {
 public:
  /// Builds an N x M grid in its local frame: particle (r, c) has index r * columns + c and rest position
  /// (c * width / (columns - 1), -r * height / (rows - 1), 0): row-major from the top-left seen from +Z.
  /// Springs: structural (rows and columns), shear (both diagonals of every cell) — the King's graph, with
  /// exactly 4nm - 3(n + m) + 2 springs — and optional bend springs. Two counter-clockwise triangles per
  /// cell.
  static FabricResult grid(const GridDesc& desc);
  /// Builds from a triangle mesh: every mesh edge a structural spring, the far vertices of every two
  /// triangles sharing an edge a bend spring. No shear family (the triangles' edges already brace them).
  static FabricResult fromMesh(const MeshDesc& desc);

  /// The number of particles.
  std::size_t particleCount() const { return static_cast<std::size_t>(restPositions_.rows()); }
  /// Rest positions in the fabric's local frame, m, one row per particle.
  const Points& restPositions() const { return restPositions_; }
  const Eigen::VectorXf& masses() const { return masses_; }  ///< kg per particle (> 0).
  /// The springs of one family, in solver order.
  const SpringSet& springs(SpringFamily family) const { return springs_[static_cast<int>(family)]; }
  std::size_t springCount() const;  ///< All families together.
  /// The long-range attachments (empty without tether anchors).
  const TetherSet& tethers() const { return tethers_; }
  /// The hinges of the linear bending model, in solver order (built for every fabric; used when
  /// CapeSettings::bendingRigidity > 0).
  const HingeSet& hinges() const { return hinges_; }
  const std::vector<std::uint32_t>& triangles() const { return triangles_; }  ///< 3 per triangle, CCW.
  /// The number of triangles.
  std::size_t triangleCount() const { return triangles_.size() / 3; }
  /// Texture coordinates, one per particle (a grid's span [0, 1]; a mesh's as given, or all 0).
  const std::vector<Eigen::Vector2f>& uvs() const { return uvs_; }
  /// The sum of the particle masses, kg.
  float totalMass() const { return static_cast<float>(masses_.sum()); }
  /// Grid dimensions, when built by grid(); 0 otherwise.
  int gridColumns() const { return gridColumns_; }
  /// Grid rows, when built by grid(); 0 otherwise.
  int gridRows() const { return gridRows_; }
  /// The largest distance between two particles at rest (bounds how far any particle can be from a pin).
  float restDiameter() const { return restDiameter_; }
  /// The connected component of each particle through the springs of every family, labelled 0, 1, ... in the
  /// order of their first particle; componentCount() of them.
  const std::vector<std::uint32_t>& components() const { return components_; }
  /// The number of connected components.
  std::uint32_t componentCount() const { return componentCount_; }
  /// Mean rest length of the structural springs, m (sizes the self-collision hash and thickness).
  float meanSpacing() const { return meanSpacing_; }
  /// Each particle's share of the rest area (a third of each triangle it belongs to), m^2.
  const Eigen::VectorXf& particleAreas() const { return particleAreas_; }
  /// Per triangle, the particles it never makes self-contacts with.
  const std::vector<TriangleLocalSet>& triangleLocal() const { return triangleLocal_; }
  /// Cluster g is triangles [clusterStart()[g], clusterStart()[g + 1]) (clusterCount() + 1 offsets).
  const std::vector<std::uint32_t>& clusterStart() const { return clusterStart_; }
  /// The number of clusters.
  std::size_t clusterCount() const { return clusterStart_.empty() ? 0 : clusterStart_.size() - 1; }
  /// Per cluster, the particles local to all its triangles.
  const std::vector<ClusterLocalSet>& clusterLocal() const { return clusterLocal_; }

  /// What the self-contact search reads to prove, before it bins anything, that a grid cape lies too flat to
  /// touch itself (SelfCollision.cpp explains the proof). A grid's rest shape is a rectangle in the plane
  /// z = 0, which the proof needs: convex, and flat.
  struct FlatProof {
    /// Per triangle, the inverse of the 2 x 2 matrix [b - a, c - a] of its rest corners' (x, y), 4 floats
    /// in column order: the cape's deformation gradient over the triangle is [xb - xa, xc - xa] times it.
    std::vector<float> restInverse;
    /// [h]: the least rest distance from a particle to a triangle it is not local to (triangleLocal()) whose
    /// farthest corner is h king's moves from it on the grid (max(|rows apart|, |columns apart|)), m; +inf
    /// where there is none. Triangles within kProofReach cells of the particle; every farther triangle is
    /// at least `beyond` away.
    std::vector<float> particleTriangle;
    /// kProofReach times the grid's smaller spacing, m.
    float beyond = 0.0f;
    /// [h]: the least rest distance between the opposite edges of a hinge (two triangles sharing an edge, a
    /// quad: the self-contact search's edge pairs) whose farthest ends are h king's moves apart, m; +inf
    /// where there is none.
    std::vector<float> edgeEdge;
    /// The least rest distance between two triangles that share no corner, m: the least from a particle to
    /// a triangle it is not a corner of (two disjoint triangles in the plane are closest at a corner of one).
    float disjointTriangles = 0.0f;
  };
  /// How many cells around a particle FlatProof::particleTriangle looks.
  static constexpr int kProofReach = 4;
  /// The flat proof's data of a grid fabric; null for a fabric built by fromMesh(). Built on the first call
  /// (thread-safe; a self-colliding cape's first search, or Cape's turning self-collision on) and shared by
  /// every cape of this fabric.
  const FlatProof* flatProof() const;
  /// The flat proof's bound: true when `positions` (one row per particle) provably keep every two points of
  /// this grid cape's surface at least `kappa` times their rest distance apart (kappa > 0; the proof is
  /// written out in Fabric.cpp), false when the proof cannot say so (folded, crumpled or inverted
  /// somewhere, not finite, or a fabric built by fromMesh()). `startTriangle` is where to start the check
  /// and, on false, becomes the triangle that failed it (a cape that fails mostly fails there again).
  bool keepsApart(const Points& positions, float kappa, std::size_t& startTriangle) const;

  /// The coarse level of a grid fabric, which a cape steps in its place at a coarse level of detail
  /// (Cape::setCoarseLevel): the same size, mass, springs and tether settings over (columns + 1) / 2 x
  /// (rows + 1) / 2 particles (a 20 x 20 grid's is 10 x 10, about a quarter of the work), each tether anchor
  /// carried to the coarse particle nearest it. Built on the first call (thread-safe) and shared by every
  /// cape of this fabric. Null for a fabric built by fromMesh() and for a grid with fewer than 3 particles
  /// along either side (nothing coarser to step).
  FabricPtr coarseLevel() const;
  /// The description a grid fabric was built from (GridDesc's defaults for a mesh fabric).
  const GridDesc& gridDesc() const { return gridDesc_; }

 private:
  Fabric() = default;
  /// Derived data in one explicit pass: colouring and runs, rest lengths, diameter, spacing, tethers, the
  /// triangle tables. Returns an error on degenerate input.
  Status finish(const std::vector<std::uint32_t>& anchors, int tethersPerParticle, float tetherScale);
  Status buildTethers(const std::vector<std::uint32_t>& anchors, int tethersPerParticle, float tetherScale);
  void buildTriangleTables();
  void buildComponents();
  void buildHinges();
  void scheduleHinges();
  /// flatProof()'s data, for a grid.
  void buildFlatProof(FlatProof& proof) const;

  float meanSpacing_ = 0.0f;
  Eigen::VectorXf particleAreas_;
  std::vector<TriangleLocalSet> triangleLocal_;
  std::vector<std::uint32_t> clusterStart_;
  std::vector<ClusterLocalSet> clusterLocal_;
  /// flatProof()'s data, built once (a pointer, as coarse_).
  struct FlatProofCache;
  std::shared_ptr<FlatProofCache> flatProof_;

  Points restPositions_;
  Eigen::VectorXf masses_;
  SpringSet springs_[kSpringFamilyCount];
  TetherSet tethers_;
  HingeSet hinges_;
  std::vector<std::uint32_t> triangles_;
  std::vector<Eigen::Vector2f> uvs_;
  int gridColumns_ = 0;
  int gridRows_ = 0;
  GridDesc gridDesc_;
  /// coarseLevel()'s fabric, built once (a pointer, so that the fabric stays movable while it is built).
  struct CoarseCache;
  std::shared_ptr<CoarseCache> coarse_;
  float restDiameter_ = 0.0f;
  std::vector<std::uint32_t> components_;
  std::uint32_t componentCount_ = 0;
};

/// The seed's spring count for an n x m King's graph: 4nm - 3(n + m) + 2.
constexpr long kingsGraphSpringCount(long n, long m) {
  return 4 * n * m - 3 * (n + m) + 2;
}

}  // namespace cape
