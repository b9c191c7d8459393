#include "RunOutput.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <ctime>
#include <stdexcept>

namespace cape::demo {

namespace fs = std::filesystem;

constexpr float kDegrees = 57.29577951f;  ///< degrees per radian
using nlohmann::json;

namespace {
json vec(const Vec3& v) {
  return json::array({v.x(), v.y(), v.z()});
}
const char* axisName(int axis) {
  return axis == 0 ? "x" : axis == 1 ? "y" : "z";
}
}  // namespace

json settingsJson(const CapeSettings& s) {
  json wind = {{"model", s.wind.model == WindSettings::Model::None       ? "none"
                         : s.wind.model == WindSettings::Model::SineWave ? "sine-wave"
                                                                         : "aerodynamic"}};
  if (s.wind.model != WindSettings::Model::None)
    wind.update({{"direction", vec(s.wind.direction)},
                 {"speed_mps", s.wind.speed},
                 {"gust_amplitude", s.wind.gustAmplitude},
                 {"gust_frequency_hz", s.wind.gustFrequency},
                 {"turbulence_scale_m", s.wind.turbulenceScale},
                 {"drag_coefficient", s.wind.dragCoefficient},
                 {"lift_coefficient", s.wind.liftCoefficient},
                 {"seed", s.wind.seed}});
  return {{"integrator", toString(s.integrator)},
          {"structural_stiffness_n_per_m", s.structuralStiffness},
          {"shear_stiffness_n_per_m", s.shearStiffness},
          {"bend_stiffness_n_per_m", s.bendStiffness},
          {"bending_rigidity_n_m", s.bendingRigidity},
          {"tethers", s.useTethers},
          {"damping_per_s", s.damping},
          {"collision_thickness_m", s.collisionThickness},
          {"friction", s.friction},
          {"substeps_per_time_step", s.substeps},
          {"time_step_s", s.timeStep},
          {"strain_limit", s.strainLimit},
          {"max_refinement", s.maxRefinement},
          {"strain_ceiling", s.strainCeiling},
          {"strain_ceiling_passes", s.strainCeilingPasses},
          {"iterations", s.iterations},
          {"gravity", vec(s.gravity)},
          {"wind", wind},
          {"self_collision", s.selfCollision},
          {"self_collision_thickness_m", s.selfCollisionThickness}};
}

json colliderJson(const Collider& c) {
  json j;
  j["name"] = c.name;
  j["type"] = toString(c.shape);
  const Pose& p = c.current;
  j["position"] = vec(p.position);
  j["rotation"] = json::array({p.rotation.x(), p.rotation.y(), p.rotation.z(), p.rotation.w()});
  switch (c.shape) {
    case ColliderShape::Sphere:
      j["radius"] = c.radius;
      break;
    case ColliderShape::Capsule:
    case ColliderShape::Cylinder:
      j["radius"] = c.radius;
      j["half_height"] = c.halfHeight;
      j["axis"] = axisName(c.axis);
      break;
    case ColliderShape::Box:
      j["half_extents"] = vec(c.halfExtents);
      break;
    case ColliderShape::Plane: {
      // World plane n . x = constant, solid below.
      const Vec3 n = p.rotation * c.normal;
      j["normal"] = vec(n);
      j["constant"] = c.constant + n.dot(p.position);
      break;
    }
    case ColliderShape::ConvexHull: {
      // In the collider's frame: its vertices and outward face planes (unit normal, offset: n . p = offset
      // on the face), enough to recompute a particle's penetration from the files alone.
      json vertices = json::array(), planes = json::array();
      for (const Vec3& v : c.hull->vertices) vertices.push_back(vec(v));
      for (const Eigen::Vector4f& q : c.hull->planes)
        planes.push_back({{"normal", vec(q.head<3>())}, {"offset", q[3]}});
      j["vertices"] = std::move(vertices);
      j["planes"] = std::move(planes);
      break;
    }
    case ColliderShape::TriangleMesh:
      j["triangles_near_cape"] = c.triangles->size();  // gathered for this step, in the collider's frame
      break;
  }
  if (c.thickness > 0.0f) j["thickness"] = c.thickness;
  return j;
}

void writeObj(const fs::path& file, const CapeMesh& mesh, std::size_t n) {
  std::FILE* f = std::fopen(file.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + file.string());
  std::fprintf(f, "# cape mesh: %zu vertices in particle order (row-major from the top-left for grids)\n", n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = mesh.positions.row(static_cast<Eigen::Index>(i));
    std::fprintf(f, "v %.6f %.6f %.6f\n", r.x(), r.y(), r.z());
  }
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = mesh.normals.row(static_cast<Eigen::Index>(i));
    std::fprintf(f, "vn %.5f %.5f %.5f\n", r.x(), r.y(), r.z());
  }
  for (std::size_t i = 0; i < n; ++i)
    std::fprintf(f, "vt %.6f %.6f\n", mesh.uvs[i].x(), 1.0f - mesh.uvs[i].y());
  for (std::size_t t = 0; t + 2 < mesh.indices.size() && mesh.indices[t] < n; t += 3) {
    const unsigned a = mesh.indices[t] + 1, b = mesh.indices[t + 1] + 1, c = mesh.indices[t + 2] + 1;
    std::fprintf(f, "f %u/%u/%u %u/%u/%u %u/%u/%u\n", a, a, a, b, b, b, c, c, c);
  }
  std::fclose(f);
}

