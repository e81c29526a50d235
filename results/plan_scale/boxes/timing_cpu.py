"""i24-boxes (from results/plan_scale/lines/timing_cpu.py, i24-lines; the routes stored too,
so a plan can be compared with a cached one): the planning time of variants as CPU time of
the process (``time.process_time``, one thread), which the machine's load barely moves,
beside the wall time; each prior's plans of all variants in turn.

``python results/plan_scale/boxes/timing_cpu.py MAP SEED[,SEED...] VARIANT[,VARIANT...] OUT.json``
"""

from __future__ import annotations

import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "planning"))

from effort_ab import _options

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior


def main(name: str, seeds: list[int], variants: list[str], out: str) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    recs = []
    for seed in seeds:
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        for v in variants:
            c0, w0 = time.process_time(), time.perf_counter()
            p = make_allocation_plan(sc, prior=prior, options=_options(v))
            cpu, wall = time.process_time() - c0, time.perf_counter() - w0
            recs.append({"map": name, "seed": seed, "variant": v, "posc": float(p["posc"]),
                         "cpu_s": cpu, "wall_s": wall, "load": os.getloadavg()[0],
                         "waypoints_m": [u["waypoints_m"] for u in p["uavs"]],
                         "polish": p["optimizer"]["settings"].get("polish")})  # fmt: skip
            print(name, seed, v, round(p["posc"], 6), round(cpu, 1), round(wall, 1),
                  round(os.getloadavg()[0], 1), flush=True)  # fmt: skip
            with open(out + ".tmp", "w") as f:
                json.dump(recs, f, indent=1)
            os.replace(out + ".tmp", out)


if __name__ == "__main__":
    main(sys.argv[1], [int(x) for x in sys.argv[2].split(",")], sys.argv[3].split(","),
         sys.argv[4])  # fmt: skip
