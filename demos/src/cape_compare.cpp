// cape_compare: the same scene (same character, colliders, attachments, stepping) with our cape and with the
// btSoftBody twin (and optionally the twin in Bullet's deformable world), side by side. Prints one
// row per solver with every metric of docs/SCENES.md, the frame and cape times and each solver's cape
// time relative to ours; writes compare.csv, compare.json,
// per-frame CSVs and PNG plots. `cape_compare --help` lists the options.
#include "BulletScene.h"
#include "CliNumbers.h"
#include "Plots.h"
#include "Progress.h"
#include "Renderer.h"
#include "RunOutput.h"
#include "SceneOptions.h"

#include "cape/bullet/CapeAction.h"
#include "cape/bullet/Convert.h"
#include "cape/compare/SoftBodyTwin.h"

#include <BulletSoftBody/btSoftBody.h>
#include <CLI/CLI.hpp>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>

using namespace cape;
using namespace cape::demo;
using nlohmann::json;

namespace {

/// A solver's lines of the plots in bounded memory: every frame's point until kPoints are kept, then every
/// second frame's, every fourth, ... (each time the lines fill up, every other point is dropped).
class PlotPoints {
 public:
  static constexpr std::size_t kPoints = 4096;
  void add(const FrameRow& r) {
    if (r.frame % stride_ != 0) return;
    if (frames_.size() == kPoints) {
      std::size_t kept = 0;
      for (std::size_t i = 0; i < frames_.size(); ++i) {
        if (frames_[i] % (2 * stride_) != 0) continue;
        frames_[kept] = frames_[i];
        for (std::vector<double>& v : values_) v[kept] = v[i];
        ++kept;
      }
      frames_.resize(kept);
      for (std::vector<double>& v : values_) v.resize(kept);
      stride_ *= 2;
      if (r.frame % stride_ != 0) return;
    }
    frames_.push_back(r.frame);
    values_[0].push_back(100.0 * r.metrics.maxStrain);
    values_[1].push_back(1000.0 * r.metrics.maxPenetration);
    values_[2].push_back(r.frameTimeUs);
  }
  /// Line `which`: 0 max strain, %; 1 penetration, mm; 2 frame time, us; against time, s.
  Series series(const std::string& name, int which) const {
    Series s{name, {}, values_[static_cast<std::size_t>(which)]};
    for (std::int64_t f : frames_) s.x.push_back(static_cast<double>(f) / 60.0);
    return s;
  }

 private:
  std::int64_t stride_ = 1;
  std::vector<std::int64_t> frames_;
  std::vector<double> values_[3];
};

/// One solver's run: its summary, timings, plotted points and per-frame CSV (written as it runs), and its
/// settings as printed.
struct SolverResult {
  std::string name;
  json settings;
  MetricsRecorder recorder;
  FrameTimings timings;
  PlotPoints plot;
  std::ofstream perFrame;
  void add(const FrameRow& r) {
    recorder.add(r.metrics);
    timings.add(r);
    plot.add(r);
    char line[512];
    std::snprintf(line, sizeof line, "%" PRId64 ",%.6f,%.2f,%.2f,%.6f,%.6f,%.6f,%d,%.3g,%d\n", r.frame,
                  r.time, r.frameTimeUs, r.capeTimeUs, r.metrics.maxStrain, r.metrics.meanStrain,
                  r.metrics.maxPenetration, r.metrics.selfIntersections, r.metrics.pinError,
                  r.metrics.blowUp ? 1 : 0);
    perFrame << line;
  }
};

/// The twins of every character of a scene, in a world of their own: btSoftBody twins in a soft-rigid world,
/// or deformable twins in Bullet's deformable world. Measured exactly as ours: the twin's nodes are copied
/// into particle arrays and go through the same measureFrame.
class TwinRun {
 public:
  enum class Kind { SoftBody, Deformable };

