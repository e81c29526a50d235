"""i24-fleet: POS_C and idle UAVs of the default allocation plan over the fleet size, with
the unfound mass split into unreachable and reachable (a script, not a test).

``python fleet.py SCENARIO N [N ...]`` (from the checkout)
    SCENARIO a scenario file (the audit's ``big.yaml``, imported at any cell size) planned on
    its own prior, ``mono2`` (results/plan_scale/i24-deconflict/repro.py's case:
    ``large_400`` at 10 km, one zone, nine sightings) or ``mini:SIDE_KM:CELL_KM[:ENDURANCE_H]``
    (the big scenario built without the import: tests/planning/test_fleet.py's ``mini``).
    One JSON line per N.

The split (reachable.py's method, i24-deconflict): a cell's mass is *in zones* for the share
the planner's sensor model cannot reach from outside the zones (1 - ``reach_share`` at W/2),
*beyond endurance* where no UAV's straight out-and-back (out at the transit speed, home at
cruise) fits 0.85 T, and *reachable* otherwise. Unfound reachable mass per cell is that
reachable mass less what the plan finds there (``sampled_sweep``), floored at 0 (the
inverse-cube sensor's tail finds some mass the W/2 model calls unreachable; a cell searched
in part counts its rest); ``idle_reach_unfound`` the same over the cells an idle UAV's own
out-and-back fits, ``untouched_reachable`` the reachable mass of cells the plan finds nothing
in.
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


def scenario(name: str, n: int):
    """The scenario with ``n`` UAVs and its prior."""
    if name.startswith("mini"):  # mini:SIDE:CELL[:ENDURANCE_H], tests/planning/test_fleet.py
        sys.path.insert(0, "tests/planning")
        from test_fleet import mini

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
    idle = [k for k, u in enumerate(plan["uavs"]) if not u["waypoints_m"]]
    by_idle = (tau[idle] < sc.uav.usable_endurance_s).any(axis=0) if idle else np.zeros_like(near)
    return {
        "found": round(float(got.sum()), 4),
        "in_zones": round(float((prior * (1 - share)).sum()), 4),
        "beyond_endurance": round(float((prior * share * ~near).sum()), 4),
        "reachable": round(float(reach.sum()), 4),
        "reachable_unfound": round(float(np.maximum(reach - got, 0).sum()), 4),
        "idle_reach_unfound": round(float(np.maximum(reach * by_idle - got, 0).sum()), 4),
        "untouched_reachable": round(float((reach * (got <= 0)).sum()), 4),
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
