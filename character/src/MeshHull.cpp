// Mesh files to simplified convex hulls (MeshHull.h): URI resolution, reading with assimp, the hull with
// Bullet's btConvexHullComputer, the simplification to a vertex budget, and the process-wide cache.
#include "MeshHull.h"

#include <LinearMath/btConvexHullComputer.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <mutex>
#include <new>
#include <queue>
#include <tuple>
#include <utility>

namespace cape::character {

namespace {

namespace fs = std::filesystem;

constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 30;  // 1 GiB
constexpr double kMaxCoordinate = 1e6;                             // m, after the scale
constexpr double kMinSize = 1e-9;       // m: the smallest mesh (bounding-box diagonal)
constexpr double kFlatFraction = 1e-5;  // of the size: thinner than this is flat (a plate), thinner along a
                                        // line is a wire. Well above the ~6e-8 relative float rounding that
                                        // btConvexHullComputer works in, so its hulls are never degenerate.
constexpr double kStopFraction = 1e-6;  // of the size: points this close to the simplified hull are not
                                        // worth a vertex (the radius still covers them exactly)
constexpr int kMaxBudget = 1024;

// --- URIs
// ---------------------------------------------------------------------------------------------------

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// %XX escapes decoded; false for a broken escape or an escaped NUL.
bool percentDecode(const std::string& in, std::string& out) {
  out.clear();
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out += in[i];
      continue;
    }
    if (i + 2 >= in.size()) return false;
    const int hi = hexValue(in[i + 1]), lo = hexValue(in[i + 2]);
    if (hi < 0 || lo < 0 || (hi == 0 && lo == 0)) return false;
    out += static_cast<char>(hi * 16 + lo);
    i += 2;
  }
  return true;
}

std::string normalised(const fs::path& p) {
  std::error_code ec;
  fs::path a = fs::absolute(p, ec);
  if (ec) a = p;
  return a.lexically_normal().string();
}

bool isRegularFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

std::string lastComponent(const fs::path& dir) {
  fs::path n = dir.lexically_normal();
  if (n.filename().empty()) n = n.parent_path();
  return n.filename().string();
}

std::vector<std::string> rosPackagePath() {
  std::vector<std::string> dirs;
  const char* env = std::getenv("ROS_PACKAGE_PATH");
  if (env == nullptr) return dirs;
  const std::string s(env);
  std::size_t start = 0;
  while (start <= s.size()) {
    const std::size_t colon = std::min(s.find(':', start), s.size());
    if (colon > start) dirs.push_back(s.substr(start, colon - start));
    start = colon + 1;
  }
  return dirs;
}

std::string joined(const std::vector<std::string>& places) {
  std::string out;
  for (const std::string& p : places) {
    if (!out.empty()) out += ", ";
    out += "'" + p + "'";
  }
  return out;
}

// --- The hull
// -----------------------------------------------------------------------------------------------

using Vec3 = Eigen::Vector3d;

// A convex polytope over a point array, its faces stored flat (no allocation per face, and reused from one
// greedy step to the next).
struct Polytope {
  std::vector<int> vertices;  ///< indices into the point array
  // Per face (structure of arrays, so that the plane distances of all faces vectorise): the outward unit
  // normal (Newell's, over its loop) and the offset of the face's own plane (through the loop's centroid).
  std::vector<double> nx, ny, nz, offset;
  std::vector<double> support;  ///< per face: the largest normal . v over the vertices, the published offset
  std::vector<int> loopStart;   ///< face f's loop is loops[loopStart[f] .. loopStart[f + 1])
  std::vector<int> loops;       ///< indices into the point array, counter-clockwise seen from outside
  mutable std::vector<double>
      scratch;  ///< distanceOutside's plane distances (a polytope is used by one thread)
  std::size_t faceCount() const { return offset.size(); }
  Vec3 normal(std::size_t f) const { return Vec3(nx[f], ny[f], nz[f]); }
  void clear() {
    vertices.clear();
    nx.clear();
    ny.clear();
    nz.clear();
    offset.clear();
    support.clear();
    loopStart.assign(1, 0);
    loops.clear();
  }
};

