#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine and runs the main job: the headless walking demo. Installs the packages,
# builds in Release, runs cape_walk (extra arguments are passed on; see `cape_walk --help`). The run goes into
# a fresh runs/<scene>-<time> folder under the current directory (or --out DIR); its last line names the
# picture (docs/OUTPUTS.md).
# Usage: bash scripts/demo.sh [cape_walk options]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build"
bash "$root/scripts/install-deps.sh"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target cape_walk
exec "$build/demos/cape_walk" "$@"
