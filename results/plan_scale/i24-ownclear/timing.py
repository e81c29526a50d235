"""i24-ownclear: paired planning CPU of the default plan with and without
``PlanOptions.own_apart`` (a script, not a test; run it from the checkout).

``python timing.py SCENARIO UAVS REPEATS``: the two plans alternated in one process (one warm-up
plan first), one JSON line per plan: CPU seconds (``time.process_time``), the 1-minute load."""

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
make_allocation_plan(sc, prior=prior)  # warm-up (compiled kernels cached)
for r in range(int(sys.argv[3])):
    for on in (False, True):
        t0 = time.process_time()
        p = make_allocation_plan(sc, prior=prior, options=PlanOptions(own_apart=on))
        rec = {"scenario": sys.argv[1], "uavs": len(p["uavs"]), "repeat": r, "own_apart": on,
               "cpu_s": round(time.process_time() - t0, 2), "posc": p["posc"],
               "load1": round(os.getloadavg()[0], 1)}  # fmt: skip
        print(json.dumps(rec), flush=True)
