// The visuals of the demos: collider meshes are their true surfaces, a recorded run comes back from its .glb
// with the expected nodes, meshes, animation and frame times, and rendered frames show the cape where the
// camera's projection of its vertices says it is.
#include "GltfExport.h"
#include "Renderer.h"
#include "ShapeMesh.h"

#include "cape/scenes/Scene.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstring>
#include <filesystem>
#include <set>

using namespace cape;
using namespace cape::demo;
namespace fs = std::filesystem;

namespace {

fs::path freshDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("cape_visuals_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<Collider> bodyOf(const SimpleScene& scene) {
  const ColliderSpan span = scene.body().bodyColliders();
  return std::vector<Collider>(span.begin(), span.end());
}

/// Reads `count` floats of a float accessor (tightly packed, as the exporter writes them).
std::vector<float> readFloats(const tinygltf::Model& m, int accessor) {
  const tinygltf::Accessor& a = m.accessors.at(static_cast<std::size_t>(accessor));
  const tinygltf::BufferView& v = m.bufferViews.at(static_cast<std::size_t>(a.bufferView));
  const int components = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type));
  std::vector<float> out(a.count * static_cast<std::size_t>(components));
  std::memcpy(out.data(),
              m.buffers.at(static_cast<std::size_t>(v.buffer)).data.data() + v.byteOffset + a.byteOffset,
              out.size() * sizeof(float));
  return out;
}

}  // namespace

TEST(ShapeMesh, VerticesOnTheTrueSurfaceAndTrianglesFacingOut) {
  const std::vector<Collider> shapes = {Collider::sphere(0.08f), Collider::capsule(0.07f, 0.33f, 1),
                                        Collider::capsule(0.05f, 0.2f, 0), Collider::cylinder(0.1f, 0.3f, 2),
                                        Collider::box(Vec3(0.2f, 0.3f, 0.12f))};
  for (const Collider& c : shapes) {
    SCOPED_TRACE(toString(c.shape));
    const ShapeMesh mesh = colliderMesh(c, 24);
    ASSERT_GT(mesh.indices.size(), 0u);
    for (std::size_t i = 0; i < mesh.vertexCount(); ++i) {
      const Vec3 p(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
      EXPECT_NEAR(localSignedDistance(c, p).distance, 0.0f, 1e-5f);
      EXPECT_NEAR(Vec3(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]).norm(), 1.0f,
                  1e-5f);
    }
    int facingOut = 0, degenerate = 0;
    for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
      Vec3 v[3], n = Vec3::Zero();
      for (int k = 0; k < 3; ++k) {
        const std::size_t i = mesh.indices[t + static_cast<std::size_t>(k)];
        v[k] = Vec3(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
        n += Vec3(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]);
      }
      const Vec3 face = (v[1] - v[0]).cross(v[2] - v[0]);
      if (face.norm() < 1e-9f) {
        ++degenerate;  // the poles of a lathe
        continue;
      }
      EXPECT_GT(face.dot(n), 0.0f) << "triangle " << t / 3 << " faces inwards";
      facingOut += face.dot(n) > 0.0f;
    }
    EXPECT_GT(facingOut, degenerate);
  }
}

