// The demos' command lines read every number whole, finite and in its documented range (CliNumbers.h), and
// refuse anything else before any work starts, writing nothing; --frames-every thins frames/*.obj and
// colliders.jsonl; --out takes a new, empty or previous-run folder (emptied first) and refuses any other.
#include "CliNumbers.h"
#include "DemoTestSupport.h"

#include <nlohmann/json.hpp>

#include <set>

namespace cape::demo_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kWalk = CAPE_WALK;
const std::string kCompare = CAPE_COMPARE;

/// Every entry under `dir`, relative to it.
std::set<std::string> tree(const fs::path& dir) {
  std::set<std::string> out;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir))
    out.insert(fs::relative(e.path(), dir).string());
  return out;
}

TEST(CliNumbers, RealsAreReadWholeFiniteAndInRange) {
  double v = -1.0;
  EXPECT_EQ(demo::parseReal("2.5", 0.01, 86400, v), "");
  EXPECT_EQ(v, 2.5);
  EXPECT_EQ(demo::parseReal("+1e3", 0.01, 86400, v), "");
  EXPECT_EQ(v, 1000.0);
  EXPECT_EQ(demo::parseReal(".5", 0.01, 86400, v), "");
  EXPECT_EQ(v, 0.5);
  EXPECT_EQ(demo::parseReal("86400", 0.01, 86400, v), "");
  EXPECT_EQ(demo::parseReal("-0.25E-1", -1, 1, v), "");
  EXPECT_EQ(v, -0.025);
  v = 7.0;
  for (const char* bad : {"nan", "inf", "-inf", "0x10", " 5", "5 ", "5junk", "", "1e", "e3", ".", "1..2",
                          "1,5", "--5", "1e+"}) {
    const std::string why = demo::parseReal(bad, 0.01, 86400, v);
    EXPECT_NE(why.find("is not a decimal number; give a number from 0.01 to 86400"), std::string::npos)
        << "'" << bad << "': " << why;
  }
  for (const char* far : {"4e7", "1e300", "1e400", "-1", "0", "0.001", "86400.5", "1e-400"}) {
    const std::string why = demo::parseReal(far, 0.01, 86400, v);
    EXPECT_NE(why.find("is out of range; give a number from 0.01 to 86400"), std::string::npos)
        << far << ": " << why;
  }
  EXPECT_EQ(v, 7.0) << "a refused text leaves the value alone";
}

TEST(CliNumbers, IntegersAreDecimalWholeNumbersWithoutOverflow) {
  std::int64_t v = -1;
  EXPECT_EQ(demo::parseInteger("020", 2, 256, v), "");
  EXPECT_EQ(v, 20) << "decimal, never octal";
  EXPECT_EQ(demo::parseInteger("+7", 2, 256, v), "");
  EXPECT_EQ(v, 7);
  for (const char* bad : {"20.0", "1e1", "0x14", " 20", "20 ", "", "-", "2a"})
    EXPECT_NE(
        demo::parseInteger(bad, 2, 256, v).find("is not a whole number; give a whole number from 2 to 256"),
        std::string::npos)
        << bad;
  for (const char* far : {"4294967316", "99999999999999999999999", "-9223372036854775809", "1", "257"})
    EXPECT_NE(demo::parseInteger(far, 2, 256, v).find("is out of range; give a whole number from 2 to 256"),
              std::string::npos)
        << far;
  EXPECT_EQ(v, 7);
}

TEST(CliNumbers, OriginIsThreeFiniteNumbersWithinTenThousandKilometres) {
  Eigen::Vector3d o(9, 9, 9);
  EXPECT_EQ(demo::parseVector3("1e4,-2.5,0", 1e7, o), "");
  EXPECT_EQ(o, Eigen::Vector3d(1e4, -2.5, 0));
  EXPECT_EQ(demo::parseVector3("-1e7,1e7,0", 1e7, o), "");
  for (const char* bad :
       {"1,2", "1,2,3,4", "1,,3", "1,2,nan", "1e8,0,0", "0,0,-1.1e7", " 1,2,3", "1;2;3", ""}) {
    const std::string why = demo::parseVector3(bad, 1e7, o);
    EXPECT_NE(why.find("give X,Y,Z: three numbers from -1e+07 to 1e+07"), std::string::npos)
        << bad << ": " << why;
  }
  EXPECT_EQ(o, Eigen::Vector3d(-1e7, 1e7, 0));
}

TEST(CliNumbers, ImageSizesAreTwoEvenWholeNumbersInRange) {
  int w = 0, h = 0;
  EXPECT_EQ(demo::parseImageSize("640x360", 16, 4096, true, w, h), "");
  EXPECT_EQ(w, 640);
  EXPECT_EQ(h, 360);
  for (const char* bad : {"4294967312x16", "64x64junk", "64x", "x64", "64", "64X64", "64x64x64", "8x64",
                          "8192x64", "65x64", "64x-64"}) {
    const std::string why = demo::parseImageSize(bad, 16, 4096, true, w, h);
    EXPECT_NE(why.find("give WxH, two even whole numbers from 16 to 4096"), std::string::npos)
        << bad << ": " << why;
  }
  EXPECT_EQ(w, 640);
  EXPECT_EQ(h, 360);
}

