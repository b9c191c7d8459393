// cape_walk's default run, as a person runs it: into a fresh runs/<scene>-<time> folder under the current
// directory, with only what a person reads or looks at (summary.json, metrics.csv, picture.png, video.mp4),
// under 5 MB, naming the picture in the summary and in its last line; --frames brings the per-frame OBJ files
// and colliders.jsonl back, --no-render leaves the picture and the video out; --width and --height size the
// cape; --fabric dresses it in a preset of cape/core/FabricPresets.h. Each run's working directory is a fresh
// folder inside the build tree, never the repository.
#include "DemoTestSupport.h"

#include "cape/core/FabricPresets.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <set>

namespace cape::demo_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kWalk = CAPE_WALK;
const std::string kCompare = CAPE_COMPARE;

/// A fresh, empty working directory inside the build tree for the running test.
fs::path freshWorkDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(CAPE_TEST_WORK_DIR) / ("work-" + std::to_string(::getpid())) /
                       (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// Whether `name` is `prefix` followed by a run's time, YYYYmmdd-HHMMSS (8 digits, a dash, 6 digits).
/// (Not std::regex: GCC 12 warns inside <regex> at -O1 with the sanitizers, and CI builds with -Werror.)
bool isRunFolder(const std::string& name, const std::string& prefix) {
  if (name.size() != prefix.size() + 15 || name.compare(0, prefix.size(), prefix) != 0) return false;
  for (std::size_t k = 0; k < 15; ++k) {
    const char c = name[prefix.size() + k];
    if (k == 8 ? c != '-' : !std::isdigit(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

/// Runs `arguments` with `work` as the current directory.
Result runIn(const fs::path& work, const std::string& program, const std::string& arguments) {
  return run("cd '" + work.string() + "' && " + program + " " + arguments);
}

/// The names of the files and folders in `dir`, recursively, relative to it.
std::set<std::string> tree(const fs::path& dir) {
  std::set<std::string> out;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir))
    out.insert(fs::relative(e.path(), dir).string());
  return out;
}

std::uintmax_t bytesIn(const fs::path& dir) {
  std::uintmax_t bytes = 0;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) bytes += e.file_size();
  return bytes;
}

std::string lastLines(const std::string& output, int count) {
  std::size_t end = output.size();
  while (end > 0 && output[end - 1] == '\n') --end;
  std::size_t start = end;
  for (int k = 0; k < count && start > 0; ++k) {
    start = output.rfind('\n', start - 1);
    if (start == std::string::npos) {
      start = 0;
      break;
    }
  }
  return output.substr(start == 0 ? 0 : start + 1, end - (start == 0 ? 0 : start + 1));
}

json summaryOf(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return json::parse(in);
}

/// The first bytes of a file.
std::string head(const fs::path& file, std::size_t bytes) {
  std::ifstream in(file, std::ios::binary);
  std::string s(bytes, '\0');
  in.read(s.data(), static_cast<std::streamsize>(bytes));
  s.resize(static_cast<std::size_t>(in.gcount()));
  return s;
}

/// The only folder in work/runs/, or an empty path.
fs::path onlyRunFolder(const fs::path& work) {
  fs::path found;
  int count = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(work / "runs")) {
    found = e.path();
    ++count;
  }
  return count == 1 ? found : fs::path();
}

/// Vertex positions of an OBJ file, in order.
std::vector<std::array<double, 3>> objVertices(const fs::path& obj) {
  std::vector<std::array<double, 3>> v;
  for (const std::string& l : lines(obj)) {
    if (l.rfind("v ", 0) != 0) continue;
    std::array<double, 3> p{};
    std::sscanf(l.c_str(), "v %lf %lf %lf", &p[0], &p[1], &p[2]);
    v.push_back(p);
  }
  return v;
}

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// The measure of issue 18: `cape_walk` with no options at all.
TEST(DefaultRun, WritesOnlyWhatAPersonLooksAtUnderFiveMegabytes) {
  const fs::path work = freshWorkDir();
  const Result r = runIn(work, kWalk, "");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const fs::path dir = onlyRunFolder(work);
  ASSERT_FALSE(dir.empty()) << "one folder in runs/";
  EXPECT_TRUE(isRunFolder(dir.filename().string(), "walk-")) << dir.filename();
  EXPECT_EQ(tree(dir), (std::set<std::string>{"summary.json", "metrics.csv", "picture.png", "video.mp4"}));
  EXPECT_EQ(tree(work), (std::set<std::string>{"runs", "runs/" + dir.filename().string(),
                                               "runs/" + dir.filename().string() + "/summary.json",
                                               "runs/" + dir.filename().string() + "/metrics.csv",
                                               "runs/" + dir.filename().string() + "/picture.png",
                                               "runs/" + dir.filename().string() + "/video.mp4"}))
      << "nothing outside its folder";
  const std::uintmax_t bytes = bytesIn(dir);
  EXPECT_LT(bytes, 5u * 1000u * 1000u) << bytes << " bytes";
  std::printf("the default run's folder: %ju bytes (picture %ju, video %ju)\n", bytes,
              fs::file_size(dir / "picture.png"), fs::file_size(dir / "video.mp4"));

  const json s = summaryOf(dir);
  EXPECT_EQ(s["picture"].get<std::string>(), "picture.png");
  EXPECT_EQ(s["video"].get<std::string>(), "video.mp4");
  EXPECT_EQ(s["scene"].get<std::string>(), "walk");
  EXPECT_EQ(lines(dir / "metrics.csv").size(), 601u) << "10 s of frames and a header";
  // The whole walk at 20 frames a second; the picture from its second second on.
  EXPECT_EQ(s["video_frames"].get<int>(), 200);
  EXPECT_GE(s["picture_frame"].get<int>(), 60);
  EXPECT_LE(s["picture_frame"].get<int>(), 600);
  // A PNG and an MP4 (ISO base media: an ftyp box first) holding H.264 (its avc1 sample entry).
  EXPECT_EQ(head(dir / "picture.png", 8), "\x89PNG\r\n\x1a\n");
  const std::string mp4 = head(dir / "video.mp4", 1 << 16);
  EXPECT_EQ(mp4.substr(4, 4), "ftyp");
  EXPECT_NE(mp4.find("avc1"), std::string::npos);

  // The last lines: the folder, then the picture, as paths from the working directory.
  const std::string rel = fs::relative(dir, work).string();
  EXPECT_EQ(lastLines(r.output, 2),
            "cape_walk: outputs in " + rel + "\ncape_walk: picture " + rel + "/picture.png")
      << r.output;
}

TEST(DefaultRun, FramesBringBackTheObjFilesAndTheColliders) {
  const fs::path work = freshWorkDir();
  const Result r = runIn(work, kWalk, "--simple-body --size 6 --seconds 0.25 --frames");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const fs::path dir = onlyRunFolder(work);
  ASSERT_FALSE(dir.empty());
  std::set<std::string> expected = {"summary.json", "metrics.csv",     "picture.png",
                                    "video.mp4",    "colliders.jsonl", "frames"};
  for (int f = 1; f <= 15; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "frames/%05d.obj", f);
    expected.insert(name);
  }
  EXPECT_EQ(tree(dir), expected);
  EXPECT_EQ(lines(dir / "colliders.jsonl").size(), 15u);
  EXPECT_EQ(countPrefixed(dir / "frames" / "00015.obj", "v "), 36);
  EXPECT_EQ(summaryOf(dir)["video_frames"].get<int>(), 5) << "frames 3, 6, ..., 15";
}

