#include "SceneRun.h"

namespace cape::demo {

std::unique_ptr<SceneRun> makeSceneRun(const RunOptions& options, std::string& error) {
  // Until the character and Bullet adapter are wired in, every run uses the simple body.
  return makeSimpleBodyRun(options, error);
}

}  // namespace cape::demo