  bool build(const RunOptions& o, Kind kind, const compare::SoftBodyTwinSettings& soft,
             const compare::DeformableTwinSettings& deformable, std::string& error) {
    scene_ = BulletScene::create(o, error,
                                 kind == Kind::Deformable ? WorldKind::Deformable : WorldKind::SoftRigid);
    if (!scene_) return false;
    const CapeSettings settings = settingsForScene(o.scene, o.settings);
    for (int k = 0; k < scene_->characterCount(); ++k) {
      // A cape action (never added to the world) places the cape and holds the attachments the twin copies.
      auto proto = std::make_unique<bullet::CapeAction>(scene_->rig().fabric, settings,
                                                        bullet::toBt(scene_->capePlacement(k)));
      scene_->startCape(k, *proto);
      for (const PinSpec& p : scene_->pins(k)) proto->attach(p.particle, p.body, p.localPivot);
      btSoftBody* body = nullptr;
      if (kind == Kind::SoftBody) {
        std::unique_ptr<btSoftBody> made = compare::makeSoftBodyTwin(*scene_->softRigidWorld(), *proto, soft);
        if (made && settings.wind.model != WindSettings::Model::None) {
          // Bullet's own aerodynamics, two-sided, in the mean wind (btSoftBody has no gust field).
          made->m_cfg.aeromodel = btSoftBody::eAeroModel::V_TwoSided;
          made->m_cfg.kDG = btScalar(settings.wind.dragCoefficient);
          made->m_cfg.kLF = btScalar(settings.wind.liftCoefficient);
          made->setWindVelocity(bullet::toBt(settings.wind.direction.normalized() * settings.wind.speed));
        }
        body = made.get();
        if (made) softBodies_.push_back(std::move(made));
      } else {
        std::unique_ptr<compare::DeformableTwin> made =
            compare::makeDeformableTwin(*scene_->deformableWorld(), *proto, deformable);
        body = made ? &made->body() : nullptr;
        if (made) deformables_.push_back(std::move(made));
      }
      if (!body) {
        error = "cannot build the Bullet twin";
        return false;
      }
      bodies_.push_back(body);
      positions_.push_back(Points::Zero(static_cast<Eigen::Index>(body->m_nodes.size()), 3));
      velocities_.push_back(Points::Zero(static_cast<Eigen::Index>(body->m_nodes.size()), 3));
      pins_.emplace_back(scene_->pins(k).size());
      counters_.emplace_back();
      protos_.push_back(std::move(proto));
    }
    return true;
  }
  ~TwinRun() {
    deformables_.clear();  // each removes itself from its world
    if (scene_)
      for (auto& b : softBodies_) scene_->softRigidWorld()->removeSoftBody(b.get());
  }
  double stepFrame(double t) { return scene_->stepFrame(t); }
  /// Character k's twin measured by the same measureFrame as our capes: its nodes' positions and velocities,
  /// and its anchors' particles with their attachment points now.
  FrameMetrics measure(int k) {
    const std::size_t c = static_cast<std::size_t>(k);
    const btSoftBody& body = *bodies_[c];
    Points& x = positions_[c];
    Points& v = velocities_[c];
    for (int i = 0; i < body.m_nodes.size(); ++i) {
      x.row(i) = bullet::toVec3(body.m_nodes[i].m_x).transpose();
      v.row(i) = bullet::toVec3(body.m_nodes[i].m_v).transpose();
    }
    const std::vector<PinSpec>& specs = scene_->pins(k);
    for (std::size_t p = 0; p < specs.size(); ++p) {
      pins_[c][p].particle = specs[p].particle;
      pins_[c][p].target = bullet::toVec3(specs[p].body->getWorldTransform() * specs[p].localPivot);
    }
    const Fabric& fabric = *scene_->rig().fabric;  // built (or build() failed) with the scene
    return measureFrame(fabric, x, v, pins_[c], scene_->bodyColliders(k), scene_->torsoCentre(k),
                        &counters_[c]);
  }
  int characterCount() const { return scene_->characterCount(); }
  const Fabric& fabric() const { return *scene_->rig().fabric; }
  /// Node positions of character k's twin as of the last measure(k), m.
  const Points& positions(int k) const { return positions_[static_cast<std::size_t>(k)]; }
  std::vector<Collider> bodyColliders(int k) const { return scene_->bodyColliders(k); }

