"""i24-glide: each UAV's final glide as exported, against T and against the DEM itself.

Usage: python glide_figures.py PLAN.json DEM.tif QGC_DIR
Per UAV: the approach side taken (turned from approach_point's, degrees), a straight glide's
angle, or the descent orbit (radius, altitudes, minutes, the glide from its tangent exit as
PX4 reads it), the flight time + orbits against eq. 18's 0.85 T; the least height above the
DEM's own pixels (terrain.dem_heights_at, the 2 x 2 pixels around each point) of the orbit's
points, of the glide from its exit (beyond 1.5 km of the field, where the UAV is not yet on its
landing) and of the exported QGC mission (qgc_clearance: the take-off item to the last item
before NAV_LAND); the QGC commands from DO_LAND_START; and the descent's minutes at PX4's
default sink-rate bound (FW_T_SINK_MAX 5 m/s) rather than eq. 19's pitch bound.
"""

import json
import math
import sys
from pathlib import Path

import numpy as np

from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.plan import approach_point, load_plan
from poc_env.agents.mission.terrain import dem_heights_at, from_record, plan_profiles, qgc_clearance

#: PX4's default maximum sink rate (FW_T_SINK_MAX, m/s; fw_pos_control TECS parameters).
SINK_MAX_MPS = 5.0

plan_path, dem, qgc_dir = sys.argv[1], sys.argv[2], Path(sys.argv[3])
plan = load_plan(plan_path)
t = from_record(plan["terrain"])
crs = plan["crs"]
print(f"UAVs {len(plan['uavs'])}; usable endurance 0.85 T = {t.usable_endurance_s / 60:.1f} min")
for u, p in zip(plan["uavs"], plan_profiles(plan)):
    land = np.asarray(u["landing_m"], float)
    app0 = np.asarray(approach_point(u, plan.get("no_fly_zones_m")), float)
    app = p.points_m[-1]
    turn = math.degrees(math.atan2(*(app - land)[::-1]) - math.atan2(*(app0 - land)[::-1]))
    turn = (turn + 180) % 360 - 180
    doc = json.loads((qgc_dir / f"{Path(plan_path).stem}_uav{u['id']}.plan").read_text())
    least, legs = qgc_clearance(doc, dem)
    cmds = [it["command"] for it in doc["mission"]["items"]]
    tail = cmds[cmds.index(189) :]
    fl = u["flight_time_s"] / 60
    d = p.descent
    if d is None:
        glide = (p.amsl_m[-1] - p.landing_field_m) / np.hypot(*(land - app))
        print(
            f"UAV {u['id']}: side turned {turn:+.0f} deg, straight glide "
            f"{math.degrees(math.atan(glide)):.2f} deg; flight {fl:.1f} min; QGC least height "
            f"above the DEM {least:.0f} m ({legs} legs); from DO_LAND_START {tail}"
        )
        continue
    o = d.orbit
    xy, z = d.points()
    orbit_above = z - dem_heights_at(dem, to_geographic(xy.tolist(), crs))
    s = np.linspace(0.0, 1.0, 400)
    ex = np.asarray(d.exit_m)
    line = ex + (land - ex) * s[:, None]
    zl = o.to_m + (p.landing_field_m - o.to_m) * s
    far = np.hypot(*(line - land).T) > 1500.0
    glide_above = (zl - dem_heights_at(dem, to_geographic(line.tolist(), crs)))[far]
    glide = (o.to_m - p.landing_field_m) / d.glide_m
    extra = d.time_s / 60 + (p.climb.time_s / 60 if p.climb else 0.0)
    print(
        f"UAV {u['id']}: side turned {turn:+.0f} deg, descent orbit radius {o.radius_m:.0f} m, "
        f"{o.from_m:.0f} -> {o.to_m:.0f} m AMSL (field {p.landing_field_m:.0f} m), "
        f"{d.length_m / 1e3:.2f} km, {d.time_s / 60:.2f} min; glide from the exit "
        f"{math.degrees(math.atan(glide)):.2f} deg over {d.glide_m / 1e3:.2f} km; flight {fl:.1f}"
        f" + orbits {extra:.2f} = {fl + extra:.1f} of 0.85 T {t.usable_endurance_s / 60:.1f} min;"
        f" least height above the DEM: orbit {orbit_above.min():.0f} m, glide beyond 1.5 km "
        f"{glide_above.min():.0f} m, QGC mission {least:.0f} m ({legs} legs) (clearance "
        f"{t.min_clearance_m:g}); from DO_LAND_START {tail}"
    )
    sink = abs(o.from_m - o.to_m) / SINK_MAX_MPS / 60  # PX4's TECS sink-rate bound, default
    print(
        f"  at PX4's default FW_T_SINK_MAX {SINK_MAX_MPS:g} m/s the descent alone takes "
        f"{sink:.2f} min: flight + climb spiral + that = "
        f"{fl + (p.climb.time_s / 60 if p.climb else 0.0) + sink:.1f} of "
        f"{t.usable_endurance_s / 60:.1f} min"
    )
