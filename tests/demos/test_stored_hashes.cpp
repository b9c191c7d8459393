// Stored determinism hashes of the Bullet walk, as cape_walk runs it: the shipped humanoid and the simple
// body, each wearing the canonical cape (--cape canonical: docs/SCENES.md's 20 x 20 cape pinned by its
// corners), stepped by stepSimulation(1/60, 8, 1/240) for 2 s, in the walk and, with self-collision (which
// the walk never needs), the sprint-turn's first turn; and the humanoid in cape_walk's default cape (wool on
// a gathered collar: the bending hinges, self-collision) in both. The whole path is in them: the character,
// the adapter's discovery, pins and collider conversion, and the core step. A change of behaviour on purpose
// updates the table in the same commit, saying why.
#include "DemoTestSupport.h"

#include <nlohmann/json.hpp>

namespace cape::demo_test {
namespace {

struct StoredRun {
  const char* arguments;
  const char* hash;  ///< summary.json's state_hashes[0]
};

// One table per precision of Bullet (CAPE_BULLET_DOUBLE): the bodies' transforms, velocities and shapes
// that the character and the adapter read are btScalar, so the two differ in their last bits from the first
// step on; each is as deterministic as the other.
#ifdef BT_USE_DOUBLE_PRECISION
constexpr StoredRun kStored[] = {
    {"--cape canonical --scene walk", "37767701094250be"},
    {"--cape canonical --scene sprint-turn --self-collision", "7267b9d4a6c51b08"},
    {"--cape canonical --simple-body --scene walk", "7e841931b51c1c66"},
    {"--cape canonical --simple-body --scene sprint-turn --self-collision", "dbb0e517e32cd469"},
    {"--scene walk", "c1f51535356403a9"},
    {"--scene sprint-turn", "9363c6782bb3ba00"},
};
#else
constexpr StoredRun kStored[] = {
    {"--cape canonical --scene walk", "d97b5bf769a22361"},
    {"--cape canonical --scene sprint-turn --self-collision", "43f7aebbd2e3c59b"},
    {"--cape canonical --simple-body --scene walk", "5107e3ce3bf11888"},
    {"--cape canonical --simple-body --scene sprint-turn --self-collision", "75a0eb43f50e2214"},
    {"--scene walk", "361e24ed6bd42a6b"},
    {"--scene sprint-turn", "3c7e69d189fd7a82"},
};
#endif

TEST(StoredHashes, TheBulletWalkKeepsItsBits) {
  const std::filesystem::path dir = freshDir();
  int k = 0;
  for (const StoredRun& s : kStored) {
    const std::filesystem::path out = dir / std::to_string(k++);
    const Result r =
        run(std::string(CAPE_WALK) + " " + s.arguments + " --seconds 2 --no-frames --out " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream in(out / "summary.json");
    const nlohmann::json summary = nlohmann::json::parse(in);
    EXPECT_EQ(summary["state_hashes"][0].get<std::string>(), s.hash) << s.arguments;
  }
}

}  // namespace
}  // namespace cape::demo_test
