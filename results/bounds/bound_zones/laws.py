"""bound-zones: allocation plans planned and flown on random small maps with a zone, under the
exponential and definite-range laws, against every printed bound (laws.log). From the
checkout:

    OMP_NUM_THREADS=1 python results/bounds/bound_zones/laws.py > laws.log
"""

import os
import sys
import warnings

import numpy as np

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.policies.allocation import AllocationPlanPolicy
from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "theory"))
from test_bound_zones import _printed_bounds, _random_case

warnings.simplefilter("ignore")
for law in ("exponential", "definite_range"):
    for seed in range(6000, 6006):
        sc, prior = _random_case(seed)
        zones = [np.asarray(z) / 1000 for z in sc.map.no_fly_zones_m]
        sc = load_scenario("small", {"map.no_fly_zones_km": zones, "sensor.law": law})
        p = make_allocation_plan(sc, prior=prior)
        b = _printed_bounds(p)
        f = fly(sc, AllocationPlanPolicy(), seed=5000, prior=prior)
        over = max(p["posc"], f.posc) > min(b.values()) + 1e-12
        shown = {k: round(v, 4) for k, v in b.items()}
        flag = "VIOL" if over else ""
        print(law, seed, round(p["posc"], 4), round(f.posc, 4), f.nofly_steps, shown, flag)
