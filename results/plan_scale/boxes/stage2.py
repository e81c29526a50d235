"""i24-boxes (from results/plan_scale/lines/stage2.py, i24-lines): further polish stages tried
on stored plans (cache_plans.py), without re-planning.

``python results/plan_scale/boxes/stage2.py PLANS.json[,...] VARIANT[;VARIANT...] OUT.json``

A variant is ``kinds/radii/passes[/box_radii]``: ``kinds`` ``+``-joined names of polish moves
(``all`` for every kind of :data:`~poc_env.agents.planning.polish.KINDS`), ``radii`` and
``box_radii`` ``:``-joined sweep widths (empty or left out: the defaults), ``passes`` an
integer; e.g. ``box+stretch//4/2:4:8:16``. A variant may chain stages with ``>``
(``box+stretch//2>all+block/0.125:0.25:0.5:1:2/6``: the first stage's routes polished by the
second). Each stored
plan's routes are polished again exactly as the allocation planner's polish does it (same
speeds, budget, reserve, headings, airspace margins of ``thorough``), then scored on the 2 x 2
lattice (the planned POS) and on 8 x 8 points a cell (``effort_ab.fine_posc``); the gains over
the stored plan, paired per seed (Student's t 95 %), are printed and stored with the time
(and, with ``STAGE2_ROUTES=1`` in the environment, the polished routes, for chain_cached.py).
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "planning"))

from effort_ab import _options, fine_posc

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import sampled_sweep
from poc_env.agents.planning.flight_rules import (
    SPEED,
    plan_speeds,
    reserve_s,
)
from poc_env.agents.planning.polish import BOX_RADII, KINDS, RADII, polish_routes
from poc_env.agents.planning.refine import Airspace
from poc_env.config import load_scenario
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior


def t95(xs: list[float]) -> str:
    if len(xs) < 2:
        return f"{xs[0]:+.4f}" if xs else "-"
    m = statistics.mean(xs)
    from scipy import stats

    h = stats.t.ppf(0.975, len(xs) - 1) * statistics.stdev(xs) / len(xs) ** 0.5
    w = sum(x > 1e-9 for x in xs)
    lo = sum(x < -1e-9 for x in xs)
    return f"{m:+.4f} ± {h:.4f} ({w} / {len(xs) - w - lo} / {lo})"


def polish_again(sc, prior, uavs, variant: str, opt):
    moves, total = 0, 0
    stats: dict = {}
    for stage in variant.split(">"):
        routes, val, st = polish_stage(sc, prior, uavs, stage, opt)
        uavs = [{**u, "waypoints_m": routes[k]} for k, u in enumerate(uavs)]
        total += st["passes"]
        moves += st["moves"]
        for key in ("block_moves", "box_moves"):
            if key in st:
                stats[key] = stats.get(key, 0) + st[key]
    return routes, val, {**stats, "passes": total, "moves": moves}


def polish_stage(sc, prior, uavs, variant: str, opt):
    kinds_s, radii_s, passes_s, *box_s = variant.split("/")
    kinds = []
    for k in kinds_s.split("+"):
        kinds += list(KINDS) if k == "all" else [k]
    radii = tuple(float(r) for r in radii_s.split(":")) if radii_s else RADII
    box_radii = tuple(float(r) for r in box_s[0].split(":")) if box_s and box_s[0] else BOX_RADII
    grid = Grid.from_config(sc.map)
    takeoff = np.array([u["takeoff_m"] for u in uavs])
    landing = np.array([u["landing_m"] for u in uavs])
    u = sc.uav
    return polish_routes(
        [x["waypoints_m"] for x in uavs], takeoff, landing, prior, grid, sc.sensor,
        plan_speeds(sc, SPEED), u.usable_endurance_s, u.max_turn_rate_rad_s, reserve_s(sc),
        passes=int(passes_s), radii=radii, moves=tuple(dict.fromkeys(kinds)), box_radii=box_radii,
        headings=takeoff_heading(grid.bounds, takeoff),
        airspace=Airspace(sc.episode.dt_s, opt.separation_margin * sc.constraints.safety_distance_m,
                          opt.range_margin * sc.comms.range_m, sc.comms.min_neighbours),
    )  # fmt: skip


def _load(path: str):
    with open(path) as f:
        return json.load(f)


def main(plans: list[str], variants: list[str], out: str) -> None:
    opt = _options("thorough")
    recs = _load(out) if os.path.exists(out) else []
    done = {(r["seed"], r["variant"]) for r in recs}
    stored = [r for p in plans for r in _load(p)]
    for r in stored:
        sc = load_scenario(r["map"])
        prior = build_prior(sc.map) if r["seed"] < 0 else episode_prior(sc, r["seed"])
        grid = Grid.from_config(sc.map)
        for v in variants:
            if (r["seed"], v) in done:
                continue
            t0 = time.perf_counter()
            routes, _, stats = polish_again(sc, prior, r["uavs"], v, opt)
            dt = time.perf_counter() - t0
            paths = [[u["takeoff_m"], *routes[k], u["landing_m"]] if routes[k] else []
                     for k, u in enumerate(r["uavs"])]  # fmt: skip
            planned = float(sum(sampled_sweep(sc, grid, prior, paths)[0]))
            new = {"uavs": [{**u, "waypoints_m": routes[k]} for k, u in enumerate(r["uavs"])]}
            fine = fine_posc(sc, prior, new)
            b = r["rule_bound"]
            rec = {"map": r["map"], "seed": r["seed"], "variant": v, "planned_posc": planned,
                   "fine_posc": fine, "rule_bound": b, "base_planned": r["planned_posc"],
                   "base_fine": r["fine_posc"], "moves": stats["moves"],
                   "passes": stats["passes"], "stage_s": dt,
                   "base_plan_s": r.get("plan_s", r.get("base_plan_s")),
                   "load": os.getloadavg()[0]}  # fmt: skip
            if os.environ.get("STAGE2_ROUTES"):  # the routes too (for chain_cached.py)
                rec["uavs"] = new["uavs"]
            recs.append(rec)
            print(r["map"], r["seed"], v, f"{(planned - r['planned_posc']) / b:+.4f}",
                  f"{(fine - r['fine_posc']) / b:+.4f}", stats, round(dt, 1),
                  round(rec["load"], 1), flush=True)  # fmt: skip
            with open(out + ".tmp", "w") as f:
                json.dump(recs, f, indent=1)
            os.replace(out + ".tmp", out)
    for v in variants:
        sub = [r for r in recs if r["variant"] == v]
        g2 = [(r["planned_posc"] - r["base_planned"]) / r["rule_bound"] for r in sub]
        g8 = [(r["fine_posc"] - r["base_fine"]) / r["rule_bound"] for r in sub]
        ts = [r["stage_s"] / r["base_plan_s"] for r in sub]
        print(
            f"{v}: n={len(sub)} 2x2 {t95(g2)}  8x8 {t95(g8)}  "
            f"time/plan median {statistics.median(ts) if ts else 0:.2f}"
        )


if __name__ == "__main__":
    main(sys.argv[1].split(","), sys.argv[2].split(";"), sys.argv[3])
