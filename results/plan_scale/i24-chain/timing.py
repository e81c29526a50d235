"""i24-chain: paired planning CPU time of the default allocation plan with and without
``PlanOptions.half_fleet`` (a script, not a test; run it from the checkout).

``python timing.py SCENARIO N REPEATS``: SCENARIO a scenario file or a built-in name, N UAVs;
the two plans alternated REPEATS times in one process (one thread), one JSON line per plan:
the variant, CPU seconds (``time.process_time``), the 1-minute load average, planned POS_C."""

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
    for half in (False, True):
        t0 = time.process_time()
        p = make_allocation_plan(sc, prior=prior, options=PlanOptions(half_fleet=half))
        rec = {"scenario": sys.argv[1], "uavs": len(p["uavs"]), "repeat": r, "half_fleet": half,
               "cpu_s": round(time.process_time() - t0, 2), "load1": round(os.getloadavg()[0], 1),
               "posc": round(p["posc"], 4)}  # fmt: skip
        print(json.dumps(rec), flush=True)
