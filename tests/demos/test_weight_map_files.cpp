// Weight maps from files: PNG images through libpng (demos/src/ImageFile.h), real third-party files (assimp's
// test textures: RGBA and palette), hostile ones, and cape_walk --max-distance-map end to end.
#include "DemoTestSupport.h"
#include "ImageFile.h"

#include <nlohmann/json.hpp>

#include <fstream>

namespace cape::demo {
namespace {

namespace fs = std::filesystem;
using demo_test::freshDir;
using demo_test::run;

const std::string kWalk = CAPE_WALK;
const std::string kModels = "/usr/share/assimp/models/glTF2/";  // Debian's assimp-testmodels

GrayImage gradient(int width, int height) {
  GrayImage g;
  g.width = width;
  g.height = height;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      g.pixels.push_back(static_cast<float>(y) / static_cast<float>(height - 1));
  return g;
}

TEST(WeightMapFiles, AGrayPngRoundTripsToTheNearestEighthBit) {
  const fs::path dir = freshDir();
  const GrayImage g = gradient(7, 33);
  std::string error;
  ASSERT_TRUE(writeGrayPng(dir / "g.png", g, error)) << error;
  GrayImage back;
  ASSERT_TRUE(readGrayPng(dir / "g.png", back, error)) << error;
  ASSERT_EQ(back.width, 7);
  ASSERT_EQ(back.height, 33);
  for (std::size_t i = 0; i < g.pixels.size(); ++i)
    EXPECT_NEAR(back.pixels[i], g.pixels[i], 0.5f / 255.0f + 1e-6f);
}

TEST(WeightMapFiles, RealColourAndPaletteTexturesReadAsTheirLuminance) {
  if (!fs::exists(kModels + "BoxTexcoords-glTF/texture.png"))
    GTEST_SKIP() << "assimp-testmodels is not installed";
  for (const char* file : {"BoxTexcoords-glTF/texture.png", "BoxTextured-glTF/CesiumLogoFlat.png"}) {
    GrayImage image;
    std::string error;
    ASSERT_TRUE(readGrayPng(kModels + file, image, error)) << file << ": " << error;
    EXPECT_GT(image.width, 100) << file;
    EXPECT_EQ(image.pixels.size(),
              static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height));
    float lo = 1.0f, hi = 0.0f;
    for (float v : image.pixels) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    EXPECT_GE(lo, 0.0f);
    EXPECT_LE(hi, 1.0f);
    EXPECT_GT(hi - lo, 0.2f) << file << ": a texture has light and dark";
  }
}

TEST(WeightMapFiles, BrokenAndHostileFilesAreRefusedWithAReason) {
  const fs::path dir = freshDir();
  GrayImage image;
  std::string error;
  EXPECT_FALSE(readGrayPng(dir / "missing.png", image, error));
  EXPECT_FALSE(error.empty());
  std::ofstream(dir / "text.png") << "not a PNG at all";
  EXPECT_FALSE(readGrayPng(dir / "text.png", image, error));
  // A real PNG cut in half: its image data ends early.
  ASSERT_TRUE(writeGrayPng(dir / "whole.png", gradient(64, 64), error)) << error;
  std::ifstream in(dir / "whole.png", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir / "cut.png", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  EXPECT_FALSE(readGrayPng(dir / "cut.png", image, error));
  EXPECT_TRUE(image.pixels.empty());
  // A header that claims 20000 x 20000 pixels (its checksum made right, so libpng reads it): refused by the
  // size before anything is allocated.
  std::string huge = bytes;
  const std::size_t ihdr = huge.find("IHDR");
  ASSERT_NE(ihdr, std::string::npos);
  for (int k = 0; k < 2; ++k) {
    const std::uint32_t side = 20000;
    for (int b = 0; b < 4; ++b)
      huge[ihdr + 4 + static_cast<std::size_t>(4 * k + b)] = static_cast<char>((side >> (24 - 8 * b)) & 0xff);
  }
  std::uint32_t crc = 0xffffffffu;  // CRC-32 of the chunk's type and data (PNG specification, annex D)
  for (std::size_t i = ihdr; i < ihdr + 4 + 13; ++i) {
    crc ^= static_cast<std::uint8_t>(huge[i]);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  crc ^= 0xffffffffu;
  for (int b = 0; b < 4; ++b)
    huge[ihdr + 17 + static_cast<std::size_t>(b)] = static_cast<char>((crc >> (24 - 8 * b)) & 0xff);
  std::ofstream(dir / "huge.png", std::ios::binary) << huge;
  EXPECT_FALSE(readGrayPng(dir / "huge.png", image, error));
  EXPECT_NE(error.find("20000 x 20000"), std::string::npos) << error;
  EXPECT_TRUE(image.pixels.empty());
}

TEST(WeightMapFiles, CapeWalkHoldsEveryParticleWithinItsPaintedMaxDistance) {
  const fs::path dir = freshDir();
  std::string error;
  ASSERT_TRUE(writeGrayPng(dir / "hem.png", gradient(32, 32), error))
      << error;  // 0 at the collar, 1 at the hem
  double reach[2] = {0.0, 0.0};
  for (int k = 0; k < 2; ++k) {
    const std::string range = k == 0 ? "0 0.05" : "0 1";
    const std::string out = (dir / ("run" + std::to_string(k))).string();
    const demo_test::Result r =
        run(kWalk + " --seconds 2 --no-render --max-distance-map " + (dir / "hem.png").string() +
            " --max-distance " + range + " --out " + out);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream in(fs::path(out) / "summary.json");
    const nlohmann::json s = nlohmann::json::parse(in);
    const nlohmann::json& m = s["motion_constraints"];
    ASSERT_TRUE(m.is_object()) << s.dump();
    EXPECT_LT(m["max_distance_excess_m"].get<double>(), 1e-4) << range;
    reach[k] = m["animated_distance_max_m"].get<double>();
  }
  EXPECT_LE(reach[0], 0.05 + 1e-4);
  EXPECT_GT(reach[1], 0.1) << "with a 1 m reach the hem swings farther than 5 cm";
  const demo_test::Result missing = run(kWalk + " --seconds 0.1 --no-render --max-distance-map " +
                                        (dir / "none.png").string() + " --out " + (dir / "x").string());
  EXPECT_EQ(missing.exitCode, 1) << missing.output;
  EXPECT_NE(missing.output.find("none.png"), std::string::npos) << missing.output;
  const demo_test::Result badRange = run(kWalk + " --max-distance 0 nan");
  EXPECT_EQ(badRange.exitCode, 105) << badRange.output;
}

}  // namespace
}  // namespace cape::demo
