// Fuzz target: Fabric::fromMesh from vertex and triangle arrays decoded from the bytes, and, when the fabric
// builds, a cape of it stepped a few frames against a moving sphere and a floor with its anchors pinned and
// moving, and its render mesh. A mesh the fabric cannot be made of must come back as a Status; a fabric that
// builds must keep Fabric.h's promises (checked below); a crash, a hang or a sanitizer report is a bug.
//
// Input, little-endian, zeros once the bytes run out:
//   u8  flags: 1 bend springs, 2 positions as raw float bits (else 16-bit fixed point, 1/1024 m), 4 UVs,
//       8 self-collision, 16 the explicit integrator, 32 aerodynamic wind, 64 no strain-adaptive substeps,
//       128 a two-sided render mesh
//   u8  total mass (b / 64 kg; 0 is refused)
//   u8  tether anchors (b % 8)
//   u8  tethers per particle (b % 4)
//   u8  tether scale (0.5 + b / 64)
//   u8  frames to step (1 + b % 2: the first step's contact search, then a step that keeps or renews its
//       contacts at twice the substeps; a third and fourth frame cost most of the time, see docs/FUZZING.md)
//   u16 vertices (3 + v % 1022)
//   u16 triangles (t % 4096)
//   the anchors (u16 each, modulo vertices + 1: one past the end is out of range), the vertices (x y z),
//   UVs when asked (u v, fixed point 1/1024), the triangles (u16 indices modulo vertices + 1), then per
//   frame the pins' and the sphere's motion (x y z, 1/64 m each).
#include "FuzzSupport.h"

#include "cape/core/Cape.h"
#include "cape/core/CapeMesh.h"
#include "cape/core/Collider.h"
#include "cape/core/Fabric.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace {

using cape::Fabric;
using cape::SpringFamily;
using cape::SpringSet;

// A family's promises: ends in range and distinct, rest lengths positive and finite, colours that share
// no particle and cover the set in order, runs that cover it in order with whole blocks of four in vector
// layouts and no block across two colours.
void checkSprings(const SpringSet& set, std::size_t n, const char* family) {
  const std::string f = family;
  CAPE_FUZZ_CHECK(set.second.size() == set.size() && set.restLength.size() == set.size(),
                  f + ": array sizes");
  for (std::size_t s = 0; s < set.size(); ++s) {
    CAPE_FUZZ_CHECK(set.first[s] < n && set.second[s] < n && set.first[s] != set.second[s],
                    f + ": spring ends");
    CAPE_FUZZ_CHECK(std::isfinite(set.restLength[s]) && set.restLength[s] > 0.0f, f + ": rest length");
  }
  if (set.size() == 0) return;
  CAPE_FUZZ_CHECK(
      set.colourStart.size() >= 2 && set.colourStart.front() == 0 && set.colourStart.back() == set.size(),
      f + ": colours do not cover the springs");
  std::vector<std::uint32_t> seenIn(n, ~0u);
  for (std::size_t k = 0; k + 1 < set.colourStart.size(); ++k) {
    CAPE_FUZZ_CHECK(set.colourStart[k] <= set.colourStart[k + 1], f + ": colours out of order");
    for (std::uint32_t s = set.colourStart[k]; s < set.colourStart[k + 1]; ++s) {
      for (std::uint32_t p : {set.first[s], set.second[s]}) {
        CAPE_FUZZ_CHECK(seenIn[p] != k, f + ": two springs of colour " + std::to_string(k) +
                                            " share particle " + std::to_string(p));
        seenIn[p] = static_cast<std::uint32_t>(k);
      }
    }
  }
  std::uint32_t next = 0;
  for (const cape::SpringRun& run : set.runs) {
    CAPE_FUZZ_CHECK(run.begin == next && run.end >= run.begin && run.end <= set.size(), f + ": runs");
    if (run.layout != cape::SpringLayout::Scalar)
      CAPE_FUZZ_CHECK((run.end - run.begin) % 4 == 0, f + ": a vector run of a partial block");
    next = run.end;
  }
  CAPE_FUZZ_CHECK(next == set.size(), f + ": runs do not cover the springs");
}

