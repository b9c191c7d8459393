// cape_walk's --gltf and --render end to end: a short simple-body walk exports a .glb that loads back and
// renders frames of the requested size; bad paths and sizes fail with a one-line reason.
#include "DemoTestSupport.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

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
