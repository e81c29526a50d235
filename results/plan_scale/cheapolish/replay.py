"""i24-cheapolish: screen cheaper polish variants by replay (a script, not a test).

``python results/plan_scale/cheapolish/replay.py SEEDS VARIANT[,VARIANT...] OUT.json``
(SEEDS ``a:b`` or comma-separated, -1 the map's own prior; ``paper_6_2``): per prior the default
plan (its CPU time), then each variant's polish stages (:data:`VARIANTS`) replayed from the
default plan's routes with :func:`~poc_env.agents.planning.polish.polish_for`, in turn in one
process: the polished POS (``polish_routes``' own score, ``sampled_sweep``'s to 1e-9) over the
rule-aware bound and the stages' CPU time; the estimated CPU ratio of the plan is (default +
stages) / default. Screening only: the choice is confirmed with ``effort_ab.py polish``.
``replay.py table FILE...``: the paired table of several runs' records together (each
record's ratio is paired within its own process).
"""

import json
import os
import statistics
import sys
import time

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.polish import KINDS, MOVES, polish_for
from poc_env.config import load_scenario
from poc_env.io import write_text_atomic
from poc_env.stats import ci95
from poc_env.theory.bound import rule_bound
from poc_env.theory.probability_map import build_prior

R4 = (0.25, 0.5, 1.0, 2.0)
R5 = (0.125, 0.25, 0.5, 1.0, 2.0)
B = (*KINDS, "block")
#: variant -> stages (passes, kinds, keyword arguments of polish_for)
VARIANTS = {
    "standard": [(2, KINDS, {"radii": R4}), (1, B, {"radii": R4})],
    "lines2_w8": [(2, KINDS, {"radii": R4}), (2, B, {"radii": R5})],
    "lines2_w8_f2": [(2, KINDS, {"radii": R4}), (2, B, {"radii": R5, "focus": 2})],
    "lines2_w8_f2_bw24": [
        (2, KINDS, {"radii": R4}),
        (2, B, {"radii": R5, "focus": 2, "block_windows": (2, 4)}),
    ],
    "lines2_w8_f2_br3": [
        (2, KINDS, {"radii": R4}),
        (2, B, {"radii": R5, "focus": 2, "block_radii": (0.125, 0.25, 0.5)}),
    ],
    "lines2_w8_f2_bw246_br3": [
        (2, KINDS, {"radii": R4}),
        (
            2,
            B,
            {
                "radii": R5,
                "focus": 2,
                "block_windows": (2, 4, 6),
                "block_radii": (0.125, 0.25, 0.5),
            },
        ),
    ],
    "p2f1_lines2_w8_f2": [(2, KINDS, {"radii": R4, "focus": 1}), (2, B, {"radii": R5, "focus": 2})],
    "p1_lines2_w8_f2": [(1, KINDS, {"radii": R4}), (2, B, {"radii": R5, "focus": 2})],
    "lines1_w8": [(2, KINDS, {"radii": R4}), (1, B, {"radii": R5})],
    "std_f2": [(2, KINDS, {"radii": R4, "focus": 2}), (1, B, {"radii": R4})],
    "p2_lines2_f2": [(2, KINDS, {"radii": R4}), (2, B, {"radii": R4, "focus": 2})],
    "lines3_w8_f2": [(2, KINDS, {"radii": R4}), (3, B, {"radii": R5, "focus": 2})],
    "lines3_w8_f1": [(2, KINDS, {"radii": R4}), (3, B, {"radii": R5, "focus": 1})],
    "lines2_w8_f1": [(2, KINDS, {"radii": R4}), (2, B, {"radii": R5, "focus": 1})],
    "p1_lines1_w8": [(1, KINDS, {"radii": R4}), (1, B, {"radii": R5})],
    "p1_lines2_w8_bw24": [
        (1, KINDS, {"radii": R4}),
        (2, B, {"radii": R5, "block_windows": (2, 4)}),
    ],
    "p1_lines2_w8_bw24_br3": [
        (1, KINDS, {"radii": R4}),
        (2, B, {"radii": R5, "block_windows": (2, 4), "block_radii": (0.125, 0.25, 0.5)}),
    ],
    "p1_lines2_w8_ng_bw24": [
        (1, KINDS, {"radii": R4}),
        (2, (*MOVES, "block"), {"radii": R5, "block_windows": (2, 4)}),
    ],
    "p0_lines2_w8_bw24": [(2, B, {"radii": R5, "block_windows": (2, 4)})],
    "p0_lines3_w8_bw24": [(3, B, {"radii": R5, "block_windows": (2, 4)})],
    "p0_lines3_w8to1_bw24": [(3, B, {"radii": R5[:-1], "block_windows": (2, 4)})],
    "p0_lines2_w8": [(2, B, {"radii": R5})],
    "p1_lines2": [(1, KINDS, {"radii": R4}), (2, B, {"radii": R4})],
    "p0_lines3_w8_ng_bw24": [(3, (*MOVES, "block"), {"radii": R5, "block_windows": (2, 4)})],
    "p1_lines1_w8_bw24": [
        (1, KINDS, {"radii": R4}),
        (1, B, {"radii": R5, "block_windows": (2, 4)}),
    ],
    "lines2_w8_f0": [(2, KINDS, {"radii": R4}), (2, B, {"radii": R5, "focus": 0})],
}


