"""bound-zones: allocation plans planned and flown on random small maps with a zone, under the
exponential and definite-range laws, against every printed bound (laws.log). From the checkout:

    OMP_NUM_THREADS=1 python results/bounds/bound_zones/laws.py > results/bounds/bound_zones/laws.log
"""

import sys, warnings
warnings.simplefilter("ignore")
sys.path.insert(0, "tests/theory")
import numpy as np
from test_bound_zones import _random_case, _printed_bounds
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.policies.allocation import AllocationPlanPolicy
from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario
import dataclasses
for law in ("exponential", "definite_range"):
    for seed in range(6000, 6006):
        sc, prior = _random_case(seed)
        sc = load_scenario("small", {"map.no_fly_zones_km": [np.asarray(z)/1000 for z in sc.map.no_fly_zones_m], "sensor.law": law})
        p = make_allocation_plan(sc, prior=prior)
        b = _printed_bounds(p)
        f = fly(sc, AllocationPlanPolicy(), seed=5000, prior=prior)
        print(law, seed, round(p["posc"],4), round(f.posc,4), f.nofly_steps, {k: round(v,4) for k,v in b.items()}, "VIOL" if max(p["posc"], f.posc) > min(b.values()) + 1e-12 else "", flush=True)