void checkFabric(const Fabric& fabric, const cape::MeshDesc& desc) {
  const std::size_t n = desc.positions.size();
  CAPE_FUZZ_CHECK(fabric.particleCount() == n, "particle count");
  CAPE_FUZZ_CHECK(fabric.triangles() == desc.triangles, "triangles changed");
  CAPE_FUZZ_CHECK(fabric.uvs().size() == n, "one UV per particle");
  for (std::size_t i = 0; i < n; ++i) {
    const float m = fabric.masses()[static_cast<Eigen::Index>(i)];
    CAPE_FUZZ_CHECK(std::isfinite(m) && m > 0.0f,
                    "particle " + std::to_string(i) + " mass " + std::to_string(m));
  }
  CAPE_FUZZ_CHECK(
      std::abs(fabric.totalMass() - desc.totalMass) <= 1e-3f * desc.totalMass + 1e-6f,
      "total mass " + std::to_string(fabric.totalMass()) + " for " + std::to_string(desc.totalMass));
  checkSprings(fabric.springs(SpringFamily::Structural), n, "structural");
  checkSprings(fabric.springs(SpringFamily::Shear), n, "shear");
  checkSprings(fabric.springs(SpringFamily::Bend), n, "bend");
  CAPE_FUZZ_CHECK(fabric.springs(SpringFamily::Structural).size() > 0,
                  "a mesh fabric without structural springs");
  if (!desc.bendSprings)
    CAPE_FUZZ_CHECK(fabric.springs(SpringFamily::Bend).size() == 0, "bend springs not asked for");
  const cape::TetherSet& t = fabric.tethers();
  for (std::size_t k = 0; k < t.size(); ++k)
    CAPE_FUZZ_CHECK(
        t.particle[k] < n && t.anchor[k] < n && std::isfinite(t.maxLength[k]) && t.maxLength[k] >= 0.0f,
        "tether " + std::to_string(k));
  CAPE_FUZZ_CHECK(fabric.triangleLocal().size() == fabric.triangleCount(), "one local set per triangle");
  CAPE_FUZZ_CHECK(fabric.clusterStart().empty() || fabric.clusterStart().back() == fabric.triangleCount(),
                  "clusters do not cover the triangles");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  capefuzz::ByteReader in(data, size);
  const std::uint8_t flags = in.u8();
  cape::MeshDesc desc;
  desc.bendSprings = (flags & 1) != 0;
  desc.totalMass = static_cast<float>(in.u8()) / 64.0f;
  const int anchors = in.u8() % 8;
  desc.tethersPerParticle = in.u8() % 4;
  desc.tetherScale = 0.5f + static_cast<float>(in.u8()) / 64.0f;
  const int frames = 1 + in.u8() % 2;
  const std::uint32_t n = 3u + in.u16() % 1022u;
  const std::uint32_t triangles = in.u16() % 4096u;
  for (int a = 0; a < anchors; ++a) desc.tetherAnchors.push_back(in.u16() % (n + 1));
  constexpr float kMillimetre = 1.0f / 1024.0f;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (flags & 2)
      desc.positions.emplace_back(in.rawFloat(), in.rawFloat(), in.rawFloat());
    else
      desc.positions.emplace_back(in.fixed(kMillimetre), in.fixed(kMillimetre), in.fixed(kMillimetre));
  }
  if (flags & 4)
    for (std::uint32_t i = 0; i < n; ++i) desc.uvs.emplace_back(in.fixed(kMillimetre), in.fixed(kMillimetre));
  for (std::uint32_t k = 0; k < 3 * triangles; ++k) desc.triangles.push_back(in.u16() % (n + 1));

  const cape::FabricResult made = Fabric::fromMesh(desc);
  if (!made) {
    CAPE_FUZZ_CHECK(!made.status.ok(), "no fabric and no error");
    return 0;
  }
  CAPE_FUZZ_CHECK(made.status.ok(), "a fabric and an error");
  checkFabric(*made.fabric, desc);

  cape::CapeSettings settings;
  settings.selfCollision = (flags & 8) != 0;
  if (flags & 16) settings.integrator = cape::Integrator::ExplicitSpring;
  if (flags & 32) {
    settings.wind.model = cape::WindSettings::Model::Aerodynamic;
    settings.wind.speed = 8.0f;
    settings.wind.gustAmplitude = 0.5f;
  }
  if (flags & 64) settings.strainLimit = 0.0f;
  cape::Cape cape(made.fabric, settings);
  if (!cape.ok()) return 0;
  for (std::uint32_t a : desc.tetherAnchors)
    if (a < n) cape.pin(a, cape.state().positions.row(a).transpose());
  const cape::Vec3 centre =
      0.5f *
      (cape.state().positions.colwise().minCoeff() + cape.state().positions.colwise().maxCoeff()).transpose();
  std::vector<cape::Collider> colliders = {
      cape::Collider::sphere(0.2f, cape::Pose{centre, cape::Quat::Identity()}),
      cape::Collider::plane(cape::Vec3::UnitY(), centre.y() - 1.0f)};
  cape::CapeMesh mesh;
  mesh.allocate(*made.fabric, (flags & 128) != 0);
  constexpr float kStep = 1.0f / 64.0f;
  for (int f = 0; f < frames; ++f) {
    const cape::Vec3 pinMotion(in.fixed(kStep), in.fixed(kStep), in.fixed(kStep));
    for (std::size_t p = 0; p < cape.state().pins.size(); ++p)
      cape.movePin(p, cape.state().pins[p].target + pinMotion);
    const cape::Vec3 sphereMotion(in.fixed(kStep), in.fixed(kStep), in.fixed(kStep));
    colliders[0].moveTo(cape::Pose{colliders[0].current.position + sphereMotion, cape::Quat::Identity()});
    colliders[1].moveTo(colliders[1].current);
    cape.step(1.0f / 60.0f, colliders);
    CAPE_FUZZ_CHECK(static_cast<std::size_t>(cape.state().positions.rows()) == n, "the cape lost particles");
    mesh.update(*made.fabric, cape.state().positions);
  }
  return 0;
}
