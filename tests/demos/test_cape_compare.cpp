// cape_compare end to end: our cape and the btSoftBody twin on the same scene; compare.json holds one entry
// per solver (ours first) with every metric, compare.csv the same rows, and the plots are PNG files.
#include "DemoTestSupport.h"

#include <nlohmann/json.hpp>

namespace cape::demo_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kCompare = CAPE_COMPARE;

bool isPng(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  return in && std::string(magic + 1, 3) == "PNG" && fs::file_size(file) > 1000;
}

TEST(CapeCompare, WalkWritesOneRowPerSolverAndPlots) {
  const fs::path dir = freshDir();
  const Result r = run(kCompare + " --scene walk --size 8 --seconds 0.5 --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("btSoftBody"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("piterations"), std::string::npos)
      << "prints the btSoftBody settings: " << r.output;

  std::ifstream in(dir / "compare.json");
  const json j = json::parse(in);
  EXPECT_EQ(j["scene"], "walk");
  ASSERT_EQ(j["solvers"].size(), 2u);
  EXPECT_NE(j["solvers"][0]["name"].get<std::string>().find("ours"), std::string::npos) << "ours first";
  for (const json& s : j["solvers"]) {
    for (const char* key : {"name", "frame_time_us_median", "cape_time_us_median", "cape_time_us_p95",
                            "max_strain", "mean_strain", "max_penetration_m", "frames_penetration_over_1mm",
                            "self_intersections_max", "pin_error_max_m", "blow_up", "settings"})
      EXPECT_TRUE(s.contains(key)) << key;
    EXPECT_FALSE(s["blow_up"].get<bool>());
    EXPECT_GT(s["frame_time_us_median"].get<double>(), 0.0);
  }
  EXPECT_DOUBLE_EQ(j["solvers"][0]["cape_time_ratio_to_ours"].get<double>(), 1.0);
  // Both solvers kept their pins and the cape on the body (short of blowing up or falling off).
  EXPECT_LT(j["solvers"][0]["pin_error_max_m"].get<double>(), 1e-5);
  EXPECT_LT(j["solvers"][1]["pin_error_max_m"].get<double>(), 0.1);

  EXPECT_EQ(lines(dir / "compare.csv").size(), 3u);
  EXPECT_EQ(lines(dir / "frames_ours.csv").size(), 31u);
  EXPECT_EQ(lines(dir / "frames_btsoftbody.csv").size(), 31u);
  for (const char* png : {"strain.png", "penetration.png", "frame_time.png"})
    EXPECT_TRUE(isPng(dir / png)) << png;
}

// With --with-deformable a third row: the twin in Bullet's deformable world, with its own settings
// (the stiffness asked for) and per-frame CSV; it hangs on its pins without blowing up.
TEST(CapeCompare, WithDeformableAddsBulletsDeformableWorld) {
  const fs::path dir = freshDir();
  const Result r = run(kCompare +
                       " --scene walk --size 10 --seconds 0.5 --no-plots --with-deformable "
                       "--deformable-stiffness 40 --out " +
                       dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("btDeformable twin"), std::string::npos) << r.output;
  std::ifstream in(dir / "compare.json");
  const json j = json::parse(in);
  ASSERT_EQ(j["solvers"].size(), 3u);
  const json& d = j["solvers"][2];
  EXPECT_NE(d["name"].get<std::string>().find("Deformable"), std::string::npos);
  EXPECT_DOUBLE_EQ(d["settings"]["elastic_stiffness_N_per_m"].get<double>(), 40.0);
  EXPECT_FALSE(d["blow_up"].get<bool>());
  EXPECT_LT(d["pin_error_max_m"].get<double>(), 0.1);
  EXPECT_GT(d["cape_time_us_median"].get<double>(), 0.0);
  EXPECT_EQ(lines(dir / "compare.csv").size(), 4u);
  EXPECT_EQ(lines(dir / "frames_deformable.csv").size(), 31u);
  // The stiffness must be positive.
  EXPECT_NE(
      run(kCompare + " --with-deformable --deformable-stiffness 0 --seconds 0.1 --out " + freshDir().string())
          .exitCode,
      0);
}

TEST(CapeCompare, SimpleBodyAndNoPlots) {
  const fs::path dir = freshDir();
  const Result r =
      run(kCompare + " --simple-body --scene sprint-turn --size 6 --seconds 0.25 --no-plots --out " +
          dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "compare.json"));
  EXPECT_FALSE(fs::exists(dir / "strain.png"));
}

TEST(CapeCompare, RendersBothCapesSideBySide) {
  const fs::path dir = freshDir();
  const Result r = run(kCompare + " --size 8 --seconds 0.25 --no-plots --render " +
                       (dir / "frames").string() + " --render-size 160x60 --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  int pngs = 0;
  for (const auto& e : fs::directory_iterator(dir / "frames")) pngs += e.path().extension() == ".png" ? 1 : 0;
  EXPECT_EQ(pngs, 15);
  EXPECT_TRUE(isPng(dir / "frames" / "00015.png"));
  const Result bad = run(kCompare + " --seconds 0.1 --render " + (dir / "x").string() +
                         " --render-size big --out " + dir.string());
  EXPECT_NE(bad.exitCode, 0);
}

TEST(CapeCompare, BadOptionsFailWithAReason) {
  const fs::path dir = freshDir();
  for (const std::string args :
       {"--scene dance", "--softbody-iterations 0", "--attach nose", "--urdf /nonexistent.urdf"}) {
    const Result r = run(kCompare + " " + args + " --seconds 0.1 --out " + (dir / "x").string());
    EXPECT_NE(r.exitCode, 0) << args;
    EXPECT_FALSE(r.output.empty()) << args;
  }
}

}  // namespace
}  // namespace cape::demo_test
