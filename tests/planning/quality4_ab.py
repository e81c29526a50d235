"""Issue 24, session i24-quality4 (docs/PLANNER.md, "Excursions and what else was tried"): a
script, not a test.

``plan MAP SEED0 SEED1 VARIANT[,VARIANT...] OUT.json``
    Planned ``allocation_plan`` POS_C over the rule-aware bound on ``MAP``'s random priors
    (the priors of ``poc-env bench plan --scale``, seeds ``SEED0..SEED1-1``; the validation
    priors are 5000-5011 on ``paper_6_2`` and 5000-5002 on ``large_400``), every variant of
    :data:`VARIANTS` planned per seed in turn (interleaved); the records are rewritten after
    every seed and a paired summary against ``main`` is printed.
``fly MAP SEED0 SEED1 VARIANT OUT.json``
    The same flown in the environment (``main`` and ``VARIANT`` per seed).
``fields MAP SEED0 SEED1``
    Each fleet group alone (its UAVs only, the rest of the fleet removed): planned POS_C of
    ``allocation_plan``, its rule-aware bound with the sensor's spill (the environment's) and
    without it (``spill_m=0``), and the fleet's rule-aware and split bounds.
``bound OUT.json RECORDS.json [RECORDS.json ...]``
    The flown POSC of stored ``poc-env bench plan --scale`` records (results/plan_scale/*.json)
    over the rule-aware bound with merged airfields (``RuleBound.merged``, the bound before
    i24-tightbound) and over :func:`poc_env.theory.bound.rule_bound` (``split_bound``: without
    merged airfields), recomputed per seed from the seed's prior.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 python
tests/planning/quality4_ab.py plan large_400 5000 5003 main,excursions out.json``.
"""

from __future__ import annotations

import dataclasses
import json
import os
import statistics
import sys
import time

import numpy as np

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario
from poc_env.theory.bound import rule_bound

#: variants: the plan options' fields changed (``dataclasses.replace``; ``main`` changes none).
VARIANTS: dict[str, dict[str, object]] = {
    "main": {},
    "excursions": {"excursions": True},
    "angles45": {"angles": (45.0, 135.0)},
    "angles30": {"angles": (30.0, 60.0, 120.0, 150.0)},
    "angles45_excursions": {"angles": (45.0, 135.0), "excursions": True},
    "angles3_excursions": {"angles": (22.5, 45.0, 67.5), "excursions": True},
    "axis": {"axis": True},
    "axis_grow2": {"axis": True, "axis_grow": 2.0},
    # knobs of the existing planner
    "refine8": {"refine": 8},
    "refine_all_starts": {"refine_starts": 3, "refine_within": 0.0},
    "rounds4": {"rounds": 4, "chain_rounds": 4},
    "excursions_top24": {"excursions": True, "excursion_top": 24, "excursion_exact": 12},
}


def variant(name: str) -> PlanOptions:
    """The plan options of variant ``name``: the defaults with its fields changed."""
    return dataclasses.replace(PlanOptions(), **VARIANTS[name])  # type: ignore[arg-type]


def summary(recs: list[dict], key: str) -> None:
    from poc_env.stats import ci95

    names = sorted({r["variant"] for r in recs} - {"main"})
    base = {r["seed"]: r[key] / r["rule_bound"] for r in recs if r["variant"] == "main"}
    for v in names:
        d = np.array(
            [r[key] / r["rule_bound"] - base[r["seed"]] for r in recs
             if r["variant"] == v and r["seed"] in base]
        )  # fmt: skip
        if not len(d):
            continue
        half = ci95(d) if len(d) > 1 else float("nan")
        wtl = f"{(d > 1e-9).sum()}/{(abs(d) <= 1e-9).sum()}/{(d < -1e-9).sum()}"
        mean0 = statistics.mean(base.values())
        print(f"{v} - main ({key}/rule): {d.mean():+.4f} +- {half:.4f} {wtl} (n {len(d)}); "
              f"main mean {mean0:.4f}", flush=True)  # fmt: skip


def plan(name: str, seed0: int, seed1: int, names: list[str], out: str) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    recs = []
    for seed in range(seed0, seed1):
        prior = episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        for v in names:
            t0 = time.perf_counter()
            p = make_allocation_plan(sc, prior=prior, options=variant(v))
            dt = time.perf_counter() - t0
            recs.append(
                {"map": name, "seed": seed, "variant": v, "planned_posc": float(p["posc"]),
                 "rule_bound": bound, "start": p["start"], "refined": p["refined"],
                 "plan_s": dt, "load": os.getloadavg()[0]}
            )  # fmt: skip
            print(name, seed, v, round(p["posc"] / bound, 4), p["start"], p["refined"],
                  round(dt, 1), flush=True)  # fmt: skip
        with open(out, "w") as f:
            json.dump(recs, f, indent=1)
    summary(recs, "planned_posc")


