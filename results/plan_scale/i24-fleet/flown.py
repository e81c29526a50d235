"""i24-fleet: the default allocation plan flown (a script, not a test; run it in each tree).

``python flown.py SCENARIO N [N ...]`` (from the checkout; SCENARIO as in fleet.py)
    Per N: the ``allocation_plan`` episode (seed 5000, the scenario's own prior) through
    results/plan_scale/i24-deconflict/repro.py's ``flown_collisions``: flown POSC, collision
    UAV-steps (all / away from the fields), one JSON line.
"""

import json
import sys

sys.path.insert(0, "results/plan_scale/i24-deconflict")
sys.path.insert(0, "results/plan_scale/i24-fleet")
from fleet import scenario
from repro import flown_collisions

for n in map(int, sys.argv[2:]):
    sc, prior = scenario(sys.argv[1], n)
    steps, away, posc = flown_collisions(sc, prior)
    rec = {"case": sys.argv[1], "uavs": n, "flown_posc": round(posc, 4), "collision_steps": steps,
           "away_from_fields": away}  # fmt: skip
    print(json.dumps(rec), flush=True)
