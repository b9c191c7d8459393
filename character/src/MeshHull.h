// Internal: URDF `<mesh filename=... scale=...>` collision elements made into simplified convex hulls.
//
// resolveMeshUri turns the filename attribute into a path on disk; loadMeshHull reads the file with assimp
// (STL binary and ASCII, OBJ and COLLADA are the formats meant and tested; whatever else assimp reads is
// read the same way), takes the convex hull of every triangle's corners and simplifies it to a vertex
// budget, with a rounding radius that covers what the simplification cut off. Nothing throws and nothing
// crashes on a bad file: every failure is a Status (FileNotFound, InvalidModel for the file's content,
// InvalidArgument for the caller's values).
#pragma once

#include "cape/character/Status.h"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace cape::character {

struct MeshHullOptions {
  int maxVertices = 64;        ///< the simplified hull's vertex budget, 4 to 1024
  int maxTriangles = 2000000;  ///< larger meshes (every node instance counted) are refused, >= 1
};

/// A mesh's simplified convex hull, in the mesh file's frame with the scale applied, in metres (for COLLADA:
/// with its <unit meter> applied and its <up_axis> ignored, see loadMeshHull). Plain, immutable data.
struct MeshHull {
  /// The simplified hull's corners: at most maxVertices, at least 4 and not all in one plane. Each is a
  /// corner of the mesh (for a flat mesh: of its outline moved off the plane, see loadMeshHull).
  std::vector<Eigen::Vector3d> vertices;
  /// One per face of the hull spanned by `vertices`: outward unit normal n and offset d, inside where
  /// n . p <= d; every vertex satisfies it (the offset is the largest n . v over the vertices).
  std::vector<Eigen::Vector4d> planes;
  /// Rounding, m: the largest distance of any mesh vertex outside the hull, so that the hull grown by
  /// radius (its Minkowski sum with a ball) covers the whole mesh. 0 when no vertex is outside.
  double radius = 0.0;
  int meshVertices = 0;   ///< distinct vertex positions of the triangles loaded (every node instance)
  int meshTriangles = 0;  ///< triangles loaded (every node instance counted)
};

struct MeshHullResult {
  Status status;
  std::shared_ptr<const MeshHull> hull;  ///< null unless status is ok
  /// The file was refused for having more than MeshHullOptions::maxTriangles triangles (counting stops
  /// there).
  bool overTriangleLimit = false;
  bool ok() const { return status.ok() && hull != nullptr; }
};

/// URDF mesh URIs to a path on disk (absolute, lexically normalised; symbolic links are not followed):
/// - "package://NAME/rel/path": DIR/NAME/rel/path for each DIR in `packagePaths`, then for each entry of the
///   ROS_PACKAGE_PATH environment variable (colon separated, read at every call); DIR/rel/path is also
///   accepted when DIR's last component is NAME (DIR is the package folder itself). The first regular file
///   found wins.
/// - "file:///abs/path" (also "file://localhost/abs/path"); in both URI forms %XX escapes are decoded.
/// - an absolute path, or a path relative to `baseDir` (the URDF file's folder; the working directory when
///   empty).
/// FileNotFound names the URI and every place looked; InvalidArgument for an empty URI, a package URI
/// without a name or a path, and other schemes (http://, model://, ...).
Status resolveMeshUri(const std::string& uri, const std::string& baseDir,
                      const std::vector<std::string>& packagePaths, std::string& resolvedPath);

/// Loads every triangle of every mesh the file's node tree instances (node transforms applied; meshes no
/// node uses are left out, as renderers do), scales by `scale` (per axis, the URDF attribute), and makes the
/// simplified hull:
/// - scale components that are not finite and positive, and options out of range: InvalidArgument;
/// - a path that is not a readable regular file: FileNotFound;
/// - an empty file, a file over 1 GiB, one assimp cannot read or whose scene fails assimp's validation, no
///   triangles, more than maxTriangles, a vertex that is not finite or (scaled) farther than 1e6 m from the
///   origin, a mesh smaller than 1 nm, or all vertices on one line: InvalidModel naming the problem.
/// - COLLADA (what assimp may read as COLLADA: .dae, .zae, .xml, or "<collada" near the start) is checked
///   before assimp reads it, and refused (InvalidModel naming the byte) where Debian's assimp 5.2 would loop
///   or allocate without bound: a <p> or <vcount> list holding anything but digits, signs and white space, a
///   count attribute that is not a decimal number or exceeds the file's size, an array without a count, an
///   accessor reaching past its array, a control byte (UTF-16/32 text or a zip archive).
/// - A flat mesh (every vertex within 1e-5 of its size from one plane: a plate, a single triangle) is a
///   legitimate collision mesh: its vertices are moved off the plane by +-h along the plane's normal, h =
///   0.5 mm but at least 1e-4 and at most 1e-2 of the mesh's size, so the hull is a thin solid slab.
/// Results are cached process-wide (thread-safe) by canonical path, file size, modification time, scale and
/// options: a second load of an unchanged file returns the same object. A file rewritten with the same size
/// within the file system's timestamp granularity is not noticed; clearMeshHullCache() forgets everything.
MeshHullResult loadMeshHull(const std::string& path, const Eigen::Vector3d& scale,
                            const MeshHullOptions& options = {});

/// The checks made before assimp reads a file (the COLLADA hazards listed at loadMeshHull): success for any
/// file that is not read as COLLADA, else InvalidModel naming the problem.
Status precheckMeshFile(const std::string& path);

/// Empties loadMeshHull's cache (hulls already handed out stay valid: they are shared).
void clearMeshHullCache();

}  // namespace cape::character
