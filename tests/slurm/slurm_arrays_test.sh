#!/usr/bin/env bash
# A real one-node Slurm cluster on localhost (munged, slurmctld and slurmd
# from Debian's munge and slurm-wlm, a generated slurm.conf in a temporary
# folder), started and stopped here: a 6-case sweep is submitted as an array
# of 3 tasks (2 cases each), waited for and collected, and its table and
# force logs must equal the same sweep run locally; then a 6-configuration
# study as docs/cluster.md submits it (its reference as one job, an array of
# 3 shards that waits for it), collected, must give the local study's table.
# Usage: slurm_arrays_test.sh ORGANSIM_EXE WORKDIR
# Exit 77 (ctest: skipped) only when the Slurm or munge programs are missing.
#
# Nothing this test starts outlives it, however it ends: every process it
# starts carries ORGANSIM_SLURM_TEST=<its temporary folder> in its
# environment or runs in that folder (the script works there, so the daemons
# and the jobs start there; slurmstepd, which slurmd detaches, overwrites the
# start of its environment with its title but keeps the jobs' folder), and
# stop_cluster ends exactly those. It runs on exit, on SIGINT/SIGTERM, and,
# when the script is killed outright (SIGKILL: ctest's timeout kills the
# test's process tree), from a watchdog started in its own session outside
# that tree, which waits for the script's process to end. The daemons run in
# the foreground (not forked off), so they stay in the tree too.
set -euo pipefail

