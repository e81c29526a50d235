"""Issue 24 (i24-losschain): the loss chain from the rule-aware bound to the flown POS of
``allocation_plan``, per prior (:mod:`poc_env.agents.benchmarks.losschain` defines the links).

Run from the repository root, one thread:

    OMP_NUM_THREADS=1 PYTHONPATH=. python results/plan_scale/losschain/losschain.py run \
        paper_6_2 --seeds 5000-5011 --own \
        --out results/plan_scale/losschain/paper_6_2_validation.json
    OMP_NUM_THREADS=1 PYTHONPATH=. python results/plan_scale/losschain/losschain.py run \
        large_400 --seeds 5000-5002 --groups \
        --out results/plan_scale/losschain/large_400_validation.json
    PYTHONPATH=. python results/plan_scale/losschain/losschain.py table \
        results/plan_scale/losschain/paper_6_2_validation.json ...

``run``: per seed, the prior of ``poc-env bench plan --scale`` / ``evaluate --random-priors``
(:func:`poc_env.agents.experiments.evaluate.episode_prior`), ``allocation_plan`` flown in the
environment on it (the whole fleet; with ``--groups`` also each fleet group alone, the rest of
the fleet removed, as tests/planning/quality4_ab.py ``fields`` does) and the chain of the plan
it flew. ``--own`` adds the scenario's own prior (episode seed 0). The records are rewritten
after every case. ``refine``: the planned chain (no flight) of the allocation plan with and
without its refinement, per seed. ``shift``: the plan's planned POS translated by parts of a
cell (the sample lattice's share of the line-geometry link). ``table``: the mean of every
value and link over the bound, per map and fleet/group, as a markdown table.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import sys
import time

import numpy as np

from poc_env.agents.benchmarks.losschain import LINKS, VALUES, fly_allocation, loss_chain
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.io import write_text_atomic
from poc_env.theory.probability_map import build_prior


def seeds_of(text: str) -> list[int]:
    """``A-B`` (inclusive) or ``A,B,C``."""
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",") if s]


def run(name: str, seeds: list[int], own: bool, groups: bool, out: str) -> None:
    sc = load_scenario(name)
    cases: list[tuple[str, int, np.ndarray]] = []
    if own:
        cases.append(("own", 0, build_prior(sc.map)))
    cases += [(str(s), s, episode_prior(sc, s)) for s in seeds]
    recs: list[dict] = []
    for label, seed, prior in cases:
        fleets = [("fleet", sc)]
        if groups:
            fleets += [
                (f"group {i} ({g.takeoff}, {g.count} UAVs)", dataclasses.replace(sc, fleet=(g,)))
                for i, g in enumerate(sc.fleet)
            ]
        for who, one in fleets:
            t0 = time.perf_counter()
            flown, plan = fly_allocation(one, prior, seed)
            t1 = time.perf_counter()
            ch = loss_chain(one, prior, plan, flown)
            t2 = time.perf_counter()
            b = ch["values"]["bound"]
            recs.append(
                {"map": name, "prior": label, "seed": seed, "who": who, **ch,
                 "start": plan.get("start"), "refined": plan.get("refined"),
                 "fly_s": t1 - t0, "chain_s": t2 - t1, "load": os.getloadavg()[0]}
            )  # fmt: skip
            print(f"{name} {label} {who}: bound {b:.4f} flown {flown:.4f} "
                  f"({flown / b:.3f}); " + ", ".join(
                      f"{k} {v / b:+.3f}" for k, v in ch["links"].items())
                  + f"; ideal tracks {ch['side']['ideal_tracks'] / b:.3f}"
                  f" ({t1 - t0:.0f} + {t2 - t1:.0f} s)", flush=True)  # fmt: skip
            write_text_atomic(out, json.dumps(recs, indent=1))


def refine(name: str, seeds: list[int], out: str) -> None:
    """The planned chain (no flight) of the allocation plan with its default refinement and
    with ``refine=0``, per seed: what the refinement (scored by W x length per cell) gains in
    the planners' model and in the sensor model."""
    from poc_env.agents.planning.allocation import REFINE, make_allocation_plan

    sc = load_scenario(name)
    recs: list[dict] = []
    for seed in seeds:
        prior = episode_prior(sc, seed)
        for passes in (REFINE, 0):
            plan = make_allocation_plan(sc, prior=prior, refine=passes)
            ch = loss_chain(sc, prior, plan)
            v, b = ch["values"], ch["values"]["bound"]
            recs.append(
                {"map": name, "prior": str(seed), "seed": seed, "who": f"refine {passes}", **ch,
                 "start": plan["start"], "refined": plan["refined"], "load": os.getloadavg()[0]}
            )  # fmt: skip
            print(f"{name} {seed} refine={passes} ({plan['start']}, kept refined: "
                  f"{plan['refined']}): cell model {v['cell_model'] / b:.3f}, planned "
                  f"{v['planned'] / b:.3f}, line geometry "
                  f"{ch['links']['line geometry'] / b:+.3f}", flush=True)  # fmt: skip
            write_text_atomic(out, json.dumps(recs, indent=1))


