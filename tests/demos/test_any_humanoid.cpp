// Any humanoid URDF a user brings, end to end through cape_walk with no option but --urdf: humanoids the
// test writes itself in the shapes public models use (capsules only, as Bullet's and PyBullet's humanoids;
// links that are all meshes in binary and ASCII STL and OBJ behind package:// URIs; the root at the pelvis;
// a T-pose), and a Z-up world equal to the Y-up one. Each must stand on the ground, wear its cape on its back
// and keep the measures of the URDF issue: median per-frame max strain <= 3 %, p95 <= 5 %, no particle
// deeper than 1 mm in any collider, the lowest particle above 0.1 m.
#include "DemoTestSupport.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

namespace cape::demo_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

enum class Geometry { Primitives, Capsules, Meshes };

struct Humanoid {
  Geometry geometry = Geometry::Primitives;
  bool tPose = false;  // arms straight out to the sides in the zero pose, with shoulder roll joints
};

// --- Mesh files the test writes: a unit cube (binary STL, ASCII STL) and an octagonal prism (OBJ) ----------

struct Point {
  float x, y, z;
};

std::vector<Point> cubeTriangles() {
  // 12 triangles of the cube [-0.5, 0.5]^3, counter-clockwise seen from outside.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<Point> out;
  const auto corner = [](int k) {
    return Point{k & 1 ? 0.5f : -0.5f, k & 2 ? 0.5f : -0.5f, k & 4 ? 0.5f : -0.5f};
  };
  for (const auto& f : faces) {
    for (int t : {1, 2}) {
      out.push_back(corner(f[0]));
      out.push_back(corner(f[t]));
      out.push_back(corner(f[t + 1]));
    }
  }
  return out;
}

void writeBinaryStl(const fs::path& file, const std::vector<Point>& corners) {
  std::ofstream out(file, std::ios::binary);
  char header[80] = "cape test cube";
  out.write(header, sizeof header);
  const std::uint32_t count = static_cast<std::uint32_t>(corners.size() / 3);
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (std::size_t t = 0; t < count; ++t) {
    const float normal[3] = {0.0f, 0.0f, 0.0f};  // readers recompute it
    out.write(reinterpret_cast<const char*>(normal), 12);
    for (int k = 0; k < 3; ++k) {
      const Point& p = corners[3 * t + static_cast<std::size_t>(k)];
      const float xyz[3] = {p.x, p.y, p.z};
      out.write(reinterpret_cast<const char*>(xyz), 12);
    }
    const std::uint16_t attribute = 0;
    out.write(reinterpret_cast<const char*>(&attribute), 2);
  }
}

void writeAsciiStl(const fs::path& file, const std::vector<Point>& corners) {
  std::ofstream out(file);
  out << "solid cube\n";
  for (std::size_t t = 0; t + 2 < corners.size(); t += 3) {
    out << "  facet normal 0 0 0\n    outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const Point& p = corners[t + static_cast<std::size_t>(k)];
      out << "      vertex " << p.x << " " << p.y << " " << p.z << "\n";
    }
    out << "    endloop\n  endfacet\n";
  }
  out << "endsolid cube\n";
}

// An octagonal prism of radius 1 about z, from z = -0.5 to 0.5 (a limb, scaled by the URDF).
void writePrismObj(const fs::path& file) {
  std::ofstream out(file);
  out << "# octagonal prism\n";
  for (int z : {-1, 1})
    for (int k = 0; k < 8; ++k) {
      const double a = 2.0 * 3.14159265358979 * k / 8.0;
      out << "v " << std::cos(a) << " " << std::sin(a) << " " << 0.5 * z << "\n";
    }
  for (int k = 0; k < 8; ++k) {
    const int a = k + 1, b = (k + 1) % 8 + 1;
    out << "f " << a << " " << b << " " << b + 8 << " " << a + 8 << "\n";
  }
  out << "f 8 7 6 5 4 3 2 1\nf 9 10 11 12 13 14 15 16\n";
}

