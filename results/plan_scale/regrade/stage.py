"""i24-regrade: the regrade stage tried on stored plans (results/plan_scale/lines/cache_plans.py),
without re-planning (README).

``python results/plan_scale/regrade/stage.py PLANS.json[,...] VARIANT[;VARIANT...] OUT.json``

A variant is a sequence of stages (:func:`run_variant`), e.g.
``rg=2/0:-1:1:2/2/2/+polish=2+lines=1``: the regrade ``passes/counts/sweeps/min_lines/radii``
(``counts`` ``:``-joined integers; ``radii`` ``:``-joined sweep widths, empty for the
default), then ``standard``'s two polish stages. Each stored plan's routes are regraded (and
polished) as the allocation planner does it (``polish_for(..., routine=regrade_routes)``:
the plan's speeds, budget, reserve, headings and airspace margins), then scored on the 2 x 2
lattice (the planned POS) and on 8 x 8 points a cell (``effort_ab.fine_posc``); the gains over
the stored plan, paired per seed (Student's t 95 %), are printed and stored with the stage's
CPU time.
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "planning"))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "lines"))

from effort_ab import fine_posc
from stage2 import t95

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import sampled_sweep
from poc_env.agents.planning.polish import KINDS, polish_for
from poc_env.agents.planning.regrade import SEARCH_RADII, regrade_routes
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior


def run_variant(sc, prior, routes, variant: str):
    """``variant``: steps joined by ``+``, in order: ``rg=passes/counts/sweeps/min_lines/radii``
    (the regrade; a last ``/q``: with the lines clipped to their strips' mass quantiles too),
    ``polish=N`` (N passes of the polish with its grade moves, as
    ``standard``'s first stage), ``lines=N`` (N passes of the second polish, as ``standard``'s
    second stage); a bare ``passes/counts/...`` is ``rg=...``."""
    stats: dict = {}
    for step in variant.split("+"):
        key, _, val = step.rpartition("=")
        key = key or "rg"
        if key == "rg":
            passes, counts, sweeps, min_lines, radii, *flags = val.split("/")
            kw = {
                "counts": tuple(int(x) for x in counts.split(":")),
                "sweeps": int(sweeps),
                "min_lines": int(min_lines),
                "quantiles": "q" in flags,
                "radii": tuple(float(r) for r in radii.split(":")) if radii else SEARCH_RADII,
            }
            if int(passes):
                routes, _, st = polish_for(sc, routes, prior, int(passes), routine=regrade_routes,
                                           **kw)  # fmt: skip
                stats = {**stats, **{f"rg_{k}": v for k, v in st.items()}}
        elif key == "polish":
            routes, _, st = polish_for(sc, routes, prior, int(val), moves=KINDS)
            stats = {**stats, "polish_moves": st["moves"]}
        elif key == "lines":
            routes, _, st = polish_for(sc, routes, prior, int(val), moves=(*KINDS, "block"))
            stats = {**stats, "lines_moves": st["moves"]}
        else:
            raise ValueError(step)
    return routes, stats


def _load(path: str):
    with open(path) as f:
        return json.load(f)


def main(plans: list[str], variants: list[str], out: str) -> None:
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
            c0 = time.process_time()
            routes, stats = run_variant(sc, prior, [u["waypoints_m"] for u in r["uavs"]], v)
            dc = time.process_time() - c0
            paths = [[u["takeoff_m"], *routes[k], u["landing_m"]] if routes[k] else []
                     for k, u in enumerate(r["uavs"])]  # fmt: skip
            planned = float(sum(sampled_sweep(sc, grid, prior, paths)[0]))
            new = {"uavs": [{**u, "waypoints_m": routes[k]} for k, u in enumerate(r["uavs"])]}
            fine = fine_posc(sc, prior, new)
            b = r["rule_bound"]
            rec = {"map": r["map"], "seed": r["seed"], "variant": v, "base": r["variant"],
                   "planned_posc": planned, "fine_posc": fine, "rule_bound": b,
                   "base_planned": r["planned_posc"], "base_fine": r["fine_posc"],
                   "stats": stats, "stage_cpu_s": dc, "load": os.getloadavg()[0]}  # fmt: skip
            if os.environ.get("STAGE_ROUTES"):
                rec["uavs"] = new["uavs"]
            recs.append(rec)
            print(r["map"], r["seed"], v, f"{(planned - r['planned_posc']) / b:+.4f}",
                  f"{(fine - r['fine_posc']) / b:+.4f}", stats, round(dc, 2),
                  round(rec["load"], 1), flush=True)  # fmt: skip
            with open(out + ".tmp", "w") as f:
                json.dump(recs, f, indent=1)
            os.replace(out + ".tmp", out)
    for v in variants:
        sub = [r for r in recs if r["variant"] == v]
        g2 = [(r["planned_posc"] - r["base_planned"]) / r["rule_bound"] for r in sub]
        g8 = [(r["fine_posc"] - r["base_fine"]) / r["rule_bound"] for r in sub]
        cpu = [r["stage_cpu_s"] for r in sub]
        print(f"{v}: n={len(sub)} 2x2 {t95(g2)}  8x8 {t95(g8)}  "
              f"stage CPU median {statistics.median(cpu) if cpu else 0:.2f} s "
              f"(max {max(cpu) if cpu else 0:.2f})")  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1].split(","), sys.argv[2].split(";"), sys.argv[3])
