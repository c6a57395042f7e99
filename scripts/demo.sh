#!/usr/bin/env bash
# README command 1: set up, build, then mesh and run the default scenario.
# demo.sh [OUTDIR]   (default out/default)
# Prints a line per stage; the full apt, configure and compiler output go to
# out/logs/{apt,configure,build}.log, and a failing stage prints its log's tail.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/out/default}
build=${ORGANSIM_BUILD_DIR:-$root/build}
logs=$root/out/logs
mkdir -p "$logs"
start=$SECONDS
rel() { local p=$1; echo "${p#"$PWD"/}"; }
took() { local s=$((SECONDS - $1)); if [ $s -ge 60 ]; then echo "$((s / 60)) min $((s % 60)) s"; else echo "$s s"; fi; }
stage() { printf 'demo: %-10s ' "$1"; }
failed() {
  echo "FAILED; the last lines of $(rel "$1"):"
  tail -n 40 "$1" | sed 's/^/  | /'
  echo "demo: the whole log is $(rel "$1")"
  exit 1
}

# Only the packages the executable needs (scripts/packages/demo.txt); the
# tests' own are scripts/test.sh's.
stage packages; t=$SECONDS
bash "$root/scripts/setup.sh" >"$logs/apt.log" 2>&1 </dev/null || failed "$logs/apt.log"
echo "ok ($(tail -n 1 "$logs/apt.log" | sed -E 's/^setup: //; s/^(installing .{40}).*/\1.../'); $(took $t))"

# No tests in this configuration: no GoogleTest needed; test.sh adds them
# in the same build folder without rebuilding the executable.
stage configure; t=$SECONDS
ORGANSIM_BUILD_STEPS=configure ORGANSIM_BUILD_TESTS=${ORGANSIM_BUILD_TESTS:-OFF} \
  ORGANSIM_CONFIGURE_LOG="$logs/configure.log" bash "$root/scripts/build.sh" 2>>"$logs/configure.log" ||
  failed "$logs/configure.log"
echo "ok ($(took $t))"

# Only the executable (and the libraries it links), not the test binaries.
# ninja's "[done/total]" count is shown as it goes.
stage build; t=$SECONDS
tty=0; [ -t 1 ] && tty=1
if ! ORGANSIM_BUILD_STEPS=build ORGANSIM_BUILD_TARGETS=organsim bash "$root/scripts/build.sh" 2>&1 |
    tee "$logs/build.log" |
    awk -v tty=$tty -v prefix="$(stage build)" '
      match($0, /^\[[0-9]+\/[0-9]+\]/) {
        count = substr($0, RSTART, RLENGTH); split(substr(count, 2, RLENGTH - 2), n, "/")
        if (tty) { printf "\r%s%s ", prefix, count; fflush() }
        else if (int(4 * n[1] / n[2]) > quarter) { quarter = int(4 * n[1] / n[2]); printf "%s ", count; fflush() }
      }'; then
  echo; failed "$logs/build.log"
fi
echo "ok ($(took $t))"

stage run; echo "organsim run scenarios/default.json -o $(rel "$out")"
"$build/app/organsim" run "$root/scenarios/default.json" -o "$out"
echo "demo: done in $(took $start): the force log is $(rel "$out")/forces.json, the frames, video and contact sheet beside it; logs in $(rel "$logs")/"
