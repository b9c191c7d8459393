#!/usr/bin/env bash
# Fuzzing (docs/FUZZING.md): builds the libFuzzer targets of tests/fuzz with clang (CAPE_FUZZ=ON,
# RelWithDebInfo with line tables, ASan + UBSan; only the fuzz targets), writes the seed
# corpus, and runs a target for SECONDS, or every target one after another for SECONDS each.
#   bash scripts/fuzz.sh TARGET|all SECONDS [libFuzzer options...]   e.g. bash scripts/fuzz.sh urdf 3600
#   bash scripts/fuzz.sh build                                       configure, build, write the seeds
# Targets: urdf, mesh_hull, urdf_mesh, fabric, motion. Each run reads its seeds and tests/fuzz/regressions/TARGET/
# and keeps what it learns in BUILD/corpus/run/TARGET/ (a later run goes on from there). Anything found
# (a crash, an input over 2 s, a leak, a sanitizer report, over 2 GB) stops the run with libFuzzer's non-zero
# status and is written to BUILD/artifacts/TARGET/. Environment: CAPE_FUZZ_BUILD (the build folder,
# default build-fuzz), CAPE_FUZZ_CXX (default clang++, Debian 12's clang 14), CAPE_FUZZ_SKIP_BUILD=1
# (use the build as it is, for runs side by side).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${CAPE_FUZZ_BUILD:-$root/build-fuzz}"
targets=(urdf mesh_hull urdf_mesh fabric motion)
usage() { sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
[ $# -ge 1 ] || usage

if [ "${CAPE_FUZZ_SKIP_BUILD:-0}" != 1 ]; then
  cxx="${CAPE_FUZZ_CXX:-clang++}"
  # Line tables only (-gline-tables-only): the reports' stacks have their files and lines, and the build takes
  # a fraction of the time full debug information does.
  cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCAPE_FUZZ=ON \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
    -DCAPE_BUILD_BENCHMARKS=OFF -DCAPE_BUILD_DEMOS=OFF >/dev/null
  cmake --build "$build" -j"$(nproc)" --target cape_fuzz_all
  "$build/tests/fuzz/cape_fuzz_corpus" "$root/character/models" "$build/corpus" >/dev/null
fi
[ "$1" != build ] || exit 0
[ $# -ge 2 ] || usage
what="$1" seconds="$2"
shift 2
case "$seconds" in '' | *[!0-9]*) echo "fuzz.sh: SECONDS must be a whole number, not '$seconds'" >&2; exit 2 ;; esac
if [ "$what" = all ]; then run=("${targets[@]}"); else run=("$what"); fi

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/tests/fuzz/lsan.supp}"
if [ -z "${ASAN_SYMBOLIZER_PATH:-}" ] && command -v llvm-symbolizer >/dev/null; then
  export ASAN_SYMBOLIZER_PATH="$(command -v llvm-symbolizer)"  # stacks with file and line
fi
for t in "${run[@]}"; do
  case " ${targets[*]} " in *" $t "*) ;; *) echo "fuzz.sh: no target '$t' (${targets[*]})" >&2; exit 2 ;; esac
  case "$t" in
    urdf) extra=(-max_len=32768 -dict="$root/tests/fuzz/urdf.dict") ;;
    mesh_hull | urdf_mesh) extra=(-max_len=16384 -dict="$root/tests/fuzz/mesh.dict") ;;
    fabric) extra=(-max_len=32768) ;;
    motion) extra=(-max_len=16384 -dict="$root/tests/fuzz/motion.dict") ;;
  esac
  corpus=("$build/corpus/run/$t" "$build/corpus/seeds/$t")
  [ -d "$root/tests/fuzz/regressions/$t" ] && corpus+=("$root/tests/fuzz/regressions/$t")
  mkdir -p "$build/corpus/run/$t" "$build/artifacts/$t"
  echo "=== fuzz $t for $seconds s"
  "$build/tests/fuzz/cape_fuzz_$t" -max_total_time="$seconds" -timeout=2 -rss_limit_mb=2048 \
    -artifact_prefix="$build/artifacts/$t/" -print_final_stats=1 "${extra[@]}" "$@" "${corpus[@]}"
done