def shift(name: str, seeds: list[int], out: str) -> None:
    """The planned POS (sensor model) of the allocation plan translated as a whole by ``(d, d)``,
    ``d`` from 0 to 7/16 of a cell in sixteenths (across lines along x or y alike): how much the
    sample points' lattice alone moves the score (aliasing)."""
    from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
    from poc_env.theory.bound import rule_bound
    from poc_env.theory.probability_map import Grid

    sc = load_scenario(name)
    grid = Grid.from_config(sc.map)
    recs: list[dict] = []
    for seed in seeds:
        prior = episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        plan = make_allocation_plan(sc, prior=prior)
        paths = [
            np.vstack([u["takeoff_m"], np.reshape(u["waypoints_m"], (-1, 2)), u["landing_m"]])
            if u["waypoints_m"] else [] for u in plan["uavs"]
        ]  # fmt: skip
        dys = [grid.cell_m / 16 * i for i in range(8)]
        vals = [
            float(sum(sampled_sweep(sc, grid, prior, [p + np.array([dy, dy]) if len(p) else []
                                                      for p in paths])[0])) / bound
            for dy in dys
        ]  # fmt: skip
        recs.append({"map": name, "seed": seed, "shift_m": dys, "planned_over_bound": vals,
                     "load": os.getloadavg()[0]})  # fmt: skip
        print(f"{name} {seed}: " + " ".join(f"{v:.3f}" for v in vals)
              + f"; range {max(vals) - min(vals):.3f}, mean - unshifted "
              f"{statistics.mean(vals) - vals[0]:+.3f}", flush=True)  # fmt: skip
        write_text_atomic(out, json.dumps(recs, indent=1))
    gaps = [statistics.mean(r["planned_over_bound"]) - r["planned_over_bound"][0] for r in recs]
    ranges = [max(r["planned_over_bound"]) - min(r["planned_over_bound"]) for r in recs]
    print(f"{name}, {len(recs)} priors: range {min(ranges):.3f}-{max(ranges):.3f}, mean of the "
          f"shifts - unshifted {statistics.mean(gaps):+.4f}", flush=True)  # fmt: skip


