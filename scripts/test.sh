#!/usr/bin/env bash
# README command 2: set up, build, run every test, then a seeded pass of
# every fuzz harness (scripts/fuzz.sh --runs: its seeds, then a fixed number
# of inputs made from them with a fixed libFuzzer seed; docs/robustness.md).
# The fuzz pass runs after ctest, so a finding cannot hide the test results,
# and the script fails if either failed; its last line says which.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/setup.sh" --tests
bash "$root/scripts/build.sh"
ctest_result=passed
(cd "${ORGANSIM_BUILD_DIR:-$root/build}" && ctest --output-on-failure -j "${ORGANSIM_TEST_JOBS:-2}" --timeout 900) ||
  ctest_result=FAILED
# ORGANSIM_FUZZ_RUNS inputs per harness (default 1000); 0 skips the pass.
fuzz_result=skipped
if [ "${ORGANSIM_FUZZ_RUNS:-1000}" != 0 ]; then
  fuzz_result=passed
  bash "$root/scripts/fuzz.sh" --runs "${ORGANSIM_FUZZ_RUNS:-1000}" || fuzz_result=FAILED
fi
echo "test.sh: ctest $ctest_result, fuzz pass $fuzz_result"
[ "$ctest_result" = passed ] && [ "$fuzz_result" != FAILED ]
