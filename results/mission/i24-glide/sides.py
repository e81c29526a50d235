"""Probe 13: for UAVs 3 and 4, what each of the 9 nearest approach sides gives.

Usage (in the work folder holding swall.json): python sides.py
Per side (turned from approach_point's): a straight glide and a descent orbit, each ``flies``,
``steep`` (flies with a glide steeper than the flat export's, warned) or ``no`` (refused).
"""

import json
import math
import warnings
from pathlib import Path

import numpy as np

from poc_env.agents.mission.plan import approach_sides, flight
from poc_env.agents.mission.terrain import SteepGlideWarning, from_record, mission_path, profile
from poc_env.errors import ConfigError

plan = json.loads(Path("swall.json").read_text())
t = from_record(plan["terrain"])
v = flight(plan)["transit_speed_mps"]
for k in (2, 3):
    u = plan["uavs"][k]
    path = mission_path(u, plan.get("no_fly_zones_m"))
    land = np.asarray(u["landing_m"], float)
    first = None
    for app in list(approach_sides(u, plan.get("no_fly_zones_m")))[:9]:
        ang = math.degrees(math.atan2(app[1] - land[1], app[0] - land[0]))
        first = ang if first is None else first
        row = []
        for loiter in (False, True):
            with warnings.catch_warnings(record=True) as said:
                warnings.simplefilter("always")
                try:
                    profile(t, [*path[:-1], app], "x", land, 0.0, v, loiter)
                    steep = any(issubclass(w.category, SteepGlideWarning) for w in said)
                    row.append("steep" if steep else "flies")
                except ConfigError:
                    row.append("no")
        turn = (ang - first + 180) % 360 - 180
        print(f"UAV {u['id']} side {turn:+.0f} deg: straight {row[0]}, orbit {row[1]}")
