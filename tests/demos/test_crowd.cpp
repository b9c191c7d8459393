// cape_walk's crowd (issue 15): up to 4096 characters on docs/SCENES.md's square grid, 2 m apart (rows of
// ceil(sqrt K)), centred on the origin; with --no-frames nothing per character is written but the summary;
// the summary splits the frame into the capes' time (also per cape) and Bullet's own; a crowd too large is
// refused like any other bad number.
#include "DemoTestSupport.h"

#include "cape/core/Simd.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace cape::demo_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kWalk = CAPE_WALK;

json summaryOf(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return json::parse(in);
}

/// Every entry under `dir`, relative to it.
std::set<std::string> tree(const fs::path& dir) {
  std::set<std::string> out;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir))
    out.insert(fs::relative(e.path(), dir).string());
  return out;
}

/// Each character's torso position (x, z: the ground plane) in colliders.jsonl's first line, by its index.
std::map<int, std::array<double, 2>> torsos(const fs::path& dir) {
  const std::vector<std::string> jsonl = lines(dir / "colliders.jsonl");
  std::map<int, std::array<double, 2>> out;
  if (jsonl.empty()) return out;
  const json first = json::parse(jsonl.front());
  for (const json& c : first["colliders"]) {
    const std::string name = c["name"];
    const std::size_t slash = name.find('/');
    if (name[0] != 'k' || slash == std::string::npos || name.substr(slash + 1) != "torso") continue;
    out[std::stoi(name.substr(1, slash - 1))] = {c["position"][0].get<double>(),
                                                 c["position"][2].get<double>()};
  }
  return out;
}