 private:
  std::unique_ptr<BulletScene> scene_;
  std::vector<std::unique_ptr<bullet::CapeAction>> protos_;
  std::vector<std::unique_ptr<btSoftBody>> softBodies_;
  std::vector<std::unique_ptr<compare::DeformableTwin>> deformables_;
  std::vector<btSoftBody*> bodies_;
  std::vector<Points> positions_, velocities_;
  std::vector<std::vector<Pin>> pins_;  ///< per character: each anchored node and its attachment point now
  std::vector<SelfIntersectionCounter> counters_;
};

json twinSettingsJson(const compare::SoftBodyTwinSettings& t) {
  return {{"links", std::string(t.structuralLinks ? "structural " : "") + (t.shearLinks ? "shear " : "") +
                        (t.bendLinks ? "bend" : "")},
          {"piterations", t.positionIterations},
          {"viterations", t.velocityIterations},
          {"diterations", t.driftIterations},
          {"kLST", t.linearStiffness},
          {"kDP", t.damping},
          {"kDF", t.friction},
          {"kAHR", t.anchorHardness},
          {"kCHR", t.rigidContactHardness},
          {"margin_m", t.margin},
          {"collisions", "SDF_RS"}};
}

json deformableSettingsJson(const compare::DeformableTwinSettings& t) {
  return {{"links", std::string(t.structuralLinks ? "structural " : "") + (t.shearLinks ? "shear " : "") +
                        (t.bendLinks ? "bend" : "")},
          {"world", "btDeformableMultiBodyDynamicsWorld, explicit"},
          {"elastic_stiffness_N_per_m", t.elasticStiffness},
          {"damping_stiffness_Ns_per_m", t.dampingStiffness},
          {"kDF", t.friction},
          {"margin_m", t.margin},
          {"collisions", "SDF_RD | SDF_RDF"},
          {"wind", "none"}};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "cape_compare: the same scene with our cape and with Bullet's btSoftBody twin (and, with "
      "--with-deformable, its deformable-world twin), side by side; prints every metric of docs/SCENES.md "
      "per "
      "solver and writes compare.csv, compare.json and PNG plots. Every number is read whole and checked "
      "against its range before the run starts."};
  addVersionFlag(app, "cape_compare");
  app.footer(
      "Exit status: 0 when the run is done; 1 when the URDF, the settings or the output cannot be used; "
      "CLI11's codes (from 100; 105 for a number out of range or not a number) for a bad command line.");
  SceneCli sceneCli;
  std::string out;
  int iterations = 10;
  bool noPlots = false;
  bool withDeformable = false;
  double deformableStiffness = 50.0;
  std::string render, renderSize = "960x360";
  sceneCli.cape = "canonical";  // the comparison's cape (docs/SCENES.md), so figures stay comparable
  addSceneOptions(app, sceneCli);
  app.add_option("--softbody-iterations", iterations, "btSoftBody position iterations (m_cfg.piterations)")
      ->transform(strictInteger(1, 200))
      ->capture_default_str();
  app.add_option("--out", out,
                 "output folder (default: a fresh runs/compare-<scene>-<time> folder). A folder that holds "
                 "a previous cape_compare run (only compare.csv, compare.json, frames_*.csv and the three "
                 "plots) is emptied of it first; a folder with any other file is refused and left as it is");
  app.add_flag("--no-plots", noPlots, "do not draw the PNG plots");
  app.add_flag("--with-deformable", withDeformable,
               "also run the twin in Bullet's deformable world (btDeformableMultiBodyDynamicsWorld)");
  app.add_option("--deformable-stiffness", deformableStiffness,
                 "the deformable twin's spring stiffness, N/m (from 100 it blows up on the 20 x 20 cape)")
      ->transform(strictReal(1e-3, 1e6))
      ->capture_default_str();
  app.add_option(
      "--render", render,
      "also render both capes side by side (ours left, btSoftBody right) as PNG frames, and run.mp4 and "
      "run.gif with ffmpeg, into this folder");
  app.add_option("--render-size", renderSize, "rendered image size, WxH")
      ->check(strictImageSize(kMinImageSide, kMaxImageSide, true))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  RunOptions o;
  std::string optionError;
  if (!toRunOptions(sceneCli, o, optionError)) {
    std::fprintf(stderr, "cape_compare: %s\n", optionError.c_str());
    return 1;
  }
  const std::string& scene = sceneCli.scene;
  const std::filesystem::path dir =
      out.empty() ? freshRunFolder("compare-" + scene) : std::filesystem::path(out);
  std::string error;
  if (!checkOutFolder(dir, RunFolderKind::Compare, error)) {
    std::fprintf(stderr, "cape_compare: %s\n", error.c_str());
    return 1;
  }