RunWriter::RunWriter(const fs::path& dir, bool writeFrames, int characters, bool writeColliders)
    : dir_(dir), writeFrames_(writeFrames), characters_(characters), writeColliders_(writeColliders) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw std::runtime_error("cannot create output folder " + dir_.string() + ": " + ec.message());
  if (writeFrames_) {
    if (characters_ > 1) {
      for (int k = 0; k < characters_; ++k)
        fs::create_directories(dir_ / "frames" / ("k" + std::to_string(k)), ec);
    } else {
      fs::create_directories(dir_ / "frames", ec);
    }
    if (ec) throw std::runtime_error("cannot create " + (dir_ / "frames").string() + ": " + ec.message());
  }
  csv_.open(dir_ / "metrics.csv");
  if (writeColliders_) jsonl_.open(dir_ / "colliders.jsonl");
  if (!csv_ || (writeColliders_ && !jsonl_)) throw std::runtime_error("cannot write into " + dir_.string());
  csv_ << "frame,time_s,frame_time_us,cape_time_us,max_strain,mean_strain,max_penetration_m,self_"
          "intersections,"
          "pin_error_m,mean_speed_mps,blow_up,guard_restored,mean_dihedral_deg,dihedral_change_deg\n";
}

void RunWriter::frame(const FrameRow& r) {
  char line[512];
  std::snprintf(line, sizeof line, "%" PRId64 ",%.6f,%.2f,%.2f,%.6f,%.6f,%.6f,%d,%.3g,%.5f,%d,%u,%.4f,%.4f\n",
                r.frame, r.time, r.frameTimeUs, r.capeTimeUs, r.metrics.maxStrain, r.metrics.meanStrain,
                r.metrics.maxPenetration, r.metrics.selfIntersections, r.metrics.pinError,
                r.metrics.meanSpeed, r.metrics.blowUp ? 1 : 0, static_cast<unsigned>(r.metrics.guardRestored),
                r.metrics.meanDihedral * kDegrees, r.metrics.dihedralChange * kDegrees);
  csv_ << line;
}

void RunWriter::capeMesh(std::int64_t frame, int character, const Fabric& fabric, const Points& positions) {
  if (!writeFrames_) return;
  if (mesh_.positions.rows() != static_cast<Eigen::Index>(fabric.particleCount()))
    mesh_.allocate(fabric, false);
  mesh_.update(fabric, positions);
  char name[32];
  std::snprintf(name, sizeof name, "%05" PRId64 ".obj", frame);
  const fs::path folder =
      characters_ > 1 ? dir_ / "frames" / ("k" + std::to_string(character)) : dir_ / "frames";
  writeObj(folder / name, mesh_, fabric.particleCount());
}

void RunWriter::colliders(std::int64_t frame, const std::vector<Collider>& colliders) {
  if (!writeColliders_) return;
  json j;
  j["frame"] = frame;
  j["colliders"] = json::array();
  for (const Collider& c : colliders) j["colliders"].push_back(colliderJson(c));
  jsonl_ << j.dump() << '\n';
}

void RunWriter::summary(const json& s) {
  std::ofstream out(dir_ / "summary.json");
  out << s.dump(2) << '\n';
  if (!out) throw std::runtime_error("cannot write " + (dir_ / "summary.json").string());
}

