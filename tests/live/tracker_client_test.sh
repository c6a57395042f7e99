#!/usr/bin/env bash
# An independent client against `organsim serve`: upstream OpenIGTLink's
# example TrackerClient (streams TRANSFORM "Tracker" on a 50 mm circle at a
# given rate and never reads), built here from Debian's openigtlink-examples
# (never copied into the repository). The server must accept its stream,
# answer every tick (sent or, as it never reads, dropped), refuse the poses
# outside the scene, and the recorded session must replay bit for bit.
# Usage: tracker_client_test.sh ORGANSIM_EXE WORKDIR. Exit 77 (skip) only
# where the examples package is not installed.
set -euo pipefail
organsim=$1
work=$2
examples=/usr/share/doc/openigtlink-examples/examples/Tracker
root=$(cd "$(dirname "$0")/../.." && pwd)
if [ ! -f "$examples/TrackerClient.cxx" ]; then
  echo "openigtlink-examples is not installed (scripts/setup.sh --tests installs it)"
  exit 77
fi
rm -rf "$work"
mkdir -p "$work"
# Configure quietly, build only TrackerClient (one file).
cmake -S "$examples" -B "$work/tracker" -DCMAKE_BUILD_TYPE=Release -Wno-dev >"$work/cmake.log" 2>&1 ||
  { cat "$work/cmake.log"; exit 1; }
cmake --build "$work/tracker" --target TrackerClient >>"$work/cmake.log" 2>&1 || { cat "$work/cmake.log"; exit 1; }

# TrackerClient's circle lies in its x = z plane; this rotation lays it flat
# 75 mm above the scene's origin, so it passes over the 4 cm box (no contact)
# and leaves the scene's box on one side (those poses are refused).
cat >"$work/client_to_scene.json" <<'JSON'
{"matrix": [[0.70710678118654752, 0, 0.70710678118654752, 20],
            [0, 1, 0, 20],
            [-0.70710678118654752, 0, 0.70710678118654752, 75],
            [0, 0, 0, 1]]}
JSON

"$organsim" serve "$root/scenarios/stress/gentle_push.json" --port 0 --duration 1 \
  --client-transform "$work/client_to_scene.json" -o "$work/out" >"$work/serve.out" 2>"$work/serve.err" &
serve_pid=$!
tracker_pid=
cleanup() {
  [ -n "$tracker_pid" ] && kill "$tracker_pid" 2>/dev/null || true
  kill "$serve_pid" 2>/dev/null || true
}
trap cleanup EXIT
# shellcheck source=scripts/serve_port.sh
. "$root/scripts/serve_port.sh"
port=$(serve_port "$work/serve.out" "$serve_pid" 600)
[ -n "$port" ] || { echo "organsim serve printed no port"; cat "$work/serve.err"; exit 1; }
"$work/tracker/TrackerClient" 127.0.0.1 "$port" 200 >"$work/tracker.out" 2>&1 &
tracker_pid=$!
status=0
wait "$serve_pid" || status=$?
kill "$tracker_pid" 2>/dev/null || true
tracker_pid=
[ "$status" -eq 0 ] || { echo "organsim serve exited $status"; cat "$work/serve.err"; exit 1; }

"$organsim" run "$work/out/session.json" -o "$work/replay" >"$work/replay.out" 2>&1 ||
  { cat "$work/replay.out"; exit 1; }
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
served = json.load(open(f"{work}/out/forces.json"))
replay = json.load(open(f"{work}/replay/forces.json"))
live = served["meta"]["live"]
link = live["link"]
problems = []
if live["ticks"] != 1000: problems.append(f"ticks {live['ticks']}, expected 1000")
if live["device"] != "Tracker": problems.append(f"followed device {live['device']!r}, expected 'Tracker'")
if live["poses_applied"] < 20: problems.append(f"only {live['poses_applied']} poses applied")
if link["replies_sent"] + link["replies_dropped"] != live["ticks"]:
    problems.append(f"replies sent {link['replies_sent']} + dropped {link['replies_dropped']} != ticks")
if live["poses_refused"].get("outside_scene", 0) < 1: problems.append("no pose refused as outside the scene")
if served["samples"] != replay["samples"]: problems.append("the replay's samples differ from the session's")
if problems:
    print("\n".join(problems)); sys.exit(1)
print(f"TrackerClient: {live['poses_received']} poses, {live['poses_applied']} applied, "
      f"{live['poses_refused']} refused, {link['replies_sent']} replies sent, {link['replies_dropped']} dropped; replay identical")
PY
