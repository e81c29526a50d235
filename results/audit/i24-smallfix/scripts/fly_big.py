"""i24-smallfix, F1: the 500 km scenario planned and flown with and without F1 (a script).

``python fly_big.py OUT.json N``: ``/tmp/dayaudit/big_3.125.yaml`` with ``with_uavs(N)``,
the default plan (``nothing`` 1e-4) and ``PlanOptions(nothing=0)`` (every route flown, the
first of the highest kept: main's rule), each flown once (seed 5000) by the plan policies'
waypoint follower (``agents.testing.flights.fly``): digest, planned and flown POS_C, UAVs
flying, total flight hours, no-fly and collision steps.
"""

import json
import os
import sys
import time
from pathlib import Path

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[4] / "tests" / "planning"))
from effort_ab import _digest
from flyseeds import Saved

out, n = sys.argv[1], int(sys.argv[2])
sc = load_scenario("/tmp/dayaudit/big_3.125.yaml").with_uavs(n)
recs = {}
for name, opt in (("default", PlanOptions()), ("nothing=0", PlanOptions(nothing=0.0))):
    t = time.perf_counter()
    p = make_allocation_plan(sc, options=opt)
    plan_s = time.perf_counter() - t
    r = fly(sc, Saved(p), seed=5000)
    recs[name] = {
        "digest": _digest(p),
        "planned": p["posc"],
        "flown": r.posc,
        "flying": sum(1 for u in p["uavs"] if u["waypoints_m"]),
        "hours": sum(u["flight_time_s"] for u in p["uavs"]) / 3600,
        "nofly_steps": r.nofly_steps,
        "collision_steps": r.collision_steps,
        "landed": r.landed,
        "plan_s": plan_s,
        "load": os.getloadavg()[0],
    }
    print(n, name, recs[name], flush=True)
    Path(out).write_text(json.dumps(recs, indent=1))