TEST(DefaultRun, NoRenderLeavesThePictureAndTheVideoOut) {
  const fs::path work = freshWorkDir();
  const Result r = runIn(work, kWalk, "--simple-body --size 6 --seconds 0.25 --no-render");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const fs::path dir = onlyRunFolder(work);
  ASSERT_FALSE(dir.empty());
  EXPECT_EQ(tree(dir), (std::set<std::string>{"summary.json", "metrics.csv"}));
  const json s = summaryOf(dir);
  EXPECT_TRUE(s["picture"].is_null());
  EXPECT_TRUE(s["video"].is_null());
  EXPECT_EQ(lastLines(r.output, 1), "cape_walk: no picture (--no-render)") << r.output;
}

TEST(DefaultRun, TwoRunsInOneSecondGetTwoFolders) {
  const fs::path work = freshWorkDir();
  for (int k = 0; k < 2; ++k)
    ASSERT_EQ(runIn(work, kWalk, "--simple-body --size 4 --seconds 0.05 --no-render").exitCode, 0);
  std::set<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(work / "runs")) {
    names.insert(e.path().filename().string());
    EXPECT_TRUE(fs::exists(e.path() / "summary.json")) << e.path();
  }
  EXPECT_EQ(names.size(), 2u);
}

TEST(DefaultRun, CapeCompareWritesIntoRunsToo) {
  const fs::path work = freshWorkDir();
  const Result r = runIn(work, kCompare, "--simple-body --size 6 --seconds 0.1 --no-plots");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const fs::path dir = onlyRunFolder(work);
  ASSERT_FALSE(dir.empty());
  EXPECT_TRUE(isRunFolder(dir.filename().string(), "compare-walk-")) << dir.filename();
  EXPECT_TRUE(fs::exists(dir / "compare.json"));
}

