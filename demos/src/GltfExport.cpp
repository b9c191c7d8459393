#include "GltfExport.h"

#include "ShapeMesh.h"

// Debian ships tinygltf as a shared library (libtinygltf.so, its JSON and stb symbols hidden), so this file
// includes only the declarations and links TinyGLTF::TinyGLTF; no TINYGLTF_IMPLEMENTATION here.
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

namespace cape::demo {

namespace {

/// Builds buffer views and accessors into the model's single buffer (the GLB's binary chunk).
class BufferBuilder {
 public:
  explicit BufferBuilder(tinygltf::Model& model) : model_(model) { model_.buffers.resize(1); }

  /// Appends bytes as a new buffer view (4-byte aligned, as float and uint32 accessors need).
  int view(const void* data, std::size_t bytes, int target) {
    std::vector<unsigned char>& bin = model_.buffers[0].data;
    bin.resize((bin.size() + 3) / 4 * 4, 0);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = bin.size();
    v.byteLength = bytes;
    v.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    bin.insert(bin.end(), p, p + bytes);
    model_.bufferViews.push_back(std::move(v));
    return static_cast<int>(model_.bufferViews.size() - 1);
  }

  /// A float accessor of `count` elements of `components` floats each (SCALAR, VEC2, VEC3, VEC4).
  int floats(const float* data, std::size_t count, int components, int target = 0, bool bounds = false) {
    const int view = this->view(data, count * components * sizeof(float), target);
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = count;
    a.type = components == 1   ? TINYGLTF_TYPE_SCALAR
             : components == 2 ? TINYGLTF_TYPE_VEC2
             : components == 3 ? TINYGLTF_TYPE_VEC3
                               : TINYGLTF_TYPE_VEC4;
    if (bounds) {
      a.minValues.assign(static_cast<std::size_t>(components), 1e30);
      a.maxValues.assign(static_cast<std::size_t>(components), -1e30);
      for (std::size_t i = 0; i < count; ++i) {
        for (int c = 0; c < components; ++c) {
          const double x = data[i * static_cast<std::size_t>(components) + static_cast<std::size_t>(c)];
          a.minValues[static_cast<std::size_t>(c)] = std::min(a.minValues[static_cast<std::size_t>(c)], x);
          a.maxValues[static_cast<std::size_t>(c)] = std::max(a.maxValues[static_cast<std::size_t>(c)], x);
        }
      }
    }
    model_.accessors.push_back(std::move(a));
    return static_cast<int>(model_.accessors.size() - 1);
  }

