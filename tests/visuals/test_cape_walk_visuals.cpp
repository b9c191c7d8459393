// cape_walk's --gltf and --render end to end: a short simple-body walk exports a .glb that loads back and
// renders frames of the requested size; bad paths and sizes fail with a one-line reason. The default run's
// picture shows the cape whole.
#include "DemoTestSupport.h"

#include <gtest/gtest.h>
#include <png.h>
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

/// An RGB PNG read whole (libpng's simplified API), rows from the top.
bool readPng(const fs::path& file, unsigned& width, unsigned& height, std::vector<unsigned char>& rgb) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, file.c_str())) return false;
  image.format = PNG_FORMAT_RGB;
  rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, rgb.data(), 0, nullptr)) return false;
  width = image.width;
  height = image.height;
  return true;
}

}  // namespace

// The picture of a default run: 960 x 540, the cape's red outside (or its gold lining) over a good share
// of it, and all of the cape inside the image, away from its edges.
TEST(CapeWalkVisuals, TheDefaultPictureShowsTheWholeCape) {
  const fs::path dir = freshDir();
  for (const std::string scene : {"walk", "sprint-turn"}) {
    const fs::path out = dir / scene;
    const Result r = runWalk("--scene " + scene + " --seconds 3 --out " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    unsigned w = 0, h = 0;
    std::vector<unsigned char> rgb;
    ASSERT_TRUE(readPng(out / "picture.png", w, h, rgb)) << scene;
    ASSERT_EQ(w, 960u);
    ASSERT_EQ(h, 540u);
    std::size_t cape = 0;
    unsigned left = w, right = 0, top = h, bottom = 0;
    for (unsigned y = 0; y < h; ++y) {
      for (unsigned x = 0; x < w; ++x) {
        const unsigned char* p = &rgb[3 * (static_cast<std::size_t>(y) * w + x)];
        const int r8 = p[0], g8 = p[1], b8 = p[2];
        const bool outside = r8 > 60 && r8 > 2 * g8 && r8 > 2 * b8;
        const bool lining = r8 > 90 && g8 > 60 && b8 < g8 / 2 && r8 > g8;
        if (!outside && !lining) continue;
        ++cape;
        left = std::min(left, x), right = std::max(right, x), top = std::min(top, y),
        bottom = std::max(bottom, y);
      }
    }
    EXPECT_GT(cape, static_cast<std::size_t>(w) * h / 50) << scene << ": the cape covers under 2 %";
    EXPECT_GT(left, w / 20) << scene;
    EXPECT_LT(right, w - w / 20) << scene;
    EXPECT_GT(top, h / 20) << scene;
    EXPECT_LT(bottom, h - h / 20) << scene;
  }
  fs::remove_all(dir);
}

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
