// cape_walk: the headless walking demo. A character walks (or stands, sprints and turns, stands in the wind,
// or walks in a crowd), its cape follows, and every metric of docs/SCENES.md is written per frame.
// `cape_walk --help` lists the options; with none it runs the walk scene into a fresh folder it names.
#include "GltfExport.h"
#include "Progress.h"
#include "Renderer.h"
#include "RunOutput.h"
#include "SceneOptions.h"
#include "SceneRun.h"

#include <CLI/CLI.hpp>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>

using namespace cape;
using namespace cape::demo;

namespace {

// A cape and its colliders turned from a Z-up world into the Y-up scene frame, for glTF and the renderer.
struct YUpView {
  Points positions;
  CapeMesh mesh;
  std::vector<Collider> colliders;
  void turn(const Cape& cape, const std::vector<Collider>& world, const Eigen::Matrix3f& toScene) {
    positions = cape.state().positions * toScene.transpose();
    if (mesh.positions.rows() == 0) mesh.allocate(cape.fabric(), false);
    mesh.update(cape.fabric(), positions);
    const Quat turn(toScene);
    colliders = world;
    for (Collider& c : colliders) {
      for (Pose* p : {&c.previous, &c.current}) {
        p->position = toScene * p->position;
        p->rotation = (turn * p->rotation).normalized();
      }
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "cape_walk: a character walks headlessly with a cape; writes metrics.csv, summary.json, "
      "frames/NNNNN.obj and colliders.jsonl to an output folder."};
  SceneCli sceneCli;
  std::string solver = "xpbd", out;
  int threads = 1, substeps = -1;
  bool noFrames = false, selfCollision = false;
  addSceneOptions(app, sceneCli);
  app.add_option("--solver", solver, "xpbd (default) | explicit (the seed's explicit springs)")
      ->check(CLI::IsMember({"xpbd", "explicit"}))
      ->capture_default_str();
  app.add_option("--substeps", substeps, "solver substeps per 1/60 s frame (default: the solver's)")
      ->check(CLI::Range(1, 64));
  app.add_flag("--self-collision", selfCollision, "keep the cape from passing through itself");
  app.add_option("--threads", threads, "worker threads stepping the capes")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  app.add_option("--out", out, "output folder (default: a fresh cape_run_<scene>_<time> folder)");
  app.add_flag("--no-frames", noFrames, "do not write frames/*.obj");
  std::string gltf, render, renderSize = "640x360";
  app.add_option("--gltf", gltf, "also write the run as an animated glTF 2.0 binary (.glb)");
  app.add_option("--render", render,
                 "also render PNG frames (and run.mp4, run.gif with ffmpeg) into this folder");
  app.add_option("--render-size", renderSize, "rendered image size, WxH")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  RunOptions o;
  std::string optionError;
  if (!toRunOptions(sceneCli, o, optionError)) {
    std::fprintf(stderr, "cape_walk: %s\n", optionError.c_str());
    return 1;
  }
  o.threads = threads;
  const std::string& scene = sceneCli.scene;
  const std::string& attachment = sceneCli.attachment;
  const int size = sceneCli.size;
  if (solver == "explicit") {
    o.settings = CapeSettings::unitySeed();
    o.settings.timeStep = 1.0f / 60.0f;
    o.settings.substeps =
        8;  // 1/480 s: within the explicit springs' stability bound (0.00875 s is the seed's)
    // At 1/480 s the explicit springs stay stable up to ~57 N/m on the canonical cape's 1 g particles; the
    // seed's 3 N/m (stable at 0.00875 s) would let the cape stretch to several times its length.
    o.settings.structuralStiffness = 40.0f;
    o.settings.shearStiffness = 40.0f;
  }
  if (substeps > 0) o.settings.substeps = substeps;
  o.settings.selfCollision = selfCollision;
  if (Status s = o.settings.validate(); !s.ok()) {
    std::fprintf(stderr, "cape_walk: %s\n", s.message().c_str());
    return 1;
  }

  std::string error;
  std::unique_ptr<SceneRun> run = makeSceneRun(o, error);
  if (!run) {
    std::fprintf(stderr, "cape_walk: %s\n", error.c_str());
    return 1;
  }
  const double length = o.seconds > 0.0 ? o.seconds : MotionDesc::forScene(o.scene).duration;
  const int frames = static_cast<int>(std::lround(length * 60.0));
  const std::filesystem::path dir = out.empty() ? freshRunFolder(scene) : std::filesystem::path(out);
  std::unique_ptr<RunWriter> writer;
  try {
    writer = std::make_unique<RunWriter>(dir, !noFrames, run->characterCount());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cape_walk: %s\n", e.what());
    return 1;
  }
  std::unique_ptr<GltfRecorder> gltfRecorder;
  std::unique_ptr<RunRenderer> renderer;
  int renderWidth = 0, renderHeight = 0;
  if (!gltf.empty() && !std::ofstream(gltf, std::ios::binary)) {
    std::fprintf(stderr, "cape_walk: cannot write %s\n", gltf.c_str());
    return 1;
  }
  if (!gltf.empty()) gltfRecorder = std::make_unique<GltfRecorder>(run->characterCount());
  if (!render.empty()) {
    if (std::sscanf(renderSize.c_str(), "%dx%d", &renderWidth, &renderHeight) != 2) {
      std::fprintf(stderr, "cape_walk: --render-size %s is not WxH\n", renderSize.c_str());
      return 1;
    }
    renderer = std::make_unique<RunRenderer>(render, run->characterCount(), renderWidth, renderHeight);
    if (!renderer->ok()) {
      std::fprintf(stderr, "cape_walk: %s\n", renderer->error().c_str());
      return 1;
    }
  }

  std::vector<YUpView> views(static_cast<std::size_t>(run->characterCount()));
  const Eigen::Matrix3f toScene = character::Skeleton::sceneToWorld(o.up).transpose().cast<float>();
  std::vector<MetricsRecorder> recorders(static_cast<std::size_t>(run->characterCount()));
  std::vector<SelfIntersectionCounter> counters(recorders.size());
  std::vector<FrameRow> rows;
  rows.reserve(static_cast<std::size_t>(frames));
  Progress progress("cape_walk " + scene, frames);
  bool blowUp = false;
  // The lowest particle above the ground over the run (m; the ground is the plane through the origin normal
  // to the world's up): a cape that hangs on the back stays well above it.
  double lowest = std::numeric_limits<double>::infinity();
  const Vec3 up = run->up();
  for (int f = 1; f <= frames && !blowUp; ++f) {
    run->advanceFrame();
    FrameRow row;
    row.frame = f;
    row.time = f / 60.0;
    row.frameTimeUs = run->lastFrameTimeUs();
    row.capeTimeUs = run->lastCapeTimeUs();
    std::vector<Collider> allColliders;
    for (int k = 0; k < run->characterCount(); ++k) {
      const std::vector<Collider> colliders = run->bodyColliders(k);
      const FrameMetrics m =
          measureFrame(run->cape(k), colliders, run->torsoCentre(k), &counters[static_cast<std::size_t>(k)]);
      recorders[static_cast<std::size_t>(k)].add(m);
      if (run->cape(k).state().positions.rows() > 0)
        lowest = std::min(lowest, static_cast<double>((run->cape(k).state().positions * up).minCoeff()));
      row.metrics = k == 0 ? m : worstOf(row.metrics, m);  // a crowd's row holds the worst of its characters
      writer->capeMesh(f, k, run->cape(k));
      if (o.up == character::UpAxis::Y) {
        if (gltfRecorder) gltfRecorder->record(k, run->cape(k), colliders);
        if (renderer) renderer->record(k, run->cape(k), colliders);
      } else if (gltfRecorder || renderer) {
        // glTF and the renderer are Y-up: a Z-up world is turned back into the scene frame for them.
        YUpView& v = views[static_cast<std::size_t>(k)];
        v.turn(run->cape(k), colliders, toScene);
        if (gltfRecorder) gltfRecorder->record(k, run->cape(k).fabric(), v.positions, v.colliders);
        if (renderer) renderer->record(k, v.mesh, v.colliders);
      }
      for (Collider c : colliders) {
        if (run->characterCount() > 1) c.name = "k" + std::to_string(k) + "/" + c.name;
        allColliders.push_back(std::move(c));
      }
    }
    writer->frame(row);
    writer->colliders(f, allColliders);
    rows.push_back(row);
    blowUp = row.metrics.blowUp;
    progress.update(f);
  }
  progress.finish();
  if (gltfRecorder && !gltfRecorder->write(gltf, error)) {
    std::fprintf(stderr, "cape_walk: %s\n", error.c_str());
    return 1;
  }
  if (renderer && !renderer->finish(error)) {
    std::fprintf(stderr, "cape_walk: %s\n", error.c_str());
    return 1;
  }
  if (gltfRecorder) std::printf("cape_walk: glTF animation -> %s\n", gltf.c_str());
  if (renderer) {
    std::printf("cape_walk: %d frames rendered at %dx%d (%.1f ms each) -> %s\n", renderer->frames(),
                renderWidth, renderHeight, renderer->meanRenderMs(), render.c_str());
  }

  // Summary: per character and, for the table, the worst character.
  MetricsRecorder worst;
  for (const FrameRow& r : rows) worst.add(r.metrics);
  const RunSummary q = worst.summary();
  nlohmann::json summary;
  summary["scene"] = scene;
  summary["body"] = run->describe();
  summary["attachment"] = attachment;
  summary["characters"] = run->characterCount();
  summary["threads"] = threads;
  summary["grid"] = {{"columns", size},
                     {"rows", size},
                     {"particles", size * size},
                     {"springs", run->cape(0).fabric().springCount()}};
  summary["cape"] = {{"width_m", run->capeSize().width},
                     {"height_m", run->capeSize().height},
                     {"mass_kg", run->cape(0).fabric().totalMass()}};
  summary["frame_time_s"] = 1.0 / 60.0;
  summary["seconds"] = length;
  summary["settings"] = settingsJson(settingsForScene(o.scene, o.settings));
  summary["summary"] = summaryFigures(rows, q);
  summary["summary"]["lowest_particle_m"] = std::isfinite(lowest) ? lowest : 0.0;
  summary["up"] = o.up == character::UpAxis::Z ? "z" : "y";
  // Each cape's final state (stateHash: the bits of its positions and velocities), for determinism checks.
  for (int k = 0; k < run->characterCount(); ++k) {
    char hex[32];
    std::snprintf(hex, sizeof hex, "%016" PRIx64, stateHash(run->cape(k).state()));
    summary["state_hashes"].push_back(hex);
  }
  if (run->characterCount() > 1) {
    for (std::size_t k = 0; k < recorders.size(); ++k) {
      std::vector<FrameRow> own;
      for (std::size_t f = 0; f < rows.size(); ++f)
        own.push_back(
            {rows[f].frame, rows[f].time, rows[f].frameTimeUs, rows[f].capeTimeUs, recorders[k].frames()[f]});
      summary["per_character"].push_back(summaryFigures(own, recorders[k].summary()));
    }
  }
  writer->summary(summary);

  const nlohmann::json& s = summary["summary"];
  std::printf("cape_walk: scene %s, %d x %d cape, %d character(s), %d frames -> %s\n", scene.c_str(), size,
              size, run->characterCount(), static_cast<int>(rows.size()), dir.c_str());
  std::printf("  %-34s %10.1f us (p95 %.1f)\n", "frame time, median", s["frame_time_us_median"].get<double>(),
              s["frame_time_us_p95"].get<double>());
  std::printf("  %-34s %10.1f us (p95 %.1f)\n", "cape time, median", s["cape_time_us_median"].get<double>(),
              s["cape_time_us_p95"].get<double>());
  std::printf("  %-34s %10.2f %%  (median frame %.2f %%, p95 frame %.2f %%)\n", "strain, max",
              100.0 * q.maxStrain, 100.0 * q.medianFrameMaxStrain, 100.0 * q.p95FrameMaxStrain);
  std::printf("  %-34s %10.3f %%\n", "strain, mean", 100.0 * q.meanStrain);
  std::printf("  %-34s %10.4f m  (%d frames over 1 mm)\n", "penetration, max", q.maxPenetration,
              q.framesPenetrationOver1mm);
  std::printf("  %-34s %10d    (%d frames with any)\n", "self-intersections, max", q.selfIntersectionsMax,
              q.framesWithSelfIntersections);
  std::printf("  %-34s %10.2g m\n", "pin error, max", q.pinErrorMax);
  std::printf("  %-34s %10.3f m\n", "lowest particle above the ground", std::isfinite(lowest) ? lowest : 0.0);
  if (o.scene == SceneKind::Hang)
    std::printf("  %-34s %10.4f m/s\n", "rest jitter (last second)", q.restJitter);
  std::printf("  %-34s %10s\n", "blow-up", q.blowUp ? "YES" : "no");
  if (blowUp) {
    std::fprintf(stderr,
                 "cape_walk: the cape blew up at frame %d (NaN or a particle > 10 m from the torso)\n",
                 static_cast<int>(rows.size()));
    return 2;
  }
  return 0;
}
