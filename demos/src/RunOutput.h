// What a run writes to its output folder (see the README, "Reading the outputs"):
//   metrics.csv      one row per frame with every metric of docs/SCENES.md
//   summary.json     scene, settings, grid and cape dimensions, summary figures
//   frames/NNNNN.obj the cape mesh of each frame (frames/kK/NNNNN.obj per character in a crowd)
//   colliders.jsonl  one JSON object per frame with every body collider
#pragma once

#include "cape/core/CapeMesh.h"
#include "cape/scenes/Metrics.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace cape::demo {

/// One row of metrics.csv (for a crowd: the worst over its characters).
struct FrameRow {
  int frame = 0;
  double time = 0.0;         ///< s, at the end of the frame
  double frameTimeUs = 0.0;  ///< wall time of the whole frame step
  double capeTimeUs = 0.0;   ///< the cape solver's share
  FrameMetrics metrics;
};

/// The cape's settings as written to summary.json and compare.json (units in the key names).
nlohmann::json settingsJson(const CapeSettings& settings);

/// The JSON description of a collider at its current pose (the colliders.jsonl schema).
nlohmann::json colliderJson(const Collider& collider);

/// Writes a cape mesh as Wavefront OBJ: v, vn, vt, f (v/vt/vn), vertices in particle order.
void writeObj(const std::filesystem::path& file, const CapeMesh& mesh, std::size_t particleCount);

class RunWriter {
 public:
  /// Creates the folder (and frames/ unless writeFrames is false). Throws std::runtime_error if it cannot.
  RunWriter(const std::filesystem::path& dir, bool writeFrames, int characters);
  void frame(const FrameRow& row);
  void capeMesh(int frame, int character, const Cape& cape);
  void colliders(int frame, const std::vector<Collider>& colliders);
  void summary(const nlohmann::json& summary);
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  bool writeFrames_;
  int characters_;
  std::ofstream csv_;
  std::ofstream jsonl_;
  CapeMesh mesh_;
};

/// Summary figures of a run, the timings over frames 11..end as docs/SCENES.md defines them.
nlohmann::json summaryFigures(const std::vector<FrameRow>& rows, const RunSummary& quality);

/// A fresh folder name in the current directory: <prefix>_<scene>_<YYYYmmdd-HHMMSS>[-N].
std::filesystem::path freshRunFolder(const std::string& scene, const std::string& prefix = "cape_run");

}  // namespace cape::demo
