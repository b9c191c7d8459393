// cape_textile end to end: both tests print a row per fabric, write JSON that parses with the library's
// figures and a picture; bad options fail with a message.
#include "DemoTestSupport.h"

#include "cape/core/FabricPresets.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

namespace cape {
namespace {

using demo_test::freshDir;
using demo_test::run;
using nlohmann::json;

const std::string kTextile = CAPE_TEXTILE;

json readJson(const std::filesystem::path& file) {
  std::ifstream in(file);
  return json::parse(in);
}

// One fabric (every preset's cantilever and drape are the core tests' FabricCantilever and FabricDrape).
TEST(CapeTextile, TheCantileverMeetsTheBendingLength) {
  const std::filesystem::path dir = freshDir();
  const demo_test::Result r =
      run(kTextile + " cantilever --fabric denim --segments 8 --json " + (dir / "c.json").string() +
          " --render " + (dir / "c.png").string() + " --render-size 400x120");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const json j = readJson(dir / "c.json");
  EXPECT_EQ(j["test"], "cantilever");
  ASSERT_EQ(j["fabrics"].size(), 1u);
  for (const json& f : j["fabrics"]) {
    const FabricMaterial* m = findFabric(f["name"].get<std::string>());
    ASSERT_NE(m, nullptr);
    EXPECT_NEAR(f["bending_length_m"].get<double>(), m->bendingLength(), 1e-7);
    EXPECT_NEAR(f["simulated_bending_length_m"].get<double>() / m->bendingLength(), 1.0, 0.03) << m->name;
    EXPECT_NE(r.output.find(m->name), std::string::npos);
  }
  EXPECT_GT(std::filesystem::file_size(dir / "c.png"), 1000u);
}

TEST(CapeTextile, TheDrapeOfOneFabricIsMeasuredAndDrawn) {
  const std::filesystem::path dir = freshDir();
  const demo_test::Result r =
      run(kTextile + " drape --fabric wool --spacing 0.012 --seconds 1.5 --json " +
          (dir / "d.json").string() + " --render " + (dir / "d.png").string() + " --render-size 200x160");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const json j = readJson(dir / "d.json");
  ASSERT_EQ(j["fabrics"].size(), 1u);
  const json& f = j["fabrics"][0];
  EXPECT_EQ(f["name"], "wool");
  EXPECT_GT(f["drape_coefficient"].get<double>(), 0.2);
  EXPECT_LT(f["drape_coefficient"].get<double>(), 0.8);
  EXPECT_GE(f["folds"].get<int>(), 3);
  EXPECT_NEAR(f["disc_area_m2"].get<double>(), 3.14159265 * 0.09 * 0.09, 1e-6);
  EXPECT_GT(std::filesystem::file_size(dir / "d.png"), 1000u);
}

TEST(CapeTextile, BadOptionsFailWithAMessage) {
  struct Case {
    const char* args;
    int code;
    const char* says;
  };
  for (const Case& c : {Case{"bogus", 105, "bogus"}, Case{"--fabric velvet", 1, "velvet"},
                        Case{"--spacing nan", 105, "nan"}, Case{"--spacing 1", 105, "0.05"},
                        Case{"cantilever --segments 1", 105, "2"}, Case{"--render-size 15x15", 105, "16"}}) {
    const demo_test::Result r = run(kTextile + " " + c.args);
    EXPECT_EQ(r.exitCode, c.code) << c.args << ":\n" << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.args << ":\n" << r.output;
  }
  const demo_test::Result help = run(kTextile + " --help");
  EXPECT_EQ(help.exitCode, 0);
  EXPECT_NE(help.output.find("ASTM D1388"), std::string::npos);
  const demo_test::Result version = run(kTextile + " --version");
  EXPECT_EQ(version.exitCode, 0);
  EXPECT_NE(version.output.find("cape_textile"), std::string::npos);
}

}  // namespace
}  // namespace cape