// The convex hull of pts[subset] by btConvexHullComputer (exact integer arithmetic on the points rounded to
// btScalar, which is float here: the points are centred first so that only their spread is rounded). Its
// faces are polygons (coplanar triangles merged). The geometry is then taken in double from the original
// points it names (original_vertex_index), and each face's published offset is the largest n . v over all
// vertices, so that every vertex is inside every plane whatever the rounding. False when the hull is not a
// solid.
bool buildPolytope(const std::vector<Vec3>& pts, const std::vector<int>& subset, Polytope& out) {
  out.clear();
  if (subset.size() < 4) return false;
  Vec3 lo = pts[static_cast<std::size_t>(subset[0])], hi = lo;
  for (int i : subset) {
    lo = lo.cwiseMin(pts[static_cast<std::size_t>(i)]);
    hi = hi.cwiseMax(pts[static_cast<std::size_t>(i)]);
  }
  const Vec3 centre = 0.5 * (lo + hi);
  std::vector<double> coords(3 * subset.size());
  for (std::size_t k = 0; k < subset.size(); ++k) {
    const Vec3 p = pts[static_cast<std::size_t>(subset[k])] - centre;
    coords[3 * k] = p.x();
    coords[3 * k + 1] = p.y();
    coords[3 * k + 2] = p.z();
  }
  btConvexHullComputer chc;
  chc.compute(coords.data(), static_cast<int>(3 * sizeof(double)), static_cast<int>(subset.size()), 0, 0);
  const int nv = chc.vertices.size();
  if (nv < 4 || chc.faces.size() < 4 || chc.original_vertex_index.size() != nv) return false;
  Vec3 mean = Vec3::Zero();
  for (int k = 0; k < nv; ++k) {
    const int o = chc.original_vertex_index[k];
    if (o < 0 || o >= static_cast<int>(subset.size())) return false;
    out.vertices.push_back(subset[static_cast<std::size_t>(o)]);
    mean += pts[static_cast<std::size_t>(out.vertices.back())];
  }
  mean /= nv;
  for (int f = 0; f < chc.faces.size(); ++f) {
    const std::size_t first = out.loops.size();
    const btConvexHullComputer::Edge* start = &chc.edges[chc.faces[f]];
    const btConvexHullComputer::Edge* e = start;
    do {
      out.loops.push_back(out.vertices[static_cast<std::size_t>(e->getSourceVertex())]);
      e = e->getNextEdgeOfFace();
    } while (e != start && out.loops.size() - first <= static_cast<std::size_t>(chc.edges.size()));
    const std::size_t m = out.loops.size() - first;
    Vec3 c = Vec3::Zero();
    for (std::size_t i = first; i < out.loops.size(); ++i) c += pts[static_cast<std::size_t>(out.loops[i])];
    c /= static_cast<double>(std::max<std::size_t>(m, 1));
    Vec3 n = Vec3::Zero();
    for (std::size_t i = 0; i < m; ++i) {
      const Vec3& a = pts[static_cast<std::size_t>(out.loops[first + i])];
      const Vec3& b = pts[static_cast<std::size_t>(out.loops[first + (i + 1) % m])];
      n += (a - c).cross(b - c);
    }
    const double len = n.norm();
    if (m < 3 || !(len > 0.0) ||
        !std::isfinite(len)) {  // a sliver the rounding made: its neighbours bound it
      out.loops.resize(first);
      continue;
    }
    n /= len;
    if (n.dot(mean - c) > 0.0) {  // keep the outward side (the vertices' mean is inside a solid)
      n = -n;
      std::reverse(out.loops.begin() + static_cast<std::ptrdiff_t>(first), out.loops.end());
    }
    double support = -std::numeric_limits<double>::infinity();
    for (int v : out.vertices) support = std::max(support, n.dot(pts[static_cast<std::size_t>(v)]));
    out.nx.push_back(n.x());
    out.ny.push_back(n.y());
    out.nz.push_back(n.z());
    out.offset.push_back(n.dot(c));
    out.support.push_back(support);
    out.loopStart.push_back(static_cast<int>(out.loops.size()));
  }
  return out.faceCount() >= 4;
}

double segmentDistance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

// Distance from p, `above` face f's own plane (> 0), to the face polygon: to the plane when p's projection
// falls inside the polygon, else to the nearest edge.
double faceDistance(const Polytope& poly, std::size_t f, const std::vector<Vec3>& pts, const Vec3& p,
                    double above) {
  const Vec3 n = poly.normal(f);
  const Vec3 q = p - above * n;
  const int* loop = poly.loops.data() + poly.loopStart[f];
  const std::size_t m = static_cast<std::size_t>(poly.loopStart[f + 1] - poly.loopStart[f]);
  bool inside = true;
  for (std::size_t i = 0; i < m && inside; ++i) {
    const Vec3& a = pts[static_cast<std::size_t>(loop[i])];
    const Vec3& b = pts[static_cast<std::size_t>(loop[(i + 1) % m])];
    inside = (b - a).cross(q - a).dot(n) >= 0.0;
  }
  if (inside) return above;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < m; ++i)
    best = std::min(best, segmentDistance(p, pts[static_cast<std::size_t>(loop[i])],
                                          pts[static_cast<std::size_t>(loop[(i + 1) % m])]));
  return best;
}

// The Euclidean distance from p to the polytope, 0 inside. The nearest point of a convex polytope to an
// outside point lies on a face that the point is above (the offset p - nearest is in the normal cone there),
// so only those faces are measured, and a face no nearer than the best so far (its plane distance is a lower
// bound) is skipped.
double distanceOutside(const Polytope& poly, const std::vector<Vec3>& pts, const Vec3& p) {
  const std::size_t faces = poly.faceCount();
  std::vector<double>& above = poly.scratch;
  above.resize(faces);
  const double x = p.x(), y = p.y(), z = p.z();
  for (std::size_t f = 0; f < faces; ++f)
    above[f] = poly.nx[f] * x + poly.ny[f] * y + poly.nz[f] * z - poly.offset[f];
  double best = std::numeric_limits<double>::infinity();
  bool outside = false;
  for (std::size_t f = 0; f < faces; ++f) {
    if (!(above[f] > 0.0)) continue;
    outside = true;
    if (above[f] < best) best = std::min(best, faceDistance(poly, f, pts, p, above[f]));
  }
  return outside ? best : 0.0;
}

