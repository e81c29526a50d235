"""i24-gainhour: ``--effort standard`` on the 500 km scenario at 24 UAVs (a script):
``python standard_big.py OUT.json [--fly]``: the standard plan with the floor (default) and
with ``gain_per_hour=0``; planned POS_C, UAVs flying, flight hours, the UAVs kept home, CPU s;
with ``--fly`` each flown once (seed 5000): flown POS_C, no-fly and collision steps."""

import dataclasses
import json
import os
import sys
import time
from pathlib import Path

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario

sc = load_scenario("/tmp/gainhour/big.yaml").with_uavs(24)
recs = {}
for name, g in (("standard", None), ("standard, gain_per_hour=0", 0.0)):
    opt = PlanOptions.preset("standard")
    if g is not None:
        opt = dataclasses.replace(opt, gain_per_hour=g)
    c = time.process_time()
    p = make_allocation_plan(sc, options=opt)
    recs[name] = {
        "posc": p["posc"],
        "flying": sum(1 for u in p["uavs"] if u["waypoints_m"]),
        "hours": sum(u["flight_time_s"] for u in p["uavs"]) / 3600,
        "home": p["optimizer"]["settings"].get("home", []),
        "cpu_s": time.process_time() - c,
        "load": os.getloadavg()[0],
    }
    if "--fly" in sys.argv:
        sys.path.insert(
            0, str(Path(__file__).resolve().parents[4] / "results/audit/i24-smallfix/scripts")
        )
        from flyseeds import Saved

        r = fly(sc, Saved(p), seed=5000)
        recs[name] |= {"flown": r.posc, "nofly_steps": r.nofly_steps,
                       "collision_steps": r.collision_steps, "landed": r.landed}  # fmt: skip
    print(name, {k: v for k, v in recs[name].items() if k != "home"}, flush=True)
    Path(sys.argv[1]).write_text(json.dumps(recs, indent=1))
