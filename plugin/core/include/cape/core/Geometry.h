/// \file
/// Small geometric queries shared by the core and the Bullet adapter.
#pragma once

#include "cape/core/Export.h"
#include "cape/core/Types.h"

namespace cape {

/// The point of triangle (a, b, c) nearest to p, as barycentric weights (nearest = wa a + wb b + wc c), and
/// whether it lies inside the face rather than on an edge or a corner. Ericson, "Real-Time Collision
/// Detection" (2005), 5.1.5: the Voronoi regions of the vertices, the edges and the face. A degenerate
/// triangle gives its first corner.
struct TriangleNearest {
  /// The weights of corners a, b and c (their sum is 1).
  ///@{
  float wa, wb, wc;
  ///@}
  bool inFace;  ///< True inside the face, false on an edge or a corner.
};
/// The point of triangle (a, b, c) nearest to p (all in the same frame, m), as TriangleNearest describes.
CAPE_CORE_API TriangleNearest nearestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace cape
