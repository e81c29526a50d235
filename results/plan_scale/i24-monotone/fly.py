"""i24-monotone: saved plans flown once by the waypoint follower (``allocation_plan``'s
episode, seed 5000: deterministic here), with the eq. 21 collision UAV-steps in all and away
from the fields (results/plan_scale/i24-chain/chain.py's ``flown``, reused) (a script, not a
test; run it from the checkout).

``python fly.py SCENARIO LABEL PLAN.json [PLAN.json ...]``: one JSON line per plan: the label,
UAVs, planned POS_C, UAVs flying, flown POSC and collision steps."""

import json
import sys

sys.path.insert(0, "results/plan_scale/i24-chain")
from chain import flown, scenario

sc_all, prior = scenario(sys.argv[1])
for path in sys.argv[3:]:
    with open(path) as f:
        plan = json.load(f)
    n = len(plan["uavs"])
    rec = {"label": sys.argv[2], "plan": path, "uavs": n, "posc": round(plan["posc"], 6),
           "flying": sum(1 for u in plan["uavs"] if u["waypoints_m"]),
           **flown(sc_all.with_uavs(n), prior, plan, set())}  # fmt: skip
    print(json.dumps(rec), flush=True)