// The simplification: greedy farthest point insertion. Start from a tetrahedron of extreme points and add,
// one at a time, the point farthest (Euclidean) outside the hull of those kept, until the budget is spent or
// every point is within `tol` of that hull. Each step removes the largest error there is, the error left is
// exactly what the radius has to cover, and the kept points are corners of the mesh, so the simplified hull
// never sticks out of the mesh's own hull. Ties go to the lower index, so the result depends only on the
// points (same file, same bits).
//
// The farthest point is found lazily: a point's distance to a growing hull never increases, so a distance
// measured against an earlier hull is an upper bound, and the top of a max-heap is re-measured until it is
// current; the result is the same as measuring every point at every step. The same bound gives `radius`,
// the largest distance of any point from the final hull, without measuring every point again: the points
// left in the heap are re-measured from the top down until the next bound is below the largest found, and
// the points set aside as within `tol` are measured again.
bool simplify(const std::vector<Vec3>& pts, std::vector<int> kept, int maxVertices, double tol,
              Polytope& result, double& radius) {
  const int n = static_cast<int>(pts.size());
  radius = 0.0;
  if (n <= maxVertices) {
    kept.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) kept[static_cast<std::size_t>(i)] = i;
    if (!buildPolytope(pts, kept, result)) return false;
    for (const Vec3& p : pts) radius = std::max(radius, distanceOutside(result, pts, p));
    return true;
  }
  Polytope& poly = result;
  if (!buildPolytope(pts, kept, poly)) return false;
  std::vector<char> isKept(static_cast<std::size_t>(n), 0);
  for (int i : kept) isKept[static_cast<std::size_t>(i)] = 1;
  struct Candidate {
    double distance;
    int index;
    int stamp;  ///< the hull (number of insertions) the distance was measured against
  };
  const auto lower = [](const Candidate& x, const Candidate& y) {
    return x.distance < y.distance || (x.distance == y.distance && x.index > y.index);
  };
  std::vector<Candidate> initial;
  // Points measured within tol of the hull at some step (or not insertable): measured again at the end. A
  // point inside a hull is inside every later one and drops out for good.
  std::vector<int> setAside;
  for (int i = 0; i < n; ++i) {
    if (isKept[static_cast<std::size_t>(i)]) continue;
    const double d = distanceOutside(poly, pts, pts[static_cast<std::size_t>(i)]);
    if (d > tol) {
      initial.push_back({d, i, 0});
    } else if (d > 0.0) {
      setAside.push_back(i);
    }
  }
  std::priority_queue<Candidate, std::vector<Candidate>, decltype(lower)> heap(lower, std::move(initial));
  Polytope next;
  int stamp = 0;
  while (!heap.empty()) {
    const Candidate top = heap.top();
    const bool full = static_cast<int>(kept.size()) >= maxVertices;
    if (full && top.distance <= radius) break;  // no point left can be farther than the largest found
    heap.pop();
    if (top.stamp != stamp) {
      const double d = distanceOutside(poly, pts, pts[static_cast<std::size_t>(top.index)]);
      if (d > tol) {
        heap.push({d, top.index, stamp});
      } else if (d > 0.0) {
        setAside.push_back(top.index);
      }
      continue;
    }
    if (full) {  // the final hull: this is a current distance
      radius = std::max(radius, top.distance);
      continue;
    }
    kept.push_back(top.index);
    if (!buildPolytope(pts, kept, next)) {  // not seen when rounded to float: left to the radius
      kept.pop_back();
      setAside.push_back(top.index);
      continue;
    }
    std::swap(poly, next);
    ++stamp;
  }
  for (int i : setAside)
    radius = std::max(radius, distanceOutside(poly, pts, pts[static_cast<std::size_t>(i)]));
  return true;
}

Status invalidModel(const std::string& path, const std::string& what) {
  return Status::error(ErrorCode::InvalidModel, "mesh file '" + path + "': " + what);
}

