#!/usr/bin/env python3
"""check_force_log.py FORCES_JSON VERSION: the force log of a completed
scenarios/default.json run by organsim VERSION: valid JSON, meta.completed,
as many force samples as times (1000 ticks of 1 ms), every force finite, and
the 2 cm sphere's push reaching over 1 N (2.3 N at 1 s)."""
import json
import math
import sys

path, version = sys.argv[1], sys.argv[2]
with open(path) as f:
    log = json.load(f)
meta, samples = log["meta"], log["samples"]
errors = []
if meta.get("completed") is not True:
    errors.append(f"meta.completed is {meta.get('completed')!r}")
if meta.get("organsim_version") != version:
    errors.append(f"meta.organsim_version is {meta.get('organsim_version')!r}, not {version!r}")
t, force = samples["t"], samples["force"]
if len(t) != 1000 or len(force) != len(t):
    errors.append(f"{len(t)} times and {len(force)} forces, not 1000 of each")
if not all(len(f) == 3 and all(math.isfinite(c) for c in f) for f in force):
    errors.append("a force sample is not three finite numbers")
peak = max((math.sqrt(sum(c * c for c in f)) for f in force), default=0.0)
if not peak > 1.0:
    errors.append(f"peak tool force {peak} N, expected over 1 N")
if errors:
    print(f"{path}: " + "; ".join(errors))
    sys.exit(1)
print(f"{path}: {len(t)} samples, peak tool force {peak:.3f} N")