// --width and --height: the rest lengths measured in the first frame's cape (its top row is pinned at its
// two ends, so the row keeps its rest length; the columns hang with at most a little strain).
TEST(CapeSize, WidthAndHeightSizeTheCapeWithSquareCells) {
  const fs::path work = freshWorkDir();
  const Result r = runIn(
      work, kWalk,
      "--cape canonical --width 0.8 --height 1.2 --size 9 --seconds 0.05 --frames --no-render --out run");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const json s = summaryOf(work / "run");
  EXPECT_EQ(s["grid"]["columns"].get<int>(), 9);
  EXPECT_EQ(s["grid"]["rows"].get<int>(), 13) << "8 cells of 0.1 m across, 12 down";
  EXPECT_EQ(s["grid"]["particles"].get<int>(), 9 * 13);
  EXPECT_NEAR(s["cape"]["width_m"].get<double>(), 0.8, 1e-6);
  EXPECT_NEAR(s["cape"]["height_m"].get<double>(), 1.2, 1e-6);
  const auto v = objVertices(work / "run" / "frames" / "00001.obj");
  ASSERT_EQ(v.size(), 9u * 13u);
  double across = 0.0, down = 0.0;
  for (int c = 0; c + 1 < 9; ++c)
    across += distance(v[static_cast<std::size_t>(c)], v[static_cast<std::size_t>(c + 1)]);
  for (int row = 0; row + 1 < 13; ++row)
    down += distance(v[static_cast<std::size_t>(9 * row)], v[static_cast<std::size_t>(9 * (row + 1))]);
  EXPECT_NEAR(across, 0.8, 0.8 * 0.01);
  EXPECT_NEAR(down, 1.2, 1.2 * 0.03);
  EXPECT_NEAR(distance(v[0], v[8]), 0.8, 0.8 * 0.01) << "the pinned corners are the width apart";

  // Only the width: the height stays the humanoid's fitted one, the rows follow it.
  const Result fitted =
      runIn(work, kWalk, "--cape canonical --size 9 --seconds 0.05 --no-render --out fitted");
  const Result wide =
      runIn(work, kWalk, "--cape canonical --width 1.0 --size 9 --seconds 0.05 --no-render --out wide");
  ASSERT_EQ(fitted.exitCode, 0) << fitted.output;
  ASSERT_EQ(wide.exitCode, 0) << wide.output;
  const json f = summaryOf(work / "fitted"), w = summaryOf(work / "wide");
  EXPECT_EQ(f["grid"]["rows"].get<int>(), 9) << "no --width or --height: the N x N grid as ever";
  EXPECT_NEAR(w["cape"]["width_m"].get<double>(), 1.0, 1e-6);
  const double height = f["cape"]["height_m"].get<double>();
  EXPECT_EQ(w["cape"]["height_m"].get<double>(), height);
  EXPECT_EQ(w["grid"]["rows"].get<int>(), static_cast<int>(std::lround(8.0 * height / 1.0)) + 1);
  // The simple body's canonical cape, twice as long.
  const Result simple = runIn(
      work, kWalk, "--cape canonical --simple-body --height 2 --size 7 --seconds 0.05 --no-render --out s");
  ASSERT_EQ(simple.exitCode, 0) << simple.output;
  const json t = summaryOf(work / "s");
  EXPECT_NEAR(t["cape"]["width_m"].get<double>(), 0.6, 1e-6);
  EXPECT_EQ(t["grid"]["rows"].get<int>(), 21);
}