// --- The humanoid URDF: the root at the pelvis (0.965 m above its feet), capsule / box / mesh limbs --------

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

class UrdfWriter {
 public:
  explicit UrdfWriter(const Humanoid& h) : h_(h) {}

  // A limb of radius r and length l centred at `xyz` along the axis `rpy` turns z onto.
  std::string limb(double r, double l, const std::string& xyz, const std::string& rpy) const {
    std::string g;
    if (h_.geometry == Geometry::Capsules) {
      g = "<capsule radius=\"" + num(r) + "\" length=\"" + num(l - 2 * r) + "\"/>";
    } else if (h_.geometry == Geometry::Meshes) {
      g = "<mesh filename=\"package://testbot/meshes/prism.obj\" scale=\"" + num(r) + " " + num(r) + " " +
          num(l) + "\"/>";
    } else {
      g = "<cylinder radius=\"" + num(r) + "\" length=\"" + num(l) + "\"/>";
    }
    return collision(xyz, rpy, g);
  }
  std::string block(double x, double y, double z, const std::string& xyz, bool ascii) const {
    std::string g;
    if (h_.geometry == Geometry::Meshes) {
      g = std::string("<mesh filename=\"") +
          (ascii ? "meshes/cube_ascii.stl" : "package://testbot/meshes/cube.stl") + "\" scale=\"" + num(x) +
          " " + num(y) + " " + num(z) + "\"/>";
    } else if (h_.geometry == Geometry::Capsules) {
      // The longest side as a capsule's axis, the shortest as its diameter.
      const double r = 0.5 * std::min(x, std::min(y, z));
      const double along = std::max(x, std::max(y, z));
      const std::string rpy = along == x ? "0 1.5707963 0" : along == y ? "1.5707963 0 0" : "0 0 0";
      return collision(xyz, rpy,
                       "<capsule radius=\"" + num(r) + "\" length=\"" + num(along - 2 * r) + "\"/>");
    } else {
      g = "<box size=\"" + num(x) + " " + num(y) + " " + num(z) + "\"/>";
    }
    return collision(xyz, "0 0 0", g);
  }
  std::string ball(double r, const std::string& xyz) const {
    if (h_.geometry == Geometry::Meshes) return block(1.6 * r, 1.6 * r, 1.6 * r, xyz, false);
    return collision(xyz, "0 0 0", "<sphere radius=\"" + num(r) + "\"/>");
  }

  std::string text() const {
    std::string u = "<?xml version=\"1.0\"?>\n<robot name=\"testbot\">\n";
    u += link("pelvis", block(0.16, 0.30, 0.14, "0 0 0", false));
    u += joint("waist", "revolute", "pelvis", "torso", "0 0 0.08", "0 0 1");
    u += link("torso", block(0.22, 0.36, 0.50, "0 0 0.3", true));
    u += joint("neck", "revolute", "torso", "head", "0 0 0.6", "0 1 0");
    u += link("head", ball(0.10, "0 0 0.12"));
    for (int side : {1, -1}) {
      const std::string s = side > 0 ? "left" : "right";
      const double y = side * 0.21;
      // Shoulder: pitch (about y), then roll (about x); in a T-pose the arm lies along +-y.
      u += joint(s + "_shoulder_pitch", "revolute", "torso", s + "_shoulder_link", "0 " + num(y) + " 0.52",
                 "0 1 0");
      u += link(s + "_shoulder_link", "");
      u += joint(s + "_shoulder_roll", "revolute", s + "_shoulder_link", s + "_upper_arm", "0 0 0", "1 0 0",
                 -2.0, 2.0);
      const std::string down = h_.tPose ? "0 " + num(side * 0.15) + " 0" : "0 0 -0.15";
      const std::string axis = h_.tPose ? "1.5707963 0 0" : "0 0 0";
      u += link(s + "_upper_arm", limb(0.045, 0.28, down, axis));
      const std::string elbow = h_.tPose ? "0 " + num(side * 0.30) + " 0" : "0 0 -0.30";
      u += joint(s + "_elbow", "revolute", s + "_upper_arm", s + "_forearm", elbow, "0 1 0", -2.5, 0.0);
      u += link(s + "_forearm", limb(0.04, 0.26, down, axis));
      const double hy = side * 0.10;
      u += joint(s + "_hip_pitch", "revolute", "pelvis", s + "_thigh", "0 " + num(hy) + " -0.05", "0 1 0");
      u += link(s + "_thigh", limb(0.065, 0.40, "0 0 -0.21", "0 0 0"));
      u += joint(s + "_knee", "revolute", s + "_thigh", s + "_shin", "0 0 -0.42", "0 1 0", 0.0, 2.5);
      u += link(s + "_shin", limb(0.055, 0.40, "0 0 -0.21", "0 0 0"));
      u += joint(s + "_ankle", "revolute", s + "_shin", s + "_foot", "0 0 -0.42", "0 1 0");
      u += link(s + "_foot", block(0.22, 0.09, 0.05, "0.04 0 -0.05", false));
    }
    return u + "</robot>\n";
  }