// The hull of the mesh points (distinct, in metres) into `out`.
Status makeHull(const std::string& path, const std::vector<Vec3>& mesh, int maxVertices, MeshHull& out) {
  Vec3 lo = mesh[0], hi = mesh[0];
  for (const Vec3& p : mesh) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double size = (hi - lo).norm();
  if (!(size >= kMinSize)) return invalidModel(path, "the mesh is smaller than 1 nm (after the scale)");
  // A tetrahedron of extreme points: the farthest pair among the six axis extremes, the point farthest from
  // their line, and the point farthest from the plane of the three.
  std::array<int, 6> extreme{};
  for (int i = 0; i < static_cast<int>(mesh.size()); ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      if (mesh[static_cast<std::size_t>(i)][axis] < mesh[static_cast<std::size_t>(extreme[2 * axis])][axis])
        extreme[2 * axis] = i;
      if (mesh[static_cast<std::size_t>(i)][axis] >
          mesh[static_cast<std::size_t>(extreme[2 * axis + 1])][axis])
        extreme[2 * axis + 1] = i;
    }
  }
  int a = extreme[0], b = extreme[1];
  double far = -1.0;
  for (int i : extreme) {
    for (int j : extreme) {
      const double d = (mesh[static_cast<std::size_t>(i)] - mesh[static_cast<std::size_t>(j)]).norm();
      if (d > far) {
        far = d;
        a = i;
        b = j;
      }
    }
  }
  const Vec3 pa = mesh[static_cast<std::size_t>(a)];
  const Vec3 u = (mesh[static_cast<std::size_t>(b)] - pa).normalized();
  int c = a;
  double dc = -1.0;
  for (int i = 0; i < static_cast<int>(mesh.size()); ++i) {
    const Vec3 r = mesh[static_cast<std::size_t>(i)] - pa;
    const double d = (r - r.dot(u) * u).norm();
    if (d > dc) {
      dc = d;
      c = i;
    }
  }
  if (!(dc > kFlatFraction * size))
    return invalidModel(path, "all its vertices lie on one line: a wire has no surface to collide with");
  const Vec3 normal = u.cross(mesh[static_cast<std::size_t>(c)] - pa).normalized();
  int d4 = a;
  double dd = -1.0;
  for (int i = 0; i < static_cast<int>(mesh.size()); ++i) {
    const double d = std::abs(normal.dot(mesh[static_cast<std::size_t>(i)] - pa));
    if (d > dd) {
      dd = d;
      d4 = i;
    }
  }
  // A flat mesh is a plate: moved off its plane to both sides it becomes a thin slab, a solid that every
  // consumer of hulls takes (the core's hulls and btConvexHullShape want corners not all in one plane).
  std::vector<Vec3> slab;
  const bool flat = !(dd > kFlatFraction * size);
  if (flat) {
    const double h = std::clamp(0.5e-3, 1e-4 * size, 1e-2 * size);
    slab.reserve(2 * mesh.size());
    for (const Vec3& p : mesh) {
      slab.push_back(p + h * normal);
      slab.push_back(p - h * normal);
    }
  }
  const std::vector<Vec3>& pts = flat ? slab : mesh;
  const std::vector<int> tetrahedron =
      flat ? std::vector<int>{2 * a, 2 * b, 2 * c, 2 * a + 1} : std::vector<int>{a, b, c, d4};
  Polytope hull;
  double radius = 0.0;
  if (!simplify(pts, tetrahedron, maxVertices, kStopFraction * size, hull, radius))
    return invalidModel(path, "no convex hull could be made of its vertices");
  out.vertices.clear();
  out.planes.clear();
  for (int v : hull.vertices) out.vertices.push_back(pts[static_cast<std::size_t>(v)]);
  for (std::size_t f = 0; f < hull.faceCount(); ++f)
    out.planes.emplace_back(hull.nx[f], hull.ny[f], hull.nz[f], hull.support[f]);
  // The rounding that covers the whole mesh: the simplification measured its points; a plate's are the mesh's
  // vertices moved off the plane, so its mesh is measured here.
  out.radius = radius;
  if (flat) {
    out.radius = 0.0;
    for (const Vec3& p : mesh) out.radius = std::max(out.radius, distanceOutside(hull, pts, p));
  }
  return Status::success();
}

// --- Reading
// ------------------------------------------------------------------------------------------------

// Distinct points by exact position, in the order first met: an open-addressing table of indices, so that
// only the distinct points are stored (a triangle soup, as STL is, repeats each corner about six times).
class DistinctPoints {
 public:
  explicit DistinctPoints(std::vector<Vec3>& out) : out_(out), table_(1024, -1) {}
  void insert(const Vec3& raw) {
    const Vec3 p = raw.array() + 0.0;  // -0 is +0
    if (2 * (out_.size() + 1) > table_.size()) grow();
    const std::size_t mask = table_.size() - 1;
    for (std::size_t h = hash(p) & mask;; h = (h + 1) & mask) {
      const int at = table_[h];
      if (at < 0) {
        table_[h] = static_cast<int>(out_.size());
        out_.push_back(p);
        return;
      }
      if (out_[static_cast<std::size_t>(at)] == p) return;
    }
  }

 private:
  static std::size_t hash(const Vec3& p) {
    std::uint64_t h = 0;
    for (int k = 0; k < 3; ++k) {
      std::uint64_t u = 0;
      std::memcpy(&u, &p[k], sizeof u);
      h = (h ^ u) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 29;
    }
    return static_cast<std::size_t>(h);
  }
  void grow() {
    table_.assign(2 * table_.size(), -1);
    const std::size_t mask = table_.size() - 1;
    for (std::size_t i = 0; i < out_.size(); ++i) {
      std::size_t h = hash(out_[i]) & mask;
      while (table_[h] >= 0) h = (h + 1) & mask;
      table_[h] = static_cast<int>(i);
    }
  }
  std::vector<Vec3>& out_;
  std::vector<int> table_;
};

Eigen::Matrix4d toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d t;
  t << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return t;
}

// --- COLLADA text checked before assimp
// ------------------------------------------------------------------------------------------------
//
// Debian's assimp 5.2 reads a <p> index list (ColladaParser::ReadPrimitives) in a loop that ends only at the
// text's end: each turn reads an integer (strtol10, which consumes a sign and digits) and skips spaces, tabs
// and line ends. Any other character (a letter, '.', '*', a control byte, a character reference that
// pugixml decodes) is consumed by neither, so the loop appends 0 indices until an allocation fails: 257 s
// for a 1 KB file in Release. The post-processing steps play no part (it hangs the same with none). So a
// file that assimp may read as COLLADA is checked here first, in one linear pass over its text, and refused
// when assimp would loop or reserve without bound.

bool isXmlSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

// What the index list reader consumes: digits and signs (strtol10), spaces, tabs and line ends.
bool isIndexListChar(char c) {
  return (c >= '0' && c <= '9') || c == '+' || c == '-' || isXmlSpace(c);
}

std::string describeByte(char c) {
  static const char* const hex = "0123456789abcdef";
  const unsigned u = static_cast<unsigned char>(c);
  std::string out = "byte 0x";
  out += hex[u >> 4];
  out += hex[u & 15];
  if (u > 32 && u < 127) out += std::string(" '") + c + "'";
  return out;
}

