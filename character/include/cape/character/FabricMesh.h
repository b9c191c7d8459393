/// \file
/// A cape from an artist's mesh file (OBJ, PLY, glTF, COLLADA, STL: whatever assimp reads) as a MeshDesc for
/// Fabric::fromMesh, with its UVs and its vertex colours, from which cape/core/WeightMap.h's
/// weightMapFromColours paints a weight map (a max distance, a drive, a stiffness scale) per particle.
#pragma once

#include "cape/character/Export.h"
#include "cape/character/Status.h"
#include "cape/core/Fabric.h"

#include <string>
#include <vector>

namespace cape::character {

/// How to read a fabric mesh file.
struct CAPE_CHARACTER_API FabricMeshOptions {
  double scale = 1.0;          ///< Every coordinate times this (a file in centimetres: 0.01), finite, > 0.
  float totalMass = 0.4f;      ///< kg, the MeshDesc's totalMass (finite, > 0).
  int maxTriangles = 1000000;  ///< Larger meshes (every node instance counted) are refused, >= 1.
};

/// A fabric mesh read from a file, or why not.
struct CAPE_CHARACTER_API FabricMeshFile {
  Status status;  ///< Why there is no mesh.
  /// The vertices welded by position (after node transforms and the scale, m: a UV seam's split vertices are
  /// one particle), the triangles counter-clockwise as the file has them (degenerate ones, with a repeated
  /// vertex after welding, dropped), UVs from the first channel with (0, 0) at the image's top-left
  /// (glTF's and WeightMap.h's convention: an OBJ's or PLY's v, which grows upwards, is flipped), or none.
  MeshDesc mesh;
  /// The first vertex-colour set's RGB, each in 0..1 (clamped), one per vertex of `mesh`; empty when the
  /// file has none. At a welded seam, the first vertex's colour.
  std::vector<Vec3> colours;
  int fileVertices = 0;      ///< Vertices the file's triangles use, before welding.
  int droppedTriangles = 0;  ///< Triangles dropped as degenerate after welding.
  /// True when the mesh was read.
  bool ok() const { return status.ok() && !mesh.positions.empty(); }
};

/// Reads every triangle of every mesh the file's node tree instances (node transforms applied), welds by
/// position and keeps UVs and colours as FabricMeshFile says. Never throws: FileNotFound for a path that is
/// not a readable regular file; InvalidArgument for options out of range; InvalidModel for an empty file, one
/// over 1 GiB, one assimp cannot read or whose scene fails its validation, no triangles, more than
/// maxTriangles, a vertex, UV or colour that is not finite, a vertex farther than 1e6 m from the origin, and
/// the COLLADA hazards loadMeshHull refuses. Build the fabric with Fabric::fromMesh(result.mesh).
CAPE_CHARACTER_API FabricMeshFile loadFabricMesh(const std::string& path,
                                                 const FabricMeshOptions& options = {});

}  // namespace cape::character
