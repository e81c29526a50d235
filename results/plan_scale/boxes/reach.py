"""i24-boxes: what a group move towards the mass would gain, and the time it would need.

``python results/plan_scale/boxes/reach.py PLANS.json[,...] OUT.json``

For each stored plan (cache_plans.py / stage2.py records with routes) and each airfield's
group of UAVs, every translation of the group's search parts (all inner waypoints, as the
polish's ``group`` move makes it, no squeeze) by 1-32 sweep widths in 8 directions is scored
in the environment's sensor model (``polish.Exposure``: the gain in planned POS, over the
rule-aware bound) and timed: the most any member's route then overruns eq. 18's return rule
(``max_i t_i + |p_i - landing| / v_home + reserve - T_usable``, seconds; <= 0: it fits). The
best gain of all, the time it lacks, and the best gain that fits are printed and stored.
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.flight_rules import SPEED, plan_speeds, reserve_s
from poc_env.agents.planning.polish import _DIRS, Exposure
from poc_env.agents.planning.refine import arrival_times
from poc_env.config import load_scenario
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior

RADII = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0)


def overrun(path, v, turn, budget, reserve, h0) -> float:
    t = arrival_times(path, v, turn, h0)
    home = np.hypot(*(np.asarray(path) - np.asarray(path[-1])).T) / v.home
    return float(np.max(t + home + reserve) - budget)


def main(plans: list[str], out: str) -> None:
    recs = []
    for p in plans:
        with open(p) as f:
            stored = json.load(f)
        for r in stored:
            sc = load_scenario(r["map"])
            prior = build_prior(sc.map) if r["seed"] < 0 else episode_prior(sc, r["seed"])
            grid = Grid.from_config(sc.map)
            v = plan_speeds(sc, SPEED)
            s, w = sc.sensor.samples_per_cell, sc.sensor.sweep_width_m
            ex = Exposure(
                grid,
                s,
                w,
                sc.sensor.law,
                sc.sensor.cutoff_sweep_widths * w,
                grid.refine(np.asarray(prior, dtype=float), s),
            )
            uavs = r["uavs"]
            paths = [np.array([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]) for u in uavs]
            for pth in paths:
                ex.add(pth[:-1], pth[1:])
            take = np.array([u["takeoff_m"] for u in uavs])
            h0 = takeoff_heading(grid.bounds, take)
            budget, reserve, turn = (
                sc.uav.usable_endurance_s,
                reserve_s(sc),
                sc.uav.max_turn_rate_rad_s,
            )
            groups: dict[tuple, list[int]] = {}
            for k, u in enumerate(uavs):
                groups.setdefault(tuple(u["takeoff_m"]), []).append(k)
            for ks in groups.values():
                offs = [(rad, d) for rad in RADII for d in range(8)]
                cands = []
                for rad, d in offs:
                    o = rad * w * _DIRS[d]
                    cands.append(
                        [np.vstack([paths[k][0], paths[k][1:-1] + o, paths[k][-1]]) for k in ks]
                    )
                first = np.zeros(len(cands) + 1, dtype=np.int64)
                first[1:] = np.cumsum([sum(len(q) - 1 for q in c) for c in cands])
                gain = (
                    ex.gains(
                        np.vstack([paths[k][:-1] for k in ks]),
                        np.vstack([paths[k][1:] for k in ks]),
                        np.vstack([q[:-1] for c in cands for q in c]),
                        np.vstack([q[1:] for c in cands for q in c]),
                        first,
                    )
                    / r["rule_bound"]
                )
                over = np.array(
                    [
                        max(overrun(q, v, turn, budget, reserve, h0[k]) for k, q in zip(ks, c))
                        for c in cands
                    ]
                )
                best = int(np.argmax(gain))
                fit = over <= 0
                rec = {
                    "map": r["map"],
                    "seed": r["seed"],
                    "airfield_m": list(paths[ks[0]][0]),
                    "uavs": ks,
                    "best_gain": float(gain[best]),
                    "best_offset_km": [
                        float(x) for x in offs[best][0] * w * _DIRS[offs[best][1]] / 1e3
                    ],
                    "best_overrun_s": float(over[best]),
                    "best_fitting_gain": float(gain[fit].max()) if fit.any() else None,
                    "base_overrun_s": max(
                        overrun(paths[k], v, turn, budget, reserve, h0[k]) for k in ks
                    ),
                }
                recs.append(rec)
                print(
                    r["map"],
                    r["seed"],
                    ks,
                    f"best {rec['best_gain']:+.4f}",
                    rec["best_offset_km"],
                    f"lacks {rec['best_overrun_s'] / 60:.1f} min",
                    f"fitting {rec['best_fitting_gain']}",
                    flush=True,
                )
    with open(out + ".tmp", "w") as f:
        json.dump(recs, f, indent=1)
    os.replace(out + ".tmp", out)


if __name__ == "__main__":
    main(sys.argv[1].split(","), sys.argv[2])