// Whether assimp 5.2 may read the file as COLLADA: its ColladaLoader::CanRead takes the extensions dae, zae
// and xml, a file with "<collada" in its first 200 bytes (NUL bytes dropped, any case) when no reader before
// it claims the file, and a zip archive holding COLLADA (.zae). All of those are checked here (more than
// assimp reads as COLLADA, never less). A file without an extension is taken by its content, as assimp
// does (a binary STL without one is read by assimp's STL reader, and still is).
bool readAsCollada(const std::string& path, const std::string& head) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".dae" || ext == ".zae" || ext == ".xml") return true;
  if (startsWith(head, "PK")) return true;
  std::string h;
  for (char c : head)
    if (c != '\0') h += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return h.find("<collada") != std::string::npos;
}

// The element starting at text[at] ('<') is named `name` (not a longer name with the same start).
bool elementNamed(const std::string& text, std::size_t at, const char* name) {
  const std::size_t n = std::strlen(name);
  if (text.compare(at + 1, n, name) != 0 || at + 1 + n >= text.size()) return false;
  const char next = text[at + 1 + n];
  return next == '>' || next == '/' || isXmlSpace(next);
}

// The value of attribute `name` in the start tag text[at .. close], false when it has none.
bool attributeOf(const std::string& text, std::size_t at, std::size_t close, const std::string& name,
                 std::string& value) {
  for (std::size_t i = text.find(name, at); i != std::string::npos && i < close; i = text.find(name, i + 1)) {
    if (!isXmlSpace(text[i - 1])) continue;
    std::size_t j = i + name.size();
    while (j < close && isXmlSpace(text[j])) ++j;
    if (j >= close || text[j] != '=') continue;
    ++j;
    while (j < close && isXmlSpace(text[j])) ++j;
    if (j >= close || (text[j] != '"' && text[j] != '\'')) continue;
    const std::size_t end = text.find(text[j], j + 1);
    if (end == std::string::npos || end > close) return false;
    value = text.substr(j + 1, end - j - 1);
    return true;
  }
  return false;
}

// A plain decimal number (white space around it allowed), capped just above `cap`; false for anything else.
bool plainNumber(const std::string& s, std::uintmax_t cap, std::uintmax_t& value) {
  std::size_t i = 0, digits = 0;
  while (i < s.size() && isXmlSpace(s[i])) ++i;
  value = 0;
  for (; i < s.size() && s[i] >= '0' && s[i] <= '9'; ++i, ++digits)
    if (value <= cap) value = 10 * value + static_cast<std::uintmax_t>(s[i] - '0');
  while (i < s.size() && isXmlSpace(s[i])) ++i;
  return digits > 0 && i == s.size();
}

