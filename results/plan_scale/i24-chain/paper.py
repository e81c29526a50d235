"""i24-chain: the default allocation plan on ``paper_6_2``'s random priors with and without
``PlanOptions.half_fleet`` (a script, not a test; run it from the checkout).

``python paper.py FIRST LAST``: one JSON line per prior seed (``episode_prior``): planned POS_C
both ways, whether they are equal waypoint for waypoint, UAVs without a route, and whether the
half fleet was tried (``optimizer.settings.fleet``)."""

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
    off = make_allocation_plan(sc, prior=prior, options=PlanOptions(half_fleet=False))
    rec = {
        "seed": seed,
        "posc_on": on["posc"],
        "posc_off": off["posc"],
        "same": [u["waypoints_m"] for u in on["uavs"]] == [u["waypoints_m"] for u in off["uavs"]],
        "no_route": sum(not u["waypoints_m"] for u in off["uavs"]),
        "fleet": on["optimizer"]["settings"].get("fleet"),
    }
    print(json.dumps(rec), flush=True)
