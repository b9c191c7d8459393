// The command-line options every demo shares: which scene, on which body, with which cape.
#pragma once

#include "SceneRun.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cape::demo {

/// The ranges of the shared options (each refused outside it, before any work starts).
constexpr double kMinSeconds = 0.01;          ///< --seconds, s: rounds to one 1/60 s frame
constexpr double kMaxSeconds = 86400.0;       ///< --seconds, s: 24 h of simulated time, 5,184,000 frames
constexpr double kMaxRootHeight = 1e3;        ///< |--root-height|, m
constexpr double kMaxOrigin = 1e7;            ///< |X|, |Y|, |Z| of --origin, m
constexpr std::int64_t kMaxFrames = 5184000;  ///< 1/60 s frames in kMaxSeconds (--frames-every's bound)
constexpr int kMinImageSide = 16;             ///< --render-size, px (each side even, for the H.264 video)
constexpr int kMaxImageSide = 4096;
constexpr int kMaxCharacters = 4096;  ///< --characters: the crowd's size, on a square grid 2 m apart
constexpr double kMinCapeSide = 0.1;  ///< --width, --height, m
constexpr double kMaxCapeSide = 5.0;  ///< --width, --height, m

struct SceneCli {
  std::string scene = "walk";
  /// The cape: "cape" (gathered along a collar across the shoulders, of wool) or "canonical"
  /// (docs/SCENES.md's comparison cape: pinned by its corners, the canonical stiffness). The caller sets the
  /// default.
  std::string cape = "cape";
  std::string attachment;  ///< corners | collar | gathered; empty: the cape's own
  std::string urdf;
  std::string attach;                   ///< comma-separated link names
  int size = 20;                        ///< particles per side, or across with --width or --height
  std::optional<double> width, height;  ///< m
  std::string fabric;                   ///< a preset's name (cape/core/FabricPresets.h); empty: none
  int characters = 3;
  double seconds = -1.0;
  bool simpleBody = false;
  std::vector<std::string> packagePaths;
  std::string up = "y";
  std::optional<double> rootHeight;
  std::string pose;  ///< name=rad,name=rad,...
  std::string modelUp = "auto";
  double scale = 1.0;
  std::string origin;  ///< X,Y,Z, m; empty: the world's origin
  std::string motion;  ///< clip file
  std::string motionFormat = "auto";
  double motionScale = 0.0;  ///< BVH metres per unit; 0: guessed
  double motionSpeed = 1.0;
  double motionStart = 0.0;  ///< s into the clip
  bool motionInPlace = false;
  bool motionOnce = false;
  std::string motionFrame = "urdf";  ///< CSV root columns: urdf | world
  std::string motionMap;             ///< BVH joint=role,...
};

/// Adds --version: "<tool> <version>" with the library's version (cape::version()), Bullet's version and its
/// precision; prints it and exits 0.
void addVersionFlag(CLI::App& app, const std::string& tool);

/// Adds --scene, --size, --width, --height, --fabric, --attachment, --seconds, --characters, --simple-body,
/// --urdf,
/// --attach,
/// --package-path, --up, --root-height, --pose, --model-up, --scale, --origin and the --motion options; every
/// number read strictly (CliNumbers.h) within the ranges above or the option's own.
void addSceneOptions(CLI::App& app, SceneCli& cli);

/// The run options they ask for (the attachment links split at commas; one character unless the crowd).
/// False and a message when --pose or --origin cannot be read.
bool toRunOptions(const SceneCli& cli, RunOptions& options, std::string& error);

}  // namespace cape::demo
