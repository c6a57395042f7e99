#!/usr/bin/env bash
# package_lists_test.sh SOURCE_DIR
# scripts/demo.sh's set-up installs no test-only package: the two package
# lists (scripts/packages/demo.txt, tests.txt) share none, the packages only
# tests use are in tests.txt and not in demo.txt, `setup.sh` installs
# demo.txt alone and `setup.sh --tests` both, demo.sh asks for the first and
# test.sh for the second.
set -euo pipefail
src=$1
fail() { echo "FAIL: $*"; exit 1; }
read_list() { grep -v '^[[:space:]]*#' "$1" | awk 'NF {print $1}' | sort; }
demo=$(read_list "$src/scripts/packages/demo.txt")
tests=$(read_list "$src/scripts/packages/tests.txt")
[ -n "$demo" ] && [ -n "$tests" ] || fail "an empty package list"

both=$(comm -12 <(echo "$demo") <(echo "$tests"))
[ -z "$both" ] || fail "in both lists: $both"
# What only the tests use: GoogleTest, the CC0 meshes, VTK's Python,
# Slurm and munge, the OpenIGTLink examples, clang and its fuzzing runtime.
for p in libgtest-dev libcgal-demo python3-vtk9 slurm-wlm munge openigtlink-examples \
         clang-14 libclang-rt-14-dev libomp-14-dev; do
  grep -qxF "$p" <<<"$demo" && fail "demo.txt holds the test-only package $p"
  grep -qxF "$p" <<<"$tests" || fail "tests.txt lacks the test-only package $p"
done
# What the main job needs stays in the demo's list.
for p in build-essential cmake ninja-build libcgal-dev libeigen3-dev libcli11-dev nlohmann-json3-dev libhwy-dev \
         libegl-mesa0 libgl1-mesa-dri libopencv-videoio-dev libopenigtlink-dev; do
  grep -qxF "$p" <<<"$demo" || fail "demo.txt lacks $p"
done

[ "$(bash "$src/scripts/setup.sh" --list | sort)" = "$demo" ] || fail "setup.sh installs other than demo.txt"
[ "$(bash "$src/scripts/setup.sh" --tests --list | sort)" = "$(sort <(echo "$demo") <(echo "$tests"))" ] ||
  fail "setup.sh --tests installs other than demo.txt and tests.txt"
grep -qE '^[^#]*scripts/setup\.sh"?( |$)' "$src/scripts/demo.sh" || fail "demo.sh does not run setup.sh"
grep -E '^[^#]*scripts/setup\.sh' "$src/scripts/demo.sh" | grep -q -- --tests && fail "demo.sh runs setup.sh --tests"
grep -qE '^[^#]*scripts/setup\.sh"? --tests' "$src/scripts/test.sh" || fail "test.sh does not run setup.sh --tests"
echo "ok: demo.txt $(wc -l <<<"$demo") packages, tests.txt $(wc -l <<<"$tests"), none in both"
