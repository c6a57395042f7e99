#!/usr/bin/env bash
# Configures and builds organsim into ${ORGANSIM_BUILD_DIR:-build} (Release,
# Ninja, ccache when present). Extra arguments go to cmake's configure step.
# ORGANSIM_BUILD_TARGETS (names separated by spaces, e.g. "organsim") builds
# only those targets and what they need; default: everything, tests included.
# ORGANSIM_BUILD_TESTS=OFF configures without the tests (no GoogleTest
# needed: scripts/demo.sh). ORGANSIM_BUILD_STEPS="configure" or "build"
# runs one of the two steps (default both); ORGANSIM_CONFIGURE_LOG names a
# file for the configure step's output (default: none kept).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ORGANSIM_BUILD_DIR:-$root/build}
steps=${ORGANSIM_BUILD_STEPS:-configure build}
export CCACHE_BASEDIR=$root
# Warnings are errors by default (Debian 12's gcc 12 builds clean), so the
# demo and the test command share one configuration and one build.
if [[ " $steps " == *" configure "* ]]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=${ORGANSIM_BUILD_TYPE:-Release} \
    -DORGANSIM_WERROR=${ORGANSIM_WERROR:-ON} -DORGANSIM_BUILD_TESTS=${ORGANSIM_BUILD_TESTS:-ON} "$@" \
    >"${ORGANSIM_CONFIGURE_LOG:-/dev/null}"
fi
if [[ " $steps " == *" build "* ]]; then
  # CGAL's Mesh_3 translation unit needs ~4 GB: two jobs fit in 24 GB.
  targets=()
  for target in ${ORGANSIM_BUILD_TARGETS:-}; do targets+=(--target "$target"); done
  cmake --build "$build" -j "${ORGANSIM_JOBS:-2}" "${targets[@]}"
fi