TEST(GltfExport, RunLoadsBackWithNodesMeshesAnimationAndFrameTimes) {
  SimpleScene scene(SceneKind::Walk, 8, PinLayout::Corners, CapeSettings());
  ASSERT_TRUE(scene.status().ok());
  const int frames = 30;
  GltfRecorder recorder(1);
  std::vector<Points> capePositions;
  std::vector<std::vector<Collider>> colliderFrames;
  for (int f = 0; f < frames; ++f) {
    scene.advanceFrame();
    recorder.record(0, scene.cape(), bodyOf(scene));
    capePositions.push_back(scene.cape().state().positions);
    colliderFrames.push_back(bodyOf(scene));
  }
  EXPECT_EQ(recorder.frames(), frames);
  const fs::path file = freshDir("gltf") / "walk.glb";
  std::string error;
  ASSERT_TRUE(recorder.write(file, error)) << error;

  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, file.string())) << err;
  EXPECT_EQ(m.asset.version, "2.0");
  const std::size_t colliders = colliderFrames[0].size();  // torso, 2 shoulders, 2 legs
  ASSERT_EQ(colliders, 5u);
  // Nodes: ground, the character's group, its colliders, its cape. Meshes: ground, colliders, cape.
  EXPECT_EQ(m.nodes.size(), 2 + colliders + 1);
  EXPECT_EQ(m.meshes.size(), 1 + colliders + 1);
  ASSERT_EQ(m.animations.size(), 1u);
  const tinygltf::Animation& anim = m.animations[0];
  EXPECT_EQ(anim.channels.size(), 2 * colliders + 1);

  // Frame times: every sampler keys the frames at 1/60 s from 0.
  for (const tinygltf::AnimationSampler& s : anim.samplers) {
    const std::vector<float> t = readFloats(m, s.input);
    ASSERT_EQ(t.size(), static_cast<std::size_t>(frames));
    for (int f = 0; f < frames; ++f) EXPECT_NEAR(t[static_cast<std::size_t>(f)], f / 60.0f, 1e-6f);
    EXPECT_NEAR(m.accessors[static_cast<std::size_t>(s.input)].maxValues.at(0), (frames - 1) / 60.0, 1e-6);
  }

  // Colliders: translation keys are the recorded positions; the cape is morph-animated with STEP weights.
  int capeNode = -1;
  for (const tinygltf::AnimationChannel& c : anim.channels) {
    const tinygltf::AnimationSampler& s = anim.samplers[static_cast<std::size_t>(c.sampler)];
    if (c.target_path == "weights") {
      capeNode = c.target_node;
      EXPECT_EQ(s.interpolation, "STEP");
      continue;
    }
    EXPECT_EQ(s.interpolation, "LINEAR");
    EXPECT_TRUE(c.target_path == "translation" || c.target_path == "rotation") << c.target_path;
    if (c.target_path != "translation") continue;
    const std::string& name = m.nodes[static_cast<std::size_t>(c.target_node)].name;
    std::size_t k = 0;
    while (k < colliders && colliderFrames[0][k].name != name) ++k;
    ASSERT_LT(k, colliders) << name;
    const std::vector<float> x = readFloats(m, s.output);
    for (int f = 0; f < frames; f += 7) {
      const Vec3& p = colliderFrames[static_cast<std::size_t>(f)][k].current.position;
      for (int a = 0; a < 3; ++a)
        EXPECT_FLOAT_EQ(x[3 * static_cast<std::size_t>(f) + static_cast<std::size_t>(a)], p[a]);
    }
  }
  ASSERT_GE(capeNode, 0);
  const tinygltf::Mesh& cape =
      m.meshes.at(static_cast<std::size_t>(m.nodes[static_cast<std::size_t>(capeNode)].mesh));
  ASSERT_EQ(cape.primitives.size(), 1u);
  const tinygltf::Primitive& p = cape.primitives[0];
  EXPECT_TRUE(m.materials.at(static_cast<std::size_t>(p.material)).doubleSided);
  EXPECT_TRUE(p.attributes.count("NORMAL"));
  ASSERT_EQ(p.targets.size(), static_cast<std::size_t>(frames - 1));
  // Frame f's mesh = base + target f - 1: the recorded positions.
  const std::vector<float> base = readFloats(m, p.attributes.at("POSITION"));
  for (int f : {0, 1, 17, frames - 1}) {
    std::vector<float> x = base;
    if (f > 0) {
      const std::vector<float> d = readFloats(m, p.targets[static_cast<std::size_t>(f - 1)].at("POSITION"));
      for (std::size_t i = 0; i < x.size(); ++i) x[i] += d[i];
    }
    const Points& want = capePositions[static_cast<std::size_t>(f)];
    ASSERT_EQ(x.size(), static_cast<std::size_t>(want.rows()) * 3);
    for (Eigen::Index i = 0; i < want.rows(); ++i) {
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(x[static_cast<std::size_t>(i) * 3 + static_cast<std::size_t>(a)], want(i, a), 1e-5f);
    }
  }
  fs::remove_all(file.parent_path());
}

TEST(GltfExport, UnwritablePathFailsWithAReason) {
  SimpleScene scene(SceneKind::Hang, 4, PinLayout::Corners, CapeSettings());
  GltfRecorder recorder(1);
  std::string error;
  EXPECT_FALSE(recorder.write("/nonexistent/folder/x.glb", error));  // nothing recorded yet
  scene.advanceFrame();
  recorder.record(0, scene.cape(), bodyOf(scene));
  EXPECT_FALSE(recorder.write("/nonexistent/folder/x.glb", error));
  EXPECT_NE(error.find("/nonexistent/folder/x.glb"), std::string::npos) << error;
}

