// cape_walk's --gltf and --render end to end: a short simple-body walk exports a .glb that loads back and
// renders frames of the requested size; bad paths and sizes fail with a one-line reason.
#include "DemoTestSupport.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

namespace fs = std::filesystem;

namespace {

using cape::demo_test::freshDir;
using cape::demo_test::Result;

Result runWalk(const std::string& arguments) {
  return cape::demo_test::run(std::string(CAPE_WALK) + " " + arguments);
}

/// Width and height from a PNG's IHDR chunk.
bool pngSize(const fs::path& file, unsigned& width, unsigned& height) {
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (!f) return false;
  unsigned char header[24];
  const bool ok = std::fread(header, 1, sizeof header, f) == sizeof header;
  std::fclose(f);
  if (!ok) return false;
  width = static_cast<unsigned>(header[16] << 24 | header[17] << 16 | header[18] << 8 | header[19]);
  height = static_cast<unsigned>(header[20] << 24 | header[21] << 16 | header[22] << 8 | header[23]);
  return true;
}

}  // namespace

TEST(CapeWalkVisuals, GltfAndRenderOfAShortWalk) {
  const fs::path dir = freshDir();
  const Result r = runWalk("--simple-body --seconds 0.25 --no-frames --out " + (dir / "run").string() +
                           " --gltf " + (dir / "walk.glb").string() + " --render " +
                           (dir / "frames").string() + " --render-size 200x120");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("15 frames rendered at 200x120"), std::string::npos) << r.output;

  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, (dir / "walk.glb").string())) << err;
  // The simple body: ground, the character, torso, two shoulders, two legs, the cape.
  EXPECT_EQ(m.nodes.size(), 8u);
  EXPECT_EQ(m.meshes.size(), 7u);
  ASSERT_EQ(m.animations.size(), 1u);
  const tinygltf::Accessor& times =
      m.accessors.at(static_cast<std::size_t>(m.animations[0].samplers.at(0).input));
  EXPECT_EQ(times.count, 15u);
  EXPECT_NEAR(times.maxValues.at(0), 14.0 / 60.0, 1e-6);

  unsigned w = 0, h = 0;
  ASSERT_TRUE(pngSize(dir / "frames" / "00015.png", w, h));
  EXPECT_EQ(w, 200u);
  EXPECT_EQ(h, 120u);
  EXPECT_FALSE(fs::exists(dir / "frames" / "00016.png"));
  fs::remove_all(dir);
}

// A motion clip's run is exported and rendered as the gait's is: the body's glTF nodes follow the clip (the
// BVH walk goes 1.2 m/s: the torso 0.58 m between the first and the last of 30 frames).
TEST(CapeWalkVisuals, AMotionClipIsExportedAndRenderedLikeTheGait) {
  const fs::path dir = freshDir();
  const Result r = runWalk("--motion " + (fs::path(CAPE_CLIPS_DIR) / "walk.bvh").string() +
                           " --seconds 0.5 --no-frames --out " + (dir / "run").string() + " --gltf " +
                           (dir / "clip.glb").string() + " --render " + (dir / "frames").string() +
                           " --render-size 96x64");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("30 frames rendered at 96x64"), std::string::npos) << r.output;
  unsigned w = 0, h = 0;
  ASSERT_TRUE(pngSize(dir / "frames" / "00030.png", w, h));
  EXPECT_EQ(w, 96u);

  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, (dir / "clip.glb").string())) << err;
  ASSERT_EQ(m.animations.size(), 1u);
  double farthest = 0.0;
  std::string which;
  for (const tinygltf::AnimationChannel& c : m.animations[0].channels) {
    if (c.target_path != "translation" ||
        m.nodes.at(static_cast<std::size_t>(c.target_node)).name.rfind("torso", 0) != 0)
      continue;
    const tinygltf::Accessor& a = m.accessors.at(
        static_cast<std::size_t>(m.animations[0].samplers.at(static_cast<std::size_t>(c.sampler)).output));
    ASSERT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
    ASSERT_EQ(a.count, 30u);
    const tinygltf::BufferView& v = m.bufferViews.at(static_cast<std::size_t>(a.bufferView));
    const auto* p = reinterpret_cast<const float*>(
        m.buffers.at(static_cast<std::size_t>(v.buffer)).data.data() + v.byteOffset + a.byteOffset);
    const float* q = p + 3 * (a.count - 1);
    const double moved = std::hypot(q[0] - p[0], q[2] - p[2]);  // horizontally (Y up)
    if (moved > farthest) farthest = moved, which = m.nodes.at(static_cast<std::size_t>(c.target_node)).name;
  }
  EXPECT_NEAR(farthest, 1.2 * 29.0 / 60.0, 0.15) << which;
  fs::remove_all(dir);
}

TEST(CapeWalkVisuals, BadPathsAndSizesFailWithOneLine) {
  const fs::path dir = freshDir();
  const std::string out = " --simple-body --seconds 0.1 --no-frames --out " + (dir / "run").string();
  for (const std::string& bad :
       {std::string("--gltf /nonexistent/folder/x.glb"), std::string("--render /proc/no/such/folder")}) {
    const Result r = runWalk(bad + out);
    EXPECT_NE(r.exitCode, 0) << bad;
    EXPECT_EQ(r.output.rfind("cape_walk: ", 0), 0u) << bad << ": " << r.output;
    EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << bad << ": " << r.output;
  }
  // A bad size is a bad number like any other (demos/src/CliNumbers.h): refused by the command line's
  // parser with CLI11's code for a bad value, in a line naming the option, the text and the range.
  for (const char* size : {"640", "8x8", "641x360"}) {
    const Result r = runWalk("--render " + (dir / "f").string() + " --render-size " + size + out);
    EXPECT_EQ(r.exitCode, 105) << size << ": " << r.output;
    EXPECT_EQ(r.output.rfind("--render-size: '" + std::string(size) + "'", 0), 0u) << r.output;
    EXPECT_NE(r.output.find("from 16 to 4096"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "f")) << "nothing is written for a bad command line";
  fs::remove_all(dir);
}
