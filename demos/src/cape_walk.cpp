// cape_walk: the headless walking demo. A character walks (or stands, sprints and turns, stands in the wind,
// or walks in a crowd), its cape follows, and every metric of docs/SCENES.md is written per frame.
// `cape_walk --help` lists the options; with none it runs the walk scene into a fresh runs/walk-<time>
// folder: summary.json, metrics.csv, a picture and a short video, and names the picture in its last line.
#include "CliNumbers.h"
#include "GltfExport.h"
#include "Progress.h"
#include "Renderer.h"
#include "RunOutput.h"
#include "SceneOptions.h"
#include "SceneRun.h"

#include "cape/bullet/CapeGroup.h"
#include "cape/core/Simd.h"

#include <CLI/CLI.hpp>

#include <chrono>
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

/// --gltf keeps every frame of every cape in memory until the run ends: a crowd of at most this many.
constexpr int kMaxGltfCharacters = 64;
/// The picture and the video are drawn by default for a crowd of at most this many (drawing more would
/// take longer than their run).
constexpr int kMaxMovieCharacters = 16;

// A cape and its colliders moved from the cape's frame into the scene's (by SceneRun::frameOffset, in
// double) and turned by `turn` (the identity, or a Z-up world into the Y-up scene frame for glTF and the
// renderer), for the outputs.
struct OutputView {
  Points positions;
  CapeMesh mesh;
  std::vector<Collider> colliders;
  void set(const Fabric& fabric, const Points& x, const std::vector<Collider>& from,
           const Eigen::Vector3d& offset, const Eigen::Matrix3f& turn) {
    positions.resize(x.rows(), 3);
    for (int c = 0; c < 3; ++c)
      positions.col(c) = (x.col(c).cast<double>().array() + offset[c]).cast<float>().matrix();
    positions = positions * turn.transpose();
    if (mesh.positions.rows() == 0) mesh.allocate(fabric, false);
    mesh.update(fabric, positions);
    const Quat q(turn);
    colliders = from;
    for (Collider& c : colliders) {
      for (Pose* p : {&c.previous, &c.current}) {
        p->position = turn * (p->position.cast<double>() + offset).cast<float>();
        p->rotation = (q * p->rotation).normalized();
      }
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "cape_walk: a character walks headlessly with a cape; writes summary.json, metrics.csv, a picture "
      "(picture.png) and a short video (video.mp4) into a fresh runs/<scene>-<time> folder (or --out), and "
      "with --frames the cape of every frame (frames/NNNNN.obj) and its colliders (colliders.jsonl). Every "
      "number is read whole and checked against its range before the run starts."};
  addVersionFlag(app, "cape_walk");
  app.footer(
      "Exit status: 0 when the run is done; 2 when the cape blew up; 1 when the URDF, the settings or the "
      "output cannot be used; CLI11's codes (from 100; 105 for a number out of range or not a number) for a "
      "bad command line.");
  SceneCli sceneCli;
  std::string solver = "xpbd", out;
  int threads = 1, substeps = -1, maxRefinement = -1, strainPasses = 1;
  double strainCeiling = 0.0;
  std::int64_t framesEvery = 1;
  bool writeFrames = false, noFrames = false, noRender = false, selfCollision = false;
  addSceneOptions(app, sceneCli);
  std::string maxDistanceMap;
  std::vector<double> maxDistanceRange = {0.0, 0.1};
  app.add_option("--max-distance-map", maxDistanceMap,
                 "a grayscale PNG painted over the cape's UVs (v = 0 at the top row): each particle's max "
                 "distance from its animated pose, black to white over --max-distance (Cape::"
                 "setMotionConstraints)");
  app.add_option("--max-distance", maxDistanceRange, "the max distance of black and of white, m: LO HI")
      ->expected(2)
      ->transform(strictReal(0.0, 10.0))
      ->capture_default_str();
  app.add_option("--solver", solver, "xpbd (default) | explicit (the seed's explicit springs)")
      ->check(CLI::IsMember({"xpbd", "explicit"}))
      ->capture_default_str();
  app.add_option("--substeps", substeps, "solver substeps per 1/60 s frame (default: the solver's)")
      ->transform(strictInteger(1, 64));
  app.add_option(
         "--max-refinement", maxRefinement,
         "strain-adaptive substepping's ceiling: while the cape's largest structural strain is above 5 %, "
         "up to N times the substeps (default: the solver's, 4; 1: never refine; a 64 x 64 cape in a "
         "sprint needs 16 to stay within 10 %, or 8 with --strain-ceiling 0.08 --strain-passes 3, "
         "docs/PERFORMANCE.md)")
      ->transform(strictInteger(1, 64));
  app.add_option("--strain-ceiling", strainCeiling,
                 "strain limiting: the most a structural spring may stretch, as a strain (0.1: 10 %), held "
                 "after the springs' solve (CapeSettings::strainCeiling; 0: off)")
      ->transform(strictReal(0.0, 10.0))
      ->capture_default_str();
  app.add_option("--strain-passes", strainPasses,
                 "with --strain-ceiling, passes over the structural springs per iteration "
                 "(CapeSettings::strainCeilingPasses)")
      ->transform(strictInteger(1, 64))
      ->capture_default_str();
  bool noSelfCollision = false;
  app.add_flag("--self-collision", selfCollision,
               "keep the cape from passing through itself (default: on for --cape cape, off for canonical)");
  app.add_flag("--no-self-collision", noSelfCollision, "let the cape pass through itself")
      ->excludes("--self-collision");
  std::vector<double> lodDistances;
  std::string viewpoint;
  CLI::Option* lodOption =
      app.add_option(
             "--lod", lodDistances,
             "levels of detail by distance from --viewpoint, m: D1[,D2[,D3]], increasing. Beyond D1 "
             "a cape steps every second internal step, beyond D2 once a frame, beyond D3 once a frame "
             "with 2 substeps (CapeGroup::setDetailPolicy, 0.5 m hysteresis; default: full detail)")
          ->delimiter(',')
          ->expected(1, 3)
          ->transform(strictReal(0.0, 1e6));
  bool lodCoarse = false;
  app.add_flag("--lod-coarse", lodCoarse,
               "with --lod: the capes beyond D2 step their grid's coarse level (a 20 x 20 cape's 10 x 10, "
               "DetailLevel::coarseFabric), their particles interpolated from it")
      ->needs(lodOption);
  app.add_option(
         "--viewpoint", viewpoint,
         "where --lod measures from (a camera), m, scene frame relative to --origin: X,Y,Z (default: 4 "
         "m behind the last row of characters, at the middle of the rows, 1.6 m up)")
      ->check(strictVector3(kMaxOrigin))
      ->needs(lodOption);
  std::string simd = simdLevelName(simdAvailable());
  app.add_option("--simd", simd,
                 "the solver kernels' instruction set: portable | avx2 (default: the widest this processor "
                 "has; every one gives the same bits, cape/core/Simd.h)")
      ->check(CLI::IsMember({"portable", "avx2"}))
      ->capture_default_str();
  app.add_option("--threads", threads, "worker threads stepping the capes")
      ->transform(strictInteger(1, 256))
      ->capture_default_str();
  bool parallelPrepare = false;
  app.add_flag("--parallel-prepare", parallelPrepare,
               "with --threads above 1, the capes read the world (discovery, poses) on the workers too "
               "(CapeGroup::setParallelPrepare; the same results)");
  double spin = bullet::CapeGroup::kDefaultSpinMicroseconds;
  app.add_option("--spin", spin,
                 "with --threads above 1, how long the threads may spin at each internal step's hand-off "
                 "before they sleep, us (CapeGroup::setSpinMicroseconds: faster where the threads have cores "
                 "of their own, slower where they have not; 0: sleep at once; the same results)")
      ->transform(strictReal(0.0, 1e6))
      ->capture_default_str();
  app.add_option("--out", out,
                 "output folder (default: a fresh runs/<scene>-<time> folder under the current one). A "
                 "folder that holds a previous cape_walk run (only metrics.csv, summary.json, picture.png, "
                 "video.mp4, colliders.jsonl and frames/[kK/]NNNNN.obj) is emptied of it first; a folder "
                 "with any other file is refused and left as it is");
  CLI::Option* framesFlag = app.add_flag(
      "--frames", writeFrames, "also write the cape of every frame (frames/NNNNN.obj) and colliders.jsonl");
  CLI::Option* everyOption =
      app.add_option("--frames-every", framesEvery,
                     "--frames for every N-th frame only (frames N, 2N, ...); metrics.csv keeps every frame")
          ->transform(strictInteger(1, kMaxFrames));
  app.add_flag("--no-frames", noFrames, "write no frames/*.obj and no colliders.jsonl (the default)")
      ->excludes(framesFlag)
      ->excludes(everyOption);
  app.add_flag("--no-render", noRender,
               "draw no picture.png and no video.mp4 (for timing runs: nothing but the simulation and "
               "metrics.csv, summary.json)");
  std::string gltf, render, renderSize = "640x360";
  app.add_option("--gltf", gltf, "also write the run as an animated glTF 2.0 binary (.glb)");
  app.add_option("--render", render,
                 "also render every frame as PNG (and run.mp4, run.gif with ffmpeg) into this folder");
  app.add_option("--render-size", renderSize, "rendered image size, WxH")
      ->check(strictImageSize(kMinImageSide, kMaxImageSide, true))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (everyOption->count() > 0) writeFrames = true;

  RunOptions o;
  std::string optionError;
  if (!toRunOptions(sceneCli, o, optionError)) {
    std::fprintf(stderr, "cape_walk: %s\n", optionError.c_str());
    return 1;
  }
  if (const Status chosen = setSimdLevel(simd == "avx2" ? SimdLevel::Avx2 : SimdLevel::Portable);
      !chosen.ok()) {
    std::fprintf(stderr, "cape_walk: --simd %s: %s\n", simd.c_str(), chosen.message().c_str());
    return 1;
  }
  o.threads = threads;
  o.parallelPrepare = parallelPrepare;
  o.spinMicroseconds = spin;
  for (std::size_t k = 1; k < lodDistances.size(); ++k) {
    if (!(lodDistances[k] > lodDistances[k - 1])) {
      std::fprintf(stderr, "cape_walk: --lod: the distances must increase (%g is not beyond %g)\n",
                   lodDistances[k], lodDistances[k - 1]);
      return 1;
    }
  }
  o.lodDistances = lodDistances;
  o.lodCoarse = lodCoarse;
  if (!viewpoint.empty()) {
    Eigen::Vector3d v;
    parseVector3(viewpoint, kMaxOrigin, v);  // checked above
    o.viewpoint = v;
  }
  o.maxDistanceMap = maxDistanceMap;
  o.maxDistanceRange = {static_cast<float>(maxDistanceRange[0]), static_cast<float>(maxDistanceRange[1])};
  if (!gltf.empty() && o.characters > kMaxGltfCharacters) {
    std::fprintf(stderr,
                 "cape_walk: --gltf keeps every frame of every cape in memory until the run ends: a crowd of "
                 "at most %d characters (not %d)\n",
                 kMaxGltfCharacters, o.characters);
    return 1;
  }
  const std::string& scene = sceneCli.scene;
  const std::string attachment = toString(o.pinLayout);
  // The explicit solver keeps the seed's springs: the cape's own fabric (wool) gives way to them; a fabric
  // asked for by name cannot.
  if (solver == "explicit" && sceneCli.fabric.empty()) o.fabric = nullptr;
  if (solver == "explicit" && o.fabric) {
    std::fprintf(stderr,
                 "cape_walk: --fabric sets the XPBD solver's springs; the explicit solver keeps the seed's "
                 "(give one or the other)\n");
    return 1;
  }
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
  if (maxRefinement > 0) o.settings.maxRefinement = maxRefinement;
  o.settings.strainCeiling = static_cast<float>(strainCeiling);
  o.settings.strainCeilingPasses = strainPasses;
  // The folding cape collides with itself unless told not to; the canonical one only when asked.
  o.settings.selfCollision = selfCollision || (!noSelfCollision && o.capeStyle == "cape");
  if (Status s = o.settings.validate(); !s.ok()) {
    std::fprintf(stderr, "cape_walk: %s\n", s.message().c_str());
    return 1;
  }

  std::string error;
  const std::filesystem::path dir = out.empty() ? freshRunFolder(scene) : std::filesystem::path(out);
  if (!checkOutFolder(dir, RunFolderKind::Walk, error)) {
    std::fprintf(stderr, "cape_walk: %s\n", error.c_str());
    return 1;
  }
  int renderWidth = 0, renderHeight = 0;
  parseImageSize(renderSize, kMinImageSide, kMaxImageSide, true, renderWidth, renderHeight);  // checked
  const auto buildStart = std::chrono::steady_clock::now();
  std::unique_ptr<SceneRun> run = makeSceneRun(o, error);
  if (!run) {
    std::fprintf(stderr, "cape_walk: %s\n", error.c_str());
    return 1;
  }
  const double buildSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - buildStart).count();
  if (o.scene == SceneKind::Crowd)
    std::printf("cape_walk: %d characters with their capes, %d Bullet collision objects, built in %.2f s\n",
                run->characterCount(), run->worldObjectCount(), buildSeconds);
  const double length = o.seconds > 0.0 ? o.seconds : MotionDesc::forScene(o.scene).duration;
  const std::int64_t frames = std::llround(length * 60.0);  // at most 60 kMaxSeconds
  std::unique_ptr<RunWriter> writer;
  try {
    if (!prepareOutFolder(dir, RunFolderKind::Walk, error)) throw std::runtime_error(error);
    writer = std::make_unique<RunWriter>(dir, writeFrames, run->characterCount(), writeFrames);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cape_walk: %s\n", e.what());
    return 1;
  }
  std::unique_ptr<GltfRecorder> gltfRecorder;
  std::unique_ptr<RunRenderer> renderer;
  std::unique_ptr<RunMovie> movie;
  if (!gltf.empty() && !std::ofstream(gltf, std::ios::binary)) {
    std::fprintf(stderr, "cape_walk: cannot write %s\n", gltf.c_str());
    return 1;
  }
  if (!gltf.empty()) gltfRecorder = std::make_unique<GltfRecorder>(run->characterCount());
  if (!render.empty()) {
    renderer = std::make_unique<RunRenderer>(render, run->characterCount(), renderWidth, renderHeight);
    if (!renderer->ok()) {
      std::fprintf(stderr, "cape_walk: %s\n", renderer->error().c_str());
      return 1;
    }
  }