// The numbers of issue 14, and more: each refused with the option's name and its range, with a non-zero exit,
// before anything is written (neither --out nor --render is made).
TEST(CliNumbers, EveryBadNumberIsRefusedBeforeAnythingIsWritten) {
  const fs::path dir = freshDir();
  const fs::path out = dir / "out", render = dir / "render";
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> common = {
      {"--seconds 4e7", "--seconds: '4e7' is out of range; give a number from 0.01 to 86400"},
      {"--seconds 1e300", "--seconds: '1e300' is out of range"},
      {"--seconds nan", "--seconds: 'nan' is not a decimal number; give a number from 0.01 to 86400"},
      {"--seconds inf", "--seconds: 'inf' is not a decimal number"},
      {"--seconds 0.001", "--seconds: '0.001' is out of range"},
      {"--seconds 2s", "--seconds: '2s' is not a decimal number"},
      {"--size 0x10", "--size: '0x10' is not a whole number; give a whole number from 2 to 256"},
      {"--size 4294967316", "--size: '4294967316' is out of range"},
      {"--width 0.05", "--width: '0.05' is out of range; give a number from 0.1 to 5"},
      {"--height 5.5", "--height: '5.5' is out of range; give a number from 0.1 to 5"},
      {"--height 1m", "--height: '1m' is not a decimal number"},
      {"--characters 4097", "--characters: '4097' is out of range; give a whole number from 1 to 4096"},
      {"--scale nan", "--scale: 'nan' is not a decimal number; give a number from 0.001 to 1000"},
      {"--root-height 1e309", "--root-height: '1e309' is out of range; give a number from -1000 to 1000"},
      {"--origin 1,2", "--origin: '1,2' is not X,Y,Z"},
      {"--origin 0,nan,0", "--origin: '0,nan,0': Y 'nan' is not a number in range"},
      {"--origin=-2e7,0,0", "three numbers from -1e+07 to 1e+07"},
      {"--render-size 4294967312x16", "--render-size: '4294967312x16' is not a size in range; give WxH"},
      {"--render-size 64x64junk", "--render-size: '64x64junk' is not a size in range"},
  };
  const std::vector<Case> walkOnly = {
      {"--frames-every 0", "--frames-every: '0' is out of range; give a whole number from 1 to 5184000"},
      {"--frames-every 1.5", "--frames-every: '1.5' is not a whole number"},
      {"--threads 1e1", "--threads: '1e1' is not a whole number; give a whole number from 1 to 256"},
      {"--substeps 65", "--substeps: '65' is out of range; give a whole number from 1 to 64"},
      {"--max-refinement 0", "--max-refinement: '0' is out of range; give a whole number from 1 to 64"},
      {"--max-refinement 2.5", "--max-refinement: '2.5' is not a whole number"},
  };
  const std::vector<Case> compareOnly = {
      {"--softbody-iterations 0",
       "--softbody-iterations: '0' is out of range; give a whole number from 1 to 200"},
      {"--deformable-stiffness inf", "--deformable-stiffness: 'inf' is not a decimal number"},
  };
  for (const std::string& demo : {kWalk, kCompare}) {
    std::vector<Case> cases = common;
    for (const Case& c : demo == kWalk ? walkOnly : compareOnly) cases.push_back(c);
    for (const Case& c : cases) {
      const Result r = run(demo + " --simple-body --size 6 " + c.args + " --render " + render.string() +
                           " --out " + out.string());
      EXPECT_NE(r.exitCode, 0) << demo << " " << c.args;
      EXPECT_NE(r.output.find(c.message), std::string::npos) << demo << " " << c.args << ":\n" << r.output;
      EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 3) << c.args << ":\n" << r.output;
      EXPECT_FALSE(fs::exists(out)) << demo << " " << c.args << " wrote its output";
      EXPECT_FALSE(fs::exists(render)) << demo << " " << c.args << " rendered";
    }
  }
}