def table(paths: list[str]) -> None:
    recs: list[dict] = []
    for p in paths:
        with open(p) as f:
            recs += json.load(f)
    keys = sorted({(r["map"], r["who"].split(" (")[0] if r["who"] != "fleet" else "fleet")
                   for r in recs})  # fmt: skip

    from poc_env.stats import ci95

    def share(rs, get) -> str:
        x = [get(r) / r["values"]["bound"] for r in rs]
        return f"{statistics.mean(x):.3f} ± {ci95(x):.3f}" if len(x) > 1 else f"{x[0]:.3f}"

    cols = []
    for m, who in keys:
        rs = [
            r for r in recs if r["map"] == m and (r["who"] == who or r["who"].startswith(who + " "))
        ]
        cols.append((f"`{m}` {who} ({len(rs)})", rs))
    print("| share of the rule-aware bound | " + " | ".join(c for c, _ in cols) + " |")
    print("| --- |" + " --- |" * len(cols))
    for i, v in enumerate(VALUES):
        print(f"| {v} | " + " | ".join(share(rs, lambda r, v=v: r["values"][v]) for _, rs in cols)
              + " |")  # fmt: skip
        if i < len(LINKS):
            k = LINKS[i]
            print(f"| - {k} | " + " | ".join(
                share(rs, lambda r, k=k: r["links"][k]) for _, rs in cols) + " |")  # fmt: skip
    side = ["ideal_tracks", "ceiling_pattern_full_effort", "ceiling_graded_footprint",
            "planned_inside_footprint", "ideal_plan_full_effort", "ideal_graded_footprint",
            "levels_1_cell", "levels_1_lines", "levels_2_cell", "levels_2_lines", "levels_3_cell",
            "levels_3_lines"]  # fmt: skip
    for k in side:
        if all(k in r["side"] for r in recs):
            print(f"| ({k}) | " + " | ".join(
                share(rs, lambda r, k=k: r["side"][k]) for _, rs in cols) + " |")  # fmt: skip
    split = [
        f"{a}_{b}" for a in ("sensor_law", "line_geometry") for b in ("shared", "single", "none")
    ]
    for k in split:
        if all(k in r["side"] for r in recs):
            print(f"| ({k}) | " + " | ".join(
                share(rs, lambda r, k=k: r["side"][k]) for _, rs in cols) + " |")  # fmt: skip
    for k in ("effort_share", "overlap_share", "coincident_share", "bound_sweep_share"):
        row = [statistics.mean(r["side"][k] for r in rs) for _, rs in cols]
        print(f"| ({k}) | " + " | ".join(f"{x:.3f}" for x in row) + " |")
    for k in ("in_map", "outside", "turns", "unused"):
        row = [statistics.mean(r["side"]["time_s"][k] / r["side"]["time_s"]["total"] for r in rs)
               for _, rs in cols]  # fmt: skip
        print(f"| (time: {k}) | " + " | ".join(f"{x:.3f}" for x in row) + " |")
    for _, rs in cols:
        a = [r["values"]["flown"] / r["values"]["bound"] for r in rs]
        load = [r["load"] for r in rs]
        print(f"{rs[0]['map']} {rs[0]['who']}: flown/bound {statistics.mean(a):.4f} (min "
              f"{min(a):.3f}, max {max(a):.3f}, >= 0.90: {sum(x >= 0.9 for x in a)}/{len(a)}); "
              f"load {min(load):.1f}-{max(load):.1f}")  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="fly allocation_plan per prior and write the chains")
    r.add_argument("map", help="scenario name, e.g. paper_6_2 or large_400")
    r.add_argument("--seeds", default="5000-5011", help="A-B (inclusive) or A,B,C")
    r.add_argument("--own", action="store_true", help="also the scenario's own prior")
    r.add_argument("--groups", action="store_true", help="also each fleet group alone")
    r.add_argument("--out", required=True, help="records (JSON), rewritten after every case")
    f = sub.add_parser("refine", help="planned chains with and without the refinement")
    f.add_argument("map")
    f.add_argument("--seeds", default="5000-5011", help="A-B (inclusive) or A,B,C")
    f.add_argument("--out", required=True)
    h = sub.add_parser("shift", help="planned POS of the plan translated by parts of a cell")
    h.add_argument("map")
    h.add_argument("--seeds", default="5000-5011", help="A-B (inclusive) or A,B,C")
    h.add_argument("--out", required=True)
    t = sub.add_parser("table", help="mean shares of the bound per map and fleet/group")
    t.add_argument("records", nargs="+")
    a = ap.parse_args(argv)
    if a.cmd == "run":
        run(a.map, seeds_of(a.seeds), a.own, a.groups, a.out)
    elif a.cmd == "refine":
        refine(a.map, seeds_of(a.seeds), a.out)
    elif a.cmd == "shift":
        shift(a.map, seeds_of(a.seeds), a.out)
    else:
        table(a.records)


if __name__ == "__main__":
    main(sys.argv[1:])
