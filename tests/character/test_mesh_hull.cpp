// Mesh files to simplified convex hulls: the formats (STL binary and ASCII, OBJ, COLLADA with its unit and up
// axis), the simplification of a sphere and its rounding, URI resolution, bad files, and the cache. Every
// file is written by the test into a fresh folder of its own (per process and test).
#include "MeshHull.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

using namespace cape::character;
namespace fs = std::filesystem;
using Eigen::Vector3d;

namespace {

using Triangle = std::array<Vector3d, 3>;

// A fresh folder per process and test, removed afterwards.
class MeshHullTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("cape_mesh_hull_" + std::to_string(::getpid())) / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    clearMeshHullCache();
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_.parent_path(), ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

void writeText(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

void put32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}

void putFloat(std::string& out, float f) {
  std::uint32_t u = 0;
  std::memcpy(&u, &f, 4);
  put32(out, u);
}

// Binary STL (little-endian floats); `declared` overrides the triangle count in the header.
void writeBinaryStl(const std::string& path, const std::vector<Triangle>& tris, long declared = -1) {
  std::string out(80, ' ');
  put32(out, static_cast<std::uint32_t>(declared < 0 ? static_cast<long>(tris.size()) : declared));
  for (const Triangle& t : tris) {
    const Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    for (int k = 0; k < 3; ++k) putFloat(out, static_cast<float>(n[k]));
    for (const Vector3d& v : t)
      for (int k = 0; k < 3; ++k) putFloat(out, static_cast<float>(v[k]));
    out += std::string(2, '\0');
  }
  writeText(path, out);
}

void writeAsciiStl(const std::string& path, const std::vector<Triangle>& tris) {
  std::ostringstream s;
  s.precision(17);
  s << "solid box\n";
  for (const Triangle& t : tris) {
    const Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    s << " facet normal " << n.x() << " " << n.y() << " " << n.z() << "\n  outer loop\n";
    for (const Vector3d& v : t) s << "   vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid box\n";
  writeText(path, s.str());
}

// An axis-aligned box from lo to hi: corners (index bit k set: hi along axis k) and outward triangles.
std::vector<Vector3d> boxCorners(const Vector3d& lo, const Vector3d& hi) {
  std::vector<Vector3d> c;
  for (int i = 0; i < 8; ++i)
    c.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  return c;
}
// Quads (counter-clockwise seen from outside), in corner indices.
const std::array<std::array<int, 4>, 6> kBoxQuads{
    {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};

std::vector<Triangle> boxTriangles(const Vector3d& lo, const Vector3d& hi) {
  const std::vector<Vector3d> c = boxCorners(lo, hi);
  std::vector<Triangle> t;
  for (const auto& q : kBoxQuads) {
    t.push_back({c[q[0]], c[q[1]], c[q[2]]});
    t.push_back({c[q[0]], c[q[2]], c[q[3]]});
  }
  return t;
}

void writeBoxObj(const std::string& path, const Vector3d& lo, const Vector3d& hi) {
  std::ostringstream s;
  s.precision(17);
  s << "# a box of quads\no box\n";
  for (const Vector3d& v : boxCorners(lo, hi)) s << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const auto& q : kBoxQuads)
    s << "f " << q[0] + 1 << " " << q[1] + 1 << " " << q[2] + 1 << " " << q[3] + 1 << "\n";
  writeText(path, s.str());
}

// COLLADA 1.4.1: the box from lo to hi as one geometry, instanced by one node per translation. `unit` is the
// <unit meter> value (none when <= 0), `upAxis` the <up_axis> text (none when empty).
std::string boxDae(const Vector3d& lo, const Vector3d& hi, double unit, const std::string& upAxis,
                   const std::vector<Vector3d>& translations) {
  std::ostringstream s;
  s.precision(17);
  s << R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>)";
  if (unit > 0) s << "<unit name=\"u\" meter=\"" << unit << "\"/>";
  if (!upAxis.empty()) s << "<up_axis>" << upAxis << "</up_axis>";
  s << R"(</asset>
  <library_geometries><geometry id="box" name="box"><mesh>
    <source id="box-pos"><float_array id="box-pos-array" count="24">)";
  for (const Vector3d& v : boxCorners(lo, hi)) s << v.x() << " " << v.y() << " " << v.z() << " ";
  s << R"(</float_array>
      <technique_common><accessor source="#box-pos-array" count="8" stride="3"><param name="X" type="float"/>
        <param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <vertices id="box-vtx"><input semantic="POSITION" source="#box-pos"/></vertices>
    <triangles count="12"><input semantic="VERTEX" source="#box-vtx" offset="0"/><p>)";
  for (const auto& q : kBoxQuads)
    s << q[0] << " " << q[1] << " " << q[2] << " " << q[0] << " " << q[2] << " " << q[3] << " ";
  s << R"(</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="Scene" name="Scene">)";
  for (std::size_t k = 0; k < translations.size(); ++k) {
    const Vector3d& t = translations[k];
    s << "<node id=\"n" << k << "\" name=\"n" << k << "\"><translate>" << t.x() << " " << t.y() << " "
      << t.z() << "</translate><instance_geometry url=\"#box\"/></node>";
  }
  s << R"(</visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>
)";
  return s.str();
}