  int indices(const std::vector<std::uint32_t>& data) {
    const int view =
        this->view(data.data(), data.size() * sizeof(std::uint32_t), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    a.count = data.size();
    a.type = TINYGLTF_TYPE_SCALAR;
    model_.accessors.push_back(std::move(a));
    return static_cast<int>(model_.accessors.size() - 1);
  }

 private:
  tinygltf::Model& model_;
};

int addMaterial(tinygltf::Model& model, const std::string& name, std::vector<double> rgba, double roughness,
                bool doubleSided) {
  tinygltf::Material m;
  m.name = name;
  m.pbrMetallicRoughness.baseColorFactor = std::move(rgba);
  m.pbrMetallicRoughness.metallicFactor = 0.0;
  m.pbrMetallicRoughness.roughnessFactor = roughness;
  m.doubleSided = doubleSided;
  model.materials.push_back(std::move(m));
  return static_cast<int>(model.materials.size() - 1);
}

/// A triangle primitive from interleaved-free arrays.
tinygltf::Primitive primitive(BufferBuilder& b, const std::vector<float>& positions,
                              const std::vector<float>& normals, const std::vector<std::uint32_t>& indices,
                              int material) {
  tinygltf::Primitive p;
  p.attributes["POSITION"] =
      b.floats(positions.data(), positions.size() / 3, 3, TINYGLTF_TARGET_ARRAY_BUFFER, true);
  p.attributes["NORMAL"] = b.floats(normals.data(), normals.size() / 3, 3, TINYGLTF_TARGET_ARRAY_BUFFER);
  p.indices = b.indices(indices);
  p.material = material;
  p.mode = TINYGLTF_MODE_TRIANGLES;
  return p;
}

int addNode(tinygltf::Model& model, tinygltf::Node node) {
  model.nodes.push_back(std::move(node));
  return static_cast<int>(model.nodes.size() - 1);
}

void copyRows(const Points& points, std::size_t rows, std::vector<float>& out) {
  out.resize(rows * 3);
  for (std::size_t i = 0; i < rows; ++i) {
    for (int c = 0; c < 3; ++c)
      out[i * 3 + static_cast<std::size_t>(c)] = points(static_cast<Eigen::Index>(i), c);
  }
}

}  // namespace

GltfRecorder::GltfRecorder(int characters, double frameTime)
    : characters_(std::max(characters, 1)),
      frameTime_(frameTime),
      tracks_(static_cast<std::size_t>(characters_)) {}

void GltfRecorder::record(int character, const Cape& cape, const std::vector<Collider>& colliders) {
  record(character, cape.fabric(), cape.state().positions, colliders);
}

void GltfRecorder::record(int character, const Fabric& fabric, const Points& positions,
                          const std::vector<Collider>& colliders) {
  if (character < 0 || character >= characters_) return;
  if (character == 0) ++frames_;  // a new frame starts with character 0
  CharacterTrack& t = tracks_[static_cast<std::size_t>(character)];
  const bool first = t.vertices == 0;
  if (first) {
    t.mesh.allocate(fabric, false);
    t.vertices = fabric.particleCount();
    t.indices = t.mesh.indices;
    t.uvs.resize(t.vertices * 2);
    for (std::size_t i = 0; i < t.vertices; ++i) {
      t.uvs[2 * i] = t.mesh.uvs[i].x();
      t.uvs[2 * i + 1] = t.mesh.uvs[i].y();
    }
    for (const Collider& c : colliders) t.colliders.push_back({c, {}, {}});
  }
  // Collider poses (a collider set that changed shape count keeps the first frame's tracks in step).
  for (std::size_t i = 0; i < t.colliders.size(); ++i) {
    ColliderTrack& track = t.colliders[i];
    const Pose& p = i < colliders.size() ? colliders[i].current : Pose();
    track.translations.insert(track.translations.end(), {p.position.x(), p.position.y(), p.position.z()});
    const Quat q = p.rotation.normalized();
    track.rotations.insert(track.rotations.end(), {q.x(), q.y(), q.z(), q.w()});
    sceneMin_ = sceneMin_.cwiseMin(p.position);
    sceneMax_ = sceneMax_.cwiseMax(p.position);
  }
  // The cape: the first frame is the base mesh, every later frame a morph target of deltas from it.
  t.mesh.update(fabric, positions);
  const std::size_t n = t.vertices;
  if (first) {
    copyRows(t.mesh.positions, n, t.basePositions);
    copyRows(t.mesh.normals, n, t.baseNormals);
    return;
  }
  const std::size_t start = t.morphs.size();
  t.morphs.resize(start + 6 * n);
  float* d = t.morphs.data() + start;
  Vec3 lo = Vec3::Constant(1e30f), hi = Vec3::Constant(-1e30f);
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      const auto row = static_cast<Eigen::Index>(i);
      const std::size_t k = i * 3 + static_cast<std::size_t>(c);
      d[k] = t.mesh.positions(row, c) - t.basePositions[k];
      d[3 * n + k] = t.mesh.normals(row, c) - t.baseNormals[k];
      lo[c] = std::min(lo[c], d[k]);
      hi[c] = std::max(hi[c], d[k]);
    }
  }
  t.morphMin.insert(t.morphMin.end(), {lo.x(), lo.y(), lo.z()});
  t.morphMax.insert(t.morphMax.end(), {hi.x(), hi.y(), hi.z()});
}

