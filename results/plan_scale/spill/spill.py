"""Issue 24, i24-spill: the spill-charged bound (:mod:`poc_env.theory.spill_bound`) beside the
rule-aware bound on the stored flights' priors; a script, not a test.

``bounds MAP SEED0 SEED1 OUT.json``
    Per prior seed (the priors of ``poc-env bench plan --scale``): the rule-aware bound
    (``rule_bound(...).upper``), the spill-charged bound and the program's value per
    configuration, seconds and the load; the records are rewritten after every seed.
``groups MAP SEED0 SEED1 OUT.json``
    The same for each fleet group alone (its UAVs only), also with the wider charge of
    :data:`GROUP_CONFIGS`.
``variants MAP SEED0 SEED1 OUT.json``
    The fleet's program under each configuration of :data:`VARIANTS` (which cells are charged:
    with and without ``alone``, ``theta`` 1 and 0.75).
``table BOUNDS.json [BOUNDS.json ...]``
    The stored flights (results/plan_scale/lines/flown_{large_400,paper_6_2}.json and
    results/plan_scale/{large_400,paper_6_2}.json) over both bounds: mean +- Student's t 95 %,
    priors at or above 0.90, per map and policy/variant; then the groups' records.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 python
results/plan_scale/spill/spill.py bounds large_400 0 25 results/plan_scale/spill/large_400.json``.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
import time

import numpy as np

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.io import write_text_atomic
from poc_env.stats import ci95
from poc_env.theory.spill_bound import CONFIGS, spill_bound

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
FLIGHTS = {
    "large_400": [
        "results/plan_scale/lines/flown_large_400.json",
        "results/plan_scale/large_400.json",
    ],
    "paper_6_2": [
        "results/plan_scale/lines/flown_paper_6_2.json",
        "results/plan_scale/paper_6_2.json",
    ],
}


#: each group alone is also bounded with a wider charge (cells from 0.75 T_u of near transit).
GROUP_CONFIGS = (*CONFIGS, (1.0, 0.75, True))


#: the fleet's charge variants of ``variants``.
VARIANTS = ((1.0, 1.0, True), (1.0, 1.0, False), (1.0, 0.75, True))


def _record(sc, prior, configs=CONFIGS, **extra) -> dict:
    t0 = time.perf_counter()
    b = spill_bound(sc, prior, configs=configs)
    return {
        **extra,
        "rule_bound": b.rule,
        "spill_bound": b.upper,
        "program": {f"r1={k[0]:g},theta={k[1]:g},alone={k[2]}": v for k, v in b.by_config.items()},
        "how": b.how,
        "seconds": time.perf_counter() - t0,
        "load": os.getloadavg()[0],
    }


def bounds(name: str, s0: int, s1: int, out: str, groups: bool = False, cfg=None) -> None:
    sc = load_scenario(name)
    recs: list[dict] = []
    for seed in range(s0, s1):
        prior = episode_prior(sc, seed)
        fleets = [(None, sc)]
        if groups:
            fleets = [(f"{g.takeoff}", dataclasses.replace(sc, fleet=(g,))) for g in sc.fleet]
        for label, one in fleets:
            r = _record(one, prior, cfg or (GROUP_CONFIGS if groups else CONFIGS), map=name,
                        seed=seed, group=label)  # fmt: skip
            recs.append(r)
            print(name, seed, label, round(r["rule_bound"], 5), round(r["spill_bound"], 5),
                  f"{1 - r['spill_bound'] / r['rule_bound']:.4f}", r["how"],
                  round(r["seconds"], 1), flush=True)  # fmt: skip
            write_text_atomic(out, json.dumps(recs, indent=1))


def _flights(name: str) -> list[dict]:
    eps: list[dict] = []
    for p in FLIGHTS[name]:
        with open(os.path.join(ROOT, p)) as f:
            d = json.load(f)
        for e in d["episodes"] if isinstance(d, dict) else d:
            eps.append({**e, "label": e.get("variant", e.get("policy")), "file": p})
    return eps


def table(paths: list[str]) -> None:
    recs: list[dict] = []
    for p in paths:
        with open(p) as f:
            recs += json.load(f)
    fleet = {(r["map"], r["seed"]): r for r in recs if r.get("group") is None and
             len(r["program"]) == len(CONFIGS)}  # fmt: skip
    print("| map | flights | n | over rule-aware | >= 0.90 | over spill-charged | >= 0.90 |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name in sorted({m for m, _ in fleet}):
        eps = [e for e in _flights(name) if (name, e["seed"]) in fleet]
        for label in sorted({(e["file"], e["label"]) for e in eps}):
            rs = [e for e in eps if (e["file"], e["label"]) == label]
            for e in rs:  # the stored bound is the one recomputed here
                rb = fleet[(name, e["seed"])]["rule_bound"]
                assert abs(e["rule_bound"] - rb) < 1e-9, (e["seed"], e["rule_bound"], rb)
            a = np.array([e["posc"] / e["rule_bound"] for e in rs])
            b = np.array([e["posc"] / fleet[(name, e["seed"])]["spill_bound"] for e in rs])
            print(f"| {name} | {os.path.basename(label[0])} {label[1]} | {len(rs)} | "
                  f"{a.mean():.4f} ± {ci95(a):.4f} | {(a >= 0.9).sum()} | "
                  f"{b.mean():.4f} ± {ci95(b):.4f} | {(b >= 0.9).sum()} |")  # fmt: skip
        fr = [r for (m, _), r in fleet.items() if m == name]
        cut = np.array([1 - r["spill_bound"] / r["rule_bound"] for r in fr])
        print(f"{name}: bound removed by the charge over {len(fr)} priors: mean {cut.mean():.5f}, "
              f"max {cut.max():.5f}; program seconds median "
              f"{np.median([r['seconds'] for r in fr]):.1f}, load "
              f"{min(r['load'] for r in fr):.1f}-{max(r['load'] for r in fr):.1f}")  # fmt: skip
    for r in recs:
        if r.get("group") is None and len(r["program"]) == len(VARIANTS):
            print(f"{r['map']} {r['seed']} fleet variants: rule {r['rule_bound']:.5f}, " +
                  ", ".join(f"{k}: {v:.5f}" for k, v in r["program"].items()))  # fmt: skip
        if r.get("group") is not None:
            prog = ", ".join(
                f"{k}: {1 - min(v, r['rule_bound']) / r['rule_bound']:.3f}"
                for k, v in r["program"].items()
            )
            print(f"{r['map']} {r['seed']} group {r['group']}: rule {r['rule_bound']:.4f}, "
                  f"spill-charged {r['spill_bound']:.4f}, removed "
                  f"{1 - r['spill_bound'] / r['rule_bound']:.3f} ({prog})")  # fmt: skip


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "table":
        table(sys.argv[2:])
    else:
        cfg = VARIANTS if cmd == "variants" else None
        bounds(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5], cmd == "groups", cfg)
