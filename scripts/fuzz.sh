#!/usr/bin/env bash
# Builds the libFuzzer harnesses of tests/fuzz/harnesses.txt with clang-14
# (ASan + UBSan) into ${ORGANSIM_FUZZ_BUILD_DIR:-build-fuzz} and runs each one.
#   scripts/fuzz.sh [--seconds S | --runs N] [--seed K] [NAME...]
# --seconds S: a campaign, each harness for S seconds (default 10), its
# corpus growing in BUILD/corpus/NAME between campaigns. --runs N: a
# seeded pass (what scripts/test.sh runs): each harness replays its seeds,
# then makes inputs from them with libFuzzer's seed K (default 1) in a
# fresh corpus, N executions in all (nearly, not bit for bit, the same
# inputs every time: docs/robustness.md).
# The seeds: the hand-made files (tests/fuzz/corpus/NAME), the inputs of
# past findings (tests/fuzz/regressions/NAME), the row's globs, and each of
# those cut short at k * size / 11 (k = 1..10) and by its last byte, as the
# truncation test cuts them. NAMEs pick rows of the table (default: all).
# ORGANSIM_FUZZ_JOBS harnesses run at once (default 2). A crash, hang or
# sanitizer report leaves its input in BUILD/artifacts/NAME/ and makes the
# script fail. Prints one line per harness: executions, coverage (edges),
# corpus size, result.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ORGANSIM_FUZZ_BUILD_DIR:-$root/build-fuzz}
limit=(-max_total_time=10)
reproducible=0
seed=  # libFuzzer's -seed: 1 for --runs, random (0) for a campaign, unless given
names=()
while [ $# -gt 0 ]; do
  case $1 in
    --seconds) limit=(-max_total_time="$2"); reproducible=0; shift 2 ;;
    --runs) limit=(-runs="$2"); reproducible=1; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) names+=("$1"); shift ;;
  esac
done

export CCACHE_BASEDIR=$root
# The fuzz build carries debug info (line tables), which makes ccache hash
# the build folder too: every fresh clone (CI's) would rebuild it all. Its objects may
# name another clone's folder in their debug info; sanitizer reports still
# name the right files and lines.
export CCACHE_NOHASHDIR=1
# -O1 with line tables only (OSS-Fuzz's flags): sanitizer reports keep their
# file and line, and core's largest units compile in about two thirds of
# their time at -O2 -g.
CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
  -DORGANSIM_FUZZ=ON -DORGANSIM_BUILD_TESTS=OFF -DORGANSIM_WERROR=OFF >/dev/null
cmake --build "$build" --target organsim_fuzz -j "${ORGANSIM_JOBS:-2}"

seed=${seed:-$reproducible}
# A seeded pass also runs without address-space randomisation:
# libFuzzer learns from compared values, and pointers are among them.
fixed_layout=(env)
if [ "$reproducible" = 1 ] && setarch "$(uname -m)" -R true 2>/dev/null; then fixed_layout=(setarch "$(uname -m)" -R); fi

# Leaks are bugs too; a hang is an input taking over 10 s; 2 GB of memory
# is far more than any input of at most 64 KiB should need.
options=(-timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1)
# Leaks inside Debian's image libraries on their error paths, named one by one.
export LSAN_OPTIONS="suppressions=$root/tests/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"

# Writes the cuts of every file in folder $1 beside it: cut_K_FILE holds
# the first K * size / 11 bytes (K = 1..10), cut_last_FILE all but the last.
add_cuts() {
  local file size k
  for file in "$1"/*; do
    [ -f "$file" ] || continue
    size=$(stat -c %s "$file")
    [ "$size" -ge 2 ] || continue
    for k in 1 2 3 4 5 6 7 8 9 10; do
      head -c $((k * size / 11)) "$file" >"$1/cut_${k}_$(basename "$file")"
    done
    head -c $((size - 1)) "$file" >"$1/cut_last_$(basename "$file")"
  done
}

# Runs harness $1, its log in BUILD/logs/NAME.log and its result line in
# BUILD/logs/NAME.result, from the seeds of the row (globs $2).
fuzz_one() {
  local name=$1 seeds=$2
  local corpus=$build/corpus/$name artifacts=$build/artifacts/$name seed_dir=$build/seeds/$name
  rm -rf "$seed_dir"
  mkdir -p "$artifacts" "$seed_dir" "$build/logs"
  cp "$root"/tests/fuzz/corpus/"$name"/* "$root"/tests/fuzz/regressions/"$name"/* "$seed_dir"/ 2>/dev/null || true
  for pattern in $seeds; do
    # shellcheck disable=SC2086  # the pattern is a glob on purpose
    cp $root/$pattern "$seed_dir"/
  done
  add_cuts "$seed_dir"
  if [ "$reproducible" = 1 ]; then
    corpus=$build/corpus_reproducible/$name
    rm -rf "$corpus"
  fi
  mkdir -p "$corpus"
  local log=$build/logs/$name.log result=ok
  if ! ORGANSIM_FUZZ_IMAGE_DIR=$build/image_files/$name "${fixed_layout[@]}" "$build/tests/fuzz/organsim_fuzz_$name" "${limit[@]}" -seed="$seed" "${options[@]}" -artifact_prefix="$artifacts/" \
      "$corpus" "$seed_dir" >"$log" 2>&1; then
    result="FAILED: $(ls -t "$artifacts" | head -1 | sed "s|^|$artifacts/|"), log $log"
  fi
  local executions coverage
  executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1) || true
  coverage=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2) || true
  printf '%-15s %12s %8s %8s  %s\n' "$name" "${executions:-?}" "${coverage:-?}" "$(ls "$corpus" | wc -l)" "$result" \
    >"$build/logs/$name.result"
}

# The harnesses run ORGANSIM_FUZZ_JOBS at a time (default 2, one per core of
# a 2-core machine); the table prints in harnesses.txt order at the end.
jobs_max=${ORGANSIM_FUZZ_JOBS:-2}
picked=()
while read -r name kind ext seeds; do
  case $name in ''|'#'*) continue ;; esac
  if [ ${#names[@]} -gt 0 ] && [[ ! " ${names[*]} " == *" $name "* ]]; then continue; fi
  picked+=("$name")
  rm -f "$build/logs/$name.result"
  while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
  fuzz_one "$name" "$seeds" &
done <"$root/tests/fuzz/harnesses.txt"
wait
failed=0
printf '%-15s %12s %8s %8s  %s\n' harness executions coverage corpus result
for name in "${picked[@]}"; do
  if [ -f "$build/logs/$name.result" ]; then
    cat "$build/logs/$name.result"
    grep -q '  ok$' "$build/logs/$name.result" || failed=1
  else
    printf '%-15s  FAILED: the harness run did not finish, log %s\n' "$name" "$build/logs/$name.log"
    failed=1
  fi
done
exit $failed
