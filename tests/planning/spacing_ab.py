"""Issue 24's dense-spacing figures (docs/PLANNER.md, results/plan_scale/dense_spacing/): a
script, not a test.

``MAP SEED0 SEED1 OUT.json``
    Flown ``allocation_plan`` over the rule-aware bound on ``MAP``'s random priors (episode
    seeds ``SEED0..SEED1-1``, the priors of ``poc-env bench plan --scale``), planned with and
    without the coverage boxes' spacings below one sweep width
    (``PlanOptions.dense_spacings``; without them the planner
    is main's), interleaved per seed; the records are rewritten after every seed.
``timing N``
    Planning time on ``paper_6_2``'s own prior (the 2 s target's case) with and without them,
    ``N`` interleaved pairs in one process after two warm-up plans; medians and pair ratios.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 python
tests/planning/spacing_ab.py paper_6_2 0 50 results/plan_scale/dense_spacing/paper_6_2.json``.
"""

from __future__ import annotations

import json
import os
import sys
import time

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario
from poc_env.theory.bound import rule_bound


def _flown(sc, seed, prior, options):
    """The allocation policy with ``options`` flown on ``sc`` with ``prior``: POSC, plan."""
    from poc_env.agents.benchmarks.plan_scale import _flown as flown
    from poc_env.agents.policies.allocation import AllocationPlanPolicy

    pol = AllocationPlanPolicy()
    pol.options = options
    return flown(sc, pol, seed, prior)


def main(name: str, seed0: int, seed1: int, out: str) -> None:
    dense = PlanOptions().dense_spacings
    sc = load_scenario(name)
    recs = []
    for seed in range(seed0, seed1):
        prior = episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        for variant, sp in (("main", ()), ("dense", dense)):
            t0 = time.perf_counter()
            posc, plan = _flown(sc, seed, prior, PlanOptions(dense_spacings=sp))
            recs.append(
                {"map": name, "seed": seed, "variant": variant, "posc": posc,
                 "rule_bound": bound, "planned_posc": float(plan["posc"]),
                 "start": plan.get("start"), "plan_s": float(plan.get("runtime_s", float("nan"))),
                 "load": os.getloadavg()[0]}
            )  # fmt: skip
            print(name, seed, variant, round(posc / bound, 4), plan.get("start"),
                  round(time.perf_counter() - t0, 1), flush=True)  # fmt: skip
        with open(out, "w") as f:
            json.dump(recs, f, indent=1)


def timing(n: int) -> None:
    import statistics

    from poc_env.agents.planning.allocation import make_allocation_plan

    dense = PlanOptions().dense_spacings
    sc = load_scenario("paper_6_2")
    make_allocation_plan(sc, refine=0)
    make_allocation_plan(sc)
    ts: dict[str, list[float]] = {"main": [], "dense": []}
    for r in range(n):
        for variant, sp in (("main", ()), ("dense", dense)):
            t0 = time.perf_counter()
            plan = make_allocation_plan(sc, options=PlanOptions(dense_spacings=sp))
            ts[variant].append(time.perf_counter() - t0)
            print(r, variant, round(ts[variant][-1], 3), round(plan["posc"], 4), "load",
                  round(os.getloadavg()[0], 2), flush=True)  # fmt: skip
    ratios = [round(b / a, 3) for a, b in zip(ts["main"], ts["dense"])]
    print({v: round(statistics.median(x), 3) for v, x in ts.items()}, "pair ratios", ratios)


if __name__ == "__main__":
    if sys.argv[1] == "timing":
        timing(int(sys.argv[2]))
    else:
        main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])
