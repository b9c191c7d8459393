/// \file
/// Render output of a cape, refreshed every frame without allocating: positions, area-weighted vertex
/// normals, UVs and counter-clockwise triangles; optionally a two-sided copy for renderers without
/// two-sided shading (back faces with flipped winding and flipped normals).
#pragma once

#include "cape/core/Export.h"
#include "cape/core/Fabric.h"

namespace cape {

/// Render output of a cape, refreshed every frame without allocating (see CapeMesh.h).
struct CAPE_CORE_API CapeMesh {
  Points positions;                    ///< m, one row per vertex.
  Points normals;                      ///< Unit, one row per vertex.
  std::vector<Eigen::Vector2f> uvs;    ///< Texture coordinates, one per vertex (the fabric's).
  std::vector<std::uint32_t> indices;  ///< 3 per triangle, counter-clockwise around the normal.

  /// Sizes the buffers for the fabric (front only, or front then back when twoSided) and fills the
  /// fixed parts (triangles, UVs). Vertices [0, n) are the front; [n, 2n) the back when two-sided.
  void allocate(const Fabric& fabric, bool twoSided);
  /// Copies positions and recomputes normals from the given particle positions. Never allocates once
  /// allocate() has been called for this fabric.
  void update(const Fabric& fabric, const Points& particlePositions);
  /// Whether the buffers hold a back copy (allocate()'s `twoSided`).
  bool twoSided() const { return twoSided_; }

 private:
  bool twoSided_ = false;
};

/// Area-weighted vertex normals: the normalised sum of the (unnormalised) face normals of the triangles
/// around each vertex, whose length is twice the triangle's area. Writes into `normals` (sized by the
/// caller).
CAPE_CORE_API void computeVertexNormals(const Points& positions, const std::vector<std::uint32_t>& triangles,
                                        Eigen::Ref<Points, 0, Eigen::OuterStride<>> normals);

}  // namespace cape
