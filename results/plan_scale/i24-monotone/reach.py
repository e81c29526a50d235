"""i24-monotone: the reachable mass saved plans leave (tests/planning/test_fleet.py's
``reachable_unfound``: per cell the prior's share a sensor reaches from outside the zones,
where some UAV's straight out and back fits 0.85 T, less what the plan finds there) (a script,
not a test; run it from the checkout).

``python reach.py SCENARIO LABEL PLAN.json [PLAN.json ...]``: one JSON line per plan."""

import json
import sys

sys.path.insert(0, "tests/planning")
from diag import scenario
from test_fleet import reachable_unfound

sc_all, prior = scenario(sys.argv[1])
for path in sys.argv[3:]:
    with open(path) as f:
        plan = json.load(f)
    n = len(plan["uavs"])
    home = plan["optimizer"]["settings"].get("home", [])
    rec = {"label": sys.argv[2], "uavs": n, "posc": round(plan["posc"], 6),
           "without_route": sum(1 for u in plan["uavs"] if not u["waypoints_m"]),
           "kept_home_by_floor": len(home),
           "reachable_unfound":
               round(reachable_unfound(sc_all.with_uavs(n), prior, plan), 6)}  # fmt: skip
    print(json.dumps(rec), flush=True)
