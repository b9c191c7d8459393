// Writes the fuzz targets' inputs that are made rather than kept:
//   OUT/seeds/<target>/  the seed corpus: the repository's own URDF models (every *.urdf in MODELS_DIR),
//                        hostile variants of them and small hand-made ones, small meshes (STL binary and
//                        ASCII, OBJ, COLLADA; good and broken), small fabrics and motion clips (CSV,
//                        DeepMimic, BVH; good and broken), each in its target's input
//                        format (the comment at the top of each fuzz_<target>.cpp);
//   OUT/large/<target>/  regression inputs too large to commit (issue 14: 40,000 and 100,000 nested
//                        elements, a 30,000-link chain, fabrics whose every particle meets every
//                        triangle), generated the same every time.
// Usage: cape_fuzz_corpus MODELS_DIR OUT
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

bool write(const fs::path& dir, const std::string& name, const std::string& bytes) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) std::fprintf(stderr, "cannot write %s\n", (dir / name).string().c_str());
  return static_cast<bool>(out);
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const std::size_t at = s.find(from);
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// --- URDF -----------------------------------------------------------------------------------------------

std::string link(const std::string& name, const std::string& body = "") {
  return body.empty() ? "<link name=\"" + name + "\"/>" : "<link name=\"" + name + "\">" + body + "</link>";
}

std::string joint(const std::string& name, const std::string& type, const std::string& parent,
                  const std::string& child, const std::string& extra = "") {
  std::string j = "<joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent +
                  "\"/><child link=\"" + child + "\"/>" + extra;
  if (type == "revolute" || type == "prismatic")
    j += "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>";
  return j + "</joint>";
}

std::string robot(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<robot name=\"r\">" + body + "</robot>\n";
}

const std::string kBox = "<collision><geometry><box size=\"0.1 0.2 0.3\"/></geometry></collision>";

// A chain of `links` links joined by revolute joints about y, each 1 cm above the last.
std::string chain(int links) {
  std::string body;
  body.reserve(static_cast<std::size_t>(links) * 260);
  body += link("l0", kBox);
  for (int i = 1; i < links; ++i) {
    body += link("l" + std::to_string(i), kBox);
    body += joint("j" + std::to_string(i), "revolute", "l" + std::to_string(i - 1), "l" + std::to_string(i),
                  "<origin xyz=\"0 0 0.01\"/><axis xyz=\"0 1 0\"/>");
  }
  return robot(body);
}

// `depth` elements nested inside a link.
std::string nested(int depth) {
  std::string open, close;
  open.reserve(static_cast<std::size_t>(depth) * 3);
  close.reserve(static_cast<std::size_t>(depth) * 4);
  for (int i = 0; i < depth; ++i) {
    open += "<a>";
    close += "</a>";
  }
  return robot("<link name=\"l\">" + open + close + "</link>");
}

