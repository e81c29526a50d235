"""i24-climb: the climb spirals of a plan, against T and against the DEM itself.

Usage: python spiral_figures.py PLAN.json DEM.tif QGC_DIR
Prints per UAV with a spiral: radius, turns, altitudes, minutes, the flight time and eq. 18's
0.85 T; the least height above the DEM's own pixels (terrain.dem_heights_at, the 2 x 2 pixels
around each point) of the orbit's points and of the exported QGC mission (qgc_clearance, the
take-off item to the last waypoint, the orbit as a climb over the field); and the refusal a
UAV gets when 0.85 T is half the spiral's time short.
"""

import json
import sys
from pathlib import Path

from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.plan import load_plan
from poc_env.agents.mission.terrain import dem_heights_at, from_record, plan_profiles, qgc_clearance
from poc_env.errors import ConfigError

plan_path, dem, qgc_dir = sys.argv[1], sys.argv[2], Path(sys.argv[3])
plan = load_plan(plan_path)
t = from_record(plan["terrain"])
profs = plan_profiles(plan)
T = t.usable_endurance_s / 0.85 if t.usable_endurance_s else float("nan")
print(f"UAVs {len(plan['uavs'])}; usable endurance 0.85 T = {t.usable_endurance_s / 60:.1f} min")
for u, p in zip(plan["uavs"], profs):
    sp = p.climb
    doc = json.loads((qgc_dir / f"{Path(plan_path).stem}_uav{u['id']}.plan").read_text())
    least, legs = qgc_clearance(doc, dem)
    cmds = [it["command"] for it in doc["mission"]["items"]]
    if sp is None:
        print(
            f"UAV {u['id']}: no spiral; QGC least height above the DEM {least:.0f} m ({legs} legs)"
        )
        continue
    xy, z = sp.points()
    ll = to_geographic(xy.tolist(), plan["crs"])
    above = z - dem_heights_at(dem, ll)
    print(
        f"UAV {u['id']}: spiral radius {sp.radius_m:.0f} m, {sp.turns:.2f} turns, "
        f"{sp.from_m:.0f} -> {sp.to_m:.0f} m AMSL (field {p.field_m:.0f} m), "
        f"{sp.length_m / 1e3:.2f} km, {sp.time_s / 60:.2f} min at {sp.speed_mps * 3.6:.0f} km/h; "
        f"flight {u['flight_time_s'] / 60:.1f} min + spiral = "
        f"{(u['flight_time_s'] + sp.time_s) / 60:.1f} of 0.85 T {t.usable_endurance_s / 60:.1f} "
        f"min; spiral = {100 * sp.time_s / T:.2f} % of T; orbit's least height above the DEM "
        f"{above.min():.0f} m (clearance {t.min_clearance_m:g}); QGC least height above the DEM "
        f"{least:.0f} m ({legs} legs), commands {cmds[:4]}"
    )
    short = {
        **plan,
        "terrain": {**plan["terrain"], "usable_endurance_s": u["flight_time_s"] + sp.time_s / 2},
    }
    try:
        plan_profiles(short)
    except ConfigError as err:  # 0.85 T is the plan's: the first UAV it does not fit is named
        mine = f"(UAV {u['id']})" in str(err)
        print(f"  with 0.85 T half its spiral short: {err if mine else 'another UAV named first'}")