TEST(CliNumbers, GoodNumbersInEveryFormRun) {
  const fs::path dir = freshDir();
  const Result r = run(kWalk + " --simple-body --size +6 --seconds 1E-1 --threads 01 --origin=-0.0,0,0 " +
                       "--render-size 64x32 --no-frames --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(lines(dir / "metrics.csv").size(), 7u);
  std::ifstream in(dir / "summary.json");
  EXPECT_EQ(json::parse(in)["grid"]["particles"].get<int>(), 36);
}

TEST(CliNumbers, HelpStatesTheNewOptionsAndTheOutPolicy) {
  for (const std::string& demo : {kWalk, kCompare}) {
    const Result r = run(demo + " --help");
    EXPECT_EQ(r.exitCode, 0);
    for (const char* text : {"--origin", "starts the scene at this world position", "in 0.01..86400",
                             "is emptied of it first", "is refused", "Exit status"})
      EXPECT_NE(r.output.find(text), std::string::npos) << demo << ": " << text;
  }
  EXPECT_NE(run(kWalk + " --help").output.find("--frames-every"), std::string::npos);
}

TEST(FramesEvery, ThreeWritesEveryThirdFrameAndEveryMetricsRow) {
  const fs::path dir = freshDir();
  const Result r =
      run(kWalk + " --simple-body --size 6 --seconds 0.25 --frames-every 3 --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(lines(dir / "metrics.csv").size(), 16u) << "a header and all 15 frames";
  const std::set<std::string> expected = {"00003.obj", "00006.obj", "00009.obj", "00012.obj", "00015.obj"};
  EXPECT_EQ(tree(dir / "frames"), expected);
  const std::vector<std::string> jsonl = lines(dir / "colliders.jsonl");
  ASSERT_EQ(jsonl.size(), 5u);
  for (std::size_t i = 0; i < jsonl.size(); ++i) {
    const json j = json::parse(jsonl[i]);
    EXPECT_EQ(j["frame"].get<int>(), 3 * static_cast<int>(i + 1));
    EXPECT_EQ(j["colliders"].size(), 5u);
  }
  EXPECT_EQ(countPrefixed(dir / "frames" / "00015.obj", "v "), 36);
}

TEST(OutFolder, ASecondRunLeavesOnlyItsOwnFiles) {
  const fs::path dir = freshDir();
  // A crowd with frames, then a shorter single-character run: no k0/, no frames beyond the 6th.
  Result r =
      run(kWalk + " --simple-body --scene crowd --characters 2 --size 6 --seconds 0.25 --frames --out " +
          dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  ASSERT_TRUE(fs::exists(dir / "frames" / "k1" / "00015.obj"));
  r = run(kWalk + " --simple-body --size 6 --seconds 0.1 --frames --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::set<std::string> expected = {"metrics.csv", "summary.json",    "picture.png",
                                    "video.mp4",   "colliders.jsonl", "frames"};
  for (int f = 1; f <= 6; ++f) expected.insert("frames/0000" + std::to_string(f) + ".obj");
  EXPECT_EQ(tree(dir), expected);
  EXPECT_EQ(lines(dir / "colliders.jsonl").size(), 6u);
  // And without frames (the default): frames/ and colliders.jsonl go; without the picture, it and the
  // video go.
  r = run(kWalk + " --simple-body --size 6 --seconds 0.1 --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(tree(dir), (std::set<std::string>{"metrics.csv", "summary.json", "picture.png", "video.mp4"}));
  r = run(kWalk + " --simple-body --size 6 --seconds 0.1 --no-frames --no-render --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(tree(dir), (std::set<std::string>{"metrics.csv", "summary.json"}));

  // cape_compare's own files: a run with the deformable twin, then one without it.
  const fs::path cmp = dir / "compare";
  r = run(kCompare + " --simple-body --size 6 --seconds 0.1 --no-plots --with-deformable --out " +
          cmp.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  ASSERT_TRUE(fs::exists(cmp / "frames_deformable.csv"));
  r = run(kCompare + " --simple-body --size 6 --seconds 0.1 --no-plots --out " + cmp.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(tree(cmp), (std::set<std::string>{"compare.csv", "compare.json", "frames_ours.csv",
                                              "frames_btsoftbody.csv"}));
  EXPECT_EQ(lines(cmp / "frames_ours.csv").size(), 7u);
}

TEST(OutFolder, AFolderWithOtherFilesIsRefusedAndLeftAsItIs) {
  const fs::path dir = freshDir();
  Result r = run(kWalk + " --simple-body --size 6 --seconds 0.1 --frames --no-render --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::ofstream(dir / "notes.txt") << "mine";
  std::ofstream(dir / "frames" / "keep.txt") << "mine too";
  const std::set<std::string> before = tree(dir);
  for (const std::string& demo : {kWalk, kCompare}) {
    r = run(demo + " --simple-body --size 6 --seconds 0.1 --out " + dir.string());
    EXPECT_NE(r.exitCode, 0) << r.output;
    const std::string reason = demo == kWalk
                                   ? " holds frames/keep.txt (and 1 more), which cape_walk does not write"
                                   : " holds colliders.jsonl (and 4 more), which cape_compare does not write";
    EXPECT_NE(r.output.find(reason), std::string::npos) << r.output;
    EXPECT_EQ(tree(dir), before) << demo << " touched the folder";
  }
  // A run folder of the other demo is not one of cape_walk's, and a file is not a folder.
  const fs::path cmp = dir / "c";
  ASSERT_EQ(run(kCompare + " --simple-body --size 6 --seconds 0.1 --no-plots --out " + cmp.string()).exitCode,
            0);
  r = run(kWalk + " --simple-body --size 6 --seconds 0.1 --out " + cmp.string());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.output.find(", which cape_walk does not write"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(cmp / "metrics.csv"));
  r = run(kWalk + " --simple-body --size 6 --seconds 0.1 --out " + (dir / "notes.txt").string());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.output.find("is not a folder"), std::string::npos) << r.output;
  EXPECT_EQ(lines(dir / "notes.txt"), std::vector<std::string>{"mine"});
}

}  // namespace
}  // namespace cape::demo_test
