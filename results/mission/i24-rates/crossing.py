"""Field-mates' concentric orbits (``export --separation-m S``): where the inner orbit's exit
leg crosses an outer orbit, how far apart in altitude are the two paths there?

For each pair of exported UAVs whose climb spirals (or descent orbits) share a centre, the
inner one leaves its orbit at the tangent point towards its next point (the first waypoint;
for a descent orbit, the landing field: PX4's NAV_LOITER_TO_ALT with heading required), and its
straight leg meets the outer circle sqrt(R^2 - r^2) further on, at its exit altitude give or
take the climb or descent over that run (eq. 19's gradients, or the rates'; a descent orbit's
exit: down its glide). The outer UAV passes that
point once a turn, at the altitudes of its helix there (and at its last altitude on the level
arc of a descent orbit, to its exit). The least vertical distance between the inner UAV's
altitude at the crossing and any of those is what separates them whatever the timing: safe
when it is at least S.

Usage: python crossing.py PLAN.json S [field|fleet] [CLIMB SINK]  (rates m/s, "-": unset)
"""

from __future__ import annotations

import math
import sys
import warnings

import numpy as np

from poc_env.agents.mission.features import with_layers
from poc_env.agents.mission.plan import flight, load_plan
from poc_env.agents.mission.terrain import (
    from_record,
    plan_profiles,
    route_speed_mps,
    tangent_exit,
    vertical_angle,
)


def passes(o, theta: float, level: tuple[float, float] | None = None) -> list[float]:
    """The altitudes at which the orbit ``o`` (a Spiral) passes the angle ``theta``; with
    ``level`` (end angle, exit angle) of a descent's level arc, its last altitude there too."""
    first = ((o.start_rad - theta) % (2 * math.pi)) * o.radius_m
    out = []
    s = first
    while s <= o.length_m + 1e-9:
        out.append(o.from_m + (o.to_m - o.from_m) * s / max(o.length_m, 1e-9))
        s += 2 * math.pi * o.radius_m
    if level is not None:
        end, ex = level
        if ((end - theta) % (2 * math.pi)) <= ((end - ex) % (2 * math.pi)):
            out.append(o.to_m)
    return out


def main() -> None:
    sep = float(sys.argv[2])
    plan = with_layers(load_plan(sys.argv[1]), sep, sys.argv[3] if len(sys.argv) > 3 else "field")
    if len(sys.argv) > 5:
        rec = dict(plan["terrain"])
        for key, v in zip(("max_climb_rate_mps", "max_sink_rate_mps"), sys.argv[4:6]):
            if v != "-":
                rec[key] = float(v)
        plan = {**plan, "terrain": rec}
    t = from_record(plan["terrain"])
    fl = flight(plan)
    up = math.tan(vertical_angle(t, route_speed_mps(fl), True))
    down = math.tan(vertical_angle(t, route_speed_mps(fl), False))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        profs = plan_profiles(plan, charge=False)
    print(
        f"{sys.argv[1]} separation {sep:g} m, rates "
        f"{plan['terrain'].get('max_climb_rate_mps')}/{plan['terrain'].get('max_sink_rate_mps')}"
    )
    for kind in ("climb", "descent"):
        orbits = []
        for u, p in zip(plan["uavs"], profs or ()):
            if not u["waypoints_m"]:
                continue
            if kind == "climb" and p.climb is not None:  # round at its top to its exit too
                o = p.climb
                first = np.asarray(u["waypoints_m"][0], float)
                _, ex_rad = tangent_exit(o.center_m, o.radius_m, first)
                end = o.start_rad - o.length_m / o.radius_m
                lvl = (end, ex_rad)
                orbits.append((u, o, first, lvl))
            if kind == "descent" and p.descent is not None:
                o = p.descent.orbit
                end = o.start_rad - o.length_m / o.radius_m
                lvl = (end, p.descent.exit_rad)
                orbits.append((u, o, np.asarray(u["landing_m"], float), lvl))
        for a in orbits:
            for b in orbits:
                ua, oa, target, _ = a
                ub, ob, _, lvl = b
                if ua is ub or oa.center_m != ob.center_m or ob.radius_m <= oa.radius_m:
                    continue
                c = np.asarray(oa.center_m)
                ex, _ = tangent_exit(c, oa.radius_m, target)
                dirn = (target - ex) / np.hypot(*(target - ex))
                run = math.sqrt(ob.radius_m**2 - oa.radius_m**2)
                x = ex + dirn * run
                theta = math.atan2(x[1] - c[1], x[0] - c[0])
                if kind == "climb":  # on to its first waypoint: climbing or descending
                    z_lo, z_hi = oa.to_m - down * run, oa.to_m + up * run
                else:  # the glide from the exit: H down at the glide's slope
                    slope = (oa.to_m - t.field_elevation(target)) / math.dist(ex, target)
                    z_lo = z_hi = oa.to_m - slope * run
                alts = passes(ob, theta, lvl)
                gap = (
                    min(
                        (0.0 if z_lo <= h <= z_hi else min(abs(h - z_lo), abs(h - z_hi)))
                        for h in alts
                    )
                    if alts
                    else math.inf
                )
                print(
                    f"{kind}: UAV {ua['id']} (r {oa.radius_m:.1f} m, leaves at {oa.to_m:.0f} m) "
                    f"crosses UAV {ub['id']}'s orbit (R {ob.radius_m:.1f} m, {ob.from_m:.0f} -> "
                    f"{ob.to_m:.0f} m) {run:.0f} m after its exit at {z_lo:.0f}-{z_hi:.0f} m; "
                    f"UAV {ub['id']} passes there at {[round(h) for h in alts]} m: least "
                    f"vertical gap {gap:.0f} m ({'safe' if gap >= sep else 'NOT separated'} "
                    f"at S = {sep:g} m)"
                )


if __name__ == "__main__":
    main()
