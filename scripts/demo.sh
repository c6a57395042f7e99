#!/usr/bin/env bash
# README command 1: set up, build, then mesh and run the default scenario.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/setup.sh"
# Only the executable (and the libraries it links), not the test binaries.
ORGANSIM_BUILD_TARGETS=organsim bash "$root/scripts/build.sh"
out=${1:-$root/out/default}
"${ORGANSIM_BUILD_DIR:-$root/build}/app/organsim" run "$root/scenarios/default.json" -o "$out"
