"""Item 3: peak memory of reach_share's sample-point path, per sample (a subprocess per size).

    OMP_NUM_THREADS=1 nice -n 10 .venv/bin/python results/audit/terrainleft/reach_mem.py \
        .venv/bin/python
"""

import json
import subprocess
import sys
from pathlib import Path

CODE = r"""
import resource, sys, shapely
from poc_env.theory.regions import reach_share
from poc_env.theory.probability_map import Grid
n, s = int(sys.argv[1]), int(sys.argv[2])
g = Grid(n, n, 1000.0)
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
zone = shapely.box(0, 0, n * 1000.0, n * 1000.0)
reach_share(zone, g, 500.0, samples_per_cell=s)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(base, peak)
"""

rows = []
for n, s in [(50, 8), (100, 8), (200, 8), (200, 12)]:
    out = subprocess.run(
        [sys.argv[1], "-c", CODE, str(n), str(s)], capture_output=True, text=True, check=False
    )
    if out.returncode:
        print(out.stderr[-800:])
        break
    base, peak = map(int, out.stdout.split())
    samples = (n * s) ** 2
    rows.append({
        "cells": n * n, "s": s, "samples": samples, "extra_kib": peak - base,
        "bytes_per_sample": (peak - base) * 1024 / samples,
    })  # fmt: skip
    print(rows[-1], flush=True)
Path(__file__).with_suffix(".json").write_text(json.dumps(rows, indent=1) + "\n")
