"""i24-relax: the default plan's CPU time with and without the relaxation-patch start,
interleaved in one process (``python results/plan_scale/relax/timing_cpu.py MAP SEED[,SEED]
ROUNDS OUT.json``; validation priors only, -1 the map's own prior)."""

import json
import os
import sys
import time

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior


def main(name: str, seeds: list[int], rounds: int, out: str) -> None:
    sc = load_scenario(name)
    recs = []
    for seed in seeds:
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        for r in range(rounds):
            pair = (("default", PlanOptions()), ("relax", PlanOptions(relax_start=True)))
            for label, opt in pair:
                t0 = time.process_time()
                p = make_allocation_plan(sc, prior=prior, options=opt)
                cpu = time.process_time() - t0
                recs.append({"map": name, "seed": seed, "round": r, "variant": label,
                             "cpu_s": cpu, "posc": p["posc"], "start": p["start"],
                             "load": os.getloadavg()[0]})  # fmt: skip
                print(name, seed, r, label, round(cpu, 2), p["start"], round(recs[-1]["load"], 1),
                      flush=True)  # fmt: skip
    with open(out + ".tmp", "w") as f:
        json.dump(recs, f)
    os.replace(out + ".tmp", out)


if __name__ == "__main__":
    main(sys.argv[1], [int(x) for x in sys.argv[2].split(",")], int(sys.argv[3]), sys.argv[4])