 private:
  static std::string collision(const std::string& xyz, const std::string& rpy, const std::string& geometry) {
    return "    <collision><origin xyz=\"" + xyz + "\" rpy=\"" + rpy + "\"/><geometry>" + geometry +
           "</geometry></collision>\n";
  }
  static std::string link(const std::string& name, const std::string& collisions) {
    return "  <link name=\"" + name +
           "\">\n    <inertial><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" "
           "ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>\n" +
           collisions + "  </link>\n";
  }
  static std::string joint(const std::string& name, const std::string& type, const std::string& parent,
                           const std::string& child, const std::string& xyz, const std::string& axis,
                           double lower = -1.5, double upper = 1.5) {
    return "  <joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent +
           "\"/><child link=\"" + child + "\"/><origin xyz=\"" + xyz + "\"/><axis xyz=\"" + axis +
           "\"/><limit lower=\"" + num(lower) + "\" upper=\"" + num(upper) +
           "\" effort=\"100\" velocity=\"10\"/></joint>\n";
  }
  Humanoid h_;
};

// Writes the humanoid (and its meshes) into dir/testbot: the URDF in dir/testbot/urdf/, the meshes in
// dir/testbot/meshes/ (package://testbot/... with dir as the package path, or relative "meshes/..." for the
// ASCII STL, next to a copy of the URDF's folder).
fs::path writeHumanoid(const fs::path& dir, const Humanoid& h) {
  const fs::path package = dir / "testbot";
  fs::create_directories(package / "meshes");
  writeBinaryStl(package / "meshes" / "cube.stl", cubeTriangles());
  writeAsciiStl(package / "meshes" / "cube_ascii.stl", cubeTriangles());
  writePrismObj(package / "meshes" / "prism.obj");
  const fs::path urdf = package / "model.urdf";  // relative "meshes/..." resolve against this folder
  std::ofstream(urdf) << UrdfWriter(h).text();
  return urdf;
}

json runWalk(const fs::path& dir, const fs::path& urdf, const std::string& extra,
             std::string* output = nullptr) {
  const fs::path out = dir / ("run" + std::to_string(std::hash<std::string>()(extra) % 100000));
  const Result r =
      run(std::string(CAPE_WALK) + " --cape canonical --urdf " + urdf.string() + " --package-path " +
          dir.string() + " --seconds 4 --no-frames --no-render --out " + out.string() + " " + extra);
  if (output) *output = r.output;
  EXPECT_EQ(r.exitCode, 0) << r.output;
  std::ifstream in(out / "summary.json");
  if (!in) return json();
  return json::parse(in);
}

