#include "cape/character/FabricMesh.h"

#include "MeshHull.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <utility>

namespace cape::character {

namespace {

namespace fs = std::filesystem;

constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 30;  // 1 GiB, as loadMeshHull's
constexpr double kMaxCoordinate = 1e6;                             // m, after the scale

Status invalid(const std::string& path, const std::string& what) {
  return Status::error(ErrorCode::InvalidModel, "fabric mesh file '" + path + "': " + what);
}

Eigen::Matrix4d toMatrix(const aiMatrix4x4& m) {
  Eigen::Matrix4d r;
  r << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return r;
}

}  // namespace

FabricMeshFile loadFabricMesh(const std::string& path, const FabricMeshOptions& options) {
  FabricMeshFile out;
  if (!std::isfinite(options.scale) || !(options.scale > 0.0) || !std::isfinite(options.totalMass) ||
      !(options.totalMass > 0.0f) || options.maxTriangles < 1) {
    out.status =
        Status::error(ErrorCode::InvalidArgument,
                      "FabricMeshOptions: scale and totalMass must be finite and > 0, maxTriangles >= 1");
    return out;
  }
  std::error_code ec;
  if (!fs::is_regular_file(path, ec) || !std::ifstream(path, std::ios::binary)) {
    out.status = Status::error(ErrorCode::FileNotFound,
                               "fabric mesh file '" + path + "' is not a readable regular file");
    return out;
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec || size == 0) {
    out.status = invalid(path, "the file is empty");
    return out;
  }
  if (size > kMaxFileBytes) {
    out.status = invalid(path, "the file is larger than 1 GiB: refused");
    return out;
  }
  if (Status checked = precheckMeshFile(path); !checked.ok()) {
    out.status = checked;
    return out;
  }
  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  // Triangulate: polygons to triangles; FlipUVs: v from the top (glTF's, WeightMap.h's); validation rejects a
  // broken scene. No welding by assimp (JoinIdenticalVertices welds by every attribute, keeping seams
  // split): the weld below is by position alone.
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_FlipUVs | aiProcess_ValidateDataStructure);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    out.status = invalid(path, std::string("assimp cannot read it: ") + importer.GetErrorString());
    return out;
  }
  // Welding by exact position (the scaled, transformed float coordinates): deterministic, in file order.
  std::map<std::array<float, 3>, std::uint32_t> weld;
  bool anyUv = false, anyColour = false;
  std::vector<Eigen::Vector2f> uvs;
  std::vector<Vec3> colours;
  std::vector<std::pair<const aiNode*, Eigen::Matrix4d>> stack{
      {scene->mRootNode, Eigen::Matrix4d::Identity()}};
  std::vector<std::int64_t> particleOf;
  int triangles = 0;
  while (!stack.empty()) {
    const aiNode* node = stack.back().first;
    const Eigen::Matrix4d world = stack.back().second * toMatrix(node->mTransformation);
    stack.pop_back();
    for (unsigned k = node->mNumChildren; k-- > 0;)
      if (node->mChildren[k] != nullptr) stack.emplace_back(node->mChildren[k], world);
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      if (node->mMeshes[k] >= scene->mNumMeshes) {
        out.status = invalid(path, "a node names a mesh that is not there");
        return out;
      }
      const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
      if (mesh == nullptr || mesh->mVertices == nullptr || mesh->mFaces == nullptr) continue;
      const aiVector3D* uv = mesh->mTextureCoords[0];
      const aiColor4D* colour = mesh->mColors[0];
      particleOf.assign(mesh->mNumVertices, -1);
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        if (face.mNumIndices != 3 || face.mIndices == nullptr) continue;  // points and lines
        if (++triangles > options.maxTriangles) {
          out.status = invalid(path, "more than " + std::to_string(options.maxTriangles) +
                                         " triangles (every node instance counted): refused");
          return out;
        }
        std::uint32_t corner[3];
        for (unsigned i = 0; i < 3; ++i) {
          const unsigned v = face.mIndices[i];
          if (v >= mesh->mNumVertices) {
            out.status = invalid(path, "a face index is out of range");
            return out;
          }
          if (particleOf[v] < 0) {
            const aiVector3D& raw = mesh->mVertices[v];
            const Eigen::Vector3d p = (world.topLeftCorner<3, 3>() * Eigen::Vector3d(raw.x, raw.y, raw.z) +
                                       world.topRightCorner<3, 1>()) *
                                      options.scale;
            if (!p.allFinite() || p.cwiseAbs().maxCoeff() > kMaxCoordinate) {
              out.status = invalid(path,
                                   "a vertex is not finite or lies farther than 1e6 m from the origin "
                                   "(after node transforms and the scale)");
              return out;
            }
            const std::array<float, 3> key = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                                              static_cast<float>(p.z())};
            const auto [it, fresh] = weld.emplace(key, static_cast<std::uint32_t>(out.mesh.positions.size()));
            ++out.fileVertices;
            if (fresh) {
              out.mesh.positions.emplace_back(key[0], key[1], key[2]);
              Eigen::Vector2f t = Eigen::Vector2f::Zero();
              if (uv != nullptr) {
                t = Eigen::Vector2f(uv[v].x, uv[v].y);
                anyUv = true;
              }
              Vec3 c = Vec3::Zero();
              if (colour != nullptr) {
                c = Vec3(colour[v].r, colour[v].g, colour[v].b);
                anyColour = true;
              }
              if (!t.allFinite() || !c.allFinite()) {
                out.status = invalid(path, "a texture coordinate or a vertex colour is not finite");
                return out;
              }
              uvs.push_back(t);
              colours.push_back(c.cwiseMax(0.0f).cwiseMin(1.0f));
            }
            particleOf[v] = it->second;
          }
          corner[i] = static_cast<std::uint32_t>(particleOf[v]);
        }
        if (corner[0] == corner[1] || corner[1] == corner[2] || corner[0] == corner[2]) {
          ++out.droppedTriangles;
          continue;
        }
        out.mesh.triangles.insert(out.mesh.triangles.end(), {corner[0], corner[1], corner[2]});
      }
    }
  }
  if (out.mesh.triangles.empty()) {
    out.mesh = MeshDesc();
    out.status = invalid(path, "it has no triangles (after welding)");
    return out;
  }
  // Vertices only degenerate triangles used are dropped, the rest renumbered in order.
  std::vector<std::int64_t> renumber(out.mesh.positions.size(), -1);
  for (std::uint32_t v : out.mesh.triangles) renumber[v] = 0;
  std::vector<Vec3> kept;
  std::vector<Eigen::Vector2f> keptUvs;
  std::vector<Vec3> keptColours;
  for (std::size_t i = 0; i < out.mesh.positions.size(); ++i) {
    if (renumber[i] < 0) continue;
    renumber[i] = static_cast<std::int64_t>(kept.size());
    kept.push_back(out.mesh.positions[i]);
    keptUvs.push_back(uvs[i]);
    keptColours.push_back(colours[i]);
  }
  for (std::uint32_t& v : out.mesh.triangles) v = static_cast<std::uint32_t>(renumber[v]);
  out.mesh.positions = std::move(kept);
  if (anyUv) out.mesh.uvs = std::move(keptUvs);
  if (anyColour) out.colours = std::move(keptColours);
  out.mesh.totalMass = options.totalMass;
  return out;
}

}  // namespace cape::character
