"""i24-monotone: saved plans flown once by the waypoint follower (``allocation_plan``'s
episode, seed 5000: deterministic here), with the eq. 21 collision UAV-steps in all and away
from the fields (results/plan_scale/i24-chain/chain.py's ``flown``, reused) (a script, not a
test; run it from the checkout).

``python fly.py SCENARIO LABEL PLAN.json [PLAN.json ...]``: one JSON line per plan: the label,
UAVs, planned POS_C, UAVs flying, flown POSC and collision steps. ``LABEL`` of the form
``NAME@FLOOR.json``: the steps away from the fields split as ``chain.py`` splits them, the
UAVs whose route is not FLOOR.json's (a plan of fewer UAVs, its routes given to UAVs of the
same fields) counted as added."""

import json
import sys

sys.path.insert(0, "results/plan_scale/i24-chain")
from chain import flown, scenario

from poc_env.agents.planning.allocation import _mapped

sc_all, prior = scenario(sys.argv[1])
label, _, floor_path = sys.argv[2].partition("@")
floor = None
if floor_path:
    with open(floor_path) as f:
        floor = json.load(f)
for path in sys.argv[3:]:
    with open(path) as f:
        plan = json.load(f)
    n = len(plan["uavs"])
    added: set[int] = set()
    if floor is not None:
        base = _mapped(sc_all.with_uavs(n), floor, check=False)
        added = {k for k in range(n) if plan["uavs"][k]["waypoints_m"] != base[k]}
    rec = {"label": label, "plan": path, "added": sorted(added), "uavs": n,
           "posc": round(plan["posc"], 6),
           "flying": sum(1 for u in plan["uavs"] if u["waypoints_m"]),
           **flown(sc_all.with_uavs(n), prior, plan, added)}  # fmt: skip
    print(json.dumps(rec), flush=True)
