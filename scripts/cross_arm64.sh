#!/usr/bin/env bash
# Cross-builds the CPU kernel and its tests for arm64 with Debian's
# g++-aarch64-linux-gnu and runs them under qemu-aarch64 (qemu-user): the
# standalone project tests/arm64 (organsim_core and tests/core's kernel
# tests; no CGAL or GL) in ${ORGANSIM_ARM64_BUILD_DIR:-build-arm64}.
# Installs what it needs (Debian multiarch: the arm64 Highway and
# GoogleTest), skipping what is there. Logs go to the build folder; a
# failing step prints its log's tail. Exits non-zero when a step or a test fails.
#
#   ORGANSIM_ARM64_FILTER  gtest filter (default '*': every kernel test);
#                          under qemu the tests run ~10-50x slower, e.g.
#                          ORGANSIM_ARM64_FILTER='*OneStep*:*Dispatch*:*RestState*'
#   ORGANSIM_ARM64_TIMEOUT seconds the test run may take (default 3600)
#   ORGANSIM_JOBS          compile jobs (default 2)
#   ORGANSIM_WERROR        warnings are errors (default ON, as scripts/build.sh)
#   ORGANSIM_BUILD_TYPE    default Release
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ORGANSIM_ARM64_BUILD_DIR:-$root/build-arm64}
triplet=aarch64-linux-gnu
# qemu-aarch64's prefix for the guest's absolute paths: "/", so that the
# loader, libc, libstdc++ and libgomp all come from Debian's arm64 multiarch
# packages (/lib/aarch64-linux-gnu), one matched set. Not the cross
# compiler's /usr/aarch64-linux-gnu: its ld.so (libc6-arm64-cross) finds
# libc6:arm64's newer libc.so.6 first (libhwy1:arm64 pulls that in), and
# that mix hangs in pthread_create, at the first OpenMP parallel region.
qemu_prefix=/
mkdir -p "$build"
export CCACHE_BASEDIR=$root

# Runs "$@" with its output in $build/$1.log (first argument: the log's
# name); on failure prints the log's tail and exits.
step() {
  local name=$1 start=$SECONDS
  shift
  if ! "$@" >"$build/$name.log" 2>&1; then
    echo "cross_arm64: $name failed (${build}/$name.log):"
    tail -n 40 "$build/$name.log"
    exit 1
  fi
  step_seconds=$((SECONDS - start))
}

# --- packages ---------------------------------------------------------------
packages=(
  cmake ninja-build libeigen3-dev nlohmann-json3-dev  # host: build tools, header-only libraries
  g++-aarch64-linux-gnu                               # the cross compiler (its libstdc++, libgomp, libc)
  qemu-user                                           # qemu-aarch64
  libhwy-dev:arm64 libgtest-dev:arm64                 # arm64 libraries (multiarch)
  libc6:arm64 libstdc++6:arm64 libgomp1:arm64         # their run-time set, for qemu
)
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
missing=()
for p in "${packages[@]}"; do installed "$p" || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  echo "cross_arm64: installing ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  export DEBIAN_FRONTEND=noninteractive
  install_packages() {
    if ! dpkg --print-foreign-architectures | grep -qx arm64; then
      "${sudo_cmd[@]}" dpkg --add-architecture arm64
    fi
    "${sudo_cmd[@]}" apt-get update
    "${sudo_cmd[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
  }
  step apt install_packages
fi

# --- configure and build ----------------------------------------------------
# The toolchain file, rewritten only when it changes (CMake reconfigures on a
# newer one). Libraries and CMake packages are found in Debian's multiarch
# folders (/usr/lib/aarch64-linux-gnu, CMAKE_LIBRARY_ARCHITECTURE) and the
# cross compiler's own (/usr/aarch64-linux-gnu, which it links against);
# header-only Eigen and nlohmann-json come from the host's /usr/include and
# /usr/share.
toolchain=$build/aarch64-toolchain.cmake
cat >"$toolchain.new" <<EOF
# Written by scripts/cross_arm64.sh.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER $triplet-gcc)
set(CMAKE_CXX_COMPILER $triplet-g++)
set(CMAKE_LIBRARY_ARCHITECTURE $triplet)
set(CMAKE_FIND_ROOT_PATH /usr/$triplet /usr/lib/$triplet)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L $qemu_prefix)
EOF
if cmp -s "$toolchain.new" "$toolchain"; then rm "$toolchain.new"; else mv "$toolchain.new" "$toolchain"; fi

generator=()
[ -f "$build/CMakeCache.txt" ] || generator=(-G Ninja)
step configure cmake -S "$root/tests/arm64" -B "$build" "${generator[@]}" -DCMAKE_TOOLCHAIN_FILE="$toolchain" \
  -DCMAKE_BUILD_TYPE="${ORGANSIM_BUILD_TYPE:-Release}" -DORGANSIM_WERROR="${ORGANSIM_WERROR:-ON}"
step build cmake --build "$build" -j "${ORGANSIM_JOBS:-2}"
echo "cross_arm64: built $build/organsim_arm64_tests (${step_seconds}s)"

# --- run under qemu ---------------------------------------------------------
filter=${ORGANSIM_ARM64_FILTER:-*}
export QEMU_LD_PREFIX=$qemu_prefix OMP_WAIT_POLICY=PASSIVE
start=$SECONDS
status=0
timeout "${ORGANSIM_ARM64_TIMEOUT:-3600}" qemu-aarch64 -L "$qemu_prefix" "$build/organsim_arm64_tests" --gtest_filter="$filter" >"$build/test.log" 2>&1 || status=$?
seconds=$((SECONDS - start))
# gtest's closing summary: from "[==========] N tests from M test suites ran." on.
summary=$(sed -n '/^\[==========\] [0-9]* tests\{0,1\} from .* ran/,$p' "$build/test.log" | grep -E '^\[|FAILED TESTS?$' || true)
if [ "$status" -ne 0 ]; then
  why="exit $status"
  [ "$status" -ne 124 ] || why="timed out"
  echo "cross_arm64: tests failed under qemu-aarch64 ($why, ${seconds}s; $build/test.log):"
  if [ -n "$summary" ]; then echo "$summary"; else tail -n 40 "$build/test.log"; fi
  exit 1
fi
if ! grep -qE '^\[  PASSED  \] [1-9]' "$build/test.log"; then
  echo "cross_arm64: no test matched filter '$filter' ($build/test.log)"
  exit 1
fi
echo "cross_arm64: qemu-aarch64, filter '$filter', ${seconds}s:"
echo "$summary"
