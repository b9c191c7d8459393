// A cape from a mesh file (cape/character/FabricMesh.h): real files of assimp's own test models (OBJ and PLY
// with vertex colours, glTF with UVs), files written here for the conventions (welding, UV orientation), and
// the weight map painted by the colours.
#include "cape/character/FabricMesh.h"
#include "cape/core/WeightMap.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace cape::character {
namespace {

namespace fs = std::filesystem;

const std::string kModels = "/usr/share/assimp/models/";  // Debian's assimp-testmodels

bool haveModels() {
  return fs::exists(kModels + "OBJ/cube_with_vertexcolors.obj");
}

/// This process's folder of written inputs, removed when the process ends.
struct InputFolder {
  fs::path path = fs::temp_directory_path() / ("cape_fabric_mesh_" + std::to_string(::getpid()));
  ~InputFolder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

fs::path writeFile(const std::string& name, const std::string& text) {
  static const InputFolder dir;
  fs::create_directories(dir.path);
  const fs::path file = dir.path / name;
  std::ofstream(file) << text;
  return file;
}

TEST(FabricMesh, AnObjCubeWithVertexColoursGivesItsColoursAndAWeightMap) {
  if (!haveModels()) GTEST_SKIP() << "assimp-testmodels is not installed (scripts/debian-packages.txt)";
  const FabricMeshFile f = loadFabricMesh(kModels + "OBJ/cube_with_vertexcolors.obj");
  ASSERT_TRUE(f.ok()) << f.status.message();
  // Eight corners: the faces' split copies (one per face and normal) welded back by position.
  EXPECT_EQ(f.mesh.positions.size(), 8u);
  EXPECT_EQ(f.mesh.triangles.size(), 36u);
  EXPECT_EQ(f.fileVertices, 36);
  ASSERT_EQ(f.colours.size(), 8u);
  int checked = 0;
  for (std::size_t i = 0; i < 8; ++i) {
    const Vec3& p = f.mesh.positions[i];
    if (p.isApprox(Vec3(0, 0, 1))) {
      EXPECT_TRUE(f.colours[i].isApprox(Vec3(0.09412f, 0.0f, 0.47451f), 1e-4f));
      ++checked;
    }
    if (p.isApprox(Vec3(1, 0, 0))) {
      EXPECT_TRUE(f.colours[i].isApprox(Vec3(0.09412f, 0.78431f, 0.09804f), 1e-4f));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2);
  FabricResult fabric = Fabric::fromMesh(f.mesh);
  ASSERT_TRUE(fabric.status.ok()) << fabric.status.message();
  const WeightMapResult w = weightMapFromColours(*fabric.fabric, f.colours, 0.0f, 0.1f);
  ASSERT_TRUE(w) << w.status.message();
  for (std::size_t i = 0; i < 8; ++i) {
    const Vec3& c = f.colours[i];
    EXPECT_NEAR(w.values[static_cast<Eigen::Index>(i)],
                0.1f * (0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z()), 1e-6f);
  }
}

TEST(FabricMesh, PlyFilesWithAndWithoutColours) {
  if (!haveModels()) GTEST_SKIP() << "assimp-testmodels is not installed (scripts/debian-packages.txt)";
  const FabricMeshFile colour = loadFabricMesh(kModels + "PLY/float-color.ply", {0.01, 0.2f});
  ASSERT_TRUE(colour.ok()) << colour.status.message();
  ASSERT_EQ(colour.mesh.positions.size(), 3u);
  EXPECT_TRUE(colour.mesh.positions[2].isApprox(Vec3(2.0f, 2.0f, 0.0f)));  // 200 cm
  ASSERT_EQ(colour.colours.size(), 3u);
  for (const Vec3& c : colour.colours) EXPECT_TRUE(c.isApprox(Vec3(0, 0, 1)));
  EXPECT_EQ(colour.mesh.totalMass, 0.2f);
  // A cube of quads without colours: triangulated, eight corners, no colours.
  const FabricMeshFile plain = loadFabricMesh(kModels + "PLY/cube.ply");
  ASSERT_TRUE(plain.ok()) << plain.status.message();
  EXPECT_EQ(plain.mesh.positions.size(), 8u);
  EXPECT_EQ(plain.mesh.triangles.size(), 36u);
  EXPECT_TRUE(plain.colours.empty());
  EXPECT_TRUE(plain.mesh.uvs.empty());
}

TEST(FabricMesh, AGltfBoxKeepsItsTextureCoordinates) {
  if (!haveModels()) GTEST_SKIP() << "assimp-testmodels is not installed (scripts/debian-packages.txt)";
  const FabricMeshFile f = loadFabricMesh(kModels + "glTF2/BoxTexcoords-glTF/boxTexcoords.gltf");
  ASSERT_TRUE(f.ok()) << f.status.message();
  EXPECT_EQ(f.mesh.positions.size(), 8u);  // 24 vertices (4 per face) welded to the corners
  ASSERT_EQ(f.mesh.uvs.size(), f.mesh.positions.size());
  for (const Eigen::Vector2f& uv : f.mesh.uvs) {
    EXPECT_GE(uv.minCoeff(), -1e-6f);
    EXPECT_LE(uv.maxCoeff(), 1.0f + 1e-6f);
  }
  // glTF's TEXCOORD_0 as the file stores it (read from boxTexcoords.bin): glTF's v already runs from the
  // top, so it comes through unchanged (assimp turns it to v-up on import, aiProcess_FlipUVs back).
  int checked = 0;
  for (std::size_t i = 0; i < f.mesh.positions.size(); ++i) {
    if (f.mesh.positions[i].isApprox(Vec3(1, 1, 1))) {
      EXPECT_TRUE(f.mesh.uvs[i].isApprox(Eigen::Vector2f(0.708984375f, 0.177734375f), 1e-5f))
          << f.mesh.uvs[i];
      ++checked;
    }
    if (f.mesh.positions[i].isApprox(Vec3(1, 1, -1))) {
      EXPECT_TRUE(f.mesh.uvs[i].isApprox(Eigen::Vector2f(0.7138671875f, 0.58203125f), 1e-5f))
          << f.mesh.uvs[i];
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2);
}

TEST(FabricMesh, ObjUvsAreTurnedToTheTopLeftConventionAndSeamsWelded) {
  // Two triangles of a unit square, the top edge at y = 1 with OBJ's vt v = 1 (OBJ's v grows upwards), and
  // the right triangle's corners written again (a UV seam): four particles, v = 0 at the top.
  const fs::path obj = writeFile("square.obj",
                                 "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 0\nv 1 1 0\n"
                                 "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                 "f 1/1 2/2 4/4\nf 5/2 6/3 4/4\n");
  const FabricMeshFile f = loadFabricMesh(obj.string());
  ASSERT_TRUE(f.ok()) << f.status.message();
  ASSERT_EQ(f.mesh.positions.size(), 4u);
  EXPECT_EQ(f.mesh.triangles.size(), 6u);
  for (std::size_t i = 0; i < 4; ++i) {
    const Vec3& p = f.mesh.positions[i];
    EXPECT_NEAR(f.mesh.uvs[i].x(), p.x(), 1e-6f);
    EXPECT_NEAR(f.mesh.uvs[i].y(), 1.0f - p.y(), 1e-6f) << "v = 0 along the top";
  }
  EXPECT_TRUE(f.colours.empty());
  FabricResult fabric = Fabric::fromMesh(f.mesh);
  EXPECT_TRUE(fabric.status.ok()) << fabric.status.message();
}

TEST(FabricMesh, BadFilesAndOptionsAreRefusedWithAReason) {
  EXPECT_EQ(loadFabricMesh("/nonexistent/cape.obj").status.code(), ErrorCode::FileNotFound);
  EXPECT_EQ(loadFabricMesh(fs::temp_directory_path().string()).status.code(), ErrorCode::FileNotFound);
  const fs::path empty = writeFile("empty.obj", "");
  EXPECT_EQ(loadFabricMesh(empty.string()).status.code(), ErrorCode::InvalidModel);
  const fs::path lines = writeFile("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n");
  const FabricMeshFile noTriangles = loadFabricMesh(lines.string());
  EXPECT_FALSE(noTriangles.ok());
  const fs::path degenerate = writeFile("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 0 0 0\nf 1 2 3\n");
  const FabricMeshFile welded = loadFabricMesh(degenerate.string());
  EXPECT_FALSE(welded.ok());
  EXPECT_NE(welded.status.message().find("no triangles"), std::string::npos) << welded.status.message();
  const fs::path far = writeFile("far.obj", "v 0 0 0\nv 1e7 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_NE(loadFabricMesh(far.string()).status.message().find("1e6 m"), std::string::npos);
  const fs::path ok = writeFile("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n");
  FabricMeshOptions one;
  one.maxTriangles = 1;
  EXPECT_NE(loadFabricMesh(ok.string(), one).status.message().find("more than 1 triangles"),
            std::string::npos);
  for (double scale : {0.0, -1.0, std::nan("")}) {
    FabricMeshOptions o;
    o.scale = scale;
    EXPECT_EQ(loadFabricMesh(ok.string(), o).status.code(), ErrorCode::InvalidArgument) << scale;
  }
  FabricMeshOptions massless;
  massless.totalMass = 0.0f;
  EXPECT_EQ(loadFabricMesh(ok.string(), massless).status.code(), ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace cape::character
