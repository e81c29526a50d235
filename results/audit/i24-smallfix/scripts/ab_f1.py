"""i24-smallfix, F1: default allocation plans of this checkout (a script, not a test).

``python ab_f1.py OUT.json``: ``paper_6_2``'s validation priors 5000-5009, 64 UAVs on the
audit's 150 km map (``/tmp/dayaudit/s150.yaml``) and ``sone_min.yaml``'s own prior; per case
the digest (as ``tests/planning/effort_ab.py digest``), planned POS_C, start, UAVs flying and
total flight hours. Run with main's and the branch's interpreter and compare the digests.
"""

import json
import os
import sys
import time
from pathlib import Path

import poc_env.agents.planning.allocation as al
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[4] / "tests" / "planning"))
from effort_ab import _digest

HERE = Path(__file__).resolve().parent.parent
CASES = [("paper_6_2", s, None) for s in range(5000, 5010)] + [
    ("/tmp/dayaudit/s150.yaml", None, 64),
    (str(HERE / "sone_min.yaml"), None, None),
]


def record(p: dict, t0: float) -> dict:
    """A plan's record: digest, planned POS_C, start, UAVs flying, flight hours, time, load."""
    return {
        "digest": _digest(p),
        "posc": p["posc"],
        "start": p["start"],
        "flying": sum(1 for u in p["uavs"] if u["waypoints_m"]),
        "hours": sum(u["flight_time_s"] for u in p["uavs"]) / 3600,
        "plan_s": time.perf_counter() - t0,
        "load": os.getloadavg()[0],
    }


if __name__ == "__main__":
    recs = {}
    for name, seed, nu in CASES:
        sc = load_scenario(name)
        if nu:
            sc = sc.with_uavs(nu)
        prior = None if seed is None else episode_prior(sc, seed)
        t = time.perf_counter()
        p = al.make_allocation_plan(sc, prior=prior)
        key = f"{os.path.basename(name)}:{seed}:{nu}"
        recs[key] = record(p, t)
        print(key, recs[key], flush=True)
    Path(sys.argv[1]).write_text(json.dumps(recs, indent=1))
