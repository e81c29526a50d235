"""i24-smallfix: plans on maps with zones, this checkout (a script, not a test).

``python zonecheck.py OUT.json``: ``small`` with test_zonepolish's ZONE and ``paper_6_2`` with
its TWO_ZONES, the allocation plan at the default and ``standard`` efforts and the greedy
rectangle plan: digest and planned POS_C, to compare main and the branch.
"""

import json
import os
import sys
import time
from pathlib import Path

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.greedy_rectangles import make_greedy_rectangles_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[4] / "tests" / "planning"))
from effort_ab import _digest

ZONE = {"map.no_fly_zones_km": [[[15, 10], [25, 10], [25, 30], [15, 30]]]}
TWO = {
    "map.no_fly_zones_km": [
        [[60, 50], [90, 50], [90, 90], [60, 90]],
        [[120, 80], [150, 80], [150, 120], [120, 120]],
    ]
}
recs = {}
for name, ov in [("small", ZONE), ("paper_6_2", TWO)]:
    sc = load_scenario(name, ov)
    for eff in ("default", "standard", "greedy"):
        t = time.perf_counter()
        if eff == "greedy":
            p = make_greedy_rectangles_plan(sc)
        else:
            p = make_allocation_plan(sc, options=PlanOptions.preset(eff))
        recs[f"{name}:{eff}"] = {
            "digest": _digest(p),
            "posc": p["posc"],
            "plan_s": time.perf_counter() - t,
            "load": os.getloadavg()[0],
        }
        print(name, eff, recs[f"{name}:{eff}"], flush=True)
Path(sys.argv[1]).write_text(json.dumps(recs, indent=1))
