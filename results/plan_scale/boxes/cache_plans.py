"""i24-lines: plan a variant on a map's priors and store the whole plans (routes included),
so that later polish stages can be tried on them without re-planning (README).

``python results/plan_scale/lines/cache_plans.py MAP SEED[,SEED...] VARIANT OUT.json``
(an explicit list of seeds, so no range reaches the reported priors by mistake; seed -1:
the map's own prior; records resumed; rewritten atomically after every seed).
"""

from __future__ import annotations

import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "planning"))

from effort_ab import _options, fine_posc

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.theory.bound import rule_bound
from poc_env.theory.probability_map import build_prior


def _load(path: str):
    with open(path) as f:
        return json.load(f)


def main(name: str, seeds: list[int], variant: str, out: str) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    recs = _load(out) if os.path.exists(out) else []
    done = {r["seed"] for r in recs}
    for seed in seeds:
        if seed in done:
            continue
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        t0 = time.perf_counter()
        p = make_allocation_plan(sc, prior=prior, options=_options(variant))
        dt = time.perf_counter() - t0
        rec = {"map": name, "seed": seed, "variant": variant, "planned_posc": float(p["posc"]),
               "fine_posc": fine_posc(sc, prior, p), "rule_bound": bound, "plan_s": dt,
               "load": os.getloadavg()[0],
               "uavs": [{k: u[k] for k in ("takeoff_m", "landing_m", "waypoints_m",
                                           "flight_time_s")} for u in p["uavs"]]}  # fmt: skip
        recs.append(rec)
        print(name, seed, variant, round(rec["planned_posc"] / bound, 4),
              round(rec["fine_posc"] / bound, 4), round(dt, 1), round(rec["load"], 1),
              flush=True)  # fmt: skip
        with open(out + ".tmp", "w") as f:
            json.dump(recs, f)
        os.replace(out + ".tmp", out)


if __name__ == "__main__":
    main(sys.argv[1], [int(x) for x in sys.argv[2].split(",")], sys.argv[3], sys.argv[4])
