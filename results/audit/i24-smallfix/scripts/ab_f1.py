"""i24-smallfix, F1: default allocation plans of this checkout (a script, not a test).

``python ab_f1.py OUT.json``: ``paper_6_2``'s validation priors 5000-5009, 64 UAVs on the
audit's 150 km map (``/tmp/dayaudit/s150.yaml``) and ``sone_min.yaml``'s own prior; per case
the digest (as ``tests/planning/effort_ab.py digest``), planned POS_C, start, UAVs flying and
total flight hours. Run with main's and the branch's interpreter and compare the digests.
"""

import hashlib
import json
import os
import sys
import time
from pathlib import Path

import poc_env.agents.planning.allocation as al
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario

HERE = Path(__file__).resolve().parent.parent
CASES = [("paper_6_2", s, None) for s in range(5000, 5010)] + [
    ("/tmp/dayaudit/s150.yaml", None, 64),
    (str(HERE / "sone_min.yaml"), None, None),
]

recs = {}
for name, seed, nu in CASES:
    sc = load_scenario(name)
    if nu:
        sc = sc.with_uavs(nu)
    prior = None if seed is None else episode_prior(sc, seed)
    t = time.perf_counter()
    p = al.make_allocation_plan(sc, prior=prior)
    h = hashlib.sha256()
    for u in p["uavs"]:
        h.update(repr([[float(a), float(b)] for a, b in u["waypoints_m"]]).encode())
    h.update(repr(float(p["posc"])).encode())
    key = f"{os.path.basename(name)}:{seed}:{nu}"
    recs[key] = {
        "digest": h.hexdigest(),
        "posc": p["posc"],
        "start": p["start"],
        "flying": sum(1 for u in p["uavs"] if u["waypoints_m"]),
        "hours": sum(u["flight_time_s"] for u in p["uavs"]) / 3600,
        "plan_s": time.perf_counter() - t,
        "load": os.getloadavg()[0],
    }
    print(key, recs[key], flush=True)
Path(sys.argv[1]).write_text(json.dumps(recs, indent=1))