# Ends every process marked with this run's folder (not the caller), SIGTERM
# first, SIGKILL after 5 s (slurmstepd ignores SIGTERM), then removes the
# folder. Pure bash while scanning, so the scan starts no process of its own.
marked_processes() {
  local environ pid entry
  for environ in /proc/[0-9]*/environ; do
    pid=${environ#/proc/}
    pid=${pid%/environ}
    if [ "$pid" = "$BASHPID" ] || [ "$pid" = "$$" ]; then continue; fi
    if [ "/proc/$pid/cwd" -ef "$run" ]; then echo "$pid"; continue; fi
    while IFS= read -r -d '' entry; do
      if [ "$entry" = "ORGANSIM_SLURM_TEST=$run" ]; then echo "$pid"; break; fi
    done 2>/dev/null <"$environ" || true
  done
}
stop_cluster() {
  local pids
  pids=$(marked_processes)
  if [ -n "$pids" ]; then kill $pids 2>/dev/null || true; fi
  for _ in $(seq 50); do
    pids=$(marked_processes)
    if [ -z "$pids" ]; then break; fi
    sleep 0.1
  done
  if [ -n "$pids" ]; then kill -KILL $pids 2>/dev/null || true; fi
  rm -rf "$run"
}

if [ "${1:-}" = --watchdog ]; then  # --watchdog SCRIPT_PID RUN_FOLDER
  run=$3
  while kill -0 "$2" 2>/dev/null; do sleep 1; done
  stop_cluster
  exit 0
fi

organsim=$(realpath "$1")
work=$(realpath -m "$2")  # absolute: the script works in its temporary folder
source_dir=$(cd "$(dirname "$0")/../.." && pwd)

for program in munged mungekey slurmctld slurmd sbatch squeue sinfo; do
  if ! command -v "$program" >/dev/null; then
    echo "SKIPPED: $program not found; install Debian's slurm-wlm and munge (bash scripts/setup.sh --tests does)"
    exit 77
  fi
done

rm -rf "$work"
mkdir -p "$work"
# Sockets need a short path (108 bytes); the daemons' files live in /tmp.
run=$(mktemp -d /tmp/organsim-slurm.XXXXXX)
chmod 755 "$run"  # munged refuses a socket folder others cannot traverse
mkdir -p "$run/munge" "$run/state" "$run/spool" "$run/log"
# The watchdog has no mark: it starts before the mark is exported.
setsid -f bash "$0" --watchdog $$ "$run" </dev/null >/dev/null 2>&1
export ORGANSIM_SLURM_TEST=$run
cd "$run"
trap stop_cluster EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
fail() {
  echo "FAILED: $*"
  for f in "$run"/log/*.log "$run"/munge/log; do [ -f "$f" ] && { echo "--- $f"; tail -n 20 "$f"; }; done
  exit 1
}

# munge: the credential daemon every Slurm message is signed with.
mungekey --create --keyfile="$run/munge/munge.key"
chmod 600 "$run/munge/munge.key"
munged --foreground --key-file="$run/munge/munge.key" --socket="$run/munge/sock" --pid-file="$run/munge/pid" \
  --log-file="$run/munge/log" --seed-file="$run/munge/seed" &
for _ in $(seq 100); do [ -S "$run/munge/sock" ] && break; sleep 0.1; done
[ -S "$run/munge/sock" ] || fail "munged did not start"

free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
host=$(hostname -s)
user=$(id -un)
cat >"$run/slurm.conf" <<CONF
ClusterName=organsimtest
SlurmctldHost=$host
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$run/munge/sock
CredType=cred/munge
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
StateSaveLocation=$run/state
SlurmdSpoolDir=$run/spool
SlurmctldPidFile=$run/slurmctld.pid
SlurmdPidFile=$run/slurmd.pid
SlurmctldLogFile=$run/log/slurmctld.log
SlurmdLogFile=$run/log/slurmd.log
# No cgroups: processes are tracked through /proc, tasks are not bound.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$run/slurm.conf
slurmctld -D &
slurmd -D &
for _ in $(seq 300); do
  [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && break
  sleep 0.1
done
[ "$(sinfo -h -o %T)" = idle ] || fail "the node did not come up (sinfo: $(sinfo -h -o %T))"

# The sweep: 3 stiffnesses x 2 push depths on the 125-point box, 50 ticks each.
cat >"$work/sweep.json" <<JSON
{"scenario": "$source_dir/scenarios/stress/gentle_push.json",
 "set": {"time.duration": 0.05, "tool.keyframes[1].t": 0.05},
 "grid": {"material.young_modulus": [4000, 6000, 8000], "tool.keyframes[1].position[2]": [0.046, 0.044]}}
JSON
"$organsim" sweep "$work/sweep.json" -o "$work/slurm" --slurm --cases-per-task 2 --time 00:05:00 --submit \
  | tee "$work/submit.txt"
grep -q -- '--array=0-2$' "$work/slurm/sweep.sbatch" || fail "expected an array of 3 tasks in sweep.sbatch"
job=$(sed -n 's/^job: *//p' "$work/submit.txt")
[ -n "$job" ] || fail "no job id printed"
for _ in $(seq 1200); do
  [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break
  sleep 0.25
done
[ -z "$(squeue -h -j "$job")" ] || fail "job $job still queued or running after 300 s: $(squeue -j "$job")"
logs=$(ls "$work/slurm/slurm/" | wc -l)
[ "$logs" = 3 ] || fail "expected 3 array task logs in $work/slurm/slurm, found $logs"
for f in "$work"/slurm/slurm/*.out; do echo "--- $f"; cat "$f"; done
# Each task ran its own slice: 2 of the 6 cases, shards 0/3, 1/3 and 2/3.
for i in 0 1 2; do
  grep -q "shard $i/3: 2 cases; 0 done, 0 failed (skipped), 2 to run" "$work"/slurm/slurm/*_$i.out \
    || fail "array task $i did not run shard $i/3 with 2 cases"
done

"$organsim" sweep --collect "$work/slurm" || fail "collect: some cases are not done"
"$organsim" sweep "$work/sweep.json" -o "$work/local" >"$work/local.txt" || fail "the local sweep failed: $(cat "$work/local.txt")"

# Same table (timing aside) and byte-identical force samples.
python3 - "$work/slurm" "$work/local" <<'PY' || fail "the Slurm sweep differs from the local one"
import json, sys, pathlib
a, b = (pathlib.Path(p) for p in sys.argv[1:3])
def rows(d):
    r = json.loads((d / "results.json").read_text())
    for row in r:
        row.pop("timing")
    return r
ra, rb = rows(a), rows(b)
assert len(ra) == 6, len(ra)
assert all(row["status"] == "done" for row in ra), ra
assert ra == rb, (ra, rb)
def samples(p):
    t = p.read_text()
    return t[t.index('\n "samples": {'):]
for row in ra:
    name = row["name"]
    assert samples(a / "cases" / name / "forces.json") == samples(b / "cases" / name / "forces.json"), name
print("slurm sweep equals the local sweep:", len(ra), "cases")
PY

# The study, as docs/cluster.md "Studies" submits it.
wait_for() {  # JOB: until it has left the queue (300 s at most)
  for _ in $(seq 1200); do
    [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0
    sleep 0.25
  done
  fail "job $1 still queued or running after 300 s: $(squeue -j "$1")"
}
args="$source_dir/scenarios/stress/gentle_push.json --dt 0.0005,0.00025,0.000125 --precision double,float --duration 0.05 --threads 1"
ref=$(sbatch --parsable --output="$work/study_ref.out" --wrap "'$organsim' study $args -o '$work/study' --reference-only")
arr=$(sbatch --parsable --dependency=afterok:"$ref" --array=0-2 --output="$work/study_%a.out" \
      --wrap "'$organsim' study $args -o '$work/study' --shard slurm")
wait_for "$ref"
wait_for "$arr"
for f in "$work"/study_*.out; do echo "--- $f"; cat "$f"; done
for i in 0 1 2; do
  grep -q "study shard $i/3: 2 of 6 configurations" "$work/study_$i.out" || fail "array task $i did not run study shard $i/3"
done
"$organsim" study --collect "$work/study" >"$work/collect.txt" || fail "study --collect: $(cat "$work/collect.txt")"
"$organsim" study $args -o "$work/study_local" >"$work/study_local.txt" || fail "the local study failed"
python3 - "$work/study/study.json" "$work/study_local/study.json" <<'PY' || fail "the Slurm study differs from the local one"
import json, sys
def table(path):
    j = json.load(open(path))
    for run in j["runs"]:
        for timing in ("wall_seconds_per_simulated_second", "steps_per_second", "pareto"):
            run.pop(timing, None)
    return j
a, b = table(sys.argv[1]), table(sys.argv[2])
assert len(a["runs"]) == 6, len(a["runs"])
assert a == b, (a, b)
print("slurm study equals the local study:", len(a["runs"]), "configurations")
PY
echo "PASSED"
