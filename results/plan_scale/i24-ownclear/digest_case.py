"""i24-ownclear: one scenario's default plan with and without ``PlanOptions.own_apart``,
planned and flown (a script, not a test; run it from the checkout).

``python digest_case.py SCENARIO``: one JSON line per setting: planned POS_C, what the rule
kept (``optimizer.settings.own_apart``) and the plan flown once by the waypoint follower
(results/plan_scale/i24-chain/chain.py's ``flown``, episode seed 5000)."""

import json
import sys

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

sys.path.insert(0, "results/plan_scale/i24-chain")
from chain import flown

sc = load_scenario(sys.argv[1])
prior = build_prior(sc.map)
for on in (False, True):
    p = make_allocation_plan(sc, prior=prior, options=PlanOptions(own_apart=on))
    f = {k: v for k, v in flown(sc, prior, p, set()).items() if not k.startswith("away_")}
    rec = {"scenario": sys.argv[1], "uavs": len(p["uavs"]), "own_apart": on, "posc": p["posc"],
           "rule": p["optimizer"]["settings"].get("own_apart"), **f}  # fmt: skip
    print(json.dumps(rec), flush=True)
