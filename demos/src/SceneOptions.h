// The command-line options every demo shares: which scene, on which body, with which cape.
#pragma once

#include "SceneRun.h"

#include <CLI/CLI.hpp>

#include <string>

namespace cape::demo {

struct SceneCli {
  std::string scene = "walk";
  std::string attachment = "corners";
  std::string urdf;
  std::string attach;  ///< comma-separated link names
  int size = 20;
  int characters = 3;
  double seconds = -1.0;
  bool simpleBody = false;
};

/// Adds --scene, --size, --attachment, --seconds, --characters, --simple-body, --urdf and --attach.
void addSceneOptions(CLI::App& app, SceneCli& cli);

/// The run options they ask for (the attachment links split at commas; one character unless the crowd).
RunOptions toRunOptions(const SceneCli& cli);

}  // namespace cape::demo