  std::unique_ptr<SceneRun> ours = makeSceneRun(o, error);
  if (!ours) {
    std::fprintf(stderr, "cape_compare: %s\n", error.c_str());
    return 1;
  }
  // Every cape as ours (with --fabric, the preset's springs, damping and drag).
  o.settings = ours->settings();

  // The twin's settings: the same masses, springs (structural + shear, the King's graph; bend springs
  // soften btSoftBody's stretch resistance and are left out), friction, thickness and air drag as ours
  // (btSoftBody damps by (1 - kDP) per step, ours by 1 / (1 + c h)); its stiffest material, and as many
  // position iterations as asked for (10 by default, the figure the issue quotes).
  compare::SoftBodyTwinSettings twin;
  const double h = 1.0 / 240.0;
  const double c = o.settings.damping;
  twin.positionIterations = iterations;
  twin.linearStiffness = 1;
  twin.damping = btScalar(c * h / (1.0 + c * h));
  twin.friction = btScalar(o.settings.friction);
  twin.margin = btScalar(o.settings.collisionThickness);

  // The deformable twin: the same links (Bullet's mass-spring force has one stiffness for every link),
  // friction and thickness, explicit steps. Its stiffness cannot be ours: with the 20 x 20 cape's 1 g nodes
  // at 1/240 s the deformable world blows up from 100 N/m (measured; ours are 20000 N/m), so the default is
  // 50 N/m.
  compare::DeformableTwinSettings deformable;
  deformable.elasticStiffness = btScalar(deformableStiffness);
  deformable.friction = btScalar(o.settings.friction);
  deformable.margin = btScalar(o.settings.collisionThickness);

  // Each twin in a world of its own, and beside it the same world with no cape at all: the rigid share of a
  // frame, so that a twin's cape time is its frame time less that (its work happens inside stepSimulation,
  // where it cannot be timed alone).
  const int twinCount = withDeformable ? 2 : 1;
  TwinRun twinRuns[2];
  std::unique_ptr<BulletScene> bare[2];
  for (int i = 0; i < twinCount; ++i) {
    const TwinRun::Kind kind = i == 0 ? TwinRun::Kind::SoftBody : TwinRun::Kind::Deformable;
    bare[i] = BulletScene::create(
        o, error, kind == TwinRun::Kind::Deformable ? WorldKind::Deformable : WorldKind::SoftRigid);
    if (!bare[i] || !twinRuns[i].build(o, kind, twin, deformable, error)) {
      std::fprintf(stderr, "cape_compare: %s\n", error.c_str());
      return 1;
    }
  }
  TwinRun& twinRun = twinRuns[0];

  if (!prepareOutFolder(dir, RunFolderKind::Compare, error)) {
    std::fprintf(stderr, "cape_compare: %s\n", error.c_str());
    return 1;
  }

  // Side by side: ours on the left, the twin on the right, each with its own camera (the first character).
  std::unique_ptr<RunRenderer> renderer;
  CapeMesh twinMesh;
  if (!render.empty()) {
    int w = 0, h = 0;
    parseImageSize(renderSize, kMinImageSide, kMaxImageSide, true, w, h);  // checked by CLI11
    renderer = std::make_unique<RunRenderer>(render, 2, w, h, RunRenderer::Layout::SideBySide);
    if (!renderer->ok()) {
      std::fprintf(stderr, "cape_compare: %s\n", renderer->error().c_str());
      return 1;
    }
    twinMesh.allocate(twinRun.fabric(), false);
  }