TEST(Crowd, AThousandWithoutFramesWriteNothingPerCharacterButTheSummary) {
  const fs::path dir = freshDir() / "run";
  const Result r = run(kWalk + " --simple-body --scene crowd --characters 1000 --size 6 --seconds 0.034 " +
                       "--no-frames --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(tree(dir), (std::set<std::string>{"metrics.csv", "summary.json"}));
  EXPECT_EQ(lines(dir / "metrics.csv").size(), 3u) << "a header and 2 frames";
  const json s = summaryOf(dir);
  EXPECT_EQ(s["characters"].get<int>(), 1000);
  EXPECT_EQ(s["state_hashes"].size(), 1000u);
  EXPECT_EQ(s["per_character"].size(), 1000u);
  // Five bodies per simple body and the ground.
  EXPECT_EQ(s["bullet_objects"].get<int>(), 5 * 1000 + 1);
  EXPECT_NE(r.output.find("1000 characters with their capes, 5001 Bullet collision objects"),
            std::string::npos)
      << r.output;
  for (const char* key : {"bullet_time_us_median", "bullet_time_us_p95", "cape_time_per_cape_us_median"})
    EXPECT_TRUE(s["summary"].contains(key)) << key;
}

TEST(Crowd, StandsOnASquareGridTwoMetresApartCentredOnTheOrigin) {
  // 1000 characters: rows of 32, 32 rows (the last one short), one frame.
  const fs::path dir = freshDir() / "run";
  const Result r = run(kWalk + " --simple-body --scene crowd --characters 1000 --size 4 --seconds 0.017 " +
                       "--frames --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const auto at = torsos(dir);
  ASSERT_EQ(at.size(), 1000u);
  double closest = 1e30, minX = 1e30, maxX = -1e30, minZ = 1e30, maxZ = -1e30;
  for (auto a = at.begin(); a != at.end(); ++a) {
    const auto& p = a->second;
    minX = std::min(minX, p[0]), maxX = std::max(maxX, p[0]);
    minZ = std::min(minZ, p[1]), maxZ = std::max(maxZ, p[1]);
    for (auto b = std::next(a); b != at.end(); ++b)
      closest = std::min(closest, std::hypot(p[0] - b->second[0], p[1] - b->second[1]));
  }
  EXPECT_NEAR(closest, 2.0, 1e-3) << "no two characters closer than 2 m";
  EXPECT_NEAR(minX, -31.0, 1e-3);
  EXPECT_NEAR(maxX, 31.0, 1e-3);
  // One frame of the walk towards -Z moves every row the same way (1.4 m/s).
  const double walked = -1.4 / 60.0;
  EXPECT_NEAR(minZ, -31.0 + walked, 1e-3);
  EXPECT_NEAR(maxZ, 31.0 + walked, 1e-3);
  // Character k stands in row k / 32, column k % 32.
  EXPECT_NEAR(at.at(33)[0] - at.at(0)[0], 2.0, 1e-3);
  EXPECT_NEAR(at.at(33)[1] - at.at(0)[1], 2.0, 1e-3);
  EXPECT_NEAR(at.at(999)[0], -31.0 + 2.0 * (999 % 32), 1e-3);
}

TEST(Crowd, UrdfCharactersStandOnTheGridToo) {
  const fs::path dir = freshDir() / "run";
  const Result r =
      run(kWalk + " --scene crowd --characters 5 --size 4 --seconds 0.017 --frames --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const json s = summaryOf(dir);
  EXPECT_EQ(s["characters"].get<int>(), 5);
  // Rows of 3: two rows, every cape beside its own character.
  const std::vector<std::string> jsonl = lines(dir / "colliders.jsonl");
  ASSERT_EQ(jsonl.size(), 1u);
  std::map<int, std::array<double, 3>> sum;
  std::map<int, int> n;
  const json first = json::parse(jsonl.front());
  for (const json& c : first["colliders"]) {
    const std::string name = c["name"];
    const int k = std::stoi(name.substr(1, name.find('/') - 1));
    for (int a = 0; a < 3; ++a) sum[k][static_cast<std::size_t>(a)] += c["position"][a].get<double>();
    ++n[k];
  }
  ASSERT_EQ(sum.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(sum[k][0] / n[k], 2.0 * (k % 3 - 1), 0.1) << "character " << k;
    EXPECT_NEAR(sum[k][2] / n[k], 2.0 * (k / 3 - 0.5), 0.3) << "character " << k;
  }
}

TEST(Crowd, FrameSplitsIntoCapesAndBullet) {
  const fs::path dir = freshDir() / "run";
  const Result r = run(kWalk + " --simple-body --scene crowd --characters 16 --size 8 --seconds 0.5 " +
                       "--no-frames --no-render --threads 2 --out " + dir.string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const json s = summaryOf(dir)["summary"];
  const double frame = s["frame_time_us_median"], cape = s["cape_time_us_median"],
               bullet = s["bullet_time_us_median"], perCape = s["cape_time_per_cape_us_median"];
  EXPECT_GT(cape, 0.0);
  EXPECT_GT(bullet, 0.0);
  EXPECT_LE(bullet, s["frame_time_us_p95"].get<double>());
  EXPECT_LE(s["bullet_time_us_median"].get<double>(), s["bullet_time_us_p95"].get<double>());
  EXPECT_DOUBLE_EQ(perCape, cape / 16.0);
  EXPECT_LE(cape, s["frame_time_us_p95"].get<double>()) << "the capes' wall time, not their summed work";
  (void)frame;
  for (const char* line : {"Bullet's own time, median", "cape time per cape, median"})
    EXPECT_NE(r.output.find(line), std::string::npos) << line << " not in\n" << r.output;
}

TEST(Crowd, MoreThan4096CharactersAreRefusedLikeAnyBadNumber) {
  const fs::path dir = freshDir();
  const fs::path out = dir / "out";
  for (const std::string& args : {std::string("--characters 4097"), std::string("--characters 0"),
                                  std::string("--characters 1e3"), std::string("--characters 99999999999")}) {
    const Result r = run(kWalk + " --simple-body --scene crowd " + args + " --out " + out.string());
    EXPECT_EQ(r.exitCode, 105) << args << ":\n" << r.output;  // CLI11's bad value, as CliNumbers says
    EXPECT_NE(r.output.find("give a whole number from 1 to 4096"), std::string::npos) << args << ":\n"
                                                                                      << r.output;
    EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 3) << args << ":\n" << r.output;
    EXPECT_FALSE(fs::exists(out)) << args << " wrote its output";
  }
}

TEST(Crowd, GltfOfALargeCrowdIsRefusedBeforeAnyWork) {
  // --gltf keeps every frame of every cape until the end.
  const fs::path dir = freshDir();
  const Result r = run(kWalk + " --simple-body --scene crowd --characters 65 --gltf " +
                       (dir / "run.glb").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("--gltf keeps every frame of every cape in memory"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_FALSE(fs::exists(dir / "run.glb"));
}

TEST(Crowd, LevelsOfDetailByDistanceFromTheViewpoint) {
  // 16 simple bodies on a 4 x 4 grid 2 m apart, --lod by distance from a viewpoint: every cape is in one of
  // the levels, nearer ones at full detail; a viewpoint far away puts every cape in the last level, and
  // levels that nothing reaches change no bit of any cape.
  const std::string crowd = kWalk + " --simple-body --scene crowd --characters 16 --size 8 --seconds 0.5 " +
                            "--no-render --no-frames";
  const auto counts = [&](const std::string& extra, json* summary = nullptr) {
    const fs::path dir = freshDir() / "run";
    const Result r = run(crowd + " " + extra + " --out " + dir.string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    const json s = summaryOf(dir);
    if (summary) *summary = s;
    return s.contains("detail") ? s["detail"]["capes_per_level_last_frame"].get<std::vector<int>>()
                                : std::vector<int>{};
  };
  json plain, allFull;
  EXPECT_TRUE(counts("", &plain).empty());
  EXPECT_FALSE(plain.contains("detail"));
  EXPECT_EQ(counts("--lod 1000", &allFull), (std::vector<int>{16, 0}));
  EXPECT_EQ(allFull["state_hashes"], plain["state_hashes"]);
  // The default viewpoint: 4 m behind the last row (z = 3 m at the start), 1.6 m up, at the middle.
  json mixed;
  const std::vector<int> m = counts("--lod 6,8,10", &mixed);
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m[0] + m[1] + m[2] + m[3], 16);
  EXPECT_GT(m[0], 0);
  EXPECT_GT(m[3], 0);
  EXPECT_NEAR(mixed["detail"]["viewpoint_m"][2].get<double>(), 7.0, 0.2);
  EXPECT_NE(mixed["state_hashes"], plain["state_hashes"]);
  EXPECT_EQ(counts("--lod 2,4 --viewpoint 0,1.6,1000"), (std::vector<int>{0, 0, 16}));
  // --lod-coarse: the same bands, the far ones on the fabric's coarse level: another result, as many
  // capes in each band, every cape finite.
  json coarse;
  EXPECT_EQ(counts("--lod 6,8,10 --lod-coarse", &coarse), m);
  EXPECT_NE(coarse["state_hashes"], mixed["state_hashes"]);
  EXPECT_FALSE(coarse["summary"]["blow_up"].get<bool>());
  EXPECT_TRUE(coarse["detail"]["coarse_fabric_beyond_second"].get<bool>());
  EXPECT_FALSE(mixed["detail"]["coarse_fabric_beyond_second"].get<bool>());
  const Result alone = run(crowd + " --lod-coarse --out " + (freshDir() / "run").string());
  EXPECT_NE(alone.exitCode, 0);
  EXPECT_NE(alone.output.find("--lod"), std::string::npos) << alone.output;
}

TEST(Crowd, ThreadsTheirPrepareAndTheirSpinGiveTheSameCapes) {
  const std::string crowd = kWalk + " --simple-body --scene crowd --characters 9 --size 8 --seconds 0.5 " +
                            "--no-render --no-frames --lod 3,5,7";
  std::vector<json> hashes;
  for (const char* extra : {"--threads 1", "--threads 2", "--threads 2 --parallel-prepare",
                            "--threads 2 --spin 0", "--threads 3 --parallel-prepare --spin 1000"}) {
    const fs::path dir = freshDir() / "run";
    const Result r = run(crowd + " " + extra + " --out " + dir.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    hashes.push_back(summaryOf(dir)["state_hashes"]);
  }
  EXPECT_EQ(hashes[0].size(), 9u);
  for (std::size_t k = 1; k < hashes.size(); ++k) EXPECT_EQ(hashes[k], hashes[0]) << k;
}

TEST(Crowd, EveryInstructionSetGivesTheSameCapes) {
  // cape_walk --simd: the portable kernels and, where this processor has them, the AVX2 ones give every cape
  // of a crowd the same bits (cape/core/Simd.h), and summary.json says which ran.
  const std::string crowd = kWalk + " --simple-body --scene crowd --characters 4 --size 12 --seconds 0.5 " +
                            "--no-render --no-frames --self-collision";
  std::vector<json> hashes;
  for (const SimdLevel level : {SimdLevel::Portable, SimdLevel::Avx2}) {
    if (level == SimdLevel::Avx2 && simdAvailable() != SimdLevel::Avx2) continue;
    const fs::path dir = freshDir() / "run";
    const Result r = run(crowd + " --simd " + simdLevelName(level) + " --out " + dir.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const json s = summaryOf(dir);
    EXPECT_EQ(s["simd"], simdLevelName(level));
    hashes.push_back(s["state_hashes"]);
  }
  for (const json& h : hashes) EXPECT_EQ(h, hashes.front());
  EXPECT_EQ(hashes.front().size(), 4u);
  const Result bad = run(kWalk + " --simple-body --seconds 0.1 --no-render --simd sse9");
  EXPECT_GE(bad.exitCode, 100) << bad.output;
  EXPECT_NE(bad.output.find("--simd"), std::string::npos) << bad.output;
}

TEST(Crowd, BadLevelsOfDetailAreRefused) {
  const std::string walk =
      kWalk + " --simple-body --seconds 0.1 --no-render --out " + (freshDir() / "run").string();
  Result r = run(walk + " --lod 5,3");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.output.find("--lod: the distances must increase"), std::string::npos) << r.output;
  EXPECT_EQ(run(walk + " --lod -1").exitCode, 105);
  EXPECT_GE(run(walk + " --lod 1,2,3,4").exitCode, 100) << "CLI11: a fourth value is refused";
  r = run(walk + " --viewpoint 0,0,0");
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.output.find("--lod"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace cape::demo_test
