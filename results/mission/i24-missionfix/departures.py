"""The take-off departures of a plan (i24-missionfix): per UAV whose take-off climbs out on a
heading of its own, the heading, the route's heading, the climb out's length, its least height
above the ground (the bilinear DEM, beyond the field's own cells, as the check reads it) and
the highest ground under it; and what the climb towards the first waypoint would have met.
``python departures.py PLAN.json``"""

import math
import sys

import numpy as np

from poc_env.agents.mission import terrain as tm
from poc_env.agents.mission.plan import flight, load_plan

plan = load_plan(sys.argv[1])
t = tm.from_record(plan["terrain"])
up = math.tan(tm.vertical_angle(t, tm.route_speed_mps(flight(plan)), True))
for u, p in zip(plan["uavs"], tm.plan_profiles(plan) or ()):
    sp = p.climb
    if sp is None or sp.depart_m <= 0.0:
        continue
    c = np.asarray(sp.center_m)
    w = np.asarray(u["waypoints_m"][0]) - c
    route = (90.0 - math.degrees(math.atan2(w[1], w[0]))) % 360.0
    for name, h in (("departure", sp.start_rad), ("towards the first waypoint", None)):
        a = math.atan2(w[1], w[0]) if h is None else h
        s = np.linspace(0.0, sp.depart_m, 401)
        xy = c + s[:, None] * [math.cos(a), math.sin(a)]
        far = ~tm._own_cells(t, c, xy)
        g = tm.bilinear(t.ground_m, t.origin_m, t.cell_m, xy)
        alt = p.field_m + up * s
        gap = alt[far] - g[far]
        print(
            f"UAV {u['id']} {name} heading {(90.0 - math.degrees(a)) % 360.0:.0f} deg (route "
            f"{route:.0f}): {sp.depart_m / 1e3:.2f} km to {sp.from_m:.0f} m AMSL at "
            f"{up * 100:.2f} % from the field at {p.field_m:.0f} m; least height above the "
            f"ground beyond the field's cells {gap.min():.0f} m, highest ground "
            f"{g[far].max():.0f} m"
        )