void FrameTimings::add(const FrameRow& row) {
  if (row.frame <= 10) return;  // frames 11..end
  frameTimeUs_.add(row.frameTimeUs);
  capeTimeUs_.add(row.capeTimeUs);
  bulletTimeUs_.add(std::max(0.0, row.frameTimeUs - row.capeTimeUs));
  motionTimeUs_.add(row.motionTimeUs);
  const double whole = row.motionTimeUs + row.frameTimeUs;
  motionShare_.add(whole > 0.0 ? row.motionTimeUs / whole : 0.0);
  metricsTimeUs_.add(row.metricsTimeUs);
}

json summaryFigures(const FrameTimings& timings, const RunSummary& q) {
  json j;
  j["frames"] = q.frames;
  j["frame_time_us_median"] = timings.frameTimeUs().percentile(50.0);
  j["frame_time_us_p95"] = timings.frameTimeUs().percentile(95.0);
  j["cape_time_us_median"] = timings.capeTimeUs().percentile(50.0);
  j["cape_time_us_p95"] = timings.capeTimeUs().percentile(95.0);
  j["max_strain"] = q.maxStrain;
  j["mean_strain"] = q.meanStrain;
  j["median_frame_max_strain"] = q.medianFrameMaxStrain;
  j["p95_frame_max_strain"] = q.p95FrameMaxStrain;
  j["max_penetration_m"] = q.maxPenetration;
  j["frames_penetration_over_1mm"] = q.framesPenetrationOver1mm;
  j["self_intersections_max"] = q.selfIntersectionsMax;
  j["frames_with_self_intersections"] = q.framesWithSelfIntersections;
  j["pin_error_max_m"] = q.pinErrorMax;
  j["rest_jitter_mps"] = q.restJitter;
  j["mean_dihedral_deg"] = q.meanDihedral * static_cast<double>(kDegrees);
  j["mean_dihedral_change_deg"] = q.meanDihedralChange * static_cast<double>(kDegrees);
  j["blow_up"] = q.blowUp;
  j["guard_restored_particles"] = q.guardRestored;
  j["frames_guard_restored"] = q.framesGuardRestored;
  return j;
}

json frameShareFigures(const FrameTimings& timings, int capes) {
  json j;
  j["bullet_time_us_median"] = timings.bulletTimeUs().percentile(50.0);
  j["bullet_time_us_p95"] = timings.bulletTimeUs().percentile(95.0);
  // The median of the frames' cape time / K is the median cape time / K.
  j["cape_time_per_cape_us_median"] = timings.capeTimeUs().percentile(50.0) / std::max(1, capes);
  j["motion_time_us_median"] = timings.motionTimeUs().percentile(50.0);
  j["motion_time_us_p95"] = timings.motionTimeUs().percentile(95.0);
  j["motion_share_median"] = timings.motionShare().percentile(50.0);
  j["metrics_time_us_median"] = timings.metricsTimeUs().percentile(50.0);
  j["metrics_time_us_p95"] = timings.metricsTimeUs().percentile(95.0);
  return j;
}