TEST(CapeSize, AbsurdSizesAreRefusedBeforeAnythingIsWritten) {
  const fs::path work = freshWorkDir();
  struct Case {
    std::string args, message;
    int exitCode;
  };
  const std::vector<Case> cases = {
      {"--width 0", "--width: '0' is out of range; give a number from 0.1 to 5", 105},
      {"--width 1e9", "--width: '1e9' is out of range", 105},
      {"--height nan", "--height: 'nan' is not a decimal number", 105},
      {"--size 256 --width 0.1 --height 5",
       "a 0.1 x 5 m cape 256 particles across needs 12751 rows for square cells, more than 256", 1},
  };
  for (const Case& c : cases) {
    const Result r = runIn(work, kWalk, c.args);
    EXPECT_EQ(r.exitCode, c.exitCode) << c.args << ":\n" << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.args << ":\n" << r.output;
    EXPECT_FALSE(fs::exists(work / "runs")) << c.args << " wrote a folder";
  }
}

TEST(FramesOptions, NoFramesContradictsFramesAndFramesEvery) {
  const fs::path work = freshWorkDir();
  for (const std::string args : {"--frames --no-frames", "--no-frames --frames-every 3"}) {
    const Result r = runIn(work, kWalk, "--simple-body --seconds 0.05 " + args);
    EXPECT_NE(r.exitCode, 0) << args;
    EXPECT_NE(r.output.find("excludes"), std::string::npos) << args << ":\n" << r.output;
    EXPECT_FALSE(fs::exists(work / "runs")) << args << " wrote a folder";
  }
}

// --fabric: the preset's mass per area makes the cape's mass, its springs and damping are applyFabric's at
// the grid's spacing, and the summary names it.
TEST(Fabric, APresetSetsTheCapeAndTheSummaryNamesIt) {
  const fs::path work = freshWorkDir();
  std::map<std::string, json> runs;
  for (const std::string name : {"silk", "denim", ""}) {
    const std::string out = name.empty() ? "none" : name;
    const Result r = runIn(work, kWalk,
                           "--cape canonical " + (name.empty() ? std::string() : "--fabric " + name) +
                               " --size 8 --seconds 0.2 --no-render --out " + out);
    ASSERT_EQ(r.exitCode, 0) << name << ":\n" << r.output;
    runs[name] = summaryOf(work / out);
  }
  EXPECT_TRUE(runs[""]["fabric"].is_null());
  for (const std::string name : {"silk", "denim"}) {
    const json& s = runs[name];
    const FabricMaterial* m = findFabric(name);
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(s["fabric"]["name"].get<std::string>(), name);
    const double area = s["cape"]["width_m"].get<double>() * s["cape"]["height_m"].get<double>();
    EXPECT_NEAR(s["cape"]["mass_kg"].get<double>(), m->arealDensity * area, 1e-4 * m->arealDensity * area)
        << name;
    EXPECT_NEAR(s["settings"]["damping_per_s"].get<double>(), m->damping, 1e-6) << name;
    EXPECT_FALSE(s["summary"]["blow_up"].get<bool>()) << name;
  }
  EXPECT_NEAR(runs["silk"]["settings"]["bending_rigidity_n_m"].get<double>(),
              findFabric("silk")->bendingRigidity, 1e-12);
  EXPECT_NE(runs["silk"]["settings"]["bending_rigidity_n_m"],
            runs["denim"]["settings"]["bending_rigidity_n_m"]);
  EXPECT_EQ(runs[""]["settings"]["bending_rigidity_n_m"].get<double>(), 0.0);
  EXPECT_NE(runs["silk"]["cape"]["mass_kg"], runs["denim"]["cape"]["mass_kg"]);
  EXPECT_NE(runs["silk"]["settings"]["structural_stiffness_n_per_m"],
            runs[""]["settings"]["structural_stiffness_n_per_m"]);
}

TEST(Fabric, UnknownNamesAreRefusedWithTheListAndHelpNamesThem) {
  const fs::path work = freshWorkDir();
  for (const std::string& demo : {kWalk, kCompare}) {
    const Result r = runIn(work, demo, "--fabric velvet --seconds 0.1");
    EXPECT_EQ(r.exitCode, 105) << r.output;
    EXPECT_NE(r.output.find("unknown fabric 'velvet'; give one of " + fabricNames()), std::string::npos)
        << r.output;
    EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 3) << r.output;
    EXPECT_FALSE(fs::exists(work / "runs"));
    EXPECT_NE(run(demo + " --help").output.find(fabricNames()), std::string::npos) << demo;
  }
  const Result r = runIn(work, kWalk, "--fabric silk --solver explicit --seconds 0.1");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("--fabric sets the XPBD solver's springs"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace cape::demo_test