// A UV sphere: `stacks` bands from pole to pole, `slices` around; 2 + (stacks - 1) slices vertices.
std::vector<Triangle> uvSphere(double r, int stacks, int slices) {
  const double pi = 3.14159265358979323846;
  const auto at = [&](int i, int j) {  // the poles and the seam exactly shared
    if (i == 0 || i == stacks) return Vector3d(0, 0, i == 0 ? r : -r);
    const double theta = pi * i / stacks, phi = 2 * pi * (j % slices) / slices;
    return Vector3d(r * std::sin(theta) * std::cos(phi), r * std::sin(theta) * std::sin(phi),
                    r * std::cos(theta));
  };
  std::vector<Triangle> t;
  for (int i = 0; i < stacks; ++i) {
    for (int j = 0; j < slices; ++j) {
      const Vector3d a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      if (i > 0) t.push_back({a, b, d});
      if (i < stacks - 1) t.push_back({b, c, d});
    }
  }
  return t;
}

// The distinct corners, as the file stores them (float).
std::vector<Vector3d> cornersOf(const std::vector<Triangle>& tris) {
  std::vector<Vector3d> v;
  for (const Triangle& t : tris)
    for (const Vector3d& p : t) v.push_back(p.cast<float>().cast<double>());
  std::sort(v.begin(), v.end(), [](const Vector3d& x, const Vector3d& y) {
    return std::lexicographical_compare(x.data(), x.data() + 3, y.data(), y.data() + 3);
  });
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// Independent of the library: the distance from p to the convex hull whose planes and vertices are given
// (0 inside). A face is the vertices on its plane; every triangle of three of them lies in the face and
// together they cover it, so the boundary's distance is the least over all those triangles.
double triangleDistance(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d n = (b - a).cross(c - a);
  const double area2 = n.squaredNorm();
  const auto seg = [&](const Vector3d& s, const Vector3d& e) {
    const double len2 = (e - s).squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - s).dot(e - s) / len2, 0.0, 1.0) : 0.0;
    return (p - s - t * (e - s)).norm();
  };
  const double edges = std::min({seg(a, b), seg(b, c), seg(c, a)});
  if (area2 <= 0) return edges;
  const Vector3d q = p - n * (n.dot(p - a) / area2);
  const double u = n.dot((b - q).cross(c - q)), v = n.dot((c - q).cross(a - q)),
               w = n.dot((a - q).cross(b - q));
  if (u >= 0 && v >= 0 && w >= 0) return std::abs(n.dot(p - a)) / std::sqrt(area2);
  return edges;
}

// The hull's faces as the vertices on each plane.
struct HullFaces {
  explicit HullFaces(const MeshHull& hull) : h(hull) {
    for (const Vector3d& v : h.vertices) size = std::max(size, (v - h.vertices[0]).norm());
    for (const Eigen::Vector4d& pl : h.planes) {
      faces.emplace_back();
      for (const Vector3d& v : h.vertices)
        if (std::abs(pl.head<3>().dot(v) - pl[3]) <= 1e-7 * size) faces.back().push_back(v);
    }
  }
  double distance(const Vector3d& p) const {
    bool outside = false;
    for (const Eigen::Vector4d& pl : h.planes) outside = outside || pl.head<3>().dot(p) > pl[3];
    if (!outside) return 0.0;
    double best = std::numeric_limits<double>::infinity();
    for (const std::vector<Vector3d>& face : faces)
      for (std::size_t i = 0; i < face.size(); ++i)
        for (std::size_t j = i + 1; j < face.size(); ++j)
          for (std::size_t k = j + 1; k < face.size(); ++k)
            best = std::min(best, triangleDistance(p, face[i], face[j], face[k]));
    return best;
  }
  const MeshHull& h;
  double size = 0;
  std::vector<std::vector<Vector3d>> faces;
};