bool GltfRecorder::write(const std::filesystem::path& file, std::string& error) {
  if (frames_ == 0) {
    error = "nothing recorded for " + file.string();
    return false;
  }
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) {
    error = "cannot write " + file.string();
    return false;
  }

  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "CapeCloth cape_walk (tinygltf)";
  BufferBuilder b(model);
  tinygltf::Scene scene;
  scene.name = "run";

  const int capeMaterial = addMaterial(model, "cape", {0.62, 0.05, 0.07, 1.0}, 0.85, true);
  const int bodyMaterial = addMaterial(model, "body", {0.45, 0.55, 0.70, 1.0}, 0.6, false);
  const int groundLight = addMaterial(model, "ground light", {0.80, 0.80, 0.78, 1.0}, 0.95, false);
  const int groundDark = addMaterial(model, "ground dark", {0.55, 0.56, 0.58, 1.0}, 0.95, false);

  // Key times, shared by every sampler: frame f at f * frameTime.
  std::vector<float> times(static_cast<std::size_t>(frames_));
  for (int f = 0; f < frames_; ++f) times[static_cast<std::size_t>(f)] = static_cast<float>(f * frameTime_);
  const int timeAccessor = b.floats(times.data(), times.size(), 1, 0, true);

  // The ground: 1 m checker tiles covering the colliders' path with 10 m to spare, two primitives.
  {
    const float margin = 10.0f;
    const int x0 = static_cast<int>(std::floor(sceneMin_.x() - margin)),
              x1 = static_cast<int>(std::ceil(sceneMax_.x() + margin));
    const int z0 = static_cast<int>(std::floor(sceneMin_.z() - margin)),
              z1 = static_cast<int>(std::ceil(sceneMax_.z() + margin));
    std::vector<float> pos[2], nrm[2];
    std::vector<std::uint32_t> idx[2];
    for (int x = x0; x < x1; ++x) {
      for (int z = z0; z < z1; ++z) {
        const int k = ((x + z) % 2 + 2) % 2;
        const auto base = static_cast<std::uint32_t>(pos[k].size() / 3);
        const float fx = static_cast<float>(x), fz = static_cast<float>(z);
        // Counter-clockwise seen from above (+Y): (x, z) -> (x, z + 1) -> (x + 1, z + 1) -> (x + 1, z).
        pos[k].insert(pos[k].end(), {fx, 0, fz, fx, 0, fz + 1, fx + 1, 0, fz + 1, fx + 1, 0, fz});
        for (int v = 0; v < 4; ++v) nrm[k].insert(nrm[k].end(), {0.0f, 1.0f, 0.0f});
        idx[k].insert(idx[k].end(), {base, base + 1, base + 2, base, base + 2, base + 3});
      }
    }
    tinygltf::Mesh mesh;
    mesh.name = "ground";
    for (int k = 0; k < 2; ++k) {
      if (!idx[k].empty())
        mesh.primitives.push_back(primitive(b, pos[k], nrm[k], idx[k], k == 0 ? groundLight : groundDark));
    }
    model.meshes.push_back(std::move(mesh));
    tinygltf::Node node;
    node.name = "ground";
    node.mesh = static_cast<int>(model.meshes.size() - 1);
    scene.nodes.push_back(addNode(model, std::move(node)));
  }

  tinygltf::Animation animation;
  animation.name = "run";
  auto animate = [&](int node, const char* path, int output, const char* interpolation) {
    tinygltf::AnimationSampler s;
    s.input = timeAccessor;
    s.output = output;
    s.interpolation = interpolation;
    animation.samplers.push_back(std::move(s));
    tinygltf::AnimationChannel c;
    c.sampler = static_cast<int>(animation.samplers.size() - 1);
    c.target_node = node;
    c.target_path = path;
    animation.channels.push_back(std::move(c));
  };

  for (std::size_t k = 0; k < tracks_.size(); ++k) {
    CharacterTrack& t = tracks_[k];
    if (t.vertices == 0) continue;
    tinygltf::Node group;
    group.name = "character " + std::to_string(k);

    for (ColliderTrack& track : t.colliders) {
      const ShapeMesh shape = colliderMesh(track.shape);
      tinygltf::Mesh mesh;
      mesh.name = track.shape.name.empty() ? std::string(toString(track.shape.shape)) : track.shape.name;
      mesh.primitives.push_back(primitive(b, shape.positions, shape.normals, shape.indices, bodyMaterial));
      model.meshes.push_back(std::move(mesh));
      tinygltf::Node node;
      node.name = model.meshes.back().name;
      node.mesh = static_cast<int>(model.meshes.size() - 1);
      node.translation.assign(track.translations.begin(), track.translations.begin() + 3);
      node.rotation.assign(track.rotations.begin(), track.rotations.begin() + 4);
      const int id = addNode(model, std::move(node));
      group.children.push_back(id);
      // Frames a collider missed (it was recorded later than others) repeat its last pose.
      const std::size_t keys = times.size();
      while (track.translations.size() < 3 * keys)
        track.translations.insert(track.translations.end(), track.translations.end() - 3,
                                  track.translations.end());
      while (track.rotations.size() < 4 * keys)
        track.rotations.insert(track.rotations.end(), track.rotations.end() - 4, track.rotations.end());
      animate(id, "translation", b.floats(track.translations.data(), keys, 3), "LINEAR");
      animate(id, "rotation", b.floats(track.rotations.data(), keys, 4), "LINEAR");
      std::vector<float>().swap(track.translations);
      std::vector<float>().swap(track.rotations);
    }

    // The cape: base mesh, one morph target per later frame, weights stepping through them.
    tinygltf::Mesh mesh;
    mesh.name = "cape " + std::to_string(k);
    tinygltf::Primitive p = primitive(b, t.basePositions, t.baseNormals, t.indices, capeMaterial);
    p.attributes["TEXCOORD_0"] = b.floats(t.uvs.data(), t.vertices, 2, TINYGLTF_TARGET_ARRAY_BUFFER);
    const std::size_t n = t.vertices, targets = t.morphMin.size() / 3;
    tinygltf::Value::Array targetNames;
    for (std::size_t m = 0; m < targets; ++m) {
      const float* d = t.morphs.data() + m * 6 * n;
      std::map<std::string, int> target;
      target["POSITION"] = b.floats(d, n, 3, TINYGLTF_TARGET_ARRAY_BUFFER);
      tinygltf::Accessor& a = model.accessors[static_cast<std::size_t>(target["POSITION"])];
      a.minValues = {t.morphMin[3 * m], t.morphMin[3 * m + 1], t.morphMin[3 * m + 2]};
      a.maxValues = {t.morphMax[3 * m], t.morphMax[3 * m + 1], t.morphMax[3 * m + 2]};
      target["NORMAL"] = b.floats(d + 3 * n, n, 3, TINYGLTF_TARGET_ARRAY_BUFFER);
      p.targets.push_back(std::move(target));
      targetNames.emplace_back("frame " + std::to_string(m + 1));
    }
    std::vector<float>().swap(t.morphs);
    mesh.primitives.push_back(std::move(p));
    if (targets > 0) {
      mesh.weights.assign(targets, 0.0);
      tinygltf::Value::Object extras;
      extras["targetNames"] = tinygltf::Value(std::move(targetNames));  // shape key names in Blender
      mesh.extras = tinygltf::Value(std::move(extras));
    }
    model.meshes.push_back(std::move(mesh));
    tinygltf::Node capeNode;
    capeNode.name = "cape " + std::to_string(k);
    capeNode.mesh = static_cast<int>(model.meshes.size() - 1);
    const int capeId = addNode(model, std::move(capeNode));
    group.children.push_back(capeId);
    if (targets > 0) {
      // Key f: all weights 0 but target f - 1 (frame f), which is 1; key 0 is the base mesh.
      const std::size_t keys = times.size();
      std::vector<float> weights(keys * targets, 0.0f);
      for (std::size_t f = 1; f < keys && f - 1 < targets; ++f) weights[f * targets + (f - 1)] = 1.0f;
      animate(capeId, "weights", b.floats(weights.data(), keys * targets, 1), "STEP");
    }
    scene.nodes.push_back(addNode(model, std::move(group)));
  }
  tracks_.clear();

  if (!animation.channels.empty()) model.animations.push_back(std::move(animation));
  model.scenes.push_back(std::move(scene));
  model.defaultScene = 0;

  tinygltf::TinyGLTF writer;
  const bool ok = writer.WriteGltfSceneToStream(&model, out, false, true);
  out.flush();
  if (!ok || !out) {
    error = "cannot write " + file.string();
    return false;
  }
  return true;
}

}  // namespace cape::demo