namespace {

bool isFrameObj(const fs::path& name) {
  const std::string n = name.string();
  if (n.size() < 9 || n.compare(n.size() - 4, 4, ".obj") != 0) return false;
  return std::all_of(n.begin(), n.end() - 4, [](char c) { return c >= '0' && c <= '9'; });
}

bool isCharacterFolder(const fs::path& name) {
  const std::string n = name.string();
  return n.size() >= 2 && n[0] == 'k' &&
         std::all_of(n.begin() + 1, n.end(), [](char c) { return c >= '0' && c <= '9'; });
}

bool isRunFile(const fs::path& name, RunFolderKind kind) {
  static const char* const walk[] = {"metrics.csv", "summary.json", kPictureFile, kVideoFile,
                                     "colliders.jsonl"};
  static const char* const compare[] = {"compare.csv",           "compare.json",          "frames_ours.csv",
                                        "frames_btsoftbody.csv", "frames_deformable.csv", "strain.png",
                                        "penetration.png",       "frame_time.png"};
  const std::string n = name.string();
  if (kind == RunFolderKind::Walk) return std::find(std::begin(walk), std::end(walk), n) != std::end(walk);
  return std::find(std::begin(compare), std::end(compare), n) != std::end(compare);
}

/// The previous run's files in `dir` (each folder after its files, so that it is empty when deleted), or
/// false and the reason when anything else is there.
bool listRunFiles(const fs::path& dir, RunFolderKind kind, std::vector<fs::path>& files, std::string& error) {
  // Only what the demo makes: regular files and (for frames) real folders, never a symbolic link. An entry
  // that cannot be read is neither, so it is refused.
  const auto type = [](const fs::path& p) {
    std::error_code unreadable;
    return fs::symlink_status(p, unreadable).type();
  };
  const auto isFile = [&](const fs::path& p) { return type(p) == fs::file_type::regular; };
  const auto isFolder = [&](const fs::path& p) { return type(p) == fs::file_type::directory; };
  std::vector<fs::path> strangers;
  std::error_code ec;
  const auto objFolder = [&](const fs::path& folder, bool characters) {
    for (const fs::directory_entry& e : fs::directory_iterator(folder, ec)) {
      const fs::path name = e.path().filename();
      if (isFile(e.path()) && isFrameObj(name)) {
        files.push_back(e.path());
      } else if (characters && isFolder(e.path()) && isCharacterFolder(name)) {
        for (const fs::directory_entry& f : fs::directory_iterator(e.path(), ec)) {
          if (isFile(f.path()) && isFrameObj(f.path().filename()))
            files.push_back(f.path());
          else
            strangers.push_back(f.path());
        }
        files.push_back(e.path());
      } else {
        strangers.push_back(e.path());
      }
    }
  };
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const fs::path name = e.path().filename();
    if (isFile(e.path()) && isRunFile(name, kind)) {
      files.push_back(e.path());
    } else if (kind == RunFolderKind::Walk && name == "frames" && isFolder(e.path())) {
      objFolder(e.path(), true);
      files.push_back(e.path());
    } else {
      strangers.push_back(e.path());
    }
  }
  if (ec) {
    error = "cannot read --out " + dir.string() + ": " + ec.message();
    return false;
  }
  if (strangers.empty()) return true;
  std::sort(strangers.begin(), strangers.end());
  const char* demo = kind == RunFolderKind::Walk ? "cape_walk" : "cape_compare";
  const std::size_t more = strangers.size() - 1;
  error = "--out " + dir.string() + " holds " + fs::relative(strangers.front(), dir, ec).string() +
          (more > 0 ? " (and " + std::to_string(more) + " more)" : "") + ", which " + demo +
          " does not write: give a new or empty folder, or one that holds nothing but a previous " + demo +
          " run (whose files are then deleted)";
  return false;
}

}  // namespace

bool checkOutFolder(const fs::path& dir, RunFolderKind kind, std::string& error) try {
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (status.type() == fs::file_type::not_found) return true;
  if (ec) {
    error = "cannot read --out " + dir.string() + ": " + ec.message();
    return false;
  }
  if (!fs::is_directory(status)) {
    error = "--out " + dir.string() + " is not a folder";
    return false;
  }
  std::vector<fs::path> files;
  return listRunFiles(dir, kind, files, error);
} catch (const fs::filesystem_error& e) {
  error = "cannot read --out " + dir.string() + ": " + e.what();
  return false;
}

bool prepareOutFolder(const fs::path& dir, RunFolderKind kind, std::string& error) try {
  if (!checkOutFolder(dir, kind, error)) return false;
  std::error_code ec;
  fs::create_directories(dir, ec);
  std::vector<fs::path> files;
  if (ec || !listRunFiles(dir, kind, files, error)) {
    if (ec) error = "cannot create output folder " + dir.string() + ": " + ec.message();
    return false;
  }
  for (const fs::path& f : files) {
    if (!fs::remove(f, ec) || ec) {
      error = "cannot delete the previous run's " + f.string() + (ec ? ": " + ec.message() : "");
      return false;
    }
  }
  return true;
} catch (const fs::filesystem_error& e) {
  error = "cannot empty --out " + dir.string() + ": " + e.what();
  return false;
}

fs::path freshRunFolder(const std::string& name) {
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&now));
  const fs::path base = fs::path("runs") / (name + "-" + stamp);
  fs::path dir = base;
  for (int k = 2; fs::exists(dir); ++k) dir = base.string() + "-" + std::to_string(k);
  return dir;
}

}  // namespace cape::demo