// Planes unit and outward, every vertex inside every plane (within 1e-9 of the hull's size).
void expectWellFormed(const MeshHull& h) {
  ASSERT_GE(h.vertices.size(), 4u);
  ASSERT_GE(h.planes.size(), 4u);
  double size = 0;
  Vector3d mean = Vector3d::Zero();
  for (const Vector3d& v : h.vertices) {
    size = std::max(size, (v - h.vertices[0]).norm());
    mean += v;
  }
  mean /= static_cast<double>(h.vertices.size());
  for (const Eigen::Vector4d& pl : h.planes) {
    EXPECT_NEAR(pl.head<3>().norm(), 1.0, 1e-12);
    EXPECT_LT(pl.head<3>().dot(mean), pl[3]) << "an inward plane";
    int on = 0;
    for (const Vector3d& v : h.vertices) {
      EXPECT_LE(pl.head<3>().dot(v) - pl[3], 1e-9 * size);
      if (std::abs(pl.head<3>().dot(v) - pl[3]) <= 1e-7 * size) ++on;
    }
    EXPECT_GE(on, 3) << "a plane with fewer than three vertices on it is no face";
  }
}

// The hull is the box from lo to hi: its 8 corners and its 6 faces.
void expectBox(const MeshHullResult& r, const Vector3d& lo, const Vector3d& hi, double tol) {
  ASSERT_TRUE(r.ok()) << r.status.message();
  const MeshHull& h = *r.hull;
  expectWellFormed(h);
  EXPECT_EQ(h.vertices.size(), 8u);
  EXPECT_EQ(h.planes.size(), 6u);
  EXPECT_LE(h.radius, tol);
  for (const Vector3d& c : boxCorners(lo, hi)) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vector3d& v : h.vertices) nearest = std::min(nearest, (v - c).norm());
    EXPECT_LE(nearest, tol) << "corner " << c.transpose();
  }
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      Vector3d n = Vector3d::Zero();
      n[axis] = side ? 1.0 : -1.0;
      const double d = side ? hi[axis] : -lo[axis];
      const bool found = std::any_of(h.planes.begin(), h.planes.end(), [&](const Eigen::Vector4d& pl) {
        return pl.head<3>().dot(n) > 1 - 1e-9 && std::abs(pl[3] - d) <= tol;
      });
      EXPECT_TRUE(found) << "face " << n.transpose() << " at " << d;
    }
  }
}

// The millimetre box every format writes: 100 x 200 x 300 mm, 10 mm along x from the origin.
const Vector3d kLoMm(10, 0, 0), kHiMm(110, 200, 300);
const Vector3d kLoM(0.010, 0, 0), kHiM(0.110, 0.200, 0.300);
const Vector3d kMm(0.001, 0.001, 0.001);
// COLLADA's unit is read as a float by assimp: the same box to float precision.
constexpr double kFloatTol = 1e-7;

}  // namespace

TEST_F(MeshHullTest, ABoxGivesTheSameHullAsBinaryStlAsciiStlObjAndCollada) {
  writeBinaryStl(file("box_bin.stl"), boxTriangles(kLoMm, kHiMm));
  writeAsciiStl(file("box_ascii.STL"), boxTriangles(kLoMm, kHiMm));
  writeBoxObj(file("box.obj"), kLoMm, kHiMm);
  // The geometry from the origin, the node moves it: node transforms are applied. Unit: mm; Z up.
  writeText(file("box.dae"), boxDae(kLoMm - kLoMm, kHiMm - kLoMm, 0.001, "Z_UP", {kLoMm}));
  for (const std::string name : {"box_bin.stl", "box_ascii.STL", "box.obj"}) {
    SCOPED_TRACE(name);
    const MeshHullResult r = loadMeshHull(file(name), kMm);
    expectBox(r, kLoM, kHiM, 1e-12);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.hull->meshVertices, 8);
    EXPECT_EQ(r.hull->meshTriangles, 12);
  }
  // COLLADA in the link frame in metres: the unit applied, the Z_UP axis not turned into assimp's Y up.
  const MeshHullResult dae = loadMeshHull(file("box.dae"), Vector3d::Ones());
  expectBox(dae, kLoM, kHiM, kFloatTol);
  ASSERT_TRUE(dae.ok());
  EXPECT_EQ(dae.hull->meshTriangles, 12);
}

TEST_F(MeshHullTest, ScaleIsAppliedPerAxis) {
  writeBoxObj(file("unit.obj"), Vector3d(-0.5, -0.5, -0.5), Vector3d(0.5, 0.5, 0.5));
  expectBox(loadMeshHull(file("unit.obj"), Vector3d(2, 3, 4)), Vector3d(-1, -1.5, -2), Vector3d(1, 1.5, 2),
            1e-12);
}

