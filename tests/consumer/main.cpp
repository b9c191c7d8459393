// Builds a canonical cape from the installed headers and library, hangs it from two pins for one second and
// checks that it fell and stayed finite; and checks that the package, the headers and the library report one
// version. Exit status 0 on success. (Built by CMake against the CMake package, and by CI with nothing but
// `pkg-config --cflags --libs capecloth-core`, where CAPE_PACKAGE_VERSION is pkg-config's --modversion.)
#include <cape/core/Cape.h>
#include <cape/core/Version.h>
#include <cape/scenes/Metrics.h>

#include <cstdio>
#include <cstring>

int main() {
  std::printf("consumer: CapeCloth headers %s, library %s, package %s\n", CAPE_VERSION_STRING,
              cape::version(), CAPE_PACKAGE_VERSION);
  if (std::strcmp(cape::version(), CAPE_VERSION_STRING) != 0 ||
      std::strcmp(cape::version(), CAPE_PACKAGE_VERSION) != 0) {
    std::fprintf(stderr, "consumer: the versions differ\n");
    return 1;
  }
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