Status checkColladaText(const std::string& path, const std::string& text) {
  const auto refuse = [&](std::size_t at, const std::string& what) {
    return invalidModel(path,
                        "COLLADA refused before assimp reads it (Debian's assimp 5.2 would loop or "
                        "allocate without bound on it): " +
                            what + " at byte " + std::to_string(at));
  };
  // XML allows no control byte but tab, line feed and carriage return. One here is UTF-16 or UTF-32 text or
  // a zip archive (.zae), which assimp would convert or unpack unseen by these checks.
  for (std::size_t i = 0; i < text.size(); ++i) {
    const unsigned char u = static_cast<unsigned char>(text[i]);
    if (u < 32 && u != '\t' && u != '\n' && u != '\r')
      return refuse(i,
                    describeByte(text[i]) +
                        " (XML text has no control bytes; UTF-16, UTF-32 and zipped COLLADA are not read)");
  }
  // Every count="N" (arrays, accessors, primitives, skins): assimp reserves and reads N items, and each item
  // takes at least one byte of the file, so a count beyond the file's size is refused. Strictly digits, as
  // every exporter writes them (pugixml would also read hex, signs and character references).
  for (std::size_t at = text.find("count"); at != std::string::npos; at = text.find("count", at + 1)) {
    if (at == 0 || !isXmlSpace(text[at - 1])) continue;
    std::size_t i = at + 5;
    while (i < text.size() && isXmlSpace(text[i])) ++i;
    if (i >= text.size() || text[i] != '=') continue;
    ++i;
    while (i < text.size() && isXmlSpace(text[i])) ++i;
    if (i >= text.size() || (text[i] != '"' && text[i] != '\'')) continue;
    const char quote = text[i++];
    while (i < text.size() && isXmlSpace(text[i])) ++i;
    std::uintmax_t value = 0;
    std::size_t digits = 0;
    for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i, ++digits)
      if (value <= text.size()) value = 10 * value + static_cast<std::uintmax_t>(text[i] - '0');
    while (i < text.size() && isXmlSpace(text[i])) ++i;
    if (digits == 0 || i >= text.size() || text[i] != quote)
      return refuse(at, "a count attribute that is not a plain decimal number");
    if (value > text.size())
      return refuse(at, "a count attribute larger than the file (" + std::to_string(text.size()) + " bytes)");
  }
  // Every <p> and <vcount> list: only what the reader consumes, up to its own end tag (no comments, CDATA,
  // character references or elements inside). The sum of a <vcount> list (corners, each needing an index in
  // the file) is bounded by the file's size like a count.
  for (std::size_t at = text.find('<'); at != std::string::npos; at = text.find('<', at + 1)) {
    const bool isP = elementNamed(text, at, "p");
    if (!isP && !elementNamed(text, at, "vcount")) continue;
    const char* name = isP ? "p" : "vcount";
    const std::size_t close = text.find('>', at);
    if (close == std::string::npos) return refuse(at, std::string("an unclosed <") + name + "> tag");
    if (text[close - 1] == '/') continue;  // <p/>: empty
    std::uintmax_t sum = 0, value = 0;
    std::size_t i = close + 1;
    for (; i < text.size() && text[i] != '<'; ++i) {
      const char c = text[i];
      if (!isIndexListChar(c))
        return refuse(i, describeByte(c) + " in a <" + name + "> list (only digits, signs and white space)");
      if (c >= '0' && c <= '9') {
        if (value <= text.size()) value = 10 * value + static_cast<std::uintmax_t>(c - '0');
      } else {
        sum += std::min<std::uintmax_t>(value, text.size() + 1);
        value = 0;
      }
    }
    sum += std::min<std::uintmax_t>(value, text.size() + 1);
    if (i >= text.size() || text.compare(i, 2 + std::strlen(name), std::string("</") + name) != 0)
      return refuse(i, std::string("a <") + name + "> list that holds anything but its numbers");
    if (!isP && sum > text.size())
      return refuse(close + 1, "a <vcount> list whose corners outnumber the file's bytes");
    at = i;
  }
  // Arrays and the accessors that read them: assimp 5.2 reads an array's `count` values (none without the
  // attribute) and then indexes it through an accessor without checking that the accessor fits (a float_array
  // without its count segfaults). So every array has a count, and every accessor of a known array keeps
  // offset + count * stride within it.
  std::map<std::string, std::uintmax_t> arrays;
  for (const char* name : {"float_array", "int_array", "bool_array", "Name_array", "IDREF_array"}) {
    for (std::size_t at = text.find(std::string("<") + name); at != std::string::npos;
         at = text.find(std::string("<") + name, at + 1)) {
      if (!elementNamed(text, at, name)) continue;
      const std::size_t close = text.find('>', at);
      if (close == std::string::npos) return refuse(at, std::string("an unclosed <") + name + "> tag");
      std::string id, count;
      std::uintmax_t n = 0;
      if (!attributeOf(text, at, close, "count", count) || !plainNumber(count, text.size(), n))
        return refuse(at, std::string("a <") + name + "> without a plain decimal count");
      if (attributeOf(text, at, close, "id", id)) arrays[id] = n;
    }
  }
  for (std::size_t at = text.find("<accessor"); at != std::string::npos;
       at = text.find("<accessor", at + 1)) {
    if (!elementNamed(text, at, "accessor")) continue;
    const std::size_t close = text.find('>', at);
    if (close == std::string::npos) return refuse(at, "an unclosed <accessor> tag");
    std::string source, attr;
    if (!attributeOf(text, at, close, "source", source) || source.empty() || source[0] != '#') continue;
    const auto array = arrays.find(source.substr(1));
    if (array == arrays.end()) continue;  // assimp refuses a reference it cannot resolve
    std::uintmax_t count = 0, stride = 1, offset = 0;
    const std::uintmax_t cap = text.size();
    if ((attributeOf(text, at, close, "count", attr) && !plainNumber(attr, cap, count)) ||
        (attributeOf(text, at, close, "stride", attr) && !plainNumber(attr, cap, stride)) ||
        (attributeOf(text, at, close, "offset", attr) && !plainNumber(attr, cap, offset)))
      return refuse(at, "an <accessor> whose count, stride or offset is not a plain decimal number");
    const std::uintmax_t size = array->second;  // <= the file's size, so the product below cannot overflow
    if (count > 0 && (count > size || stride > size || offset > size || offset + count * stride > size))
      return refuse(at, "an <accessor> reaching past the end of its array '" + array->first + "'");
  }
  return Status::success();
}