  const double length = o.seconds > 0.0 ? o.seconds : MotionDesc::forScene(o.scene).duration;
  const std::int64_t frames = std::llround(length * 60.0);  // at most 60 kMaxSeconds
  std::vector<SolverResult> results(static_cast<std::size_t>(1 + twinCount));
  results[0].name = "ours (XPBD cape)";
  results[0].settings = settingsJson(settingsForScene(o.scene, o.settings));
  if (o.fabric) results[0].settings["fabric"] = o.fabric->name;
  results[1].name = "btSoftBody twin";
  results[1].settings = twinSettingsJson(twin);
  if (withDeformable) {
    results[2].name = "btDeformable twin";
    results[2].settings = deformableSettingsJson(deformable);
  }
  for (SolverResult& r : results) {
    const char* perFrameName = &r == &results[0]   ? "frames_ours"
                               : &r == &results[1] ? "frames_btsoftbody"
                                                   : "frames_deformable";
    r.perFrame.open(dir / (std::string(perFrameName) + ".csv"));
    r.perFrame << "frame,time_s,frame_time_us,cape_time_us,max_strain,mean_strain,max_penetration_m,self_"
                  "intersections,pin_error_m,blow_up\n";
    if (!r.perFrame) {
      std::fprintf(stderr, "cape_compare: cannot write into %s\n", dir.c_str());
      return 1;
    }
  }
  std::vector<FrameMeter> meters(static_cast<std::size_t>(ours->characterCount()));
  Progress progress("cape_compare " + scene, static_cast<long>(frames));
  for (std::int64_t f = 1; f <= frames; ++f) {
    const double t = f / 60.0;
    // Interleaved, so that the machine's noise falls on every solver alike.
    ours->advanceFrame();
    FrameRow a{f, t, ours->lastFrameTimeUs(), ours->lastCapeTimeUs(), {}};
    // A crowd's row holds the worst of its characters.
    for (int k = 0; k < ours->characterCount(); ++k) {
      const FrameMetrics m = meters[static_cast<std::size_t>(k)].measure(
          ours->cape(k), ours->bodyColliders(k), ours->torsoCentre(k));
      a.metrics = k == 0 ? m : worstOf(a.metrics, m);
    }
    results[0].add(a);
    for (int i = 0; i < twinCount; ++i) {
      const double twinFrame = twinRuns[i].stepFrame(t);
      const double bareFrame = bare[i]->stepFrame(t);
      FrameRow b{f, t, twinFrame, std::max(0.0, twinFrame - bareFrame), {}};
      for (int k = 0; k < twinRuns[i].characterCount(); ++k) {
        const FrameMetrics m = twinRuns[i].measure(k);
        b.metrics = k == 0 ? m : worstOf(b.metrics, m);
      }
      results[static_cast<std::size_t>(1 + i)].add(b);
    }
    if (renderer) {
      renderer->record(0, ours->cape(0), ours->bodyColliders(0));
      twinMesh.update(twinRun.fabric(), twinRun.positions(0));
      renderer->record(1, twinMesh, twinRun.bodyColliders(0));
    }
    progress.update(static_cast<long>(f));
  }
  progress.finish();

