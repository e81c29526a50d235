"""i24-flownsep: a plan's own eq. 21 conflicts for two UAVs (a script, not a test).

``python planned_pairs.py SCENARIO N A B`` (N 0: the file's fleet; SCENARIO ``mono2`` or
``lanes``: repro.py's smoke cases at N UAVs): the default allocation plan (seed 5000, the
scenario's own prior), its planned conflict pair-steps
(:func:`~poc_env.agents.planning.deconflict.conflicts`, 120 s slack, away from the fields) per
pair, and UAVs A and B's planned distance every dt with their first waypoints: whether a
flown collision was in the plan (the big scenario's 12 / 13 at 24 UAVs: one box 1.58 km
apart in trail at every whole step; 8 / 10 at 32).
"""

import sys
from pathlib import Path

import numpy as np

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.deconflict import conflicts, planned_positions
from poc_env.agents.planning.flight_rules import Speeds
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

if sys.argv[1] in ("mono2", "lanes"):  # repro.py's smoke cases
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "i24-deconflict"))
    from repro import case

    sc, prior = case(sys.argv[1], int(sys.argv[2]))
else:
    sc = load_scenario(sys.argv[1])
    sc = sc.with_uavs(int(sys.argv[2])) if int(sys.argv[2]) else sc
    prior = build_prior(sc.map)
a, b = int(sys.argv[3]), int(sys.argv[4])
p = make_allocation_plan(sc, prior=prior, seed=5000)
v = Speeds(**p["speeds_mps"])
routes = [u["waypoints_m"] for u in p["uavs"]]
t, pos, act = planned_positions(sc, routes, v)
c = conflicts(sc, pos, act)
pairs: dict = {}
for s, i, j in zip(*np.nonzero(c)):
    if i < j:
        pairs.setdefault((int(i), int(j)), []).append(int(s))
print("planned conflict pair-steps", int(c.sum()) // 2)
print({f"{i}-{j}": (len(s), s[:4]) for (i, j), s in pairs.items()})
d = np.hypot(*(pos[:, a] - pos[:, b]).T) / 1e3
both = act[:, a] & act[:, b]
print(f"{a}-{b} planned km:", [(int(s), round(float(d[s]), 2)) for s in np.flatnonzero(both)])
for k in (a, b):
    print(k, "first", np.round(np.array(routes[k][:4]) / 1e3, 1).tolist())
    print(k, "last", np.round(np.array(routes[k][-3:]) / 1e3, 1).tolist())
    at = [(int(s), *np.round(pos[s, k] / 1e3, 1).tolist()) for s in range(100, 115)]
    print(k, "planned km at steps 100-114", at)
