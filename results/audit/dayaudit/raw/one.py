"""i24-dayaudit: the one-sighting map with and without the fill (a script, not a test).

``python one.py`` in the folder holding ``sone.yaml`` (README, probe 17)."""

from poc_env.agents.planning.allocation import PlanOptions, make_allocation_plan
from poc_env.config import load_scenario

sc = load_scenario("sone.yaml")
for opt in [PlanOptions(), PlanOptions(fill_idle=False)]:
    p = make_allocation_plan(sc, options=opt)
    per_uav = [
        (u["id"], round(u["flight_time_s"] / 3600, 2), round(u["pos"], 4)) for u in p["uavs"]
    ]
    print(opt.changed(), round(p["posc"], 4), p["start"], per_uav)