  // The table, compare.csv and compare.json.
  json compare;
  compare["scene"] = scene;
  compare["body"] = ours->describe();
  const Fabric& fabric = ours->cape(0).fabric();
  compare["grid"] = {
      {"columns", fabric.gridColumns()}, {"rows", fabric.gridRows()}, {"particles", fabric.particleCount()}};
  compare["cape"] = {{"width_m", ours->capeSize().width}, {"height_m", ours->capeSize().height}};
  compare["frames"] = frames;
  const json ourSummary = summaryFigures(results[0].timings, results[0].recorder.summary());
  const double ourCape = ourSummary["cape_time_us_median"].get<double>();
  std::ofstream csv(dir / "compare.csv");
  csv << "solver,frame_time_us_median,cape_time_us_median,cape_time_us_p95,cape_time_ratio_to_ours,max_"
         "strain,"
         "mean_strain,p95_frame_max_strain,max_penetration_m,frames_penetration_over_1mm,self_intersections_"
         "max,"
         "pin_error_max_m,blow_up\n";
  std::printf("cape_compare: scene %s, %d x %d cape, %" PRId64 " frames -> %s\n%s\n", scene.c_str(),
              fabric.gridColumns(), fabric.gridRows(), frames, dir.c_str(), ours->describe().c_str());
  std::printf("%-18s %9s %9s %9s %7s %8s %8s %9s %6s %6s %9s %6s\n", "solver", "frame us", "cape us",
              "cape p95", "x ours", "strain", "mean", "pen m", ">1mm", "self", "pin m", "blowup");
  for (SolverResult& r : results) {
    const RunSummary q = r.recorder.summary();
    r.perFrame.close();
    json s = summaryFigures(r.timings, q);
    const double ratio = ourCape > 0.0 ? s["cape_time_us_median"].get<double>() / ourCape : 0.0;
    json row = {{"name", r.name},
                {"frame_time_us_median", s["frame_time_us_median"]},
                {"cape_time_us_median", s["cape_time_us_median"]},
                {"cape_time_us_p95", s["cape_time_us_p95"]},
                {"cape_time_ratio_to_ours", ratio},
                {"max_strain", q.maxStrain},
                {"mean_strain", q.meanStrain},
                {"p95_frame_max_strain", q.p95FrameMaxStrain},
                {"max_penetration_m", q.maxPenetration},
                {"frames_penetration_over_1mm", q.framesPenetrationOver1mm},
                {"self_intersections_max", q.selfIntersectionsMax},
                {"pin_error_max_m", q.pinErrorMax},
                {"blow_up", q.blowUp},
                {"settings", r.settings}};
    compare["solvers"].push_back(row);
    char line[512];
    std::snprintf(line, sizeof line, "%s,%.2f,%.2f,%.2f,%.3f,%.6f,%.6f,%.6f,%.6f,%" PRId64 ",%d,%.3g,%d\n",
                  r.name.c_str(), s["frame_time_us_median"].get<double>(),
                  s["cape_time_us_median"].get<double>(), s["cape_time_us_p95"].get<double>(), ratio,
                  q.maxStrain, q.meanStrain, q.p95FrameMaxStrain, q.maxPenetration,
                  q.framesPenetrationOver1mm, q.selfIntersectionsMax, q.pinErrorMax, q.blowUp ? 1 : 0);
    csv << line;
    std::printf("%-18s %9.1f %9.1f %9.1f %7.2f %7.2f%% %7.3f%% %9.4f %6" PRId64 " %6d %9.2g %6s\n",
                r.name.c_str(), s["frame_time_us_median"].get<double>(),
                s["cape_time_us_median"].get<double>(), s["cape_time_us_p95"].get<double>(), ratio,
                100.0 * q.maxStrain, 100.0 * q.meanStrain, q.maxPenetration, q.framesPenetrationOver1mm,
                q.selfIntersectionsMax, q.pinErrorMax, q.blowUp ? "YES" : "no");
  }
  std::printf("settings:\n  ours:         %s\n  btSoftBody:   %s\n", results[0].settings.dump().c_str(),
              results[1].settings.dump().c_str());
  if (withDeformable) std::printf("  btDeformable: %s\n", results[2].settings.dump().c_str());
  std::ofstream(dir / "compare.json") << compare.dump(2) << "\n";
  if (renderer) {
    if (!renderer->finish(error)) {
      std::fprintf(stderr, "cape_compare: %s\n", error.c_str());
      return 1;
    }
    std::printf("cape_compare: %d side-by-side frames rendered -> %s\n", renderer->frames(), render.c_str());
  }

  if (!noPlots) {
    auto series = [&](int which) {
      std::vector<Series> out;
      for (const SolverResult& r : results) out.push_back(r.plot.series(r.name, which));
      return out;
    };
    const bool drawn =
        plotLines(dir / "strain.png", "Max structural strain per frame (" + scene + ")", "time, s",
                  "strain, %", series(0), error) &&
        plotLines(dir / "penetration.png", "Deepest particle inside a body collider (" + scene + ")",
                  "time, s", "penetration, mm", series(1), error) &&
        plotLines(dir / "frame_time.png", "Wall time of stepSimulation per frame (" + scene + ")", "time, s",
                  "frame time, us", series(2), error);
    if (!drawn) std::fprintf(stderr, "cape_compare: plots not drawn: %s\n", error.c_str());
  }
  return 0;
}