def seeds_of(arg: str) -> list[int]:
    if ":" in arg:
        a, b = arg.split(":")
        return list(range(int(a), int(b)))
    return [int(s) for s in arg.split(",")]


def main(seeds, names, out):
    sc = load_scenario("paper_6_2")
    recs = []
    if os.path.exists(out):
        with open(out) as f:
            recs = json.load(f)
    done = {(r["seed"], r["variant"]) for r in recs}
    make_allocation_plan(sc)  # warm-up
    polish_for(sc, [u["waypoints_m"] for u in make_allocation_plan(sc)["uavs"]],
               build_prior(sc.map), 1, moves=B)  # fmt: skip
    for seed in seeds:
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        c0 = time.process_time()
        base = make_allocation_plan(sc, prior=prior)
        c_default = time.process_time() - c0
        for v in names:
            if (seed, v) in done:
                continue
            routes = [u["waypoints_m"] for u in base["uavs"]]
            c0 = time.process_time()
            moves = 0
            for passes, kinds, kw in VARIANTS[v]:
                routes, val, stats = polish_for(sc, routes, prior, passes, moves=kinds, **kw)
                moves += stats["moves"]
            cpu = time.process_time() - c0
            recs.append({"seed": seed, "variant": v, "value": val / bound,
                         "default": float(base["posc"]) / bound, "cpu_polish": cpu,
                         "cpu_default": c_default, "ratio": (c_default + cpu) / c_default,
                         "moves": moves, "load": os.getloadavg()[0]})  # fmt: skip
            r = recs[-1]
            print(seed, v, f"{r['value']:.4f} polish {cpu:.2f} s ratio {r['ratio']:.2f} "
                  f"load {r['load']:.1f}", flush=True)  # fmt: skip
            write_text_atomic(out, json.dumps(recs, indent=1))
    table(recs)


def table(recs):
    base = {r["seed"]: r for r in recs if r["variant"] == "standard"}
    for v in dict.fromkeys(r["variant"] for r in recs):
        rs = [r for r in recs if r["variant"] == v and r["seed"] in base]
        d = [r["value"] - base[r["seed"]]["value"] for r in rs]
        cpu = [r["cpu_polish"] / base[r["seed"]]["cpu_polish"] for r in rs]
        ratio = [r["ratio"] for r in rs]
        if not d:
            continue
        half = ci95(d) if len(d) > 1 else float("nan")
        w = sum(x > 1e-9 for x in d), sum(abs(x) <= 1e-9 for x in d), sum(x < -1e-9 for x in d)
        print(f"{v:28s} n {len(d):2d} vs standard {statistics.mean(d):+.4f} +- {half:.4f} "
              f"{w[0]}/{w[1]}/{w[2]}; polish CPU / standard's {statistics.median(cpu):.2f}; "
              f"est. ratio median {statistics.median(ratio):.2f} max {max(ratio):.2f}")  # fmt: skip


if __name__ == "__main__":
    if sys.argv[1] == "table":  # table FILE...: the records of several runs together
        rows = []
        for path in sys.argv[2:]:
            with open(path) as f:
                rows += json.load(f)
        table(rows)
    else:
        main(seeds_of(sys.argv[1]), sys.argv[2].split(","), sys.argv[3])