  // Last before the run: the picture and the video (ffmpeg starts here).
  const bool drawMovie = !noRender && run->characterCount() <= kMaxMovieCharacters;
  if (!noRender && !drawMovie)
    std::printf(
        "cape_walk: no picture or video for a crowd of more than %d characters (--render DIR draws "
        "every frame)\n",
        kMaxMovieCharacters);
  if (drawMovie) {
    RunMovie::Settings settings;
    settings.runFrames = frames;
    movie = std::make_unique<RunMovie>(dir / kPictureFile, dir / kVideoFile, run->characterCount(), settings);
    if (!movie->ok()) {
      std::fprintf(stderr, "cape_walk: %s\n", movie->error().c_str());
      return 1;
    }
    if (!movie->writesVideo()) std::printf("cape_walk: ffmpeg is not on PATH: no %s\n", kVideoFile);
  }

  // Per character: the cape and its colliders in the scene's frame (when the cape's frame is elsewhere), and
  // turned Y-up (a Z-up world, for glTF and the renderer).
  std::vector<OutputView> shifted(static_cast<std::size_t>(run->characterCount()));
  std::vector<OutputView> views(shifted.size());
  const Eigen::Matrix3f toScene = character::Skeleton::sceneToWorld(o.up).transpose().cast<float>();
  // The summary, streamed: per character, the worst character's (the table's) and the timings.
  std::vector<MetricsRecorder> recorders(static_cast<std::size_t>(run->characterCount()));
  // One meter per cape; the first character's also measures folds (a crowd's others are not: it costs per
  // edge). A cape that slept through a frame among still bodies keeps its last frame's figures.
  std::vector<FrameMeter> meters;
  meters.reserve(recorders.size());
  for (std::size_t k = 0; k < recorders.size(); ++k) meters.emplace_back(k == 0);
  MetricsRecorder worst;
  FrameTimings timings;
  std::int64_t framesRun = 0;
  Progress progress("cape_walk " + scene, static_cast<long>(frames));
  bool blowUp = false;
  // The lowest particle above the ground over the run (m; the ground is the plane through the origin normal
  // to the world's up): a cape that hangs on the back stays well above it.
  double lowest = std::numeric_limits<double>::infinity();
  // With --max-distance-map: the farthest any particle got from its animated position, and the most it
  // went beyond its max distance (m, every character, every frame).
  double animatedDistanceMax = 0.0, maxDistanceExcess = 0.0;
  const Vec3 up = run->up();
  for (std::int64_t f = 1; f <= frames && !blowUp; ++f) {
    run->advanceFrame();
    const bool kept = f % framesEvery == 0;        // frames/*.obj and colliders.jsonl
    const bool filmed = movie && movie->wants(f);  // the picture's and the video's time
    FrameRow row;
    row.frame = f;
    row.time = f / 60.0;
    row.frameTimeUs = run->lastFrameTimeUs();
    row.capeTimeUs = run->lastCapeTimeUs();
    row.motionTimeUs = run->lastMotionTimeUs();
    std::vector<Collider> allColliders;
    for (int k = 0; k < run->characterCount(); ++k) {
      // The metrics in the cape's frame (precise however far away the character is)...
      const auto metricsStart = std::chrono::steady_clock::now();
      const Cape& cape = run->cape(k);
      const std::vector<Collider> frameColliders = run->bodyColliders(k);
      // What the numerical guard restored this frame was a blow-up it kept from lasting.
      const FrameMetrics m = meters[static_cast<std::size_t>(k)].measure(
          cape, frameColliders, run->torsoCentre(k), run->guardRestoredLastFrame(k));
      row.metricsTimeUs +=
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - metricsStart).count();
      if (!o.maxDistanceMap.empty() && cape.animatedPositions().rows() == cape.state().positions.rows()) {
        const Eigen::VectorXf d = (cape.state().positions - cape.animatedPositions()).rowwise().norm();
        const Eigen::VectorXf& limit = cape.motionConstraints().maxDistance;
        for (Eigen::Index i = 0; i < d.size(); ++i) {
          if (!(cape.state().inverseMasses[i] > 0.0f)) continue;  // pins are left alone
          animatedDistanceMax = std::max(animatedDistanceMax, static_cast<double>(d[i]));
          if (i < limit.size())
            maxDistanceExcess = std::max(maxDistanceExcess, static_cast<double>(d[i] - limit[i]));
        }
      }
      recorders[static_cast<std::size_t>(k)].add(m);
      row.metrics = k == 0 ? m : worstOf(row.metrics, m);  // a crowd's row holds the worst of its characters
      // ...the outputs in the scene's.
      const Eigen::Vector3d offset = run->frameOffset(k);
      const Points* x = &cape.state().positions;
      const std::vector<Collider>* colliders = &frameColliders;
      if (!offset.isZero()) {
        OutputView& s = shifted[static_cast<std::size_t>(k)];
        s.set(cape.fabric(), *x, frameColliders, offset, Eigen::Matrix3f::Identity());
        x = &s.positions;
        colliders = &s.colliders;
      }
      if (x->rows() > 0) lowest = std::min(lowest, static_cast<double>((*x * up).minCoeff()));
      if (kept) writer->capeMesh(f, k, cape.fabric(), *x);
      if (o.up == character::UpAxis::Y) {
        if (gltfRecorder) gltfRecorder->record(k, cape.fabric(), *x, *colliders);
        if (renderer || filmed) {
          OutputView& v = views[static_cast<std::size_t>(k)];
          if (v.mesh.positions.rows() == 0) v.mesh.allocate(cape.fabric(), false);
          v.mesh.update(cape.fabric(), *x);
          if (renderer) renderer->record(k, v.mesh, *colliders);
          if (filmed) movie->record(f, k, v.mesh, *colliders);
        }
      } else if (gltfRecorder || renderer || filmed) {
        // glTF and the renderer are Y-up: a Z-up world is turned back into the scene frame for them.
        OutputView& v = views[static_cast<std::size_t>(k)];
        v.set(cape.fabric(), *x, *colliders, Eigen::Vector3d::Zero(), toScene);
        if (gltfRecorder) gltfRecorder->record(k, cape.fabric(), v.positions, v.colliders);
        if (renderer) renderer->record(k, v.mesh, v.colliders);
        if (filmed) movie->record(f, k, v.mesh, v.colliders);
      }
      if (!kept || !writer->writesColliders()) continue;
      for (Collider c : *colliders) {
        if (run->characterCount() > 1) c.name = "k" + std::to_string(k) + "/" + c.name;
        allColliders.push_back(std::move(c));
      }
    }
    writer->frame(row);
    if (kept) writer->colliders(f, allColliders);
    worst.add(row.metrics);
    timings.add(row);
    framesRun = f;
    blowUp = row.metrics.blowUp;
    progress.update(static_cast<long>(f));
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
  if (movie && !movie->finish(error)) {
    std::fprintf(stderr, "cape_walk: %s\n", error.c_str());
    return 1;
  }
  if (movie && movie->writesVideo())
    std::printf("cape_walk: %d video frames at %dx%d (%.1f ms each to draw) -> %s\n", movie->videoFrames(),
                RunMovie::Settings().videoWidth, RunMovie::Settings().videoHeight, movie->meanRenderMs(),
                (dir / kVideoFile).c_str());
  if (gltfRecorder) std::printf("cape_walk: glTF animation -> %s\n", gltf.c_str());
  if (renderer) {
    std::printf("cape_walk: %d frames rendered at %dx%d (%.1f ms each) -> %s\n", renderer->frames(),
                renderWidth, renderHeight, renderer->meanRenderMs(), render.c_str());
  }

