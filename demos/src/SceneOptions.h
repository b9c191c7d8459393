// The command-line options every demo shares: which scene, on which body, with which cape.
#pragma once

#include "SceneRun.h"

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

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
  std::vector<std::string> packagePaths;
  std::string up = "y";
  std::optional<double> rootHeight;
  std::string pose;  ///< name=rad,name=rad,...
  std::string modelUp = "auto";
  double scale = 1.0;
};

/// Adds --scene, --size, --attachment, --seconds, --characters, --simple-body, --urdf, --attach,
/// --package-path, --up, --root-height, --pose, --model-up and --scale.
void addSceneOptions(CLI::App& app, SceneCli& cli);

/// The run options they ask for (the attachment links split at commas; one character unless the crowd).
/// False and a message when --pose cannot be read.
bool toRunOptions(const SceneCli& cli, RunOptions& options, std::string& error);

}  // namespace cape::demo