TEST_F(MeshHullTest, ColladaUpAxisIsIgnoredAndTheUnitDefaultsToMetres) {
  // As RViz shows a URDF's COLLADA mesh: a Y_UP file is not turned either; without <unit> it is in metres.
  writeText(file("y_up.dae"), boxDae(kLoMm, kHiMm, 0.001, "Y_UP", {Vector3d::Zero()}));
  writeText(file("no_unit.dae"), boxDae(kLoM, kHiM, 0.0, "", {Vector3d::Zero()}));
  writeText(file("cm.dae"), boxDae(kLoMm / 10, kHiMm / 10, 0.01, "Z_UP", {Vector3d::Zero()}));
  expectBox(loadMeshHull(file("y_up.dae"), Vector3d::Ones()), kLoM, kHiM, kFloatTol);
  expectBox(loadMeshHull(file("no_unit.dae"), Vector3d::Ones()), kLoM, kHiM, kFloatTol);
  // The URDF scale multiplies after the unit.
  expectBox(loadMeshHull(file("cm.dae"), Vector3d(2, 2, 2)), 2 * kLoM, 2 * kHiM, kFloatTol);
}

TEST_F(MeshHullTest, ColladaThatAssimpWouldLoopOnIsRefusedAndPlainIndexListsStillLoad) {
  // Debian's assimp 5.2 reads a <p> list until its text ends, and a character that is neither a number nor
  // white space stops it for good (it appends 0 indices until memory runs out: 257 s for such a 1 KB file).
  // Such files are refused before assimp sees them; this test finishes at once or times out.
  const std::string box = boxDae(kLoM, kHiM, 1, "Z_UP", {Vector3d::Zero()});
  const std::size_t p = box.find("<p>") + 3;
  ASSERT_NE(p, std::string::npos + 3);
  const std::size_t space = box.find(' ', p + 6);
  const auto edited = [&](const std::string& with) {
    std::string s = box;
    s.replace(space, 1, with);
    return s;
  };
  const auto expectRefused = [&](const std::string& name, const std::string& text, const std::string& says) {
    writeText(file(name), text);
    const MeshHullResult r = loadMeshHull(file(name), Vector3d::Ones());
    EXPECT_FALSE(r.ok()) << name;
    EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel) << r.status.message();
    EXPECT_NE(r.status.message().find(name), std::string::npos) << r.status.message();
    EXPECT_NE(r.status.message().find(says), std::string::npos) << r.status.message();
  };
  expectRefused("control.dae", edited("\x1e"), "byte 0x1e");
  expectRefused("dot.dae", edited("."), "'.' in a <p> list");
  expectRefused("word.dae", edited(" vertex "), "'v' in a <p> list");
  expectRefused("reference.dae", edited("&#30;"), "'&' in a <p> list");
  expectRefused("comment.dae", edited("<!-- x -->"), "anything but its numbers");
  // assimp picks its COLLADA reader by content: the extension does not matter.
  expectRefused("collada_named.stl", edited("*"), "'*' in a <p> list");
  // A count beyond the file's size (assimp reserves that many) and one that is not a decimal number.
  std::string huge = box;
  huge.replace(huge.find("count=\"12\""), 10, "count=\"4000000000\"");
  expectRefused("huge_count.dae", huge, "count attribute larger than the file");
  std::string hex = box;
  hex.replace(hex.find("count=\"12\""), 10, "count=\"0xc\"");
  expectRefused("hex_count.dae", hex, "not a plain decimal number");
  // An array without its count (assimp reads no value, then indexes it: a segfault) and an accessor reaching
  // past its array's end.
  std::string uncounted = box;
  uncounted.replace(uncounted.find("count=\"24\""), 5, "coune");
  expectRefused("uncounted.dae", uncounted, "without a plain decimal count");
  std::string reaching = box;
  reaching.replace(reaching.find("count=\"8\""), 9, "count=\"9\"");
  expectRefused("reaching.dae", reaching, "reaching past the end of its array");
  std::string utf16;
  for (char c : box) (utf16 += c) += '\0';
  expectRefused("utf16.dae", utf16, "byte 0x00");
  // Tabs, line ends and a sign in a <p> list still read as before.
  const std::string plain = edited("\r\n\t+");
  writeText(file("plain.dae"), plain);
  expectBox(loadMeshHull(file("plain.dae"), Vector3d::Ones()), kLoM, kHiM, kFloatTol);
}

TEST_F(MeshHullTest, EveryNodeInstanceOfAMeshIsLoaded) {
  // One geometry, two nodes 1 m apart along y: the hull spans both.
  writeText(file("two.dae"),
            boxDae(Vector3d::Zero(), Vector3d::Ones(), 0.0, "Z_UP", {Vector3d::Zero(), Vector3d(0, 1, 0)}));
  const MeshHullResult r = loadMeshHull(file("two.dae"), Vector3d::Ones());
  expectBox(r, Vector3d::Zero(), Vector3d(1, 2, 1), kFloatTol);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.hull->meshTriangles, 24);
  EXPECT_EQ(r.hull->meshVertices, 12);  // the shared face's corners coincide
}

