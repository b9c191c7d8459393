#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine and runs the whole test suite: installs the packages, builds in Release,
# runs every test through ctest. Usage: bash scripts/test.sh [build-dir [extra CMake options]]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
if [ $# -gt 0 ]; then shift; fi
bash "$root/scripts/install-deps.sh"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build "$build" -j"$(nproc)"
ctest --test-dir "$build" --output-on-failure -j"$(nproc)"
