#!/usr/bin/env bash
# Measures `organsim serve` as a haptic loop at liver size: the server steps
# scenarios/liver7750_realtime.json (7.7k points, validated material, the
# guaranteed step) while tests/live/client/live_client.cpp streams TRANSFORM
# poses at 1 kHz on localhost, pressing the tool into the liver over the first
# half and holding it there. Prints ticks served, late ticks, reply latency
# (receipt of a pose to the force reply of its tick: median, p99, max) and
# the real-time factor from the force log's meta, with the CPU and the load,
# the CPU time of the reply's stiffness on each tick in contact, how late
# the loop woke from its waits on the clock (the machine's scheduling), and
# the backend's device at the end (the CPU backend's thread count then).
# ORGANSIM_LIVE_BENCH_SCENARIO=FILE serves another scenario of examples/liver.off
# (e.g. the same one meshed finer, for a GPU); the client's path is the same.
# With ORGANSIM_LIVE_BENCH_CUT=S the client's tool points down into the liver
# and it sends the STRING command "CUT 40 30" after S seconds; the cut's figures are
# printed: what was built off the tick's path on a worker thread (the new
# Model, model_ms, its dt check, dt_check_prepare_ms, and the backend's
# tables, backend_prepare_ms), what stayed
# on it (the backend's adoption of those tables and the dt check, ms), and
# how many ticks after the request it went in.
# A benchmark, not a test: its figures depend on the machine and its load
# (docs/live.md lists what it measured).
# Usage: [ORGANSIM_LIVE_BENCH_SCENARIO=FILE] [ORGANSIM_LIVE_BENCH_CUT=S] scripts/live_bench.sh [SECONDS (default 60)] [extra organsim serve options...]
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

scenario=${ORGANSIM_LIVE_BENCH_SCENARIO:-$root/scenarios/liver7750_realtime.json}
"$organsim" serve "$scenario" --port 0 --duration "$seconds" -o "$out/session" "$@" \
  >"$out/serve.out" 2>"$out/serve.err" &
serve_pid=$!
trap 'kill "$serve_pid" 2>/dev/null || true' EXIT
# shellcheck source=scripts/serve_port.sh
. "$root/scripts/serve_port.sh"
port=$(serve_port "$out/serve.out" "$serve_pid" 1800)  # meshing the liver comes first
[ -n "$port" ] || { echo "live_bench: organsim serve printed no port"; cat "$out/serve.err"; exit 1; }
# The scenario's own press, in mm: from 88 mm down to 53 mm above the origin at x = 30 mm.
cut=()
if [ -n "${ORGANSIM_LIVE_BENCH_CUT:-}" ]; then
  # 40 mm deep from the tool centre (the tool's radius is 20 mm), 30 mm wide.
  cut=(--down --cut "$(python3 -c "print(round(1000 * float('$ORGANSIM_LIVE_BENCH_CUT')))")" --cut-text "CUT 40 30")
fi
"$client" "$port" 1000 "$((seconds + 2))" 30,0,88 30,0,53 "${cut[@]}" >"$out/client.out" 2>&1 || true
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
print(f"device:   {meta.get('device_at_end', meta['device'])}")
print(f"served:   {live['ticks']} ticks, {live['late_ticks']} late, real-time factor {live['real_time_factor']:.3f}")
print(f"latency:  median {lat['median_ms']:.3f} ms, p99 {lat['p99_ms']:.3f} ms, max {lat['max_ms']:.3f} ms over {lat['count']} poses")
st = live["reply_stiffness"]
print(f"stiffness: median {st['median_ms']:.3f} ms, p99 {st['p99_ms']:.3f} ms, max {st['max_ms']:.3f} ms of CPU before each of {st['count']} replies in contact")
peak = max((sum(c * c for c in f) ** 0.5 for f in json.load(open(sys.argv[1]))["samples"]["force"]), default=0)
wake = live["wake_up"]
print(f"wake-up:  {wake['count']} waits ran out on the clock; the loop ran median {wake['median_ms']:.3f} ms, "
      f"p99 {wake['p99_ms']:.3f} ms, max {wake['max_ms']:.3f} ms after the deadline; "
      f"{wake['over_0.25_ms']} over 0.25 ms, {wake['over_0.5_ms']} over 0.5 ms, {wake['over_1_ms']} over 1 ms")
slow = ", ".join(f"tick {s['tick']} {s['ms']:.1f} ms" for s in live.get("slowest_ticks", []))
print(f"slowest:  {slow} (wall time from the reply before)")
print(f"contact:  peak tool force {peak:.3g} N; replies sent {live['link']['replies_sent']}, dropped {live['link']['replies_dropped']}")
tick = meta["dt"] * meta["substeps"]
for cut in live.get("cuts", []):
    e = next((e for e in meta.get("events", []) if e["sources"][0].get("name") == cut["name"]), None)
    if e is None:
        print(f"cut:      {cut['name']} at tick {cut['tick']} separated nothing (or was not in by the end)")
        continue
    print(f"cut:      {cut['name']} asked at tick {cut['tick']}, in at tick {cut.get('applied_tick', '-')}: "
          f"{e['faces_separated']} faces, {e['points_added']} points added; off the tick's path {e['model_ms']:.1f} ms "
          f"(the new Model) + {e.get('dt_check_prepare_ms', 0):.1f} ms (dt check, {e['dt_check']}) "
          f"+ {e.get('backend_prepare_ms', 0):.1f} ms (the backend's tables) on the worker, "
          f"on it {e['backend_rebuild_ms']:.2f} ms backend adopt + {e['dt_check_ms']:.2f} ms dt check")
if live.get("commands_refused"):
    print(f"refused:  {live['commands_refused']}")
PY
