"""i24-fleet: one warm allocation plan's CPU and wall time (pair.sh runs it per tree).

``python warm_plan.py SCENARIO N``: a warm-up plan (``refine=0``: the compiled kernels
loaded), then one default plan timed; one JSON line (cpu, s, posc).
"""

import json
import sys
import time

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

sc = load_scenario(sys.argv[1]).with_uavs(int(sys.argv[2]))
pr = build_prior(sc.map)
make_allocation_plan(sc, prior=pr, refine=0)
c0, t0 = time.process_time(), time.perf_counter()
p = make_allocation_plan(sc, prior=pr)
print(
    json.dumps({"cpu": time.process_time() - c0, "s": time.perf_counter() - t0, "posc": p["posc"]})
)