void expectTheIssuesMeasures(const json& s, const std::string& what) {
  ASSERT_TRUE(s.contains("summary")) << what;
  const json& q = s["summary"];
  EXPECT_FALSE(q["blow_up"].get<bool>()) << what;
  EXPECT_LE(q["median_frame_max_strain"].get<double>(), 0.03) << what;
  EXPECT_LE(q["p95_frame_max_strain"].get<double>(), 0.05) << what;
  EXPECT_LE(q["max_penetration_m"].get<double>(), 0.001) << what;
  EXPECT_GT(q["lowest_particle_m"].get<double>(), 0.1) << what;
}

TEST(AnyHumanoid, PelvisRootedModelsOfEveryGeometryStandAndWearTheCape) {
  const fs::path dir = freshDir();
  for (Geometry g : {Geometry::Primitives, Geometry::Capsules, Geometry::Meshes}) {
    Humanoid h;
    h.geometry = g;
    const fs::path folder = dir / ("g" + std::to_string(static_cast<int>(g)));
    std::string output;
    const json s = runWalk(folder, writeHumanoid(folder, h), "", &output);
    const std::string what = "geometry " + std::to_string(static_cast<int>(g)) + ":\n" + output;
    expectTheIssuesMeasures(s, what);
    // The cape went onto the shoulders the mapping found, with no --attach, and said so.
    EXPECT_NE(output.find("shoulder"), std::string::npos) << what;
    EXPECT_EQ(output.find("cannot be used"), std::string::npos) << what;  // every mesh loaded
  }
}

// The deepest any particle of frames/NNNNN.obj is inside any convex hull of colliders.jsonl's line for that
// frame, recomputed from the files alone: the hull's planes (in its frame: position, rotation x y z w) grown
// by its thickness (the rounding that covers the mesh), depth = thickness - max_k (n_k . p - offset_k).
double deepestInHulls(const fs::path& dir, int frame, int* hulls) {
  const std::vector<std::string> jsonl = lines(dir / "colliders.jsonl");
  const json colliders = json::parse(jsonl.at(static_cast<std::size_t>(frame - 1)))["colliders"];
  char name[32];
  std::snprintf(name, sizeof name, "%05d.obj", frame);
  std::vector<std::array<double, 3>> particles;
  for (const std::string& l : lines(dir / "frames" / name)) {
    if (l.rfind("v ", 0) != 0) continue;
    std::istringstream in(l.substr(2));
    std::array<double, 3> p{};
    in >> p[0] >> p[1] >> p[2];
    particles.push_back(p);
  }
  double deepest = -1.0;
  *hulls = 0;
  for (const json& c : colliders) {
    if (c["type"] != "convex_hull") continue;
    ++*hulls;
    const double qx = c["rotation"][0], qy = c["rotation"][1], qz = c["rotation"][2], qw = c["rotation"][3];
    const double t = c.value("thickness", 0.0);
    for (const auto& x : particles) {
      // p = R^T (x - position), R from the unit quaternion.
      const double d[3] = {x[0] - c["position"][0].get<double>(), x[1] - c["position"][1].get<double>(),
                           x[2] - c["position"][2].get<double>()};
      const double r[3][3] = {
          {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)},
          {2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)},
          {2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)}};
      double p[3];
      for (int i = 0; i < 3; ++i) p[i] = r[0][i] * d[0] + r[1][i] * d[1] + r[2][i] * d[2];
      double outside = -1e30;
      for (const json& plane : c["planes"]) {
        const double n0 = plane["normal"][0], n1 = plane["normal"][1], n2 = plane["normal"][2];
        outside = std::max(outside, n0 * p[0] + n1 * p[1] + n2 * p[2] - plane["offset"].get<double>());
      }
      deepest = std::max(deepest, t - outside);
    }
  }
  return deepest;
}