// A file that assimp would read as COLLADA, checked (checkColladaText); any other passes.
Status precheck(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(200, '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  if (!readAsCollada(path, head)) return Status::success();
  in.clear();
  in.seekg(0);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return invalidModel(path, "it cannot be read");
  return checkColladaText(path, text);
}

// The file's triangles' corners, node transforms and scale applied, as distinct points.
Status readMesh(const std::string& path, const Vec3& scale, const MeshHullOptions& options,
                std::vector<Vec3>& points, int& triangles, bool& overTriangleLimit) {
  overTriangleLimit = false;
  if (Status checked = precheck(path); !checked.ok()) return checked;
  Assimp::Importer importer;
  // COLLADA: assimp puts the <unit meter> scale and the <up_axis> rotation to its Y-up convention into the
  // root node's transform. URDF consumers (RViz skips the root node's transform and applies <unit meter>
  // itself; Gazebo's own COLLADA reader applies the unit and not the axis) show a mesh in the link frame in
  // metres with its up axis ignored, so: the up axis is ignored here and the root transform, then the unit
  // scale alone, is applied like every other node transform. A Z_UP file therefore reads as written (and a
  // Y_UP one is not turned either, as in RViz).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  // A scene without meshes gets no made-up skeleton geometry.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  // Triangulate: polygons to triangles, so the count is of triangles; ValidateDataStructure: assimp checks
  // the scene (indices in range, counts consistent) and rejects a broken one. Nothing that moves, welds,
  // rescales or reorients vertices (no JoinIdenticalVertices, which welds by all attributes: the points are
  // made distinct below by position alone; no PreTransformVertices, GlobalScale, MakeLeftHanded).
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  if (scene == nullptr)
    return invalidModel(path, std::string("assimp cannot read it: ") + importer.GetErrorString());
  if (scene->mRootNode == nullptr) return invalidModel(path, "assimp read no scene graph");
  points.clear();
  DistinctPoints distinct(points);
  triangles = 0;
  std::vector<std::pair<const aiNode*, Eigen::Matrix4d>> stack{
      {scene->mRootNode, Eigen::Matrix4d::Identity()}};
  std::vector<char> used;
  while (!stack.empty()) {
    const aiNode* node = stack.back().first;
    const Eigen::Matrix4d world = stack.back().second * toEigen(node->mTransformation);
    stack.pop_back();
    for (unsigned k = 0; k < node->mNumChildren; ++k)
      if (node->mChildren[k] != nullptr) stack.emplace_back(node->mChildren[k], world);
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      if (node->mMeshes[k] >= scene->mNumMeshes)
        return invalidModel(path, "a node names a mesh that is not there");
      const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
      if (mesh == nullptr || mesh->mVertices == nullptr || mesh->mFaces == nullptr) continue;
      used.assign(mesh->mNumVertices, 0);
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        if (face.mNumIndices != 3 || face.mIndices == nullptr) continue;  // points and lines
        if (triangles >= options.maxTriangles) {
          overTriangleLimit = true;
          return invalidModel(path, "more than " + std::to_string(options.maxTriangles) +
                                        " triangles (every node instance counted): refused");
        }
        ++triangles;
        for (unsigned i = 0; i < 3; ++i) {
          if (face.mIndices[i] >= mesh->mNumVertices)
            return invalidModel(path, "a face index is out of range");
          used[face.mIndices[i]] = 1;
        }
      }
      for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
        if (!used[v]) continue;
        const aiVector3D& raw = mesh->mVertices[v];
        if (!std::isfinite(raw.x) || !std::isfinite(raw.y) || !std::isfinite(raw.z))
          return invalidModel(path, "a vertex is not a finite number");
        const Vec3 p =
            (world.topLeftCorner<3, 3>() * Vec3(raw.x, raw.y, raw.z) + world.topRightCorner<3, 1>())
                .cwiseProduct(scale);
        if (!p.allFinite() || p.cwiseAbs().maxCoeff() > kMaxCoordinate)
          return invalidModel(path,
                              "a vertex lies farther than 1e6 m from the origin (after node transforms and "
                              "the scale)");
        distinct.insert(p);
      }
    }
  }
  if (triangles == 0) return invalidModel(path, "it has no triangles");
  return Status::success();
}

// --- The cache
// ----------------------------------------------------------------------------------------------

std::uint64_t bitsOf(double x) {
  std::uint64_t u = 0;
  std::memcpy(&u, &x, sizeof u);
  return u;
}

using CacheKey = std::tuple<std::string, std::uint64_t, std::uint64_t, std::uint64_t, int, int>;
struct CacheEntry {
  std::uintmax_t size = 0;
  std::int64_t mtime = 0;
  std::shared_ptr<const MeshHull> hull;
};

std::mutex& cacheMutex() {
  static std::mutex m;
  return m;
}

std::map<CacheKey, CacheEntry>& cache() {
  static std::map<CacheKey, CacheEntry> c;
  return c;
}

MeshHullResult loadUncaught(const std::string& path, const Vec3& scale, const MeshHullOptions& options) {
  if (!scale.allFinite() || !(scale.minCoeff() > 0.0))
    return {Status::error(ErrorCode::InvalidArgument, "mesh scale must be finite and positive on every axis"),
            nullptr};
  if (options.maxVertices < 4 || options.maxVertices > kMaxBudget)
    return {Status::error(ErrorCode::InvalidArgument, "MeshHullOptions::maxVertices must be 4 to 1024, not " +
                                                          std::to_string(options.maxVertices)),
            nullptr};
  if (options.maxTriangles < 1)
    return {Status::error(ErrorCode::InvalidArgument, "MeshHullOptions::maxTriangles must be at least 1"),
            nullptr};
  // Stat before reading, so that a file changed meanwhile is read again next time.
  std::error_code ec;
  const bool regular = fs::is_regular_file(path, ec);
  if (!regular || !std::ifstream(path, std::ios::binary))
    return {Status::error(ErrorCode::FileNotFound, "mesh file '" + path + "' is not a readable regular file"),
            nullptr};
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec)
    return {Status::error(ErrorCode::FileNotFound, "mesh file '" + path + "': " + ec.message()), nullptr};
  if (size == 0) return {invalidModel(path, "the file is empty"), nullptr};
  if (size > kMaxFileBytes) return {invalidModel(path, "the file is larger than 1 GiB: refused"), nullptr};
  const std::int64_t mtime =
      static_cast<std::int64_t>(fs::last_write_time(path, ec).time_since_epoch().count());
  fs::path canonical = fs::canonical(path, ec);
  const CacheKey key{ec ? normalised(path) : canonical.string(),
                     bitsOf(scale.x()),
                     bitsOf(scale.y()),
                     bitsOf(scale.z()),
                     options.maxVertices,
                     options.maxTriangles};
  {
    std::lock_guard<std::mutex> lock(cacheMutex());
    const auto it = cache().find(key);
    if (it != cache().end() && it->second.size == size && it->second.mtime == mtime)
      return {Status::success(), it->second.hull};
  }
  // Read and build outside the lock: other threads' loads go on meanwhile.
  std::vector<Vec3> points;
  auto hull = std::make_shared<MeshHull>();
  bool overTriangleLimit = false;
  Status status = readMesh(path, scale, options, points, hull->meshTriangles, overTriangleLimit);
  if (!status.ok()) return {status, nullptr, overTriangleLimit};
  hull->meshVertices = static_cast<int>(points.size());
  status = makeHull(path, points, options.maxVertices, *hull);
  if (!status.ok()) return {status, nullptr};
  std::lock_guard<std::mutex> lock(cacheMutex());
  CacheEntry& entry = cache()[key];
  if (entry.hull != nullptr && entry.size == size && entry.mtime == mtime)
    return {Status::success(), entry.hull};
  entry = CacheEntry{size, mtime, hull};
  return {Status::success(), hull};
}

}  // namespace

