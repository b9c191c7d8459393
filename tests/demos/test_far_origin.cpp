// cape_walk far from the world's origin (--origin): the walk 10 km away is the walk at the origin, and every
// output is written in the scene's frame (relative to --origin), also for crowd characters whose capes keep
// frames of their own.
#include "DemoTestSupport.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

namespace {

using namespace cape::demo_test;
namespace fs = std::filesystem;
using nlohmann::json;

json summaryOf(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return json::parse(in);
}

/// Mean of the vertex positions of an OBJ file.
std::array<double, 3> meanVertex(const fs::path& obj) {
  std::array<double, 3> sum{0, 0, 0};
  int n = 0;
  for (const std::string& l : lines(obj)) {
    if (l.rfind("v ", 0) != 0) continue;
    std::istringstream s(l.substr(2));
    double x, y, z;
    s >> x >> y >> z;
    sum = {sum[0] + x, sum[1] + y, sum[2] + z};
    ++n;
  }
  EXPECT_GT(n, 0) << obj;
  return {sum[0] / n, sum[1] / n, sum[2] / n};
}

TEST(FarOrigin, TheWalkTenKilometresAwayIsTheWalkAtTheOrigin) {
  const fs::path dir = freshDir();
  const std::string common = std::string(CAPE_WALK) + " --seconds 10 --frames-every 150 ";
  const Result home = run(common + "--out " + (dir / "home").string());
  const Result far = run(common + "--origin 10000,0,-3000 --out " + (dir / "far").string());
  ASSERT_EQ(home.exitCode, 0) << home.output;
  ASSERT_EQ(far.exitCode, 0) << far.output;
  const json a = summaryOf(dir / "home")["summary"], b = summaryOf(dir / "far")["summary"];
  const double m0 = a["median_frame_max_strain"], m1 = b["median_frame_max_strain"];
  EXPECT_NEAR(m1, m0, 0.1 * m0);
  EXPECT_FALSE(b["blow_up"].get<bool>());
  EXPECT_LT(b["max_penetration_m"].get<double>(), 1e-3);
  EXPECT_NEAR(b["lowest_particle_m"].get<double>(), a["lowest_particle_m"].get<double>(), 0.02);
  // The frames are written relative to --origin: the cape where it is at the origin, to the centimetre.
  for (const char* name : {"00150.obj", "00600.obj"}) {
    const auto p = meanVertex(dir / "home" / "frames" / name), q = meanVertex(dir / "far" / "frames" / name);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(q[c], p[c], 0.01) << name << " axis " << c;
  }
}

TEST(FarOrigin, CrowdOutputsAreInOneFrameThoughEachCapeHasItsOwn) {
  // A hundred characters on docs/SCENES.md's 10 x 10 grid, 2 m apart: the outer rows and columns are 9 m
  // from the origin, more than half a frame spacing (8 m), so their capes simulate in frames of their own;
  // what is written must not show it.
  constexpr int kCount = 100, kColumns = 10;
  const fs::path dir = freshDir();
  const Result r = run(std::string(CAPE_WALK) + " --scene crowd --characters " + std::to_string(kCount) +
                       " --size 6 --seconds 0.25 --frames --out " + (dir / "crowd").string());
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::vector<std::string> jsonl = lines(dir / "crowd" / "colliders.jsonl");
  ASSERT_FALSE(jsonl.empty());
  const json last = json::parse(jsonl.back());
  std::array<double, 3> first{};
  for (int k = 0; k < kCount; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "k%d/%05d.obj", k, static_cast<int>(jsonl.size()));
    const auto c = meanVertex(dir / "crowd" / "frames" / name);
    if (k == 0) first = c;
    const double expectedX = 2.0 * (k % kColumns - 4.5);
    const double rowZ = 2.0 * (k / kColumns);  // behind the first row
    EXPECT_NEAR(c[0], expectedX, 0.5) << "character " << k;
    EXPECT_NEAR(c[2] - first[2], rowZ, 0.05) << "character " << k;
    // Its colliders are beside it too.
    double sumX = 0.0;
    int n = 0;
    for (const json& col : last["colliders"]) {
      const std::string colName = col["name"];
      if (colName.rfind("k" + std::to_string(k) + "/", 0) != 0) continue;
      sumX += col["position"][0].get<double>();
      ++n;
    }
    ASSERT_GT(n, 0);
    EXPECT_NEAR(sumX / n, expectedX, 0.5) << "character " << k;
  }
}

}  // namespace
