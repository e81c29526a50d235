"""i24-relax: the default plan with and without the relaxation-patch start flown in the
environment (``allocation_plan`` with the options; validation priors only): planned and flown
POS over the rule-aware bound.

``python results/plan_scale/relax/fly.py MAP SEED[,SEED...] OUT.json``
"""

import json
import os
import sys
import time

from poc_env.agents.benchmarks.plan_scale import _flown
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.policies.allocation import AllocationPlanPolicy
from poc_env.config import load_scenario
from poc_env.theory.bound import rule_bound


def main(name: str, seeds: list[int], out: str) -> None:
    sc = load_scenario(name)
    recs = []
    for seed in seeds:
        prior = episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        for label, opt in (("default", PlanOptions()), ("relax", PlanOptions(relax_start=True))):
            pol = AllocationPlanPolicy()
            pol.options = opt
            t0 = time.perf_counter()
            flown, plan = _flown(sc, pol, seed, prior)
            wall = time.perf_counter() - t0
            recs.append({"map": name, "seed": seed, "variant": label, "start": plan["start"],
                         "planned": plan["posc"] / bound, "flown": flown / bound,
                         "wall_s": wall, "load": os.getloadavg()[0]})  # fmt: skip
            print(recs[-1], flush=True)
    with open(out + ".tmp", "w") as f:
        json.dump(recs, f)
    os.replace(out + ".tmp", out)


if __name__ == "__main__":
    main(sys.argv[1], [int(x) for x in sys.argv[2].split(",")], sys.argv[3])
