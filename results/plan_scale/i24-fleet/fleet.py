"""i24-fleet: POS_C and idle UAVs of the default allocation plan over the fleet size, with
the unfound mass split into unreachable and reachable (a script, not a test).

``python fleet.py SCENARIO N [N ...]``
    SCENARIO a scenario file (the audit's ``big.yaml``, imported at any cell size) planned on
    its own prior, or ``mono2`` (results/plan_scale/i24-deconflict/repro.py's case:
    ``large_400`` at 10 km, one zone, nine sightings). One JSON line per N.

The split (reachable.py's method, i24-deconflict): a cell's mass is *in zones* for the share
the planner's sensor model cannot reach from outside the zones (1 - ``reach_share`` at W/2),
*beyond endurance* where no UAV's straight out-and-back (out at the transit speed, home at
cruise) fits 0.85 T, and *reachable* otherwise. Unfound reachable mass per cell is that
reachable mass less what the plan finds there (``sampled_sweep``), floored at 0 (the
inverse-cube sensor's tail finds some mass the W/2 model calls unreachable).
"""

import json
import sys
import time

import numpy as np

from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.agents.planning.flight_rules import SPEED, plan_speeds
from poc_env.agents.planning.relax_patches import out_and_back
from poc_env.config import load_scenario
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import Grid, build_prior


def mini(side_km: float, cell_km: float, n: int, endurance_h: float = 3.0):
    """The audit's big scenario (results/audit/scale/raw/make_inputs.py) without the import:
    ``large_400``'s UAV on a ``side_km`` square of ``cell_km`` cells, four airfields 15 km
    outside the sides, its three zones and twelve weighted sightings (seed 7) at the same
    relative places, ``n`` UAVs round-robin."""
    s = side_km
    fields = {"North": (s / 2, s + 15), "South": (s / 2, -15), "West": (-15, s / 2),
              "East": (s + 15, s / 2)}  # fmt: skip
    boxes = [(0.2, 0.3, 0.35, 0.45), (0.6, 0.55, 0.7, 0.62), (0.45, 0.8, 0.55, 0.9)]
    zones = [[[a * s, b * s], [c * s, b * s], [c * s, d * s], [a * s, d * s]] for a, b, c, d in boxes]
    sc = load_scenario("large_400", {
        "map.width_km": s, "map.height_km": s, "map.cell_km": cell_km,
        "map.no_fly_zones_km": zones, "uav.endurance_h": endurance_h,
        "airfields": [{"name": k, "position_km": list(v)} for k, v in fields.items()],
        "fleet": [{"takeoff": "North", "count": 1}],
    }).with_uavs(n)  # fmt: skip
    rng = np.random.default_rng(7)
    pts = rng.uniform(0.05 * s, 0.95 * s, (12, 2))
    w = rng.uniform(0.2, 1, 12)
    g = Grid.from_config(sc.map)
    prior = np.zeros(g.shape)
    for (x, y), m in zip(pts, w, strict=True):
        prior[int(y // cell_km), int(x // cell_km)] += m
    return sc, prior / prior.sum()


def scenario(name: str, n: int):
    """The scenario with ``n`` UAVs and its prior."""
    if name.startswith("mini"):  # mini:SIDE:CELL[:ENDURANCE_H]
        return mini(*map(float, name.split(":")[1:3]), n, *map(float, name.split(":")[3:]))
    if name == "mono2":
        sys.path.insert(0, "results/plan_scale/i24-deconflict")
        from repro import case

        return case("mono2", n)
    sc = load_scenario(name).with_uavs(n)
    return sc, build_prior(sc.map)


def split(sc, prior, plan) -> dict:
    """The mass found, unreachable (in zones, beyond endurance) and reachable but unfound."""
    g = Grid.from_config(sc.map)
    share = ZoneRouter.for_scenario(sc).reach_share(g, reach_m=0.5 * sc.sensor.sweep_width_m)
    to = np.asarray(sc.takeoff_m, float).reshape(-1, 2)
    la = np.asarray(sc.landing_m, float).reshape(-1, 2)
    tau = out_and_back(g, to, la, plan_speeds(sc, SPEED))
    near = (tau < sc.uav.usable_endurance_s).any(axis=0)
    paths = [[to[k], *u["waypoints_m"], la[k]] if u["waypoints_m"] else []
             for k, u in enumerate(plan["uavs"])]  # fmt: skip
    _, found = sampled_sweep(sc, g, prior, paths)
    got = sum(found, np.zeros(g.shape))
    reach = prior * share * near
    return {
        "found": round(float(got.sum()), 4),
        "in_zones": round(float((prior * (1 - share)).sum()), 4),
        "beyond_endurance": round(float((prior * share * ~near).sum()), 4),
        "reachable": round(float(reach.sum()), 4),
        "reachable_unfound": round(float(np.maximum(reach - got, 0).sum()), 4),
    }


if __name__ == "__main__":
    for n in map(int, sys.argv[2:]):
        sc, prior = scenario(sys.argv[1], n)
        t0 = time.perf_counter()
        p = make_allocation_plan(sc, prior=prior)
        dt = time.perf_counter() - t0
        rec = {
            "case": sys.argv[1],
            "uavs": n,
            "cells": list(Grid.from_config(sc.map).shape),
            "posc": round(float(p["posc"]), 4),
            "start": p["start"],
            "refined": p["refined"],
            "no_route": sum(1 for u in p["uavs"] if not u["waypoints_m"]),
            "fleet": p["optimizer"]["settings"].get("fleet"),
            **split(sc, prior, p),
            "plan_s": round(dt, 1),
        }
        print(json.dumps(rec), flush=True)
