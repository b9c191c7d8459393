// Fuzz target: URDF text, as a user hands it to UrdfModel::fromString, then the character built from it
// (ModelChecks.h). The whole input is the text (meshes off: a fuzzed filename must not open the machine's
// files; fuzz_urdf_mesh covers the mesh path). Bad text must come back as a Status; a crash, a hang, a
// sanitizer report or a loaded model that breaks Urdf.h's promises is a bug.
#include "FuzzSupport.h"
#include "ModelChecks.h"

#include "cape/character/Urdf.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace cape::character;
  const std::string text(reinterpret_cast<const char*>(data), size);
  UrdfLoadOptions options;
  options.loadMeshes = false;
  const UrdfLoadResult loaded = UrdfModel::fromString(text, options);
  CAPE_FUZZ_CHECK(loaded.ok() || !loaded.status.ok(), "a load that failed without an error");
  CAPE_FUZZ_CHECK(loaded.status.ok() || !loaded.status.message().empty(), "an error without a message");
  capefuzz::buildCharacter(loaded);
  return 0;
}
