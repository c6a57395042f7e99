#!/usr/bin/env bash
# README command 2: set up, build, run a brief pass of every fuzz harness
# (scripts/fuzz.sh; docs/robustness.md), then every test. ctest runs last so
# its closing summary is the last thing printed.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/setup.sh" --tests
bash "$root/scripts/build.sh"
# ~10 s per harness; ORGANSIM_FUZZ_SECONDS=0 skips the fuzzing.
if [ "${ORGANSIM_FUZZ_SECONDS:-10}" != 0 ]; then
  bash "$root/scripts/fuzz.sh" --seconds "${ORGANSIM_FUZZ_SECONDS:-10}"
fi
cd "${ORGANSIM_BUILD_DIR:-$root/build}"
ctest --output-on-failure -j "${ORGANSIM_TEST_JOBS:-2}" --timeout 900