void urdfSeeds(const fs::path& models, const fs::path& out) {
  std::vector<std::pair<std::string, std::string>> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(models, ec)) {
    if (e.path().extension() != ".urdf") continue;
    std::ifstream in(e.path(), std::ios::binary);
    files.emplace_back(e.path().stem().string(),
                       std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()));
  }
  for (const auto& [name, text] : files) {
    write(out, name + ".urdf", text);
    write(out, name + "_nul_then_junk.urdf", text + std::string(1, '\0') + "<junk>");
    write(out, name + "_truncated.urdf", text.substr(0, text.size() / 2));
    // Hostile variants of the model: each number-bearing attribute made extreme or broken at its first use.
    write(out, name + "_huge_origin.urdf", replaced(text, "xyz=\"0 0 0.95\"", "xyz=\"1e30 0 0.95\""));
    write(out, name + "_nan_size.urdf", replaced(text, "size=\"", "size=\"nan "));
    write(out, name + "_zero_axis.urdf", replaced(text, "<axis xyz=\"0 0 1\"/>", "<axis xyz=\"0 0 0\"/>"));
    write(out, name + "_spaced_numbers.urdf", replaced(text, "radius=\"", "radius=\" "));
    write(out, name + "_second_empty_parent.urdf", replaced(text, "</joint>", "<parent/></joint>"));
    write(out, name + "_inverted_limits.urdf",
          replaced(text, "lower=\"-0.5\" upper=\"0.5\"", "lower=\"0.5\" upper=\"-0.5\""));
  }
  write(out, "chain_50.urdf", chain(50));
  write(out, "nested_300.urdf", nested(300));
  write(out, "entity_bomb.urdf",
        "<?xml version=\"1.0\"?><!DOCTYPE r [<!ENTITY a \"aaaaaaaa\"><!ENTITY b \"&a;&a;&a;&a;&a;&a;\">"
        "<!ENTITY c \"&b;&b;&b;&b;&b;&b;\">]><robot name=\"&c;\"><link name=\"l\"/></robot>");
  write(out, "cycle.urdf",
        robot(link("a") + link("b") + joint("ab", "fixed", "a", "b") + joint("ba", "fixed", "b", "a")));
  write(out, "two_parents.urdf",
        robot(link("a") + link("b") + link("c") + joint("ac", "fixed", "a", "c") +
              joint("bc", "fixed", "b", "c")));
  write(out, "missing_link.urdf", robot(link("a") + joint("ax", "fixed", "a", "x")));
  write(out, "two_roots.urdf", robot(link("a") + link("b")));
  write(out, "no_robot.urdf", "<?xml version='1.0'?><!-- c --><notarobot/>");
  write(out, "shapes.urdf",
        robot(link("base",
                   "<inertial><mass value=\" 2 \"/></inertial>"
                   "<collision><geometry><capsule radius=\"0.05\" length=\"0.3\"/></geometry></collision>"
                   "<collision><origin xyz=\"0 0 0.1\" rpy=\"0 1.57 0\"/><geometry><cylinder radius="
                   "\"0.04\" length=\"0.2\"/></geometry></collision>"
                   "<collision><geometry><sphere radius=\"0.1\"/></geometry></collision>"
                   "<collision><geometry><mesh filename=\"package://p/m.stl\"/></geometry></collision>") +
              link("ball", kBox) + joint("s", "spherical", "base", "ball", "<origin xyz=\"0 0 0.5\"/>") +
              link("slide", kBox) + joint("p", "prismatic", "base", "slide", "<axis xyz=\"1 0 0\"/>") +
              link("mim", kBox) +
              joint("m", "continuous", "base", "mim",
                    "<mimic joint=\"p\" multiplier=\"2\"/><axis xyz=\"0 0 1\"/>")));
  write(out, "floating_world.urdf",
        robot(link("world") + link("pelvis", kBox) + joint("float", "floating", "world", "pelvis") +
              link("thigh", kBox) +
              joint("hip", "revolute", "pelvis", "thigh",
                    "<origin xyz=\"0 0.1 -0.4\"/><axis xyz=\"0 1 0\"/>")));
  write(out, "y_up_long.urdf",
        robot(link("root", "<collision><geometry><box size=\"0.1 2 0.1\"/></geometry></collision>") +
              link("leg", kBox) +
              joint("hip", "revolute", "root", "leg", "<origin xyz=\"0 -1 0\"/><axis xyz=\"0 0 1\"/>")));
}

// --- Meshes ---------------------------------------------------------------------------------------------

using Corner = std::array<float, 3>;
using Triangle = std::array<Corner, 3>;

void put32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}

void putFloat(std::string& out, float f) {
  std::uint32_t u = 0;
  std::memcpy(&u, &f, 4);
  put32(out, u);
}

std::vector<Corner> cubeCorners(float h) {
  std::vector<Corner> c;
  for (int i = 0; i < 8; ++i) c.push_back({i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h});
  return c;
}
const int kQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

std::vector<Triangle> cubeTriangles(float h) {
  const std::vector<Corner> c = cubeCorners(h);
  std::vector<Triangle> t;
  for (const auto& q : kQuads) {
    t.push_back({c[q[0]], c[q[1]], c[q[2]]});
    t.push_back({c[q[0]], c[q[2]], c[q[3]]});
  }
  return t;
}

std::string binaryStl(const std::vector<Triangle>& tris, long declared = -1) {
  std::string out(80, ' ');
  put32(out, static_cast<std::uint32_t>(declared < 0 ? static_cast<long>(tris.size()) : declared));
  for (const Triangle& t : tris) {
    for (int k = 0; k < 3; ++k) putFloat(out, 0.0f);
    for (const Corner& v : t)
      for (float x : v) putFloat(out, x);
    out += std::string(2, '\0');
  }
  return out;
}

