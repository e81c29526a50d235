"""i24-monotone: the default allocation plan on ``paper_6_2``'s random priors with the
three-quarter floor (default, from 32 UAVs) and without it (``three_quarter_from=0``, main's
rule) (a script, not a test; run it from the checkout).

``python paper.py FIRST LAST``: one JSON line per prior seed (``episode_prior``): planned POS_C
both ways and whether the plans are equal waypoint for waypoint."""

import json
import sys

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario

sc = load_scenario("paper_6_2")
for seed in range(int(sys.argv[1]), int(sys.argv[2]) + 1):
    prior = episode_prior(sc, seed)
    on = make_allocation_plan(sc, prior=prior)
    off = make_allocation_plan(sc, prior=prior, options=PlanOptions(three_quarter_from=0))
    same = [u["waypoints_m"] for u in on["uavs"]] == [u["waypoints_m"] for u in off["uavs"]]
    rec = {"seed": seed, "uavs": len(on["uavs"]), "posc_on": on["posc"],
           "posc_off": off["posc"], "same": same}  # fmt: skip
    print(json.dumps(rec), flush=True)