def fly(name: str, seed0: int, seed1: int, v: str, out: str) -> None:
    from poc_env.agents.benchmarks.plan_scale import _flown as flown
    from poc_env.agents.policies.allocation import AllocationPlanPolicy

    def _flown(sc, seed, prior, options):  # plan_scale._flown with the policy's options
        pol = AllocationPlanPolicy()
        pol.options = options
        return flown(sc, pol, seed, prior)

    sc = load_scenario(name)
    recs = []
    for seed in range(seed0, seed1):
        prior = episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        for var in ("main", v):
            posc, p = _flown(sc, seed, prior, variant(var))
            recs.append(
                {"map": name, "seed": seed, "variant": var, "posc": posc,
                 "planned_posc": float(p["posc"]), "rule_bound": bound, "start": p.get("start"),
                 "plan_s": float(p.get("runtime_s", float("nan"))), "load": os.getloadavg()[0]}
            )  # fmt: skip
            print(name, seed, var, round(posc / bound, 4), flush=True)
        with open(out, "w") as f:
            json.dump(recs, f, indent=1)
    summary(recs, "posc")
    summary(recs, "planned_posc")


def fields(name: str, seed0: int, seed1: int) -> None:
    import dataclasses

    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    for seed in range(seed0, seed1):
        prior = episode_prior(sc, seed)
        sb = rule_bound(sc, prior)
        print(f"{name} {seed} fleet: rule {sb.merged:.4f} split {sb.upper:.4f} ({sb.how})")
        for i, g in enumerate(sc.fleet):
            one = dataclasses.replace(sc, fleet=(g,))
            p = make_allocation_plan(one, prior=prior)
            b, b0 = rule_bound(one, prior).upper, rule_bound(one, prior, spill_m=0.0).upper
            print(f"{name} {seed} group {i} ({g.takeoff}, {g.count} UAVs): planned "
                  f"{p['posc']:.4f}, rule {b:.4f} ({p['posc'] / b:.3f}), rule without spill "
                  f"{b0:.4f} ({p['posc'] / b0:.3f})", flush=True)  # fmt: skip


def bound(out: str, paths: list[str]) -> None:
    from poc_env.stats import ci95

    eps = []
    for p in paths:
        with open(p) as f:
            eps += json.load(f)["episodes"]
    recs = []
    for name in sorted({e["map"] for e in eps}):
        sc = load_scenario(name)
        for seed in sorted({e["seed"] for e in eps if e["map"] == name}):
            sb = rule_bound(sc, episode_prior(sc, seed))
            for e in eps:
                if e["map"] == name and e["seed"] == seed:
                    # records written before i24-tightbound hold the merged relaxation
                    rec = e.get("rule_bound_merged", e["rule_bound"])
                    assert abs(rec - sb.merged) < 1e-9 * max(1.0, sb.merged), e
                    recs.append({**e, "rule_bound": sb.merged, "split_bound": sb.upper,
                                 "split_how": sb.how})  # fmt: skip
            print(name, seed, round(sb.merged, 4), round(sb.upper, 4), sb.how, flush=True)
            with open(out, "w") as f:
                json.dump(recs, f, indent=1)
        for pol in sorted({e["policy"] for e in recs if e["map"] == name}):
            rs = [e for e in recs if e["map"] == name and e["policy"] == pol]
            a = np.array([e["posc"] / e["rule_bound"] for e in rs])
            b = np.array([e["posc"] / e["split_bound"] for e in rs])
            print(f"{name} {pol} (n {len(rs)}): flown/rule {a.mean():.4f} +- {ci95(a):.4f}, "
                  f"flown/split {b.mean():.4f} +- {ci95(b):.4f}, priors >= 0.90: "
                  f"{(a >= 0.9).sum()} / {(b >= 0.9).sum()}", flush=True)  # fmt: skip


if __name__ == "__main__":
    if sys.argv[1] == "bound":
        bound(sys.argv[2], sys.argv[3:])
        sys.exit()
    if sys.argv[1] == "fields":
        fields(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
        sys.exit()
    cmd, name, s0, s1, vs, out = sys.argv[1:7]
    if cmd == "plan":
        plan(name, int(s0), int(s1), vs.split(","), out)
    else:
        fly(name, int(s0), int(s1), vs, out)
