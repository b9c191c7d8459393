// What a run writes to its output folder (see the README, "Reading the outputs"):
//   metrics.csv      one row per frame with every metric of docs/SCENES.md
//   summary.json     scene, settings, grid and cape dimensions, summary figures
//   frames/NNNNN.obj the cape mesh of each kept frame (frames/kK/NNNNN.obj per character in a crowd)
//   colliders.jsonl  one JSON object per kept frame with every body collider (not in a crowd with
//                    --no-frames: nothing per character is written then but the summary)
// and how a demo takes its --out folder (checkOutFolder, prepareOutFolder).
#pragma once

#include "cape/core/CapeMesh.h"
#include "cape/scenes/Metrics.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace cape::demo {

/// One row of metrics.csv (for a crowd: the worst over its characters).
struct FrameRow {
  std::int64_t frame = 0;
  double time = 0.0;         ///< s, at the end of the frame
  double frameTimeUs = 0.0;  ///< wall time of the whole frame step
  double capeTimeUs = 0.0;   ///< the cape solver's share (the rest is Bullet's own)
  FrameMetrics metrics;
  /// Wall time of moving the characters to the frame's pose before the step (the gait or a motion clip:
  /// forward kinematics and the kinematic bodies' transforms and velocities), not in frameTimeUs.
  double motionTimeUs = 0.0;
  /// Wall time of the frame's metrics (every cape's FrameMeter::measure), after the step.
  double metricsTimeUs = 0.0;
};

/// The cape's settings as written to summary.json and compare.json (units in the key names).
nlohmann::json settingsJson(const CapeSettings& settings);

/// The JSON description of a collider at its current pose (the colliders.jsonl schema).
nlohmann::json colliderJson(const Collider& collider);

/// Writes a cape mesh as Wavefront OBJ: v, vn, vt, f (v/vt/vn), vertices in particle order.
void writeObj(const std::filesystem::path& file, const CapeMesh& mesh, std::size_t particleCount);

class RunWriter {
 public:
  /// Creates the folder (and frames/ unless writeFrames is false; colliders.jsonl unless writeColliders is
  /// false). Throws std::runtime_error if it cannot.
  RunWriter(const std::filesystem::path& dir, bool writeFrames, int characters, bool writeColliders = true);
  void frame(const FrameRow& row);
  void capeMesh(std::int64_t frame, int character, const Fabric& fabric, const Points& positions);
  void colliders(std::int64_t frame, const std::vector<Collider>& colliders);
  bool writesFrames() const { return writeFrames_; }
  bool writesColliders() const { return writeColliders_; }
  void summary(const nlohmann::json& summary);
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  bool writeFrames_;
  int characters_;
  bool writeColliders_;
  std::ofstream csv_;
  std::ofstream jsonl_;
  CapeMesh mesh_;
};

/// The frame and cape times of a run over frames 11..end, as docs/SCENES.md defines them, in constant memory.
/// Bullet's own share of a frame is its stepSimulation wall time less the cape time (never below 0).
class FrameTimings {
 public:
  void add(const FrameRow& row);
  const PercentileEstimator& frameTimeUs() const { return frameTimeUs_; }
  const PercentileEstimator& capeTimeUs() const { return capeTimeUs_; }
  const PercentileEstimator& bulletTimeUs() const { return bulletTimeUs_; }
  const PercentileEstimator& motionTimeUs() const { return motionTimeUs_; }
  const PercentileEstimator& motionShare() const { return motionShare_; }  ///< per frame, 0..1
  const PercentileEstimator& metricsTimeUs() const { return metricsTimeUs_; }

 private:
  PercentileEstimator frameTimeUs_, capeTimeUs_, bulletTimeUs_, motionTimeUs_, motionShare_, metricsTimeUs_;
};

/// Summary figures of a run: its timings' median and p95 and the quality summary.
nlohmann::json summaryFigures(const FrameTimings& timings, const RunSummary& quality);

/// How a cape_walk frame divides: Bullet's own share (bullet_time_us_median, _p95), the cape time per
/// cape (cape_time_per_cape_us_median: the median cape time over `capes`), and the characters' motion
/// before the step (motion_time_us_median, _p95; motion_share_median: the median over frames of motion
/// time / (motion time + frame time)), and the metrics measured after the step (metrics_time_us_median,
/// _p95).
nlohmann::json frameShareFigures(const FrameTimings& timings, int capes);

/// Which demo's files an output folder holds.
enum class RunFolderKind {
  Walk,     ///< cape_walk: metrics.csv, summary.json, picture.png, video.mp4, colliders.jsonl,
            ///< frames/[kK/]NNNNN.obj
  Compare,  ///< cape_compare: compare.csv, compare.json, frames_*.csv, strain.png, penetration.png,
            ///< frame_time.png
};

/// Whether `dir` can take a run of `kind`, checked before any work: a folder that does not exist yet, an
/// empty one, or one that holds nothing but files that kind of run writes (a previous run, finished or
/// not). False with the reason for anything else: a file, a folder with any other file or folder in it
/// (nothing is deleted then), or one that cannot be read.
bool checkOutFolder(const std::filesystem::path& dir, RunFolderKind kind, std::string& error);

/// Makes `dir` (as checkOutFolder accepts it) and deletes the previous run's files in it, so that the new
/// run's are all it holds. False with the reason if that fails.
bool prepareOutFolder(const std::filesystem::path& dir, RunFolderKind kind, std::string& error);

/// A fresh folder name under runs/ in the current directory: runs/<name>-<YYYYmmdd-HHMMSS>[-N] (local
/// time; -2, -3, ... when that folder already exists).
std::filesystem::path freshRunFolder(const std::string& name);

/// The names of cape_walk's picture and video in its folder (summary.json's "picture" and "video").
constexpr const char* kPictureFile = "picture.png";
constexpr const char* kVideoFile = "video.mp4";

}  // namespace cape::demo
