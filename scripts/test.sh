#!/usr/bin/env bash
# README command 2: set up, build and run every test (ctest prints the summary).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
cd "${ORGANSIM_BUILD_DIR:-$root/build}"
ctest --output-on-failure -j "${ORGANSIM_TEST_JOBS:-2}" --timeout 900
