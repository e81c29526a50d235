"""Region planning for §6.1: optimise each region's track spacing and direction (Table 3).

Given a region plan (polygons searched by the variable-angle parallel search, search-base
circles by a sector or expanding-square search), each UAV's spacing S and direction theta are
chosen to maximise its POS = POC x POD within the time limit t <= 0.85 T (eq. 17-18). POD falls
as S grows (eq. 10), so for every direction theta on a grid (every ``step_deg`` degrees) the
smallest feasible S is found by bisection on the generated track's flight time, and the
direction with the smallest feasible S wins (ties: the shorter flight). Circles have no
direction to choose; their spacing is found the same way. The regions' POCs do not depend on S
or theta, so maximising each UAV's POD maximises the swarm's POS_C.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from poc_env.agents.planning.survey import RegionPlan, RegionSpec, _airfields_for, load_regions
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.timing import flight_time_s


def _time(spec: RegionSpec, sc, takeoff, landing) -> float:
    tr = spec.track(start=takeoff)
    u = sc.uav
    return flight_time_s(takeoff, tr.waypoints, landing, u.cruise_speed_mps, u.search_speed_mps)


def _smallest_spacing(spec, sc, takeoff, landing, lo, hi, iters=30):
    """Smallest spacing in [lo, hi] whose track fits in 0.85 T, or None if even ``hi`` does not."""
    limit = sc.uav.usable_endurance_s
    if _time(dataclasses.replace(spec, spacing_m=hi), sc, takeoff, landing) > limit:
        return None
    if _time(dataclasses.replace(spec, spacing_m=lo), sc, takeoff, landing) <= limit:
        return lo
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        if _time(dataclasses.replace(spec, spacing_m=mid), sc, takeoff, landing) <= limit:
            hi = mid
        else:
            lo = mid
    return hi


def optimise_regions(
    scenario: Any = "paper_6_1",
    regions: RegionPlan | str | None = None,
    *,
    step_deg: float = 10.0,
    min_spacing_w: float = 0.3,
    max_spacing_w: float = 8.0,
) -> RegionPlan:
    """The region plan with every region's spacing (and direction) optimised; see the module doc.

    Spacing is searched in ``[min_spacing_w, max_spacing_w] x W``; a region whose track does not
    fit even at the largest spacing raises ConfigError naming it.
    """
    sc = load_scenario(scenario)
    plan = (
        regions
        if isinstance(regions, RegionPlan)
        else load_regions(regions or f"{sc.name}_polygons")
    )
    if not 0 < step_deg <= 90:
        raise ConfigError("step_deg", step_deg, "a number in (0, 90]")
    w = sc.sensor.sweep_width_m
    lo, hi = min_spacing_w * w, max_spacing_w * w
    takeoffs, landings = _airfields_for(sc, plan)
    out = []
    for spec, t0, t1 in zip(plan.regions, takeoffs, landings):
        thetas = (
            np.radians(np.arange(0.0, 180.0, step_deg))
            if spec.pattern == "parallel"
            else [spec.direction_rad]
        )
        best = None
        for th in thetas:
            cand = dataclasses.replace(spec, direction_rad=float(th))
            s = _smallest_spacing(cand, sc, t0, t1, lo, hi)
            if s is None:
                continue
            cand = dataclasses.replace(cand, spacing_m=float(s))
            key = (s, _time(cand, sc, t0, t1))
            if best is None or key < best[0]:
                best = (key, cand)
        if best is None:
            raise ConfigError(
                f"regions[{spec.id}]",
                spec.kind,
                f"a region whose track fits 0.85 T at spacing <= {max_spacing_w:g} W",
            )
        out.append(best[1])
    return dataclasses.replace(plan, name=f"{plan.name}_optimised", regions=tuple(out))
