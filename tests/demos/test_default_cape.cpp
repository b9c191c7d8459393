// cape_walk's default cape against the canonical one (issue 17): with no options the walking character
// wears a cape gathered along a collar across its shoulders, of wool (cape/core/FabricPresets.h), that hangs
// in folds and changes shape as it sways; `--cape canonical` is docs/SCENES.md's comparison cape (pinned by
// its two top corners, 0.6 x 1.0 m, the canonical stiffness), the one cape_compare uses by default, so that
// figures stay comparable over time (its bits are the stored hashes of test_stored_hashes.cpp).
#include "DemoTestSupport.h"

#include <nlohmann/json.hpp>

#include <fstream>

namespace cape::demo_test {
namespace {

using nlohmann::json;

json summaryOf(const std::filesystem::path& dir, const std::string& arguments) {
  const Result r =
      run(std::string(CAPE_WALK) + " " + arguments + " --no-frames --no-render --out " + dir.string());
  EXPECT_EQ(r.exitCode, 0) << r.output;
  std::ifstream in(dir / "summary.json");
  return in ? json::parse(in) : json();
}

TEST(DefaultCape, IsAGatheredWoolCapeThatFoldsAndSwaysWhereTheCanonicalOneIsABoard) {
  const std::filesystem::path dir = freshDir();
  for (const char* body : {"", "--simple-body"}) {
    SCOPED_TRACE(body[0] ? body : "the shipped humanoid");
    const json cape = summaryOf(dir / "cape", std::string(body) + " --seconds 4");
    const json board = summaryOf(dir / "canonical", std::string(body) + " --seconds 4 --cape canonical");
    ASSERT_TRUE(cape.contains("summary") && board.contains("summary"));
    EXPECT_EQ(cape["cape_style"], "cape");
    EXPECT_EQ(cape["attachment"], "gathered");
    EXPECT_EQ(cape["fabric"]["name"], "wool");
    EXPECT_EQ(board["cape_style"], "canonical");
    EXPECT_EQ(board["attachment"], "corners");
    EXPECT_TRUE(board["fabric"].is_null());
    // Both keep recording the grid and the size; the cape is as wide as the canonical one, only gathered.
    for (const json* s : {&cape, &board}) {
      EXPECT_EQ((*s)["grid"]["columns"], 20);
      EXPECT_EQ((*s)["grid"]["rows"], 20);
      EXPECT_NEAR((*s)["cape"]["width_m"].get<double>(), 0.6, 1e-6);
      EXPECT_NEAR((*s)["cape"]["height_m"].get<double>(), 1.0, 1e-6);
    }
    // A cape as sound as the canonical one: on the body, not in it, not stretched, nothing restored.
    const json& q = cape["summary"];
    EXPECT_FALSE(q["blow_up"].get<bool>());
    EXPECT_EQ(q["guard_restored_particles"], 0);
    EXPECT_EQ(q["frames_penetration_over_1mm"], 0);
    EXPECT_LT(q["p95_frame_max_strain"].get<double>(), 0.05);
    EXPECT_GT(q["lowest_particle_m"].get<double>(), 0.2);
    // Folds: the mean dihedral angle over interior edges several times the board's, and a shape that changes
    // from frame to frame several times as much.
    const double folds = q["mean_dihedral_deg"], boardFolds = board["summary"]["mean_dihedral_deg"];
    const double sway = q["mean_dihedral_change_deg"],
                 boardSway = board["summary"]["mean_dihedral_change_deg"];
    std::printf(
        "%s: mean dihedral %.2f deg (canonical %.2f), its change per frame %.3f deg (canonical %.3f)\n",
        body[0] ? body : "humanoid", folds, boardFolds, sway, boardSway);
    EXPECT_GT(folds, 3.0 * boardFolds);
    EXPECT_GT(sway, 2.0 * boardSway);
  }
}

TEST(DefaultCape, AttachmentAndFabricChangeEitherCape) {
  const std::filesystem::path dir = freshDir();
  const json a = summaryOf(dir / "a", "--seconds 0.5 --attachment corners --fabric silk");
  EXPECT_EQ(a["cape_style"], "cape");
  EXPECT_EQ(a["attachment"], "corners");
  EXPECT_EQ(a["fabric"]["name"], "silk");
  const json b = summaryOf(dir / "b", "--seconds 0.5 --cape canonical --attachment gathered --fabric denim");
  EXPECT_EQ(b["cape_style"], "canonical");
  EXPECT_EQ(b["attachment"], "gathered");
  EXPECT_EQ(b["fabric"]["name"], "denim");
  const Result bad = run(std::string(CAPE_WALK) + " --cape board --no-render --out " + (dir / "c").string());
  EXPECT_NE(bad.exitCode, 0);
  EXPECT_NE(bad.output.find("--cape"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace cape::demo_test
