"""Per UAV of a plan with terrain: flight + climb spiral (with a departure of its own) +
descent orbit minutes against eq. 18's 0.85 T, and the take-off departure (i24-missionfix).
``python figures.py PLAN.json``"""

import json
import sys

from poc_env.agents.mission.plan import load_plan
from poc_env.agents.mission.terrain import departure_heading_deg, plan_profiles

plan = load_plan(sys.argv[1])
fit = plan.get("orbit_fit")
usable = plan["terrain"]["usable_endurance_s"] / 60
print(f"{sys.argv[1]} POS_C {plan['posc']:.4f} usable {usable:.1f} min orbit_fit",
      json.dumps(fit) if fit else "-")  # fmt: skip
for u, p in zip(plan["uavs"], plan_profiles(plan) or ()):
    f = u["flight_time_s"] / 60
    c, d = p.climb, p.descent
    cs = c.time_s / 60 if c else 0.0
    ds = d.time_s / 60 if d else 0.0
    dep = ""
    if c is not None and c.depart_m > 0:
        dep = (f" departs heading {departure_heading_deg(c):.0f} deg {c.depart_m / 1e3:.2f} km "
               f"to {c.from_m:.0f} m, orbit to {c.to_m:.0f} m, {c.turns:.2f} turns")  # fmt: skip
    elif c is not None:
        dep = f" spiral {c.from_m:.0f}-{c.to_m:.0f} m {c.turns:.2f} turns"
    print(f"  UAV {u['id']}: wps {len(u['waypoints_m'])} flight {f:.1f} + climb {cs:.2f} + "
          f"descent {ds:.2f} = {f + cs + ds:.1f} min{dep}")  # fmt: skip
