"""Per-UAV minutes charged (flight + climb spiral + descent orbit, against eq. 18's 0.85 T)
and POS of a plan, its orbits read at the plan's own terrain record, or at given rates.

Usage: python figures.py PLAN.json SCENARIO.yaml [CLIMB SINK]  (rates in m/s, "-" unset;
none: the plan's record). POS_C is also scored by the orbit fit's own scorer
(allocation.sampled_sweep, eq. 14 along every flight path), so that a trimmed plan (scored
again by it) and an untrimmed one (the planner's score) compare on one scorer.
"""

from __future__ import annotations

import sys
import warnings

from poc_env.agents.mission.plan import load_plan
from poc_env.agents.mission.terrain import plan_profiles
from poc_env.agents.planning.allocation import sampled_sweep
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior


def main() -> None:
    plan = load_plan(sys.argv[1])
    sc = load_scenario(sys.argv[2])
    pos, _ = sampled_sweep(
        sc, Grid.from_config(sc.map), build_prior(sc.map),
        [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else []
         for u in plan["uavs"]],
    )  # fmt: skip
    rec = dict(plan["terrain"])
    if len(sys.argv) > 4:
        for key, v in zip(("max_climb_rate_mps", "max_sink_rate_mps"), sys.argv[3:5]):
            if v != "-":
                rec[key] = float(v)
    usable = rec["usable_endurance_s"] / 60
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        profs = plan_profiles({**plan, "terrain": rec}, charge=False)
    rates = {k: rec.get(k) for k in ("max_climb_rate_mps", "max_sink_rate_mps")}
    print(
        f"{sys.argv[1]} rates {rates} POS_C {plan['posc']:.4f} (sampled sweep "
        f"{sum(pos):.4f}) usable {usable:.1f} min"
    )
    print("UAV | flight | climb spiral | descent orbit | total | over 0.85 T | pos | sweep pos")
    for u, p, pk in zip(plan["uavs"], profs or (), pos):
        f = u["flight_time_s"] / 60
        c = 0.0 if p.climb is None else p.climb.time_s / 60
        d = 0.0 if p.descent is None else p.descent.time_s / 60
        tot = f + c + d
        print(
            f"{u['id']} | {f:.1f} | {c:.2f} | {d:.2f} | {tot:.1f} | "
            f"{max(0.0, tot - usable):.1f} | {u['pos']:.4f} | {pk:.4f}"
        )


if __name__ == "__main__":
    main()
