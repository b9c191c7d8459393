// Builds a canonical cape from the installed headers and library, hangs it from two pins for one second and
// checks that it fell and stayed finite. Exit status 0 on success.
#include <cape/core/Cape.h>
#include <cape/scenes/Metrics.h>

#include <cstdio>

int main() {
  cape::GridDesc grid;
  grid.tetherAnchors = {0, 19};
  const cape::FabricResult fabric = cape::Fabric::grid(grid);
  if (!fabric) {
    std::fprintf(stderr, "%s\n", fabric.status.message().c_str());
    return 1;
  }
  cape::Cape cape(fabric.fabric, cape::CapeSettings());
  cape.pin(0, cape::Vec3(0.0f, 0.0f, 0.0f));
  cape.pin(19, cape::Vec3(0.6f, 0.0f, 0.0f));
  for (int frame = 0; frame < 60; ++frame) cape.step(1.0f / 60.0f, {});
  const float y = cape.state().positions.col(1).minCoeff();
  const bool ok = !cape::isBlownUp(cape.state().positions, cape::Vec3::Zero()) && y < -0.9f;
  std::printf("consumer: lowest particle at y = %.3f m, pin error %.2g m: %s\n", y,
              cape::maxPinError(cape.state()), ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
