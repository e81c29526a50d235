"""i24-fleet: ``plan_fleets`` over fleet sizes (a script, not a test).

``python fleets.py SCENARIO N [N ...]`` (from the checkout; SCENARIO as in fleet.py)
    Plans every N with :func:`~poc_env.agents.planning.allocation.plan_fleets` (each size
    planned with the plan of the one before as its floor) and prints per size: UAVs, POS_C,
    the start kept, the floor record (``optimizer.settings.fleet``), UAVs without a route,
    reachable mass unfound (fleet.py's split) and the plan's own runtime; then the total.
"""

import sys
import time

sys.path.insert(0, "results/plan_scale/i24-fleet")
from fleet import scenario, split

from poc_env.agents.planning.allocation import plan_fleets

sc, prior = scenario(sys.argv[1], 1)
t0 = time.perf_counter()
ps = plan_fleets(sc, [int(x) for x in sys.argv[2:]], prior=prior)
for p in ps:
    n = len(p["uavs"])
    print(
        n,
        round(p["posc"], 4),
        p["start"],
        p["optimizer"]["settings"].get("fleet"),
        sum(1 for u in p["uavs"] if not u["waypoints_m"]),
        split(sc.with_uavs(n), prior, p)["reachable_unfound"],
        round(p["runtime_s"], 1),
    )
print("total", round(time.perf_counter() - t0, 1))
