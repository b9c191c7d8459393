// Fuzz target: a mesh file read through assimp into a simplified convex hull (MeshHull.h's loadMeshHull),
// from the fuzzer's bytes written to a file of this process. Input: one byte picks the format by the file's
// extension (stl, obj, dae), one the vertex budget (4 + 4 b: 4 to 1024), the rest is the file. Every bad
// file must come back as a Status; a hull that loads must keep MeshHull's promises (checked below).
#include "FuzzSupport.h"
#include "MeshHull.h"

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

namespace {

// MeshHull.h: 4 to maxVertices corners, not all in one plane; every plane a unit normal with every corner
// inside it; the rounding finite and >= 0; the counts of what was read.
void checkHull(const cape::character::MeshHull& h, int budget) {
  const int n = static_cast<int>(h.vertices.size());
  CAPE_FUZZ_CHECK(n >= 4 && n <= budget,
                  "hull of " + std::to_string(n) + " vertices, budget " + std::to_string(budget));
  CAPE_FUZZ_CHECK(h.planes.size() >= 4, "hull with fewer than 4 planes");
  CAPE_FUZZ_CHECK(std::isfinite(h.radius) && h.radius >= 0.0, "rounding " + std::to_string(h.radius));
  CAPE_FUZZ_CHECK(h.meshTriangles >= 1 && h.meshVertices >= 3, "counts of the mesh read");
  Eigen::Vector3d lo = h.vertices[0], hi = lo;
  for (const Eigen::Vector3d& v : h.vertices) {
    CAPE_FUZZ_CHECK(v.allFinite(), "a hull vertex is not finite");
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double size = (hi - lo).norm();
  CAPE_FUZZ_CHECK(size > 0.0, "a hull of no size");
  bool solid = false;
  for (const Eigen::Vector4d& p : h.planes) {
    const Eigen::Vector3d normal = p.head<3>();
    CAPE_FUZZ_CHECK(p.allFinite() && std::abs(normal.norm() - 1.0) < 1e-9, "a plane's normal is not a unit");
    double least = p[3];
    for (const Eigen::Vector3d& v : h.vertices) {
      // The offset is the largest n . v over the vertices, so none may be outside by more than rounding.
      CAPE_FUZZ_CHECK(normal.dot(v) <= p[3] + 1e-12 * (1.0 + std::abs(p[3])), "a vertex outside a plane");
      least = std::min(least, normal.dot(v));
    }
    if (p[3] - least > 1e-9 * size) solid = true;  // some vertex off this plane: not all in one plane
  }
  CAPE_FUZZ_CHECK(solid, "every vertex lies in one plane");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace cape::character;
  capefuzz::hugePagesForLargeBlocks();
  capefuzz::ByteReader in(data, size);
  const char* extension = capefuzz::meshExtension(in.u8());
  MeshHullOptions options;
  options.maxVertices = 4 + 4 * in.u8();
  const std::string path = (capefuzz::ScratchDir::path() / (std::string("mesh.") + extension)).string();
  capefuzz::writeFile(path, in.rest());
  clearMeshHullCache();  // the cache keys on size and time: a rewrite within the clock's tick would hit it
  const MeshHullResult r = loadMeshHull(path, Eigen::Vector3d::Ones(), options);
  if (r.ok())
    checkHull(*r.hull, options.maxVertices);
  else
    CAPE_FUZZ_CHECK(!r.status.ok() && r.hull == nullptr, "a failed load that says ok or gives a hull");
  return 0;
}
