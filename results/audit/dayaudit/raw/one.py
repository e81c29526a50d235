import numpy as np
from poc_env.agents.planning.allocation import make_allocation_plan, PlanOptions
from poc_env.config import load_scenario
sc = load_scenario("sone.yaml")
for opt in [PlanOptions(), PlanOptions(fill_idle=False)]:
    p = make_allocation_plan(sc, options=opt)
    print(opt.changed(), round(p["posc"],4), p["start"], [(u["id"], round(u["flight_time_s"]/3600,2), round(u["pos"],4)) for u in p["uavs"]])
