#!/usr/bin/env bash
# Measures `organsim serve` as a haptic loop at liver size: the server steps
# scenarios/liver7750_realtime.json (7.7k points, validated material, the
# guaranteed step) while tests/live/client/live_client.cpp streams TRANSFORM
# poses at 1 kHz on localhost, pressing the tool into the liver over the first
# half and holding it there. Prints ticks served, late ticks, reply latency
# (receipt of a pose to the force reply of its tick: median, p99, max) and
# the real-time factor from the force log's meta, with the CPU and the load.
# A benchmark, not a test: its figures depend on the machine and its load
# (docs/live.md lists what it measured).
# Usage: scripts/live_bench.sh [SECONDS (default 60)] [extra organsim serve options...]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ORGANSIM_BUILD_DIR:-$root/build}
seconds=${1:-60}
shift || true
organsim=$build/app/organsim
client=$build/tests/organsim_live_client
for exe in "$organsim" "$client"; do
  [ -x "$exe" ] || { echo "live_bench: $exe is missing (ORGANSIM_BUILD_TARGETS=\"organsim organsim_live_client\" bash scripts/build.sh)"; exit 1; }
done
out=${ORGANSIM_LIVE_BENCH_OUT:-$root/out/live_bench}
rm -rf "$out"
mkdir -p "$out"

"$organsim" serve "$root/scenarios/liver7750_realtime.json" --port 0 --duration "$seconds" -o "$out/session" "$@" \
  >"$out/serve.out" 2>"$out/serve.err" &
serve_pid=$!
trap 'kill "$serve_pid" 2>/dev/null || true' EXIT
# shellcheck source=scripts/serve_port.sh
. "$root/scripts/serve_port.sh"
port=$(serve_port "$out/serve.out" "$serve_pid" 1800)  # meshing the liver comes first
[ -n "$port" ] || { echo "live_bench: organsim serve printed no port"; cat "$out/serve.err"; exit 1; }
# The scenario's own press, in mm: from 88 mm down to 53 mm above the origin at x = 30 mm.
"$client" "$port" 1000 "$((seconds + 2))" 30,0,88 30,0,53 >"$out/client.out" 2>&1 || true
wait "$serve_pid"
trap - EXIT
cat "$out/serve.out"
python3 - "$out/session/forces.json" <<'PY'
import json, os, platform, sys
meta = json.load(open(sys.argv[1]))["meta"]
live = meta["live"]
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
lat = live["latency"]
print(f"cpu:      {cpu}, {os.cpu_count()} hardware threads, load average {os.getloadavg()[0]:.1f} at the end")
print(f"model:    {meta['points']} points on {meta['backend']} ({meta['precision']}), dt {meta['dt']} s x {meta['substeps']}")
print(f"served:   {live['ticks']} ticks, {live['late_ticks']} late, real-time factor {live['real_time_factor']:.3f}")
print(f"latency:  median {lat['median_ms']:.3f} ms, p99 {lat['p99_ms']:.3f} ms, max {lat['max_ms']:.3f} ms over {lat['count']} poses")
peak = max((sum(c * c for c in f) ** 0.5 for f in json.load(open(sys.argv[1]))["samples"]["force"]), default=0)
print(f"contact:  peak tool force {peak:.3g} N; replies sent {live['link']['replies_sent']}, dropped {live['link']['replies_dropped']}")
PY
