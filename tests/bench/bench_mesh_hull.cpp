// Google Benchmark over loadMeshHull (character/src/MeshHull.h): 100 distinct meshes of 4992 triangles
// (2498 vertices) each, as a URDF's collision meshes might be: noisy ellipsoids ("scanned limbs") written as
// binary STL into a fresh temporary folder. One iteration loads all 100.
// - BM_MeshHullCold/N: the cache emptied first, so every load reads the file with assimp, builds the hull
//   and simplifies it to N vertices.
// - BM_MeshHullCached: the same 100 loads again, each a cache hit (a stat of the file and a lookup).
// Reported: time per iteration (100 loads) and per_mesh, the time per load in seconds ("m" ms, "u" us).
#include "MeshHull.h"

#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using cape::character::loadMeshHull;
using Eigen::Vector3d;

void put32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}

void putFloat(std::string& out, double d) {
  const float f = static_cast<float>(d);
  std::uint32_t u = 0;
  std::memcpy(&u, &f, 4);
  put32(out, u);
}

// A UV ellipsoid (40 stacks, 64 slices) with semi-axes `axes`, every vertex moved radially by up to 1 %.
void writeNoisyEllipsoid(const std::string& path, const Vector3d& axes, unsigned seed) {
  const int stacks = 40, slices = 64;
  const double pi = 3.14159265358979323846;
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> noise(0.99, 1.01);
  std::vector<Vector3d> v;
  for (int i = 0; i <= stacks; ++i) {
    for (int j = 0; j < slices; ++j) {
      const double theta = pi * i / stacks, phi = 2 * pi * j / slices;
      const Vector3d unit(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      v.push_back(noise(random) * unit.cwiseProduct(axes));
      if (i == 0 || i == stacks) break;  // one vertex at each pole
    }
  }
  const auto at = [&](int i, int j) -> const Vector3d& {
    if (i == 0) return v.front();
    if (i == stacks) return v.back();
    return v[static_cast<std::size_t>(1 + (i - 1) * slices + (j % slices))];
  };
  std::string out(80, ' ');
  put32(out, static_cast<std::uint32_t>(2 * slices * (stacks - 1)));
  const auto triangle = [&](const Vector3d& a, const Vector3d& b, const Vector3d& c) {
    for (int k = 0; k < 3; ++k) putFloat(out, 0.0);
    for (const Vector3d* p : {&a, &b, &c})
      for (int k = 0; k < 3; ++k) putFloat(out, (*p)[k]);
    out += std::string(2, '\0');
  };
  for (int i = 0; i < stacks; ++i) {
    for (int j = 0; j < slices; ++j) {
      if (i > 0) triangle(at(i, j), at(i + 1, j), at(i, j + 1));
      if (i < stacks - 1) triangle(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
    }
  }
  std::ofstream(path, std::ios::binary) << out;
}

// The 100 files, written once per process and removed at exit.
struct MeshFiles {
  fs::path dir;
  std::vector<std::string> paths;
  MeshFiles() {
    dir = fs::temp_directory_path() / ("cape_bench_mesh_hull_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    for (unsigned k = 0; k < 100; ++k) {
      const Vector3d axes(0.05 + 0.001 * k, 0.08 + 0.0005 * k, 0.20 - 0.001 * k);  // limb-sized, m
      paths.push_back((dir / ("limb_" + std::to_string(k) + ".stl")).string());
      writeNoisyEllipsoid(paths.back(), axes, k + 1);
    }
  }
  ~MeshFiles() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

const MeshFiles& files() {
  static const MeshFiles f;
  return f;
}

void loadAll(benchmark::State& state, const cape::character::MeshHullOptions& options) {
  for (const std::string& p : files().paths) {
    const cape::character::MeshHullResult r = loadMeshHull(p, Vector3d::Ones(), options);
    if (!r.ok()) state.SkipWithError(r.status.message().c_str());
    benchmark::DoNotOptimize(r.hull.get());
  }
}

void report(benchmark::State& state) {
  const double loads = static_cast<double>(files().paths.size());
  state.counters["per_mesh"] =
      benchmark::Counter(loads, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_MeshHullCold(benchmark::State& state) {
  cape::character::MeshHullOptions options;
  options.maxVertices = static_cast<int>(state.range(0));
  files();
  for (auto _ : state) {
    cape::character::clearMeshHullCache();
    loadAll(state, options);
  }
  report(state);
}

void BM_MeshHullCached(benchmark::State& state) {
  const cape::character::MeshHullOptions options;
  cape::character::clearMeshHullCache();
  loadAll(state, options);
  for (auto _ : state) loadAll(state, options);
  report(state);
}

}  // namespace

BENCHMARK(BM_MeshHullCold)->Arg(16)->Arg(64)->Arg(256)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MeshHullCached)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
