#!/usr/bin/env bash
# Uses an installed CapeCloth as an outside project would, in every way the package offers (CI runs it on the
# static, the shared and the core-only installs):
#   1. CMake: find_package(CapeCloth 0.2) and the three consumer programs (only the core one where the
#      Bullet part was not installed), each run;
#   2. the version request: asking for 0.1, 0.3 or 1.0 must fail to configure (0.2 accepts 0.2.x only);
#   3. pkg-config: the core consumer (and the Bullet one with capecloth.pc where installed) compiled with
#      nothing but `pkg-config --cflags --libs [--static]` and run.
# Usage: bash tests/consumer/check.sh PREFIX WORKDIR [shared]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
prefix="$(cd "$1" && pwd)"
work="$2"
kind="${3:-static}"
rm -rf "$work"
mkdir -p "$work"
libdir="$(dirname "$(find "$prefix" -path '*/cmake/CapeCloth/CapeClothConfig.cmake' | head -n 1)")/../.."
libdir="$(cd "$libdir" && pwd)"
export LD_LIBRARY_PATH="$libdir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"

echo "-- CMake package ($kind)"
cmake -S "$here" -B "$work/cmake" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/cmake" -j"$(nproc)" >/dev/null
"$work/cmake/cape_consumer"
with_bullet=0
if [ -e "$work/cmake/cape_bullet_consumer" ]; then
  with_bullet=1
  "$work/cmake/cape_bullet_consumer"
  "$work/cmake/cape_character_consumer"
fi
if [ "$kind" = shared ]; then
  # A shared build: the programs load the installed libraries, not static copies of them.
  # (ldd's whole output first: `ldd | grep -q` under pipefail fails whenever grep stops reading early and ldd
  # gets SIGPIPE, which happened in CI.)
  loads="$(ldd "$work/cmake/cape_consumer")"
  grep -q "libcape_core.so" <<<"$loads" || { echo "cape_consumer does not load libcape_core.so:"; echo "$loads"; exit 1; }
fi

echo "-- version requests the package must refuse"
for v in 0.1 0.3 1.0; do
  if cmake -S "$here" -B "$work/refuse-$v" -DCMAKE_PREFIX_PATH="$prefix" -DCAPE_REQUEST_VERSION="$v" \
      >"$work/refuse-$v.log" 2>&1; then
    echo "find_package(CapeCloth $v) was accepted by the installed $(grep -o 'PACKAGE_VERSION "[^"]*"' \
      "$libdir/cmake/CapeCloth/CapeClothConfigVersion.cmake" | head -n 1)"
    exit 1
  fi
  grep -q "not compatible\|version" "$work/refuse-$v.log"
  echo "find_package(CapeCloth $v): refused"
done

if [ "$with_bullet" -eq 1 ]; then
  echo "-- a machine without Bullet: find_package fails and says what is needed"
  # Bullet's CMake package disabled and pkg-config pointed at an empty folder: neither way finds Bullet.
  mkdir -p "$work/no-pc"
  if PKG_CONFIG_LIBDIR="$work/no-pc" PKG_CONFIG_PATH="" cmake -S "$here" -B "$work/no-bullet" \
      -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_DISABLE_FIND_PACKAGE_Bullet=ON -DCAPE_CONSUMER_NEEDS_BULLET=ON \
      >"$work/no-bullet.log" 2>&1; then
    echo "find_package(CapeCloth ... bullet) succeeded without Bullet"; exit 1
  fi
  # (CMake wraps the message's lines: compare with the whitespace squeezed.)
  message="$(tr -s ' \n' '  ' <"$work/no-bullet.log")"
  grep -q "apt-get install libbullet-dev" <<<"$message" || { cat "$work/no-bullet.log"; exit 1; }
  grep -o "CapeCloth's Bullet parts need[^:]*" <<<"$message" | head -n 1
fi

echo "-- pkg-config"
export PKG_CONFIG_PATH="$libdir/pkgconfig${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}"
static=""
[ "$kind" = shared ] || static="--static"
version="$(pkg-config --modversion capecloth-core)"
# shellcheck disable=SC2046
c++ -std=c++17 -o "$work/pc_consumer" "$here/main.cpp" -DCAPE_PACKAGE_VERSION="\"$version\"" \
  $(pkg-config --cflags --libs $static capecloth-core)
"$work/pc_consumer"
if [ "$with_bullet" -eq 1 ]; then
  # shellcheck disable=SC2046
  c++ -std=c++17 -o "$work/pc_bullet_consumer" "$here/bullet_consumer.cpp" \
    $(pkg-config --cflags --libs $static capecloth)
  "$work/pc_bullet_consumer"
fi
echo "-- the installed package works ($kind)"
