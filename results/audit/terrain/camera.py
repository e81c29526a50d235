import sys

sys.path.insert(0, __import__("os").path.dirname(__file__))
import numpy as np
from probe import D, load_scenario, make_plan, scenario, write_geo

from poc_env.agents.mission.terrain import plan_profiles

dem = write_geo(D / "high.tif", "high")
for ceil in (6500, 5600):
    data = scenario(dem, max_altitude_m=ceil)
    data["sensor"] = {"model": "camera", "fov_deg": 60}
    sc = load_scenario(data)
    plan = make_plan(sc, planner="allocation", uavs=2, refine=0)
    h = sc.uav.cruise_altitude_m
    for u, p in zip(plan["uavs"], plan_profiles(plan)):
        n = len(u["waypoints_m"])
        v = p.vertex
        first = int(np.flatnonzero(v == 1)[0])
        last = int(np.flatnonzero(v == n)[0])
        seg = slice(first, last + 1)
        agl = p.amsl_m[seg] - p.ground_m[seg]
        w_low = sc.sensor.sweep_width_at(max(agl.min(), 1))
        print(
            f"ceiling {ceil}: UAV {u['id']} planned W {sc.sensor.sweep_width_m:.0f} m at h {h:g}; "
            f"search-leg AGL min {agl.min():.0f} m -> camera W {w_low:.0f} m; "
            f"points below h-1: {np.mean(agl < h - 1):.0%}"
        )
