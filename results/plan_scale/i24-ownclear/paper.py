"""i24-ownclear: the default allocation plan on ``paper_6_2``'s random priors with and without
``PlanOptions.own_apart``, planned and flown (a script, not a test; run it from the checkout).

``python paper.py FIRST LAST``: one JSON line per prior seed (``episode_prior``): planned POS_C
both ways, whether the plans are equal waypoint for waypoint, what the rule kept
(``optimizer.settings.own_apart``), and each plan flown once by the waypoint follower
(results/plan_scale/i24-chain/chain.py's ``flown``: flown POSC, collision UAV-steps in all and
away from the fields; episode seed 5000)."""

import json
import sys

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario

sys.path.insert(0, "results/plan_scale/i24-chain")
from chain import flown

sc = load_scenario("paper_6_2")
for seed in range(int(sys.argv[1]), int(sys.argv[2]) + 1):
    prior = episode_prior(sc, seed)
    on = make_allocation_plan(sc, prior=prior)
    off = make_allocation_plan(sc, prior=prior, options=PlanOptions(own_apart=False))
    f_on, f_off = flown(sc, prior, on, set()), flown(sc, prior, off, set())
    rec = {
        "seed": seed,
        "posc_on": on["posc"],
        "posc_off": off["posc"],
        "same": [u["waypoints_m"] for u in on["uavs"]] == [u["waypoints_m"] for u in off["uavs"]],
        "own_apart": on["optimizer"]["settings"].get("own_apart"),
        **{f"{k}_on": v for k, v in f_on.items() if not k.startswith("away_")},
        **{f"{k}_off": v for k, v in f_off.items() if not k.startswith("away_")},
    }
    print(json.dumps(rec), flush=True)
