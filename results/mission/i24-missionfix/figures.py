"""Per UAV: flight + climb spiral (+ departure) + descent orbit minutes, departure heading."""
import json, sys
from poc_env.agents.mission.plan import load_plan
from poc_env.agents.mission.terrain import plan_profiles, departure_heading_deg

plan = load_plan(sys.argv[1])
profs = plan_profiles(plan)
print(sys.argv[1], "POS_C", round(plan["posc"], 4), "usable", round(plan["terrain"]["usable_endurance_s"] / 60, 1), "min",
      "orbit_fit", json.dumps(plan.get("orbit_fit")) if plan.get("orbit_fit") else "-")
for u, p in zip(plan["uavs"], profs):
    f = u["flight_time_s"] / 60
    c = p.climb; d = p.descent
    cs = c.time_s / 60 if c else 0.0
    ds = d.time_s / 60 if d else 0.0
    dep = (f" departs heading {departure_heading_deg(c):.0f} deg {c.depart_m/1e3:.2f} km to {c.from_m:.0f} m, orbit to {c.to_m:.0f} m, {c.turns:.2f} turns"
           if c and c.depart_m > 0 else (f" spiral {c.from_m:.0f}-{c.to_m:.0f} m {c.turns:.2f} turns" if c else ""))
    print(f"  UAV {u['id']}: wps {len(u['waypoints_m'])} flight {f:.1f} + climb {cs:.2f} + descent {ds:.2f} = {f+cs+ds:.1f} min{dep}")
