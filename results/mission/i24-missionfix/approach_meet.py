"""Leftover g: can field-mates meet on their landing approach? (i24-missionfix)

``python approach_meet.py PLAN.json [S]``: for every pair of UAVs landing at one field, the
approach each flies as exported with ``--separation-m S`` (layers by field): from its approach
point (or its descent orbit's exit) down the final glide to the field, altitudes AMSL from the
terrain profile. Prints per pair the distance between their approach points, their altitudes
there, and how far apart the two glides are 3, 2 and 1 km from the field."""

import itertools
import sys

import numpy as np

from poc_env.agents.mission.features import with_layers
from poc_env.agents.mission.plan import load_plan
from poc_env.agents.mission.terrain import plan_profiles

plan = load_plan(sys.argv[1])
sep = float(sys.argv[2]) if len(sys.argv) > 2 else 30.0
plan = with_layers(plan, sep, "field")
profs = plan_profiles(plan, charge=False)
glides = []
for u, p in zip(plan["uavs"], profs or ()):
    if not u["waypoints_m"]:
        continue
    if p.descent is not None:
        a, za = np.asarray(p.descent.exit_m), float(p.descent.orbit.to_m)
    else:
        a, za = p.points_m[-1], float(p.amsl_m[-1])
    f = np.asarray(u["landing_m"], float)
    s = np.linspace(0.0, 1.0, 401)[:, None]
    xy = a + (f - a) * s
    z = za + (p.landing_field_m - za) * s[:, 0]
    glides.append((u["id"], tuple(np.round(f)), a, za, xy, z, u.get("layer_m", 0.0)))
pairs = 0
for g, h in itertools.combinations(glides, 2):
    if g[1] != h[1]:
        continue
    pairs += 1
    field = np.asarray(g[1], float)
    d_app = float(np.hypot(*(g[2] - h[2])))
    out = []
    for km in (3.0, 2.0, 1.0):  # where each glide is km from the field
        i = int(np.argmin(np.abs(np.hypot(*(g[4] - field).T) - km * 1e3)))
        j = int(np.argmin(np.abs(np.hypot(*(h[4] - field).T) - km * 1e3)))
        dxy = float(np.hypot(*(g[4][i] - h[4][j])))
        out.append(f"{km:g} km out {dxy:.0f} m apart, {abs(g[5][i] - h[5][j]):.0f} m vertically")
    print(
        f"UAVs {g[0]} and {h[0]} (layers {g[6]:g} / {h[6]:g} m) land at "
        f"({field[0] / 1e3:.1f}, {field[1] / 1e3:.1f}) km: approach points {d_app / 1e3:.2f} km "
        f"apart at {g[3]:.0f} / {h[3]:.0f} m AMSL; " + "; ".join(out)
    )
print(f"{sys.argv[1]}: {pairs} pairs of field-mates landing at one field")