  // Summary: per character and, for the table, the worst character.
  const RunSummary q = worst.summary();
  nlohmann::json summary;
  summary["scene"] = scene;
  summary["body"] = run->describe();
  summary["cape_style"] = o.capeStyle;
  summary["attachment"] = attachment;
  summary["characters"] = run->characterCount();
  summary["threads"] = threads;
  summary["spin_us"] = spin;
  summary["simd"] = simdLevelName(simdLevel());
  const Fabric& fabric = run->cape(0).fabric();
  summary["grid"] = {{"columns", fabric.gridColumns()},
                     {"rows", fabric.gridRows()},
                     {"particles", fabric.particleCount()},
                     {"springs", fabric.springCount()}};
  summary["cape"] = {{"width_m", run->capeSize().width},
                     {"height_m", run->capeSize().height},
                     {"mass_kg", fabric.totalMass()}};
  summary["frame_time_s"] = 1.0 / 60.0;
  summary["seconds"] = length;
  summary["settings"] = settingsJson(settingsForScene(o.scene, run->settings()));
  // The fabric preset, if any (the cape's mass and the settings above come from it).
  summary["fabric"] = o.fabric ? nlohmann::json{{"name", o.fabric->name},
                                                {"areal_density_kg_per_m2", o.fabric->arealDensity},
                                                {"bending_length_m", o.fabric->bendingLength()}}
                               : nlohmann::json();
  summary["summary"] = summaryFigures(timings, q);
  summary["summary"].update(frameShareFigures(timings, run->characterCount()));
  summary["summary"]["lowest_particle_m"] = std::isfinite(lowest) ? lowest : 0.0;
  std::int64_t reused = 0;
  for (const FrameMeter& m : meters) reused += m.reusedFrames();
  summary["summary"]["metrics_reused_cape_frames"] = reused;
  summary["motion_constraints"] =
      o.maxDistanceMap.empty()
          ? nlohmann::json()
          : nlohmann::json{{"max_distance_map", o.maxDistanceMap},
                           {"max_distance_range_m", {o.maxDistanceRange[0], o.maxDistanceRange[1]}},
                           {"animated_distance_max_m", animatedDistanceMax},
                           {"max_distance_excess_m", maxDistanceExcess}};
  summary["up"] = o.up == character::UpAxis::Z ? "z" : "y";
  summary["scene_build_s"] = buildSeconds;
  summary["bullet_objects"] = run->worldObjectCount();
  if (!o.lodDistances.empty()) {
    const Eigen::Vector3d v = run->detailViewpoint();
    summary["detail"] = {{"distances_m", o.lodDistances},
                         {"coarse_fabric_beyond_second", o.lodCoarse},
                         {"viewpoint_m", {v.x(), v.y(), v.z()}},
                         {"capes_per_level_last_frame", run->detailCounts()}};
  }
  // Each cape's final state (stateHash: the bits of its positions and velocities), for determinism checks.
  for (int k = 0; k < run->characterCount(); ++k) {
    char hex[32];
    std::snprintf(hex, sizeof hex, "%016" PRIx64, stateHash(run->cape(k).state()));
    summary["state_hashes"].push_back(hex);
  }
  if (run->characterCount() > 1) {
    for (const MetricsRecorder& r : recorders)
      summary["per_character"].push_back(summaryFigures(timings, r.summary()));
  }
  // What a person looks at, named relative to the folder.
  summary["picture"] = movie ? nlohmann::json(kPictureFile) : nlohmann::json();
  summary["video"] = movie && movie->writesVideo() ? nlohmann::json(kVideoFile) : nlohmann::json();
  if (movie) {
    summary["picture_frame"] = movie->pictureFrame();
    summary["video_frames"] = movie->videoFrames();
    summary["render_ms_per_video_frame"] = movie->meanRenderMs();
  }
  writer->summary(summary);

