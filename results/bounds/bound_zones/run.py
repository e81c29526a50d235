"""bound-zones: plans' POS_C against every printed bound with no-fly zones, the old bound
(main's: the allocation bound on the prior times the planners' W/2 area share of the keep-out
area) beside the new one (zone_reach: the law's reach from the zones, by sample points).

    OMP_NUM_THREADS=1 python results/bounds/bound_zones/run.py OUT.json [N_RANDOM]

The old figure is recomputed here by swapping ``zone_reach`` in the allocation planner and the
objective for main's discount (``old_zone_reach``); nothing else of the plan depends on it.
"""

import json
import os
import sys
import tempfile

import numpy as np

import poc_env.agents.planning.allocation as alloc_mod
import poc_env.agents.planning.objective as obj_mod
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.policies.allocation import AllocationPlanPolicy
from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.bound import zone_reach
from poc_env.theory.probability_map import Grid

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "theory"))
from test_bound_zones import _random_case, _sightings


def old_zone_reach(sc, prior):
    """main's bound input: the prior times the planners' W/2 area share, full cell areas."""
    grid = Grid.from_config(sc.map)
    m = np.asarray(prior, dtype=float)
    router = ZoneRouter.for_scenario(sc)
    if router.active:
        m = m * router.reach_share(grid, reach_m=0.5 * sc.sensor.sweep_width_m)
    return m, np.full(grid.shape, grid.cell_area_m2)


def both(fn, *args, **kw):
    """The plan with the new bound and the old bound of the same plan."""
    plan = fn(*args, **kw)
    alloc_mod.zone_reach = obj_mod.zone_reach = old_zone_reach
    try:
        old = fn(*args, **kw)
    finally:
        alloc_mod.zone_reach = obj_mod.zone_reach = zone_reach
    assert old["posc"] == plan["posc"], "the bound must not change the plan"
    return plan, float(old["upper_bound"])


def mono2(uavs):
    zone = [[100, 150], [175, 150], [175, 225], [100, 225]]
    sc = load_scenario("large_400", {"map.cell_km": 10.0, "map.no_fly_zones_km": [zone]})
    pts = [(160.9, 151.6, 0.1), (139.1, 226.6, 0.1), (301.6, 45.3, 0.06), (123.4, 98.4, 0.12),
           (373.4, 126.6, 0.1), (251.6, 273.4, 0.06), (26.6, 380, 0.15), (160.9, 380, 0.09),
           (307.8, 380, 0.04)]  # fmt: skip
    prior = _sightings(Grid.from_config(sc.map), [(x * 1e3, y * 1e3) for x, y, _ in pts],
                       [w for *_, w in pts])  # fmt: skip
    return sc.with_uavs(uavs), prior


def record(name, sc, prior, flown=True, de=True):
    rows = []
    plan, old = both(make_allocation_plan, sc, prior=prior)
    row = {"case": name, "planner": "allocation", "posc": plan["posc"], "old_upper": old,
           "upper_bound": plan["upper_bound"], **{f"bound_{k}": v for k, v in
                                                  plan.get("bounds", {}).items()},
           "bound_rule": plan["bound_rule"]}  # fmt: skip
    if flown:
        f = fly(sc, AllocationPlanPolicy(), seed=5000, prior=prior)
        row.update(flown_posc=f.posc, flown_nofly_steps=f.nofly_steps)
    rows.append(row)
    if de:
        p, old = both(make_plan, sc, prior=prior, planner="de", popsize=8, maxiter=4, seed=0)
        rows.append({"case": name, "planner": "de(8x4)", "posc": p["posc"], "old_upper": old,
                     "upper_bound": p["upper_bound"], **{f"bound_{k}": v for k, v in
                                                         p.get("bounds", {}).items()},
                     "bound_rule": p["bound_rule"]})  # fmt: skip
    for r in rows:
        print(json.dumps(r), flush=True)
    return rows


if __name__ == "__main__":
    import warnings

    warnings.simplefilter("ignore")
    out = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 20
    rows = []
    for u in (12, 24):
        rows += record(f"mono2_{u}uav", *mono2(u), flown=False, de=False)
    for seed in range(5000, 5000 + n):
        rows += record(f"small_zone_{seed}", *_random_case(seed))
    with tempfile.NamedTemporaryFile("w", dir=os.path.dirname(out) or ".", delete=False) as f:
        json.dump(rows, f, indent=1)
    os.replace(f.name, out)