TEST(AnyHumanoid, MeshLinksAreHullsInCollidersJsonlAndNoParticleIsInsideOne) {
  const fs::path dir = freshDir();
  Humanoid h;
  h.geometry = Geometry::Meshes;
  const fs::path urdf = writeHumanoid(dir, h);
  const fs::path out = dir / "run";
  const Result r = run(std::string(CAPE_WALK) + " --cape canonical --urdf " + urdf.string() +
                       " --package-path " + dir.string() + " --seconds 2 --frames --out " + out.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  double closest = -1.0;
  for (int frame = 10; frame <= 120; frame += 10) {
    int hulls = 0;
    const double deepest = deepestInHulls(out, frame, &hulls);
    EXPECT_EQ(hulls, 13) << frame;  // pelvis, torso, head, and per side two arm, two leg segments and a foot
    EXPECT_LE(deepest, 0.001) << "frame " << frame;
    closest = std::max(closest, deepest);
  }
  EXPECT_GT(closest, -0.05);  // and the cape does lie on the back: some particle within 5 cm of a hull
}

TEST(AnyHumanoid, TPoseModelWalksWithItsArmsDown) {
  const fs::path dir = freshDir();
  Humanoid h;
  h.tPose = true;
  const json s = runWalk(dir, writeHumanoid(dir, h), "");
  expectTheIssuesMeasures(s, "T-pose");
}

TEST(AnyHumanoid, ZUpWorldGivesTheSameMetricsAsYUp) {
  const fs::path dir = freshDir();
  const fs::path urdf = writeHumanoid(dir, Humanoid());
  const json y = runWalk(dir, urdf, "--up y");
  const json z = runWalk(dir, urdf, "--up z");
  ASSERT_TRUE(y.contains("summary") && z.contains("summary"));
  EXPECT_EQ(z["up"], "z");
  for (const char* key : {"max_strain", "median_frame_max_strain", "p95_frame_max_strain",
                          "max_penetration_m", "lowest_particle_m"}) {
    const double a = y["summary"][key].get<double>(), b = z["summary"][key].get<double>();
    EXPECT_NEAR(a, b, 1e-3 * std::max(1.0, std::fabs(a)) + 2e-4) << key;
  }
  // And the cape itself: a Z-up world's particle is the Y-up one's (x, y, z) turned into (-z, -x, y), to
  // float rounding. Compared at frame 20 (1/3 s), before the strain refinement's thresholds turn the two
  // worlds' rounding into different substep counts (from then on the gap grows: 0.25 mm at frame 30, about
  // 1 mm at frame 60); a wrong axis would be centimetres off from the first frame.
  std::vector<std::vector<double>> frames[2];
  for (int u = 0; u < 2; ++u) {
    const fs::path out = dir / (u == 0 ? "framesY" : "framesZ");
    const Result r = run(std::string(CAPE_WALK) + " --cape canonical --urdf " + urdf.string() +
                         " --seconds 0.34 --frames --out " + out.string() + (u == 0 ? " --up y" : " --up z"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const std::string& l : lines(out / "frames" / "00020.obj")) {
      if (l.rfind("v ", 0) != 0) continue;
      std::istringstream in(l.substr(2));
      std::vector<double> p(3);
      in >> p[0] >> p[1] >> p[2];
      frames[u].push_back(p);
    }
  }
  ASSERT_EQ(frames[0].size(), 400u);
  ASSERT_EQ(frames[1].size(), 400u);
  double worst = 0.0;
  for (std::size_t i = 0; i < 400; ++i) {
    const std::vector<double>& a = frames[0][i];
    const std::vector<double>& b = frames[1][i];
    worst = std::max({worst, std::fabs(b[0] + a[2]), std::fabs(b[1] + a[0]), std::fabs(b[2] - a[1])});
  }
  EXPECT_LT(worst, 1e-4) << "m, the largest difference of a particle after 20 frames (measured 2.6e-5)";
}

}  // namespace
}  // namespace cape::demo_test
