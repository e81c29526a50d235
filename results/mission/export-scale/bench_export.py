"""One timed export of a plan (export-scale's paired figure): wall and CPU time, the number of
terrain profiles computed and the time in the profile simplification, as one JSON line.

Usage (one thread, nice; old code by PYTHONPATH to an archive of main):
    OMP_NUM_THREADS=1 nice -n 10 python bench_export.py PLAN.json FORMAT [LABEL]
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
import warnings

from poc_env.agents.mission import terrain
from poc_env.agents.mission.export import export_plan

plan, fmt = sys.argv[1], sys.argv[2]
label = sys.argv[3] if len(sys.argv) > 3 else ""
calls = {"profile": 0, "simplify_s": 0.0}
real_profile, real_simplify = terrain.profile, terrain._simplify


def _profile(*a, **k):
    calls["profile"] += 1
    return real_profile(*a, **k)


def _simplify(*a):
    t = time.perf_counter()
    try:
        return real_simplify(*a)
    finally:
        calls["simplify_s"] += time.perf_counter() - t


terrain.profile, terrain._simplify = _profile, _simplify
load0 = os.getloadavg()[0]
with tempfile.TemporaryDirectory() as out, warnings.catch_warnings():
    warnings.simplefilter("ignore")
    w0, c0 = time.perf_counter(), time.process_time()
    files = (
        export_plan(plan, fmt, out_dir=out, allow_infeasible=True)
        if "allow_infeasible" in (export_plan.__code__.co_varnames)
        else export_plan(plan, fmt, out_dir=out)
    )
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
print(json.dumps({
    "label": label, "code": terrain.__file__, "format": fmt, "files": len(files),
    "wall_s": round(wall, 2), "cpu_s": round(cpu, 2), "profiles": calls["profile"],
    "simplify_s": round(calls["simplify_s"], 2), "load1": [round(load0, 2),
    round(os.getloadavg()[0], 2)],
}))  # fmt: skip