TEST_F(MeshHullTest, ASphereSimplifiesToTheBudgetAndTheGrownHullCoversEveryVertex) {
  const double R = 0.25;
  const std::vector<Triangle> tris = uvSphere(R, 32, 64);
  writeBinaryStl(file("sphere.stl"), tris);
  const MeshHullResult r = loadMeshHull(file("sphere.stl"), Vector3d::Ones());
  ASSERT_TRUE(r.ok()) << r.status.message();
  const MeshHull& h = *r.hull;
  EXPECT_EQ(h.meshVertices, 2 + 31 * 64);
  EXPECT_EQ(h.meshTriangles, static_cast<int>(tris.size()));
  EXPECT_LE(h.vertices.size(), 64u);
  EXPECT_GE(h.vertices.size(), 60u);  // the budget is used (none of the sphere's corners is redundant)
  expectWellFormed(h);
  for (const Vector3d& v : h.vertices) EXPECT_NEAR(v.norm(), R, 1e-6) << "not a corner of the sphere";
  // Covered: every vertex of the mesh within radius of the hull, and the radius no larger than needed.
  double worst = 0;
  const HullFaces faces(h);
  const std::vector<Vector3d> corners = cornersOf(tris);
  ASSERT_EQ(static_cast<int>(corners.size()), h.meshVertices);
  for (const Vector3d& p : corners) {
    const double d = faces.distance(p);
    EXPECT_LE(d, h.radius * (1 + 1e-9) + 1e-15);
    worst = std::max(worst, d);
  }
  EXPECT_NEAR(worst, h.radius, 1e-9 * R);
  // Small. No 64 points of a sphere do better than 3.79 % of R: by Fejes Toth's bound on the covering radius
  // r of N points, cos r <= cot(N pi / (6 (N - 2))) / sqrt 3, some point of the sphere is r away from the
  // nearest corner, and 1 - cos r from their hull. The greedy insertion gets 6.13 % of R on this mesh.
  EXPECT_LT(h.radius, 0.065 * R);
  EXPECT_GT(h.radius, 0.0379 * R * 0.9);  // the mesh samples the sphere: a little under the bound at most
  std::printf("sphere R %.3f m: %zu vertices, %zu planes, radius %.6f m = %.3f %% of R\n", R,
              h.vertices.size(), h.planes.size(), h.radius, 100 * h.radius / R);
}

TEST_F(MeshHullTest, TheSameFileGivesTheSameBits) {
  writeBinaryStl(file("sphere.stl"), uvSphere(0.1, 20, 40));
  const MeshHullResult a = loadMeshHull(file("sphere.stl"), Vector3d::Ones());
  clearMeshHullCache();
  const MeshHullResult b = loadMeshHull(file("sphere.stl"), Vector3d::Ones());
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_NE(a.hull, b.hull);
  ASSERT_EQ(a.hull->vertices.size(), b.hull->vertices.size());
  ASSERT_EQ(a.hull->planes.size(), b.hull->planes.size());
  EXPECT_EQ(std::memcmp(a.hull->vertices.data(), b.hull->vertices.data(),
                        a.hull->vertices.size() * sizeof(Vector3d)),
            0);
  EXPECT_EQ(std::memcmp(a.hull->planes.data(), b.hull->planes.data(),
                        a.hull->planes.size() * sizeof(Eigen::Vector4d)),
            0);
  EXPECT_EQ(a.hull->radius, b.hull->radius);
}

TEST_F(MeshHullTest, TheBudgetIsKeptDownToATetrahedron) {
  const std::vector<Triangle> tris = uvSphere(1.0, 16, 32);
  writeBinaryStl(file("sphere.stl"), tris);
  for (int budget : {4, 5, 12, 100}) {
    SCOPED_TRACE(budget);
    MeshHullOptions o;
    o.maxVertices = budget;
    const MeshHullResult r = loadMeshHull(file("sphere.stl"), Vector3d::Ones(), o);
    ASSERT_TRUE(r.ok()) << r.status.message();
    EXPECT_LE(static_cast<int>(r.hull->vertices.size()), budget);
    expectWellFormed(*r.hull);
    const HullFaces faces(*r.hull);
    for (const Vector3d& p : cornersOf(tris))
      EXPECT_LE(faces.distance(p), r.hull->radius * (1 + 1e-9) + 1e-15);
  }
}

