// Triangle meshes of the collider shapes, for the glTF export and the renderer: each shape in its own local
// frame (Collider.h), with outward unit normals and counter-clockwise triangles seen from outside.
#pragma once

#include "cape/core/Collider.h"

#include <cstdint>
#include <vector>

namespace cape::demo {

struct ShapeMesh {
  std::vector<float> positions;        ///< x, y, z per vertex, m, in the collider's frame.
  std::vector<float> normals;          ///< x, y, z per vertex, unit, outward.
  std::vector<std::uint32_t> indices;  ///< 3 per triangle, counter-clockwise seen from outside.
  std::size_t vertexCount() const { return positions.size() / 3; }
};

/// The collider's true surface (sphere, capsule, cylinder, box) as triangles; `segments` around the axis
/// (>= 6). A plane gives a square of side 2 * planeHalfSize centred on the point of the plane nearest the
/// local origin.
ShapeMesh colliderMesh(const Collider& collider, int segments = 24, float planeHalfSize = 20.0f);

}  // namespace cape::demo