TEST(Renderer, CapePixelsAreWhereItsVerticesProject) {
  SimpleScene scene(SceneKind::Walk, 12, PinLayout::Corners, CapeSettings());
  for (int f = 0; f < 40; ++f) scene.advanceFrame();
  const int w = 320, h = 200;
  Renderer renderer(w, h, 1);
  ASSERT_TRUE(renderer.ok()) << renderer.error();
  const Vec3 torso = scene.body().torsoCentre();
  const Vec3 target(torso.x(), 1.0f, torso.z() + 0.3f);
  const Camera camera = Camera::lookAt(target + Vec3(-1.2f, 0.4f, 2.6f), target, w, h, 40.0f);
  renderer.begin(camera, Colour(0, 0, 0), false);
  renderer.drawCape(scene.cape(), Colour(1, 0, 0), Colour(1, 0, 0));
  const Image& image = renderer.finish();
  ASSERT_EQ(image.width, w);
  ASSERT_EQ(image.height, h);

  const Points& x = scene.cape().state().positions;
  const std::vector<std::uint32_t>& tri = scene.cape().fabric().triangles();
  const Vec3 eye = camera.eye();
  int checked = 0;
  for (std::size_t t = 0; t < tri.size(); t += 3 * 7) {  // every seventh triangle
    const Vec3 a = x.row(tri[t]).transpose(), b = x.row(tri[t + 1]).transpose(),
               c = x.row(tri[t + 2]).transpose();
    const Vec3 centroid = (a + b + c) / 3.0f;
    const Vec3 normal = (b - a).cross(c - a);
    if (std::abs(normal.normalized().dot((eye - centroid).normalized())) < 0.3f) continue;  // seen edge-on
    Eigen::Vector2f pa, pb, pc, pm;
    ASSERT_TRUE(camera.project(a, pa) && camera.project(b, pb) && camera.project(c, pc) &&
                camera.project(centroid, pm));
    // Only triangles at least a few pixels across, so their centroid pixel is inside them.
    const float area = 0.5f * std::abs((pb - pa).x() * (pc - pa).y() - (pb - pa).y() * (pc - pa).x());
    if (area < 12.0f) continue;
    const int px = static_cast<int>(pm.x()), py = static_cast<int>(pm.y());
    ASSERT_TRUE(px >= 0 && px < w && py >= 0 && py < h) << "cape outside the picture";
    const std::uint8_t* rgba = image.pixel(px, py);
    EXPECT_GT(rgba[0], 200) << "triangle " << t / 3 << " at (" << px << ", " << py << ")";
    EXPECT_LT(rgba[1], 40);
    ++checked;
  }
  EXPECT_GE(checked, 10);
  // And nothing where no vertex projects: the corners of the picture stay background.
  for (auto [px, py] : {std::pair{0, 0}, std::pair{w - 1, 0}, std::pair{0, h - 1}, std::pair{w - 1, h - 1}}) {
    EXPECT_EQ(image.pixel(px, py)[0], 0);
  }

  // A cloth handed over as a two-sided mesh (as a btSoftBody twin would be) draws the same picture, lit.
  const std::vector<std::uint8_t> unlit = image.rgba;
  renderer.begin(camera);
  renderer.drawCape(scene.cape());
  const std::vector<std::uint8_t> fromCape = renderer.finish().rgba;
  CapeMesh mesh;
  mesh.allocate(scene.cape().fabric(), true);
  mesh.update(scene.cape().fabric(), scene.cape().state().positions);
  renderer.begin(camera);
  renderer.drawCape(mesh);
  EXPECT_TRUE(renderer.finish().rgba == fromCape);
  EXPECT_FALSE(fromCape == unlit);
}

