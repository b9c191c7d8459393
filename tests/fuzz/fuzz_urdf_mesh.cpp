// Fuzz target: a mesh as users reach it, through a URDF <mesh> collision element. The shipped humanoid gets
// one more collision element, on a link the input picks, naming a file of this process that holds the
// fuzzer's bytes; the model loads (UrdfModel::fromString, meshes on) and the character is built from it
// (ModelChecks.h). Input: one byte picks the format by extension (stl, obj, dae), one the link, one the
// element's uniform scale (10^-4 to 10^4), the rest is the mesh file. A mesh that cannot be used is left out
// with a warning; a crash, a hang, a sanitizer report or a broken model promise is a bug.
#include "FuzzSupport.h"
#include "MeshHull.h"
#include "ModelChecks.h"

#include "cape/character/Urdf.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace {

// Where the humanoid's text may take a collision element: just after each <link ...> tag that has a body.
const std::vector<std::size_t>& linkBodies() {
  static const std::vector<std::size_t> at = [] {
    std::vector<std::size_t> out;
    const std::string& text = cape::character::UrdfModel::humanoidUrdf();
    for (std::size_t p = text.find("<link"); p != std::string::npos; p = text.find("<link", p + 1)) {
      const std::size_t close = text.find('>', p);
      if (close != std::string::npos && text[close - 1] != '/') out.push_back(close + 1);
    }
    return out;
  }();
  return at;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace cape::character;
  capefuzz::hugePagesForLargeBlocks();
  capefuzz::ByteReader in(data, size);
  const std::string file = std::string("mesh.") + capefuzz::meshExtension(in.u8());
  const std::vector<std::size_t>& bodies = linkBodies();
  CAPE_FUZZ_CHECK(!bodies.empty(), "the shipped humanoid has no link to put a mesh on");
  const std::size_t at = bodies[in.u8() % bodies.size()];
  const std::string scale = std::to_string(std::pow(10.0, static_cast<int>(in.u8() % 9) - 4));
  capefuzz::writeFile(capefuzz::ScratchDir::path() / file, in.rest());
  clearMeshHullCache();  // the cache keys on size and time: a rewrite within the clock's tick would hit it

  std::string urdf = UrdfModel::humanoidUrdf();
  urdf.insert(
      at, "<collision name=\"fuzzed\"><origin xyz=\"0.01 0 0\" rpy=\"0 0.1 0\"/><geometry><mesh filename=\"" +
              file + "\" scale=\"" + scale + " " + scale + " " + scale + "\"/></geometry></collision>");
  UrdfLoadOptions options;
  options.baseDir = capefuzz::ScratchDir::path().string();
  const UrdfLoadResult loaded = UrdfModel::fromString(urdf, options);
  CAPE_FUZZ_CHECK(loaded.ok() || !loaded.status.message().empty(), "an error without a message");
  capefuzz::buildCharacter(loaded);
  return 0;
}