TEST_F(MeshHullTest, AFlatMeshBecomesAThinSlab) {
  // One quad, 1 m x 0.5 m at z = 0.25, and a single triangle: plates, thickened by 0.5 mm to each side.
  writeText(file("plate.obj"), "v 0 0 0.25\nv 1 0 0.25\nv 1 0.5 0.25\nv 0 0.5 0.25\nf 1 2 3 4\n");
  expectBox(loadMeshHull(file("plate.obj"), Vector3d::Ones()), Vector3d(0, 0, 0.2495),
            Vector3d(1, 0.5, 0.2505), 1e-12);
  writeText(file("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const MeshHullResult t = loadMeshHull(file("tri.obj"), Vector3d::Ones());
  ASSERT_TRUE(t.ok()) << t.status.message();
  expectWellFormed(*t.hull);
  EXPECT_EQ(t.hull->vertices.size(), 6u);
  EXPECT_EQ(t.hull->planes.size(), 5u);
  EXPECT_LE(t.hull->radius, 1e-15);
}

TEST_F(MeshHullTest, BadFilesGiveErrorsAndDoNotCrash) {
  const auto expectCode = [&](const std::string& path, ErrorCode code, const std::string& says,
                              const Vector3d& scale = Vector3d::Ones()) {
    SCOPED_TRACE(path);
    const MeshHullResult r = loadMeshHull(path, scale);
    EXPECT_FALSE(r.ok());
    EXPECT_EQ(r.hull, nullptr);
    EXPECT_EQ(r.status.code(), code) << r.status.message();
    EXPECT_NE(r.status.message().find(says), std::string::npos) << r.status.message();
  };
  expectCode(file("missing.stl"), ErrorCode::FileNotFound, "missing.stl");
  expectCode(dir_.string(), ErrorCode::FileNotFound, "regular file");
  writeText(file("empty.stl"), "");
  expectCode(file("empty.stl"), ErrorCode::InvalidModel, "empty");
  writeText(file("hello.stl"), "hello, this is no mesh\n");
  expectCode(file("hello.stl"), ErrorCode::InvalidModel, "hello.stl");
  std::mt19937 random(7);
  std::string noise(4096, '\0');
  for (char& ch : noise) ch = static_cast<char>(random());
  for (const std::string name : {"noise.stl", "noise.obj", "noise.dae", "noise.bin"}) {
    writeText(file(name), noise);
    expectCode(file(name), ErrorCode::InvalidModel, name);
  }
  writeText(file("broken.dae"), boxDae(kLoM, kHiM, 1, "Z_UP", {Vector3d::Zero()}).substr(0, 900));
  expectCode(file("broken.dae"), ErrorCode::InvalidModel, "broken.dae");
  // A binary STL whose header promises more triangles than it holds.
  writeBinaryStl(file("truncated.stl"), boxTriangles(kLoM, kHiM), 1000);
  expectCode(file("truncated.stl"), ErrorCode::InvalidModel, "truncated.stl");
  // Not-a-number, infinite and huge coordinates.
  std::vector<Triangle> bad = boxTriangles(kLoM, kHiM);
  bad[3][1].x() = std::numeric_limits<double>::quiet_NaN();
  writeBinaryStl(file("nan.stl"), bad);
  expectCode(file("nan.stl"), ErrorCode::InvalidModel, "finite");
  bad[3][1].x() = std::numeric_limits<double>::infinity();
  writeBinaryStl(file("inf.stl"), bad);
  expectCode(file("inf.stl"), ErrorCode::InvalidModel, "finite");
  writeText(file("nan.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1e39\nf 1 2 3\nf 1 2 4\n");
  expectCode(file("nan.obj"), ErrorCode::InvalidModel, "finite");
  bad[3][1].x() = 1e30;
  writeBinaryStl(file("huge.stl"), bad);
  expectCode(file("huge.stl"), ErrorCode::InvalidModel, "1e6 m");
  writeBoxObj(file("big.obj"), Vector3d::Zero(), Vector3d(1e5, 1, 1));
  expectCode(file("big.obj"), ErrorCode::InvalidModel, "1e6 m", Vector3d(100, 1, 1));
  EXPECT_TRUE(loadMeshHull(file("big.obj"), Vector3d::Ones()).ok());
  // No triangles: points and lines only; all on one line; all at one point.
  writeText(file("lines.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\np 1\n");
  expectCode(file("lines.obj"), ErrorCode::InvalidModel, "no triangles");
  writeText(file("wire.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  expectCode(file("wire.obj"), ErrorCode::InvalidModel, "one line");
  writeText(file("dot.obj"), "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n");
  expectCode(file("dot.obj"), ErrorCode::InvalidModel, "1 nm");
}

TEST_F(MeshHullTest, BadArgumentsAndTheTriangleCap) {
  writeBoxObj(file("box.obj"), kLoM, kHiM);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const Vector3d& s :
       {Vector3d(0, 1, 1), Vector3d(1, -1, 1), Vector3d(1, 1, nan), Vector3d(inf, 1, 1)}) {
    const MeshHullResult r = loadMeshHull(file("box.obj"), s);
    EXPECT_EQ(r.status.code(), ErrorCode::InvalidArgument) << s.transpose();
    EXPECT_EQ(r.hull, nullptr);
  }
  for (int budget : {3, 0, -5, 1025}) {
    MeshHullOptions o;
    o.maxVertices = budget;
    EXPECT_EQ(loadMeshHull(file("box.obj"), Vector3d::Ones(), o).status.code(), ErrorCode::InvalidArgument)
        << budget;
  }
  MeshHullOptions capped;
  capped.maxTriangles = 11;
  const MeshHullResult r = loadMeshHull(file("box.obj"), Vector3d::Ones(), capped);
  EXPECT_EQ(r.status.code(), ErrorCode::InvalidModel);
  EXPECT_NE(r.status.message().find("more than 11 triangles"), std::string::npos) << r.status.message();
  capped.maxTriangles = 12;
  EXPECT_TRUE(loadMeshHull(file("box.obj"), Vector3d::Ones(), capped).ok());
}

TEST_F(MeshHullTest, TheCacheReturnsTheSameObjectUntilTheFileChanges) {
  writeBinaryStl(file("box.stl"), boxTriangles(kLoM, kHiM));
  const MeshHullResult a = loadMeshHull(file("box.stl"), Vector3d::Ones());
  const MeshHullResult b = loadMeshHull(file("box.stl"), Vector3d::Ones());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a.hull, b.hull);
  // The same file through another spelling of its path: the same entry.
  EXPECT_EQ(loadMeshHull((dir_ / "." / "box.stl").string(), Vector3d::Ones()).hull, a.hull);
  // Another scale or budget: another hull.
  const MeshHullResult scaled = loadMeshHull(file("box.stl"), Vector3d(2, 2, 2));
  ASSERT_TRUE(scaled.ok());
  EXPECT_NE(scaled.hull, a.hull);
  MeshHullOptions o;
  o.maxVertices = 8;
  EXPECT_NE(loadMeshHull(file("box.stl"), Vector3d::Ones(), o).hull, a.hull);
  // Rewritten (same size, a later modification time): loaded again.
  const fs::file_time_type before = fs::last_write_time(file("box.stl"));
  writeBinaryStl(file("box.stl"), boxTriangles(kLoM, 2 * kHiM));
  fs::last_write_time(file("box.stl"), before + std::chrono::seconds(2));
  const MeshHullResult c = loadMeshHull(file("box.stl"), Vector3d::Ones());
  ASSERT_TRUE(c.ok());
  EXPECT_NE(c.hull, a.hull);
  expectBox(c, kLoM, 2 * kHiM, 1e-7);
  EXPECT_EQ(loadMeshHull(file("box.stl"), Vector3d::Ones()).hull, c.hull);
  // The hull handed out before stays valid and unchanged.
  expectBox(a, kLoM, kHiM, 1e-7);
  // A file that went away is an error, not its cached hull.
  fs::remove(file("box.stl"));
  EXPECT_EQ(loadMeshHull(file("box.stl"), Vector3d::Ones()).status.code(), ErrorCode::FileNotFound);
}

TEST_F(MeshHullTest, ThreadsLoadingAtOnceAgree) {
  writeBinaryStl(file("sphere.stl"), uvSphere(0.1, 16, 32));
  std::vector<std::shared_ptr<const MeshHull>> got(4);
  std::vector<std::thread> threads;
  for (std::size_t k = 0; k < got.size(); ++k)
    threads.emplace_back([&, k] { got[k] = loadMeshHull(file("sphere.stl"), Vector3d::Ones()).hull; });
  for (std::thread& t : threads) t.join();
  for (const auto& h : got) {
    ASSERT_NE(h, nullptr);
    EXPECT_EQ(h->vertices, got[0]->vertices);
    EXPECT_EQ(h->radius, got[0]->radius);
  }
  const auto cached = loadMeshHull(file("sphere.stl"), Vector3d::Ones()).hull;
  EXPECT_TRUE(std::find(got.begin(), got.end(), cached) != got.end());
}

// --- URIs ---

TEST_F(MeshHullTest, PackageUrisResolveThroughSearchPathsThenRosPackagePath) {
  writeText(file("share/robot_meshes/meshes/arm.stl"), "x");
  writeText(file("ros/other_pkg/meshes/leg.stl"), "x");
  writeText(file("ros2/robot_meshes/meshes/arm.stl"), "x");
  std::string out;
  // DIR/NAME/rel.
  Status s =
      resolveMeshUri("package://robot_meshes/meshes/arm.stl", "", {file("nowhere"), file("share")}, out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out, file("share/robot_meshes/meshes/arm.stl"));
  // DIR is the package folder itself (trailing slash or not).
  s = resolveMeshUri("package://robot_meshes/meshes/arm.stl", "", {file("share/robot_meshes/")}, out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out, file("share/robot_meshes/meshes/arm.stl"));
  // ROS_PACKAGE_PATH, after the given paths.
  const char* old = std::getenv("ROS_PACKAGE_PATH");
  const std::string saved = old ? old : "";
  ::setenv("ROS_PACKAGE_PATH", (file("missing") + "::" + file("ros2") + ":" + file("ros")).c_str(), 1);
  s = resolveMeshUri("package://other_pkg/meshes/leg.stl", "", {}, out);
  EXPECT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out, file("ros/other_pkg/meshes/leg.stl"));
  s = resolveMeshUri("package://robot_meshes/meshes/arm.stl", "", {file("share")}, out);
  EXPECT_EQ(out, file("share/robot_meshes/meshes/arm.stl")) << "the given paths come first";
  s = resolveMeshUri("package://robot_meshes/meshes/arm.stl", "", {}, out);
  EXPECT_EQ(out, file("ros2/robot_meshes/meshes/arm.stl"));
  // Not found: the URI and every place looked.
  s = resolveMeshUri("package://robot_meshes/meshes/hand.stl", "", {file("share")}, out);
  EXPECT_EQ(s.code(), ErrorCode::FileNotFound);
  EXPECT_TRUE(out.empty());
  for (const std::string& place :
       {std::string("package://robot_meshes/meshes/hand.stl"), file("share/robot_meshes/meshes/hand.stl"),
        file("missing/robot_meshes/meshes/hand.stl"), file("ros2/robot_meshes/meshes/hand.stl"),
        file("ros/robot_meshes/meshes/hand.stl")})
    EXPECT_NE(s.message().find(place), std::string::npos) << s.message() << "\n lacks " << place;
  if (old) {
    ::setenv("ROS_PACKAGE_PATH", saved.c_str(), 1);
  } else {
    ::unsetenv("ROS_PACKAGE_PATH");
  }
  s = resolveMeshUri("package://other_pkg/meshes/leg.stl", "", {}, out);
  if (!old) {
    EXPECT_EQ(s.code(), ErrorCode::FileNotFound);
  }
}

TEST_F(MeshHullTest, FileUrisAbsoluteAndRelativePathsResolve) {
  writeText(file("urdf/meshes/box.stl"), "x");
  writeText(file("with space/box.stl"), "x");
  std::string out;
  Status s = resolveMeshUri("meshes/box.stl", file("urdf"), {}, out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out, file("urdf/meshes/box.stl"));
  s = resolveMeshUri("../with space/box.stl", file("urdf"), {}, out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out, file("with space/box.stl"));
  s = resolveMeshUri(file("urdf/meshes/box.stl"), "/elsewhere", {}, out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out, file("urdf/meshes/box.stl"));
  s = resolveMeshUri("file://" + file("urdf/meshes/box.stl"), "", {}, out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out, file("urdf/meshes/box.stl"));
  s = resolveMeshUri("file://localhost" + file("with%20space/box.stl"), "", {}, out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out, file("with space/box.stl"));
  s = resolveMeshUri("meshes/nothing.stl", file("urdf"), {}, out);
  EXPECT_EQ(s.code(), ErrorCode::FileNotFound);
  EXPECT_NE(s.message().find(file("urdf/meshes/nothing.stl")), std::string::npos) << s.message();
  s = resolveMeshUri("meshes", file("urdf"), {}, out);
  EXPECT_EQ(s.code(), ErrorCode::FileNotFound) << "a folder is no mesh file";
  for (const std::string bad : {"", "package://", "package://pkg", "package://pkg/",
                                "package:///meshes/a.stl", "http://example.com/a.stl", "model://pkg/a.stl",
                                "file://relative/a.stl", "file:///bad%2", "file:///nul%00"}) {
    s = resolveMeshUri(bad, file("urdf"), {}, out);
    EXPECT_EQ(s.code(), ErrorCode::InvalidArgument) << "'" << bad << "': " << s.message();
    EXPECT_TRUE(out.empty());
  }
}

TEST_F(MeshHullTest, AResolvedPackageMeshLoads) {
  writeBinaryStl(file("share/pkg/meshes/box.stl"), boxTriangles(kLoMm, kHiMm));
  std::string path;
  ASSERT_TRUE(resolveMeshUri("package://pkg/meshes/box.stl", "", {file("share")}, path).ok());
  expectBox(loadMeshHull(path, kMm), kLoM, kHiM, 1e-12);
}