Status precheckMeshFile(const std::string& path) {
  return precheck(path);
}

Status resolveMeshUri(const std::string& uri, const std::string& baseDir,
                      const std::vector<std::string>& packagePaths, std::string& resolvedPath) {
  resolvedPath.clear();
  if (uri.empty()) return Status::error(ErrorCode::InvalidArgument, "empty mesh URI");
  std::vector<std::string> looked;
  const auto found = [&](const fs::path& p) {
    looked.push_back(normalised(p));
    if (!isRegularFile(p)) return false;
    resolvedPath = looked.back();
    return true;
  };
  const std::string packageScheme = "package://", fileScheme = "file://";
  if (startsWith(uri, packageScheme)) {
    std::string rest;
    if (!percentDecode(uri.substr(packageScheme.size()), rest))
      return Status::error(ErrorCode::InvalidArgument, "mesh URI '" + uri + "' has a broken %-escape");
    const std::size_t slash = rest.find('/');
    std::string rel = slash == std::string::npos ? std::string() : rest.substr(slash + 1);
    while (!rel.empty() && rel.front() == '/') rel.erase(0, 1);
    if (slash == 0 || slash == std::string::npos || rel.empty())
      return Status::error(ErrorCode::InvalidArgument,
                           "mesh URI '" + uri + "' needs a package name and a path: package://NAME/path");
    const std::string name = rest.substr(0, slash);
    std::vector<std::string> dirs = packagePaths;
    for (std::string& d : rosPackagePath()) dirs.push_back(std::move(d));
    for (const std::string& dir : dirs) {
      if (dir.empty()) continue;
      if (found(fs::path(dir) / name / rel)) return Status::success();
      if (lastComponent(dir) == name && found(fs::path(dir) / rel)) return Status::success();
    }
    if (looked.empty())
      return Status::error(ErrorCode::FileNotFound,
                           "mesh '" + uri +
                               "' not found: no package paths given and ROS_PACKAGE_PATH "
                               "is not set");
    return Status::error(ErrorCode::FileNotFound,
                         "mesh '" + uri + "' not found; looked at " + joined(looked));
  }
  if (startsWith(uri, fileScheme)) {
    std::string rest;
    if (!percentDecode(uri.substr(fileScheme.size()), rest))
      return Status::error(ErrorCode::InvalidArgument, "mesh URI '" + uri + "' has a broken %-escape");
    if (startsWith(rest, "localhost/")) rest.erase(0, std::string("localhost").size());
    if (rest.empty() || rest.front() != '/')
      return Status::error(ErrorCode::InvalidArgument,
                           "mesh URI '" + uri + "' must name an absolute path: file:///abs/path");
    if (found(rest)) return Status::success();
    return Status::error(ErrorCode::FileNotFound,
                         "mesh '" + uri + "' not found; looked at " + joined(looked));
  }
  const std::size_t scheme = uri.find("://");
  if (scheme != std::string::npos && scheme > 0 &&
      std::all_of(uri.begin(), uri.begin() + static_cast<std::ptrdiff_t>(scheme), [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) || ch == '+' || ch == '-' || ch == '.';
      }))
    return Status::error(ErrorCode::InvalidArgument,
                         "mesh URI '" + uri + "': only package://, file:// and file paths are read");
  fs::path p(uri);
  if (p.is_relative()) {
    std::error_code ec;
    p = (baseDir.empty() ? fs::current_path(ec) : fs::path(baseDir)) / p;
  }
  if (found(p)) return Status::success();
  return Status::error(ErrorCode::FileNotFound, "mesh '" + uri + "' not found; looked at " + joined(looked));
}

MeshHullResult loadMeshHull(const std::string& path, const Eigen::Vector3d& scale,
                            const MeshHullOptions& options) {
  try {
    return loadUncaught(path, scale, options);
  } catch (const std::bad_alloc&) {
    return {invalidModel(path, "out of memory while loading it"), nullptr};
  } catch (const std::exception& e) {
    return {invalidModel(path, std::string("failed while loading it: ") + e.what()), nullptr};
  } catch (...) {
    return {invalidModel(path, "failed while loading it"), nullptr};
  }
}

void clearMeshHullCache() {
  std::lock_guard<std::mutex> lock(cacheMutex());
  cache().clear();
}

}  // namespace cape::character