TEST(RunRenderer, FramesHaveTheRequestedSizeAndAreNotBlank) {
  SimpleScene scene(SceneKind::Walk, 10, PinLayout::Corners, CapeSettings());
  const fs::path dir = freshDir("render");
  RunRenderer renderer(dir, 1, 256, 144);
  ASSERT_TRUE(renderer.ok()) << renderer.error();
  for (int f = 0; f < 3; ++f) {
    scene.advanceFrame();
    renderer.record(0, scene.cape(), bodyOf(scene));
  }
  ASSERT_TRUE(renderer.ok()) << renderer.error();
  EXPECT_EQ(renderer.frames(), 3);
  for (const char* name : {"00001.png", "00002.png", "00003.png"})
    EXPECT_TRUE(fs::exists(dir / name)) << name;

  // Read back the last frame through the same renderer settings: the size and a picture with content
  // (ground, body and cape in many colours, not one flat colour).
  Renderer direct(256, 144);
  direct.begin(renderer.camera());
  direct.drawGround(Vec3::Zero());
  direct.drawColliders(bodyOf(scene));
  direct.drawCape(scene.cape());
  const Image& image = direct.finish();
  ASSERT_EQ(image.width, 256);
  ASSERT_EQ(image.height, 144);
  std::set<std::uint32_t> colours;
  int reddish = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = image.pixel(x, y);
      colours.insert(static_cast<std::uint32_t>(p[0]) << 16 | static_cast<std::uint32_t>(p[1]) << 8 | p[2]);
      reddish += p[0] > 2 * p[1] && p[0] > 2 * p[2] && p[0] > 60;
    }
  }
  EXPECT_GT(colours.size(), 50u);
  EXPECT_GT(reddish, 200) << "the cape (red outside) should be in view";

  std::string error;
  EXPECT_TRUE(renderer.finish(error)) << error;
  if (std::system("command -v ffmpeg >/dev/null 2>&1") == 0) {
    EXPECT_GT(fs::file_size(dir / "run.mp4"), 0u);
    EXPECT_GT(fs::file_size(dir / "run.gif"), 0u);
  }
  fs::remove_all(dir);
}

TEST(RunRenderer, UncreatableFolderFailsWithAReason) {
  RunRenderer renderer("/proc/no/such/folder", 1);
  EXPECT_FALSE(renderer.ok());
  EXPECT_NE(renderer.error().find("/proc/no/such/folder"), std::string::npos) << renderer.error();
}

TEST(RunRenderer, SideBySidePanelsEachShowTheirOwnCape) {
  // Two capes on twin characters (the second handed over as a mesh, as a btSoftBody twin would be).
  SimpleScene ours(SceneKind::Walk, 10, PinLayout::Corners, CapeSettings());
  SimpleScene twin(SceneKind::Walk, 10, PinLayout::Collar, CapeSettings());
  const fs::path dir = freshDir("side_by_side");
  RunRenderer renderer(dir, 2, 320, 120, RunRenderer::Layout::SideBySide);
  ASSERT_TRUE(renderer.ok()) << renderer.error();
  CapeMesh twinMesh;
  twinMesh.allocate(twin.cape().fabric(), false);
  for (int f = 0; f < 20; ++f) {
    ours.advanceFrame();
    twin.advanceFrame();
    twinMesh.update(twin.cape().fabric(), twin.cape().state().positions);
    renderer.record(0, ours.cape(), bodyOf(ours));
    renderer.record(1, twinMesh, bodyOf(twin));
  }
  EXPECT_EQ(renderer.frames(), 20);
  const Image& image = renderer.lastImage();
  ASSERT_EQ(image.width, 320);
  ASSERT_EQ(image.height, 120);
  // Each panel's camera puts its own cape's centre inside that panel, and the pixels there are the cape's.
  for (int panel = 0; panel < 2; ++panel) {
    SCOPED_TRACE(panel);
    const Camera& camera = renderer.camera(panel);
    EXPECT_EQ(camera.x, panel * 161);
    EXPECT_EQ(camera.width, 159);
    const SimpleScene& scene = panel == 0 ? ours : twin;
    int reddish = 0;
    for (int y = 0; y < image.height; ++y) {
      for (int x = camera.x; x < camera.x + camera.width; ++x) {
        const std::uint8_t* p = image.pixel(x, y);
        reddish += p[0] > 2 * p[1] && p[0] > 2 * p[2] && p[0] > 60;
      }
    }
    EXPECT_GT(reddish, 100);
    Eigen::Vector2f pixel;
    const Vec3 middle = scene.cape().state().positions.row(10 * 5 + 5).transpose();
    ASSERT_TRUE(camera.project(middle, pixel));
    EXPECT_GE(pixel.x(), camera.x);
    EXPECT_LT(pixel.x(), camera.x + camera.width);
  }
  fs::remove_all(dir);
}
