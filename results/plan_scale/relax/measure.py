"""i24-relax: the relaxation patches measured on validation priors (README).

``python results/plan_scale/relax/measure.py MAP SEED[,SEED...] VARIANT[;VARIANT...] OUT.json``
(an explicit list of seeds, so no range reaches the reported priors by mistake; seed -1: the
map's own prior; records resumed; rewritten atomically after every plan).

VARIANT ``start`` (or ``start+FIELD=VALUE...``, options changed as effort_ab's variants) is the
relaxation-patch start alone, unrefined (built as
``make_allocation_plan`` builds it: the allocation at each of ``relax_etas``, the patches,
field-mates fanned out, eq. 18 cuts; the best eta by W x length per cell), scored by
``sampled_sweep``; any other VARIANT is planned by ``make_allocation_plan`` with
``effort_ab._options(VARIANT)`` (e.g. ``default``, ``default+relax_start=1``,
``default+box_start=0+relax_start=1``, ``thorough+relax_start=1``).
"""

from __future__ import annotations

import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "planning"))

import numpy as np
from effort_ab import _options, fine_posc

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.theory.bound import rule_bound
from poc_env.theory.probability_map import build_prior


def start_alone(sc, prior, opt=None) -> dict:
    """The relaxation-patch start alone, as the planner builds it (no refine, no polish)."""
    from poc_env.agents.planning import allocation as al
    from poc_env.agents.planning.flight_rules import SPEED, plan_speeds, reserve_s
    from poc_env.agents.planning.options import PlanOptions
    from poc_env.agents.planning.relax_patches import out_and_back, relax_routes
    from poc_env.sim.core import takeoff_heading
    from poc_env.theory.probability_map import Grid

    opt = PlanOptions(relax_start=True) if opt is None else opt
    grid, u, v = Grid.from_config(sc.map), sc.uav, plan_speeds(sc, SPEED)
    ends = (sc.takeoff_m, sc.landing_m)
    takeoff, landing = (np.asarray(p, dtype=float).reshape(-1, 2) for p in ends)
    tau = out_and_back(grid, takeoff, landing, v)
    heading0 = takeoff_heading(grid.bounds, takeoff)
    w, law, n = sc.sensor.sweep_width_m, sc.sensor.law, len(takeoff)
    best = None
    for eta in opt.relax_etas:
        rs = relax_routes(prior, grid, w, law, v, takeoff, landing, tau, eta,
                          u.usable_endurance_s, u.max_turn_rate_rad_s, reserve_s(sc), heading0,
                          opt.levels, opt.relax_scales, opt)  # fmt: skip
        rs = al.fit_lawnmowers(rs, takeoff, landing, sc, v, heading0, opt)
        val = al._cell_pos(rs, takeoff, landing, prior, grid, w, law)
        if best is None or val > best[0]:
            best = (val, eta, rs)
    _, eta, rs = best
    paths = [[takeoff[k], *rs[k], landing[k]] if rs[k] else [] for k in range(n)]
    posc = float(sum(al.sampled_sweep(sc, grid, prior, paths)[0]))
    uavs = [{"takeoff_m": takeoff[k].tolist(), "landing_m": landing[k].tolist(),
             "waypoints_m": rs[k]} for k in range(n)]  # fmt: skip
    return {"posc": posc, "eta": eta, "start": "relax", "uavs": uavs}


def main(name: str, seeds: list[int], variants: list[str], out: str) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    recs = []
    if os.path.exists(out):
        with open(out) as f:
            recs = json.load(f)
    done = {(r["seed"], r["variant"]) for r in recs}
    for seed in seeds:
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        bound = None
        for variant in variants:
            if (seed, variant) in done:
                continue
            bound = rule_bound(sc, prior).upper if bound is None else bound
            t0 = time.perf_counter()
            if variant.split("+")[0] == "start":  # start[+field=value...]
                p = start_alone(sc, prior, _options(variant.replace("start", "default", 1)))
            else:
                p = make_allocation_plan(sc, prior=prior, options=_options(variant))
            dt = time.perf_counter() - t0
            rec = {"map": name, "seed": seed, "variant": variant, "planned_posc": float(p["posc"]),
                   "fine_posc": fine_posc(sc, prior, p), "rule_bound": bound,
                   "start": p.get("start"), "refined": p.get("refined"), "plan_s": dt,
                   "load": os.getloadavg()[0],
                   "uavs": [{k: u[k] for k in ("takeoff_m", "landing_m", "waypoints_m")}
                            for u in p["uavs"]]}  # fmt: skip
            recs.append(rec)
            print(name, seed, variant, rec["start"], rec["refined"],
                  round(rec["planned_posc"] / bound, 4), round(rec["fine_posc"] / bound, 4),
                  round(dt, 1), round(rec["load"], 1), flush=True)  # fmt: skip
            with open(out + ".tmp", "w") as f:
                json.dump(recs, f)
            os.replace(out + ".tmp", out)


if __name__ == "__main__":
    main(sys.argv[1], [int(x) for x in sys.argv[2].split(",")], sys.argv[3].split(";"),
         sys.argv[4])  # fmt: skip