std::string asciiStl(const std::vector<Triangle>& tris) {
  std::ostringstream s;
  s << "solid s\n";
  for (const Triangle& t : tris) {
    s << " facet normal 0 0 0\n  outer loop\n";
    for (const Corner& v : t) s << "   vertex " << v[0] << " " << v[1] << " " << v[2] << "\n";
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid s\n";
  return s.str();
}

std::string cubeObj(float h) {
  std::ostringstream s;
  s << "# cube\no cube\n";
  for (const Corner& v : cubeCorners(h)) s << "v " << v[0] << " " << v[1] << " " << v[2] << "\n";
  for (const auto& q : kQuads)
    s << "f " << q[0] + 1 << " " << q[1] + 1 << " " << q[2] + 1 << " " << q[3] + 1 << "\n";
  return s.str();
}

std::string cubeDae(float h, int nodes) {
  std::ostringstream s;
  s << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
       "<COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">"
       "<asset><unit name=\"cm\" meter=\"0.01\"/><up_axis>Z_UP</up_axis></asset>"
       "<library_geometries><geometry id=\"g\"><mesh><source id=\"p\"><float_array id=\"pa\" count=\"24\">";
  for (const Corner& v : cubeCorners(h)) s << v[0] << " " << v[1] << " " << v[2] << " ";
  s << "</float_array><technique_common><accessor source=\"#pa\" count=\"8\" stride=\"3\">"
       "<param name=\"X\" type=\"float\"/><param name=\"Y\" type=\"float\"/><param name=\"Z\" "
       "type=\"float\"/>"
       "</accessor></technique_common></source><vertices id=\"v\"><input semantic=\"POSITION\" "
       "source=\"#p\"/>"
       "</vertices><triangles count=\"12\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>";
  for (const auto& q : kQuads)
    s << q[0] << " " << q[1] << " " << q[2] << " " << q[0] << " " << q[2] << " " << q[3] << " ";
  s << "</p></triangles></mesh></geometry></library_geometries>"
       "<library_visual_scenes><visual_scene id=\"s\">";
  for (int k = 0; k < nodes; ++k)
    s << "<node id=\"n" << k << "\"><translate>" << k
      << " 0 0</translate><instance_geometry url=\"#g\"/></node>";
  s << "</visual_scene></library_visual_scenes><scene><instance_visual_scene "
       "url=\"#s\"/></scene></COLLADA>\n";
  return s.str();
}

// Mesh files by format byte (0 stl, 1 obj, 2 dae, as FuzzSupport.h's meshExtension), good and broken.
std::vector<std::pair<std::string, std::pair<std::uint8_t, std::string>>> meshes() {
  const std::vector<Triangle> cube = cubeTriangles(0.05f);
  Triangle one = {Corner{0, 0, 0}, Corner{0.1f, 0, 0}, Corner{0, 0.1f, 0}};
  return {
      {"cube_binary.stl", {0, binaryStl(cube)}},
      {"cube_ascii.stl", {0, asciiStl(cube)}},
      {"cube_count_lies.stl", {0, binaryStl(cube, 1000000)}},
      {"triangle.stl", {0, binaryStl({one})}},
      {"line.stl", {0, binaryStl({{Corner{0, 0, 0}, Corner{1, 0, 0}, Corner{2, 0, 0}}})}},
      {"nan.stl", {0, binaryStl({{Corner{0, 0, 0}, Corner{NAN, 0, 0}, Corner{0, 1, 0}}})}},
      {"huge.stl", {0, binaryStl({{Corner{0, 0, 0}, Corner{1e30f, 0, 0}, Corner{0, 1e30f, 1e30f}}})}},
      {"cube.obj", {1, cubeObj(0.05f)}},
      {"tetra.obj", {1, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"}},
      {"plate.obj", {1, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"}},
      {"bad_index.obj", {1, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\nf -1 -2 -3\n"}},
      {"groups.obj",
       {1, "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng x\nf 1 2 3\ng y\nf 1/1/1 2/2/2 4/3/3\nvt 0 0\n"}},
      {"cube.dae", {2, cubeDae(5.0f, 1)}},
      {"two_nodes.dae", {2, cubeDae(5.0f, 2)}},
      {"empty.dae", {2, "<?xml version=\"1.0\"?><COLLADA version=\"1.4.1\"></COLLADA>"}},
  };
}

void meshSeeds(const fs::path& hullOut, const fs::path& urdfOut) {
  for (const auto& [name, file] : meshes()) {
    const std::uint8_t format = file.first;
    // mesh_hull: format, budget byte (15: 64 vertices; 0: a tetrahedron), the file.
    write(hullOut, name, std::string{static_cast<char>(format), 15} + file.second);
    write(hullOut, "budget4_" + name, std::string{static_cast<char>(format), 0} + file.second);
    // urdf_mesh: format, link (1: the torso), scale byte (4: 1), the file.
    write(urdfOut, name, std::string{static_cast<char>(format), 1, 4} + file.second);
    write(urdfOut, "foot_cm_" + name, std::string{static_cast<char>(format), 11, 2} + file.second);
  }
}

// --- Fabrics --------------------------------------------------------------------------------------------

struct FabricInput {
  std::string bytes;
  void u8(int v) { bytes += static_cast<char>(v & 0xff); }
  void u16(int v) {
    u8(v);
    u8(v >> 8);
  }
  void metres(float x) { u16(static_cast<int>(std::lround(x * 1024.0f))); }
};

// fuzz_fabric.cpp's format: a rows x columns grid (two triangles per cell), anchors along the top row.
std::string gridFabric(int flags, int columns, int rows, int anchors, int frames) {
  FabricInput f;
  f.u8(flags);
  f.u8(26);  // 0.4 kg
  f.u8(anchors);
  f.u8(2);
  f.u8(64);  // tether scale 1.5
  f.u8(frames - 1);
  const int n = columns * rows;
  f.u16(n - 3);
  f.u16(2 * (columns - 1) * (rows - 1));
  for (int a = 0; a < anchors; ++a) f.u16(a * (columns - 1) / std::max(anchors - 1, 1));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      f.metres(0.6f * static_cast<float>(c) / static_cast<float>(columns - 1));
      f.metres(1.5f - 1.0f * static_cast<float>(r) / static_cast<float>(rows - 1));
      f.metres(0.0f);
    }
  if (flags & 4)
    for (int i = 0; i < n; ++i) {
      f.metres(static_cast<float>(i % columns) / static_cast<float>(columns));
      f.metres(static_cast<float>(i / columns) / static_cast<float>(rows));
    }
  for (int r = 0; r + 1 < rows; ++r)
    for (int c = 0; c + 1 < columns; ++c) {
      const int p = r * columns + c;
      for (int v : {p, p + columns, p + 1, p + 1, p + columns, p + columns + 1}) f.u16(v);
    }
  for (int k = 0; k < frames; ++k) {
    f.u16(k * 3);  // pins move along x a little every frame
    f.u16(0);
    f.u16(0);
    f.u16(0);  // the sphere swings through the cape
    f.u16(0);
    f.u16(-8);
  }
  return f.bytes;
}

// Issue 14: a side x side grid (self-collision on, 2 frames) and one long triangle per vertex, from it across
// the sheet to the two particles half the grid away. The long edges make the mean spacing, and with it the
// automatic self-collision thickness, about as long as the sheet, so every particle is within reach of every
// triangle: before self-contacts were bounded per particle, 32 x 32 took 10 s (2.95 million contacts).
std::string denseFabric(int side) {
  FabricInput f;
  for (int v : {1 | 8, 26, 0, 1, 64, 1}) f.u8(v);
  const int n = side * side, grid = 2 * (side - 1) * (side - 1);
  f.u16(n - 3);
  f.u16(grid + n);
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c) {
      f.metres(0.6f * static_cast<float>(c) / static_cast<float>(side - 1));
      f.metres(1.5f - 1.0f * static_cast<float>(r) / static_cast<float>(side - 1));
      f.metres(0.0f);
    }
  for (int r = 0; r + 1 < side; ++r)
    for (int c = 0; c + 1 < side; ++c) {
      const int p = r * side + c;
      for (int v : {p, p + side, p + 1, p + 1, p + side, p + side + 1}) f.u16(v);
    }
  for (int v = 0; v < n; ++v)
    for (int k : {v, (v + n / 2) % n, (v + n / 2 + side) % n}) f.u16(k);
  for (int k = 0; k < 2; ++k)
    for (int c : {k * 3, 0, 0, 0, 0, -8}) f.u16(c);  // pins along x, the sphere through the cape
  return f.bytes;
}

void fabricSeeds(const fs::path& out) {
  write(out, "quad.bin", gridFabric(1, 2, 2, 2, 2));
  write(out, "grid_6x6_pinned.bin", gridFabric(1 | 4, 6, 6, 3, 4));
  write(out, "grid_8x8_self_collision_wind.bin", gridFabric(1 | 8 | 32 | 128, 8, 8, 2, 3));
  write(out, "grid_5x5_explicit.bin", gridFabric(16 | 64, 5, 5, 2, 2));
  write(out, "grid_3x3_free.bin", gridFabric(0, 3, 3, 0, 1));
  // A closed tetrahedron, a non-manifold fan (three triangles on one edge), raw floats far apart.
  FabricInput t;
  for (int v : {1, 26, 1, 1, 64, 1}) t.u8(v);
  t.u16(1);
  t.u16(4);
  t.u16(0);
  for (float x : {0.f, 0.f, 0.f, 0.5f, 0.f, 0.f, 0.f, 0.5f, 0.f, 0.f, 0.f, 0.5f}) t.metres(x);
  for (int v : {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}) t.u16(v);
  write(out, "tetrahedron.bin", t.bytes);
  FabricInput fan;
  for (int v : {1, 26, 0, 1, 64, 0}) fan.u8(v);
  fan.u16(2);
  fan.u16(3);
  for (float x : {0.f, 0.f, 0.f, 0.f, 1.f, 0.f, 1.f, 0.f, 0.f, -1.f, 0.f, 0.f, 0.f, 0.f, 1.f}) fan.metres(x);
  for (int v : {0, 1, 2, 0, 1, 3, 0, 1, 4}) fan.u16(v);
  write(out, "non_manifold_fan.bin", fan.bytes);
  FabricInput raw;
  for (int v : {1 | 2, 26, 1, 1, 64, 1}) raw.u8(v);
  raw.u16(0);
  raw.u16(1);
  raw.u16(0);
  for (float x : {0.f, 0.f, 0.f, 1e18f, 0.f, 0.f, 0.f, 1e18f, 0.f}) {
    std::uint32_t u = 0;
    std::memcpy(&u, &x, 4);
    raw.u16(static_cast<int>(u & 0xffff));
    raw.u16(static_cast<int>(u >> 16));
  }
  for (int v : {0, 1, 2}) raw.u16(v);
  write(out, "raw_floats_far.bin", raw.bytes);
}

// --- Motion clips ---------------------------------------------------------------------------------------

std::string num(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

const char* const kHumanoidJoints[] = {
    "left_hip_pitch",      "right_hip_pitch",      "waist",      "neck",
    "left_knee",           "right_knee",           "left_ankle", "right_ankle",
    "left_shoulder_pitch", "right_shoulder_pitch", "left_elbow", "right_elbow"};

// A joint-trajectory CSV of the shipped humanoid's twelve joints: `rows` samples of a step in place.
std::string humanoidCsv(int rows, const std::string& extraColumn = "") {
  std::string s = "# a step\ntime, root_x, root_y, root_z, root_qx, root_qy, root_qz, root_qw";
  for (const char* j : kHumanoidJoints) s += std::string(", ") + j;
  s += extraColumn.empty() ? "" : ", " + extraColumn;
  s += "\n";
  for (int r = 0; r < rows; ++r) {
    const double t = 0.05 * r, phase = std::sin(6.283185307179586 * r / std::max(rows - 1, 1));
    const double yaw = 0.05 * phase;
    s += num(t) + ", " + num(0.3 * t) + ", 0, " + num(0.95 + 0.01 * phase) + ", 0, 0, " +
         num(std::sin(yaw / 2)) + ", " + num(std::cos(yaw / 2));
    for (std::size_t j = 0; j < std::size(kHumanoidJoints); ++j)
      s += ", " + num((j % 2 == 0 ? 0.3 : -0.3) * phase * (j < 4 ? 1.0 : 0.5));
    if (!extraColumn.empty()) s += ", 0.1";
    s += r % 2 ? "\r\n" : "\n";
  }
  return s;
}

// A DeepMimic motion file: `frames` frames of 44 numbers (duration, root position, root rotation w x y z,
// then chest, neck, right_hip, right_knee, right_ankle, right_shoulder, right_elbow, left_...).
std::string deepMimic(int frames, const std::string& loop = "wrap") {
  std::string s = "{\n\"Loop\": \"" + loop + "\",\n\"Frames\":\n[\n";
  for (int f = 0; f < frames; ++f) {
    const double a = 0.2 * std::sin(6.283185307179586 * f / std::max(frames - 1, 1));
    const std::string ball = num(std::cos(a / 2)) + "," + num(std::sin(a / 2)) + ",0,0";
    const std::string row = "[0.0333," + num(0.1 * f) + ",0.85,0," + "1,0,0,0," + ball + "," + ball + "," +
                            ball + "," + num(-a) + "," + ball + "," + ball + "," + num(a) + "," + ball + "," +
                            num(-a) + "," + ball + "," + ball + "," + num(a) + "]";
    s += row + (f + 1 < frames ? ",\n" : "\n");
  }
  return s + "]\n}\n";
}

// A BVH with Mixamo's names, Y up, centimetres: hips, spine, neck and head, two legs and two arms.
std::string mixamoBvh(int frames, bool mixamoPrefix = false) {
  const std::string p = mixamoPrefix ? "mixamorig:" : "";
  std::string s = "HIERARCHY\nROOT " + p +
                  "Hips\n{\n  OFFSET 0 95 0\n"
                  "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n";
  s += "  JOINT " + p + "Spine\n  {\n    OFFSET 0 10 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n";
  s +=
      "    JOINT " + p + "Neck\n    {\n      OFFSET 0 45 0\n      CHANNELS 3 Zrotation Xrotation Yrotation\n";
  s += "      JOINT " + p +
       "Head\n      {\n        OFFSET 0 10 0\n        CHANNELS 3 Zrotation Xrotation "
       "Yrotation\n        End Site\n        {\n          OFFSET 0 15 0\n        }\n      }\n    }\n";
  for (const char* side : {"Left", "Right"}) {
    const std::string x = std::string(side) == "Left" ? "18" : "-18";
    s += "    JOINT " + p + side + "Arm\n    {\n      OFFSET " + x +
         " 40 0\n      CHANNELS 3 Zrotation Xrotation Yrotation\n";
    s += "      JOINT " + p + side +
         "ForeArm\n      {\n        OFFSET 0 -28 0\n        CHANNELS 3 Zrotation "
         "Xrotation Yrotation\n        End Site\n        {\n          OFFSET 0 -25 0\n        }\n      }\n"
         "    }\n";
  }
  s += "  }\n";
  for (const char* side : {"Left", "Right"}) {
    const std::string x = std::string(side) == "Left" ? "9" : "-9";
    s += "  JOINT " + p + side + "UpLeg\n  {\n    OFFSET " + x +
         " -5 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n";
    s += "    JOINT " + p + side +
         "Leg\n    {\n      OFFSET 0 -42 0\n      CHANNELS 3 Zrotation Xrotation "
         "Yrotation\n";
    s += "      JOINT " + p + side +
         "Foot\n      {\n        OFFSET 0 -42 0\n        CHANNELS 3 Zrotation "
         "Xrotation Yrotation\n        End Site\n        {\n          OFFSET 0 -6 12\n        }\n      }\n"
         "    }\n  }\n";
  }
  s += "}\nMOTION\nFrames: " + std::to_string(frames) + "\nFrame Time: 0.0333333\n";
  // Channels in the order of the hierarchy: Hips (6), Spine, Neck, Head, LeftArm, LeftForeArm, RightArm,
  // RightForeArm, LeftUpLeg, LeftLeg, LeftFoot, RightUpLeg, RightLeg, RightFoot (3 each).
  for (int f = 0; f < frames; ++f) {
    const double a = 25.0 * std::sin(6.283185307179586 * f / std::max(frames - 1, 1));
    s += num(0.0) + " " + num(95.0) + " " + num(3.0 * f) + " 0 0 0";
    for (int j = 0; j < 13; ++j) {
      const double x = j >= 7 ? (j % 3 == 1 ? -std::abs(a) : (j < 10 ? a : -a)) : 0.2 * a;
      s += " 0 " + num(x) + " 0";
    }
    s += "\n";
  }
  return s;
}

void motionSeeds(const fs::path& out) {
  // Byte 0 as fuzz_motion.cpp reads it: bits 0-1 the format (0 CSV, 1 DeepMimic, 2 BVH), higher bits the
  // options.
  const auto seed = [&](const std::string& name, int selector, const std::string& text) {
    write(out, name, std::string(1, static_cast<char>(selector)) + text);
  };
  seed("humanoid_step.csv", 0, humanoidCsv(9));
  seed("humanoid_step_world.csv", 0 | 4, humanoidCsv(5));
  seed("humanoid_step_not_looping.csv", 0 | 0x80 | 0x40, humanoidCsv(4));
  seed("one_sample.csv", 0, humanoidCsv(1));
  seed("ball_columns.csv", 0, humanoidCsv(3, "left_shoulder_pitch.qx"));
  seed("unknown_joint.csv", 0, humanoidCsv(3, "tail"));
  seed("times_backwards.csv", 0, replaced(humanoidCsv(3), "\n0.05,", "\n-0.05,"));
  seed("nan_value.csv", 0, replaced(humanoidCsv(3), ", 0.95,", ", nan,"));
  seed("huge_position.csv", 0, replaced(humanoidCsv(4), ", 0.95,", ", 1e308,"));
  seed("header_only.csv", 0, "time, root_x, root_y, root_z, root_qx, root_qy, root_qz, root_qw\n");
  seed("walk.txt", 1, deepMimic(6));
  seed("walk_no_loop.txt", 1, deepMimic(3, "none"));
  seed("one_frame.txt", 1, deepMimic(1));
  seed("short_frame.txt", 1, "{\"Loop\":\"wrap\",\"Frames\":[[0.03,0,0.8,0,1,0,0,0]]}");
  seed("wrong_types.txt", 1, "{\"Loop\":3,\"Frames\":[[\"a\",null,{},[]]]}");
  seed("zero_quaternion.txt", 1, replaced(deepMimic(2), ",1,0,0,0,", ",0,0,0,0,"));
  seed("mixamo_walk.bvh", 2, mixamoBvh(8));
  seed("mixamo_prefix_walk.bvh", 2, mixamoBvh(4, true));
  seed("mixamo_walk_onto_balls.bvh", 3, mixamoBvh(8));  // retargeted onto the ball-jointed model
  seed("mixamo_cm_y_up.bvh", 2 | (1 << 2) | (1 << 4), mixamoBvh(4));
  seed("mixamo_metres_z_up_in_place.bvh", 2 | (2 << 2) | (2 << 4) | 0x40 | 0x80, mixamoBvh(3));
  seed("mixamo_hierarchy_only.bvh", 2, mixamoBvh(2).substr(0, mixamoBvh(2).find("MOTION")));
  seed("mixamo_frame_count_lies.bvh", 2, replaced(mixamoBvh(3), "Frames: 3", "Frames: 300"));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s MODELS_DIR OUT\n", argv[0]);
    return 2;
  }
  const fs::path models = argv[1], out = argv[2];
  if (!fs::is_directory(models)) {
    std::fprintf(stderr, "no models folder %s\n", argv[1]);
    return 2;
  }
  urdfSeeds(models, out / "seeds" / "urdf");
  meshSeeds(out / "seeds" / "mesh_hull", out / "seeds" / "urdf_mesh");
  fabricSeeds(out / "seeds" / "fabric");
  motionSeeds(out / "seeds" / "motion");
  // Issue 14, 1: urdfdom's parser recursed per level and overflowed its stack at about 37,000.
  write(out / "large" / "urdf", "nested_40000.urdf", nested(40000));
  write(out / "large" / "urdf", "nested_100000.urdf", nested(100000));
  // Issue 14, 2: the joint-cycle check walked to the root from every link (30k links: minutes).
  write(out / "large" / "urdf", "chain_30000.urdf", chain(30000));
  // Issue 14: self-contacts of every particle with every triangle (a 24 KB input: made, not kept).
  write(out / "large" / "fabric", "dense_self_contacts_32x32.bin", denseFabric(32));
  write(out / "large" / "fabric", "dense_self_contacts_24x24.bin", denseFabric(24));
  std::printf("wrote the seeds and the large regression inputs under %s\n", out.string().c_str());
  return 0;
}
