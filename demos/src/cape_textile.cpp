// cape_textile: the textile industry's tests of the fabric presets, rerun on the solver core (no Bullet):
// Peirce's cantilever bending length (ASTM D1388, BS 3356) and Cusick's drape coefficient (BS 5058,
// ISO 9073-9), for one preset or all of them. Prints one row per fabric, and can write the results as JSON
// and the settled specimens side by side as a PNG. `cape_textile --help` lists the options; the methods are
// in docs/SOLVER.md, "Validation".
#include "CliNumbers.h"
#include "Renderer.h"
#include "SceneOptions.h"

#include "cape/scenes/Textile.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

using namespace cape;
using namespace cape::demo;
using nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979;

struct Row {
  const FabricMaterial* material = nullptr;
  CantileverResult cantilever;
  DrapeResult drape;
  double seconds = 0.0;
};

// The settled specimens side by side, one panel per fabric in the order run, each from the same
// three-quarter view above the disc (drape) or from the side of the ledge (cantilever).
bool renderPanels(const std::string& test, const std::vector<Row>& rows, int width, int height,
                  const std::string& file, std::string& error) {
  Renderer renderer(width, height);
  if (!renderer.ok()) {
    error = renderer.error();
    return false;
  }
  const int n = static_cast<int>(rows.size());
  const Colour palette[5] = {Colour(0.78f, 0.70f, 0.86f), Colour(0.90f, 0.90f, 0.86f),
                             Colour(0.45f, 0.30f, 0.22f), Colour(0.20f, 0.30f, 0.55f),
                             Colour(0.30f, 0.18f, 0.10f)};
  for (int k = 0; k < n; ++k) {
    const Row& r = rows[static_cast<std::size_t>(k)];
    const int x0 = k * width / n, x1 = (k + 1) * width / n;
    const bool drape = test == "drape";
    const Points& positions = drape ? r.drape.positions : r.cantilever.positions;
    const FabricPtr& fabric = drape ? r.drape.fabric : r.cantilever.fabric;
    if (!fabric) continue;
    Camera camera;
    std::vector<Collider> props;
    if (drape) {
      camera = Camera::lookAt(Vec3(0.30f, 0.26f, 0.38f), Vec3(0.0f, -0.045f, 0.0f), x1 - x0, height, 38.0f,
                              0.02f, 10.0f);
      Pose disc;
      disc.position = Vec3(0.0f, -0.0075f, 0.0f);  // its top 4 mm under the specimen: no z-fighting
      props.push_back(Collider::cylinder(0.09f, 0.0035f, 1, disc));
      Pose stand;
      stand.position = Vec3(0.0f, -0.16f, 0.0f);
      props.push_back(Collider::cylinder(0.012f, 0.15f, 1, stand));
    } else {
      const float l = r.cantilever.overhang;
      camera = Camera::lookAt(Vec3(0.3f * l, -0.25f * l, 2.4f * l), Vec3(0.45f * l, -0.3f * l, 0.0f), x1 - x0,
                              height, 40.0f, 0.002f, 10.0f);
      Pose ledge;
      ledge.position = Vec3(-0.5f * l, -0.02f * l, 0.5f * (positions.col(2).maxCoeff()));
      props.push_back(Collider::box(Vec3(0.5f * l, 0.02f * l, 0.6f * l), ledge));
    }
    camera.x = x0;
    renderer.begin(camera, Colour(0.86f, 0.89f, 0.93f));
    renderer.drawColliders(props, Colour(0.55f, 0.58f, 0.62f));
    CapeMesh mesh;
    mesh.allocate(*fabric, false);
    mesh.update(*fabric, positions);
    const Colour outside = palette[k % 5];
    renderer.drawCape(mesh, outside, outside * 0.8f);
  }
  const Image& image = renderer.finish();
  return writePng(file, image, error);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "cape_textile: the textile tests of the fabric presets on the solver core: Peirce's cantilever "
      "bending length (ASTM D1388, BS 3356) or Cusick's drape coefficient (BS 5058, ISO 9073-9). Prints one "
      "row per fabric; --json writes the results, --render the settled specimens side by side."};
  addVersionFlag(app, "cape_textile");
  app.footer(
      "Exit status: 0 when every test ran; 1 when a test or an output cannot be made; CLI11's codes (from "
      "100; 105 for a number out of range or not a number) for a bad command line.");
  std::string test = "drape", fabricName = "all", jsonFile, render, renderSize = "1500x360";
  double spacing = 0.0075, seconds = -1.0;
  int segments = 16;
  app.add_option("test", test, "the test: drape or cantilever")
      ->check(CLI::IsMember({"drape", "cantilever"}))
      ->capture_default_str();
  app.add_option("--fabric", fabricName, "a preset (" + fabricNames() + ") or all")->capture_default_str();
  app.add_option("--spacing", spacing, "drape: the specimen mesh's edge, m")
      ->transform(strictReal(0.004, 0.05))
      ->capture_default_str();
  app.add_option("--segments", segments, "cantilever: hinges along the overhang")
      ->transform(strictInteger(2, 64))
      ->capture_default_str();
  app.add_option("--seconds", seconds,
                 "settling time, s (default: the test's own, 3 for the drape and 2 for the cantilever)")
      ->transform(strictReal(0.1, 60.0));
  app.add_option("--json", jsonFile, "write the results to this JSON file (replaced if it exists)");
  app.add_option("--render", render, "write the settled specimens side by side to this PNG (replaced)");
  app.add_option("--render-size", renderSize, "rendered image size, WxH")
      ->check(strictImageSize(kMinImageSide, kMaxImageSide, true))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  std::vector<const FabricMaterial*> fabrics;
  if (fabricName == "all") {
    for (const FabricMaterial& m : fabricPresets()) fabrics.push_back(&m);
  } else if (const FabricMaterial* m = findFabric(fabricName)) {
    fabrics.push_back(m);
  } else {
    std::fprintf(stderr, "cape_textile: unknown fabric '%s' (the presets: %s, or all)\n", fabricName.c_str(),
                 fabricNames().c_str());
    return 1;
  }
  int width = 0, height = 0;
  parseImageSize(renderSize, kMinImageSide, kMaxImageSide, true, width, height);

  std::vector<Row> rows;
  if (test == "drape") {
    std::printf("%-8s %9s %8s %8s %6s %10s %10s %8s\n", "fabric", "c (cm)", "h (mm)", "DC", "folds",
                "S (cm2)", "Sf (cm2)", "time (s)");
  } else {
    std::printf("%-8s %9s %8s %9s %11s %8s %8s\n", "fabric", "c (cm)", "hinges", "theta", "c_sim (cm)",
                "error", "time (s)");
  }
  for (const FabricMaterial* m : fabrics) {
    Row row;
    row.material = m;
    const auto t0 = std::chrono::steady_clock::now();
    if (test == "drape") {
      DrapeSpec spec;
      spec.spacing = static_cast<float>(spacing);
      if (seconds > 0.0) spec.seconds = static_cast<float>(seconds);
      row.drape = runDrape(*m, spec);
      if (!row.drape.status.ok()) {
        std::fprintf(stderr, "cape_textile: %s: %s\n", m->name.c_str(), row.drape.status.message().c_str());
        return 1;
      }
    } else {
      CantileverSpec spec;
      spec.segments = segments;
      if (seconds > 0.0) spec.seconds = static_cast<float>(seconds);
      row.cantilever = runCantilever(*m, spec);
      if (!row.cantilever.status.ok()) {
        std::fprintf(stderr, "cape_textile: %s: %s\n", m->name.c_str(),
                     row.cantilever.status.message().c_str());
        return 1;
      }
    }
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (test == "drape") {
      const DrapeResult& d = row.drape;
      std::printf("%-8s %9.2f %8.1f %8.3f %6d %10.1f %10.1f %8.1f\n", m->name.c_str(),
                  100.0 * m->bendingLength(), 1000.0 * spacing, d.coefficient, d.folds, 1e4 * d.shadowArea,
                  1e4 * d.specimenArea, row.seconds);
    } else {
      const CantileverResult& c = row.cantilever;
      std::printf("%-8s %9.2f %8d %8.1f° %11.2f %7.1f%% %8.1f\n", m->name.c_str(), 100.0 * c.expected,
                  segments, c.theta * 180.0 / kPi, 100.0 * c.bendingLength,
                  100.0 * (c.bendingLength / c.expected - 1.0), row.seconds);
    }
    std::fflush(stdout);
    rows.push_back(std::move(row));
  }

  if (!jsonFile.empty()) {
    json out = {{"tool", "cape_textile"}, {"test", test}, {"fabrics", json::array()}};
    for (const Row& r : rows) {
      json f = {{"name", r.material->name},
                {"bending_length_m", r.material->bendingLength()},
                {"areal_density_kg_per_m2", r.material->arealDensity},
                {"bending_rigidity_n_m", r.material->bendingRigidity},
                {"seconds", r.seconds}};
      if (test == "drape") {
        f["spacing_m"] = spacing;
        f["drape_coefficient"] = r.drape.coefficient;
        f["folds"] = r.drape.folds;
        f["shadow_area_m2"] = r.drape.shadowArea;
        f["specimen_area_m2"] = r.drape.specimenArea;
        f["disc_area_m2"] = r.drape.discArea;
        f["max_speed_m_per_s"] = r.drape.maxSpeed;
      } else {
        f["segments"] = segments;
        f["overhang_m"] = r.cantilever.overhang;
        f["theta_rad"] = r.cantilever.theta;
        f["simulated_bending_length_m"] = r.cantilever.bendingLength;
        f["max_speed_m_per_s"] = r.cantilever.maxSpeed;
      }
      out["fabrics"].push_back(f);
    }
    std::ofstream file(jsonFile);
    file << out.dump(2) << "\n";
    if (!file) {
      std::fprintf(stderr, "cape_textile: cannot write %s\n", jsonFile.c_str());
      return 1;
    }
  }
  if (!render.empty()) {
    std::string error;
    if (!renderPanels(test, rows, width, height, render, error)) {
      std::fprintf(stderr, "cape_textile: cannot render %s: %s\n", render.c_str(), error.c_str());
      return 1;
    }
    std::printf("cape_textile: picture in %s\n", render.c_str());
  }
  return 0;
}
