"""i24-monotone: paired planning CPU time of the default allocation plan with the
three-quarter floor from VALUES UAVs (``PlanOptions.three_quarter_from``; 0: main's rule, the
half fleet alone) (a script, not a test; run it from the checkout).

``python timing.py SCENARIO N REPEATS VALUES``: SCENARIO a scenario file or a built-in name,
N UAVs, VALUES e.g. ``0,32,1``; the variants alternated REPEATS times in one process (one
thread), one JSON line per plan: the value, CPU seconds (``time.process_time``), the 1-minute
load average, planned POS_C and a digest of the waypoints."""

import hashlib
import json
import os
import sys
import time

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

sc = load_scenario(sys.argv[1]).with_uavs(int(sys.argv[2]))
prior = build_prior(sc.map)
for r in range(int(sys.argv[3])):
    for value in (int(x) for x in sys.argv[4].split(",")):
        t0 = time.process_time()
        p = make_allocation_plan(sc, prior=prior, options=PlanOptions(three_quarter_from=value))
        wps = repr([u["waypoints_m"] for u in p["uavs"]]).encode()
        rec = {"scenario": sys.argv[1], "uavs": len(p["uavs"]), "repeat": r,
               "three_quarter_from": value, "cpu_s": round(time.process_time() - t0, 2),
               "load1": round(os.getloadavg()[0], 1), "posc": round(p["posc"], 6),
               "digest": hashlib.sha256(wps).hexdigest()[:12]}  # fmt: skip
        print(json.dumps(rec), flush=True)
