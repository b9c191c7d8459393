#!/usr/bin/env bash
# Plays a public motion capture that is not ours on the shipped humanoid with the cape: the CMU-derived
# example.bvh that the npm package bvh-loader 0.0.9 ships (GPL-3.0 package: fetched, never copied into this
# repository). It has the quirks of real files: CRLF lines, a reference pose as frame 0, CMU's odd units
# (23.4 units tall), a skeleton facing another way than its motion, and a clip that is not a cycle.
# Usage: bash scripts/try-public-bvh.sh [build-dir] [more cape_walk options]
# Needs npm (Debian's npm package) and a built cape_walk (bash scripts/test.sh, or scripts/demo.sh).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
shift || true
walk="$build/demos/cape_walk"
[ -x "$walk" ] || { echo "try-public-bvh: no $walk (build it first: bash scripts/test.sh)" >&2; exit 1; }
command -v npm >/dev/null || { echo "try-public-bvh: npm is needed (apt-get install npm)" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
(cd "$work" && npm pack --silent bvh-loader@0.0.9 >/dev/null && tar xzf bvh-loader-0.0.9.tgz)
clip="$work/package/javascript-bvh/example.bvh"
[ -f "$clip" ] || { echo "try-public-bvh: the package has no javascript-bvh/example.bvh" >&2; exit 1; }
out="${TMPDIR:-/tmp}/cape_public_bvh"
rm -rf "$out"
"$walk" --motion "$clip" --motion-once --self-collision --seconds 3 --no-frames --out "$out" "$@"
