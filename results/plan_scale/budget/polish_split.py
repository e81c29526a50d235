"""i24-budget: how much of ``standard``'s plan is the polish and how much of the polish its
compiled kernel (a script, not a test).

``python results/plan_scale/budget/polish_split.py SEEDS`` (comma-separated, -1 the map's own
prior): after a warm-up plan, ``standard``'s plan of each prior with the CPU time of the whole
plan, of ``polish_routes`` (every polish stage) and of ``exposure_gains`` (the candidates'
scoring) inside it, and the kernel's calls; the rest of the polish is its Python (candidates
built, fits, airspace checks).
"""

import json
import os
import sys
import time

sys.path.insert(0, "tests/planning")

from effort_ab import _options

import poc_env.agents.planning.polish as pol
from poc_env._kernels import sensing
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

acc = {"polish": 0.0, "kernel": 0.0, "calls": 0}


class _Timed:
    def __getattr__(self, name):
        return getattr(sensing, name)

    def exposure_gains(self, *a):
        c0 = time.process_time()
        sensing.exposure_gains(*a)
        acc["kernel"] += time.process_time() - c0
        acc["calls"] += 1


def main(seeds):
    sc = load_scenario("paper_6_2")
    opt = _options("standard")
    make_allocation_plan(sc, options=opt)  # warm-up
    pol._sensing = _Timed()
    routine = pol.polish_routes

    def timed(*a, **k):
        c0 = time.process_time()
        try:
            return routine(*a, **k)
        finally:
            acc["polish"] += time.process_time() - c0

    pol.polish_routes = timed
    for seed in seeds:
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        acc.update(polish=0.0, kernel=0.0, calls=0)
        c0 = time.process_time()
        make_allocation_plan(sc, prior=prior, options=opt)
        rec = {"seed": seed, "plan_cpu_s": round(time.process_time() - c0, 3),
               **{k: round(v, 3) for k, v in acc.items()}, "load": os.getloadavg()[0]}  # fmt: skip
        print(json.dumps(rec), flush=True)


if __name__ == "__main__":
    main([int(s) for s in sys.argv[1].split(",")])