  const nlohmann::json& s = summary["summary"];
  std::printf("cape_walk: scene %s, %d x %d cape, %d character(s), %" PRId64 " frames\n", scene.c_str(),
              fabric.gridColumns(), fabric.gridRows(), run->characterCount(), framesRun);
  std::printf("  %-34s %10.1f us (p95 %.1f)\n", "frame time, median", s["frame_time_us_median"].get<double>(),
              s["frame_time_us_p95"].get<double>());
  std::printf("  %-34s %10.1f us (p95 %.1f)\n", "cape time, median", s["cape_time_us_median"].get<double>(),
              s["cape_time_us_p95"].get<double>());
  std::printf("  %-34s %10.1f us (p95 %.1f)\n", "Bullet's own time, median",
              s["bullet_time_us_median"].get<double>(), s["bullet_time_us_p95"].get<double>());
  std::printf("  %-34s %10.2f us\n", "cape time per cape, median",
              s["cape_time_per_cape_us_median"].get<double>());
  std::printf("  %-34s %10.2f us (%.1f %% of the frame)\n", "character motion, median",
              s["motion_time_us_median"].get<double>(), 100.0 * s["motion_share_median"].get<double>());
  std::printf("  %-34s %10.2f us (p95 %.1f)\n", "metrics, median", s["metrics_time_us_median"].get<double>(),
              s["metrics_time_us_p95"].get<double>());
  std::printf("  %-34s %10.2f %%  (median frame %.2f %%, p95 frame %.2f %%)\n", "strain, max",
              100.0 * q.maxStrain, 100.0 * q.medianFrameMaxStrain, 100.0 * q.p95FrameMaxStrain);
  std::printf("  %-34s %10.3f %%\n", "strain, mean", 100.0 * q.meanStrain);
  std::printf("  %-34s %10.4f m  (%" PRId64 " frames over 1 mm)\n", "penetration, max", q.maxPenetration,
              q.framesPenetrationOver1mm);
  std::printf("  %-34s %10d    (%" PRId64 " frames with any)\n", "self-intersections, max",
              q.selfIntersectionsMax, q.framesWithSelfIntersections);
  std::printf("  %-34s %10.2g m\n", "pin error, max", q.pinErrorMax);
  std::printf("  %-34s %10.3f m\n", "lowest particle above the ground", std::isfinite(lowest) ? lowest : 0.0);
  if (o.scene == SceneKind::Hang)
    std::printf("  %-34s %10.4f m/s\n", "rest jitter (last second)", q.restJitter);
  std::printf("  %-34s %10s  (numerical guard: %" PRId64 " particles restored in %" PRId64 " frames)\n",
              "blow-up", q.blowUp ? "YES" : "no", q.guardRestored, q.framesGuardRestored);
  if (blowUp) {
    std::fprintf(stderr,
                 "cape_walk: the cape blew up at frame %" PRId64
                 " (NaN, a particle > 10 m from the torso, or particles the numerical guard restored)\n",
                 framesRun);
  }
  // Last, what to open: the folder and the picture in it.
  std::fflush(stderr);
  std::printf("cape_walk: outputs in %s\n", dir.c_str());
  if (movie) {
    std::printf("cape_walk: picture %s\n", (dir / kPictureFile).c_str());
  } else {
    std::printf("cape_walk: no picture (%s)\n", noRender ? "--no-render" : "a large crowd");
  }
  return blowUp ? 2 : 0;
}
