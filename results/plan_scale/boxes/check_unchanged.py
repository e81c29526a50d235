"""i24-boxes: ``thorough`` planned with this branch's code (timing_cpu.py's records) against
the plans cache_plans.py made of the same priors before any change of the branch: every
UAV's waypoints and the planned POS equal (``check`` lines).

``python results/plan_scale/boxes/check_unchanged.py TIMING.json CACHE.json``
"""

import json
import sys


def main(timing: str, cache: str) -> None:
    with open(timing) as f:
        now = [r for r in json.load(f) if r["variant"] == "thorough"]
    with open(cache) as f:
        before = {r["seed"]: r for r in json.load(f)}
    for r in now:
        b = before[r["seed"]]
        same = [u["waypoints_m"] for u in b["uavs"]] == r["waypoints_m"]
        print("check", r["map"], r["seed"], "waypoints equal:", same,
              "planned POS equal:", b["planned_posc"] == r["posc"])  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
