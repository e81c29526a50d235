"""Per-UAV minutes charged (flight + climb spiral + descent orbit, against eq. 18's 0.85 T)
and POS of a plan, its orbits read at the plan's own terrain record, or at given rates.

Usage: python figures.py PLAN.json [CLIMB SINK]  (rates in m/s; none: the plan's record)
"""

from __future__ import annotations

import sys
import warnings

from poc_env.agents.mission.plan import load_plan
from poc_env.agents.mission.terrain import plan_profiles


def main() -> None:
    plan = load_plan(sys.argv[1])
    rec = dict(plan["terrain"])
    if len(sys.argv) > 3:
        for key, v in zip(("max_climb_rate_mps", "max_sink_rate_mps"), sys.argv[2:4]):
            if v != "-":
                rec[key] = float(v)
    usable = rec["usable_endurance_s"] / 60
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        profs = plan_profiles({**plan, "terrain": rec}, charge=False)
    rates = {k: rec.get(k) for k in ("max_climb_rate_mps", "max_sink_rate_mps")}
    print(f"{sys.argv[1]} rates {rates} POS_C {plan['posc']:.4f} usable {usable:.1f} min")
    print("UAV | flight | climb spiral | descent orbit | total | over 0.85 T | pos")
    for u, p in zip(plan["uavs"], profs or ()):
        f = u["flight_time_s"] / 60
        c = 0.0 if p.climb is None else p.climb.time_s / 60
        d = 0.0 if p.descent is None else p.descent.time_s / 60
        tot = f + c + d
        print(
            f"{u['id']} | {f:.1f} | {c:.2f} | {d:.2f} | {tot:.1f} | "
            f"{max(0.0, tot - usable):.1f} | {u['pos']:.4f}"
        )


if __name__ == "__main__":
    main()
