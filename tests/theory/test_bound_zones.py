"""Bounds with no-fly zones (bound-zones): every bound printed beside a plan is at least what
the plan scores, when zones hide part of the prior from a sweep of half the width W/2 but not
from the inverse-cube sensor, whose lateral range runs to its cut-off
(:func:`poc_env.theory.bound.zone_reach`; results/audit/scale/README.md, "Noticed and left")."""

import numpy as np
import pytest

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.policies.allocation import AllocationPlanPolicy
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.bound import zone_reach
from poc_env.theory.probability_map import Grid


def _sightings(grid: Grid, points, weights) -> np.ndarray:
    """A prior of point sightings (x, y in m) with ``weights``, normalised."""
    prior = np.zeros(grid.shape)
    ox, oy = grid.origin_m
    for (x, y), w in zip(points, weights, strict=True):
        prior[int((y - oy) // grid.cell_m), int((x - ox) // grid.cell_m)] += w
    return prior / prior.sum()


def _printed_bounds(plan) -> dict[str, float]:
    """Every bound a plan prints: ``upper_bound`` and the ``bounds`` of its geography."""
    out = {"upper_bound": float(plan["upper_bound"])}
    out.update({k: float(v) for k, v in plan.get("bounds", {}).items()})
    out["rule"] = float(plan["bound_rule"])
    return out


def _random_case(seed: int, law: str = "inverse_cube"):
    """``small`` (detection ``law``) with one random rectangular zone and 5 point sightings, 2
    of them inside the zone deeper than the planners' W/2 (seeded; the zone's mass is what the
    old bound hid)."""
    rng = np.random.default_rng(seed)
    w_km, h_km = rng.uniform(10.0, 18.0, size=2)
    x0 = rng.uniform(2.0, 38.0 - w_km)
    y0 = rng.uniform(4.0, 38.0 - h_km)
    zone = [[x0, y0], [x0 + w_km, y0], [x0 + w_km, y0 + h_km], [x0, y0 + h_km]]
    sc = load_scenario("small", {"map.no_fly_zones_km": [zone], "sensor.law": law})
    grid = Grid.from_config(sc.map)
    # inside: at least 2.5 km (W) from the zone's edge, i.e. hidden from W/2 of the keep-out
    inside = np.column_stack(
        [rng.uniform(x0 + 2.5, x0 + w_km - 2.5, 2), rng.uniform(y0 + 2.5, y0 + h_km - 2.5, 2)]
    )
    outside = rng.uniform(0.5, 39.5, size=(3, 2))
    pts = np.vstack([inside, outside]) * 1000.0
    prior = _sightings(grid, pts, rng.uniform(0.5, 1.5, size=5))
    return sc, prior


@pytest.mark.filterwarnings("ignore:.*beyond the usable endurance")
@pytest.mark.parametrize(
    ("seed", "law"),
    [(0, "inverse_cube"), (1, "inverse_cube"), (2, "inverse_cube"), (3, "inverse_cube"),
     (4, "exponential"), (5, "definite_range")],
)  # fmt: skip
def test_plans_stay_below_every_printed_bound_with_zones(seed, law, fly):
    sc, prior = _random_case(seed, law)
    plan = make_allocation_plan(sc, prior=prior)
    bounds = _printed_bounds(plan)
    for name, b in bounds.items():
        assert plan["posc"] <= b + 1e-12, (seed, name, plan["posc"], b)
    flown = fly(sc, AllocationPlanPolicy(), seed=5000 + seed, prior=prior)
    assert flown.nofly_steps == 0  # the zone bound holds for flights that keep eq. 20
    for name, b in bounds.items():
        assert flown.posc <= b + 1e-12, (seed, name, flown.posc, b)
    de = make_plan(sc, prior=prior, planner="de", popsize=8, maxiter=4, seed=seed)
    for name, b in _printed_bounds(de).items():
        assert de["posc"] <= b + 1e-12, (seed, name, de["posc"], b)


def test_mono2_reproduction():
    """The scale audit's smoke case (results/audit/scale/raw/mono2.py): ``large_400`` at 10 km
    cells, one zone over two of nine point sightings, 12 UAVs: POS_C 0.8181 was printed beside
    an "optimum" of 0.8065."""
    zone = [[100, 150], [175, 150], [175, 225], [100, 225]]
    sc = load_scenario("large_400", {"map.cell_km": 10.0, "map.no_fly_zones_km": [zone]})
    grid = Grid.from_config(sc.map)
    sightings = [
        (160.9, 151.6, 0.1), (139.1, 226.6, 0.1), (301.6, 45.3, 0.06),
        (123.4, 98.4, 0.12), (373.4, 126.6, 0.1), (251.6, 273.4, 0.06),
        (26.6, 380, 0.15), (160.9, 380, 0.09), (307.8, 380, 0.04),
    ]  # fmt: skip
    prior = _sightings(
        grid, [(x * 1e3, y * 1e3) for x, y, _ in sightings], [s[2] for s in sightings]
    )
    plan = make_allocation_plan(sc.with_uavs(12), prior=prior)
    assert plan["posc"] > 0.8  # the case still finds the hidden sighting from outside the zone
    for name, b in _printed_bounds(plan).items():
        assert plan["posc"] <= b + 1e-12, (name, plan["posc"], b)


def test_zone_reach_credits_the_law_reach_and_nothing_without_zones():
    sc = load_scenario("small")
    grid = Grid.from_config(sc.map)
    prior = np.arange(1.0, 65.0).reshape(grid.shape)
    mass, area = zone_reach(sc, prior)  # no zones: the prior and the cell areas, unchanged
    assert np.array_equal(mass, prior) and np.all(area == grid.cell_area_m2)
    # a 30 km square zone: points deeper than the cut-off (4 W = 10 km) are hidden
    big = load_scenario("small", {"map.no_fly_zones_km": [[[5, 5], [35, 5], [35, 35], [5, 35]]]})
    mass, area = zone_reach(big, prior)
    share = mass / prior
    # sample points (4 x 4 a cell, 1.25 km apart) of rows / columns 3-4 (15-25 km) lie
    # 10.625 km or more inside the zone; every other cell's lie within 9.375 km of its edge
    hidden = np.zeros(grid.shape, dtype=bool)
    hidden[3:5, 3:5] = True
    assert np.all(share[hidden] == 0.0) and np.all(share[~hidden] == 1.0)
    assert np.all(area[hidden] == grid.cell_area_m2) and np.all(area[~hidden] == grid.cell_area_m2)
    # a reach of 11 km: in cell (3, 3) the points at 11.875 km or deeper on both axes
    # (3 x 3 of 16) are hidden
    router = ZoneRouter.for_scenario(big)
    part = router.reach_share(grid, reach_m=11000.0, zones_only=True, samples_per_cell=4)
    assert part[3, 3] == 7 / 16
    # the planners' W/2 discount hides far more than the sensor's reach does
    planner = ZoneRouter.for_scenario(big).reach_share(grid, reach_m=0.5 * sc.sensor.sweep_width_m)
    assert planner.sum() < share.sum()


def test_de_objective_bound_holds_for_a_flight_along_a_zone_edge():
    """The DE planner's ``upper_bound`` (the physical optimum for a plan's effort) against a
    flight of no more effort that keeps eq. 20: lines 1 km outside a zone's edge find the mass
    1-4 km inside it (the inverse-cube sensor), which the planners' W/2 discount hides."""
    from poc_env.agents.planning.allocation import sampled_sweep
    from poc_env.agents.planning.objective import PlanObjective

    zone = [[10, 10], [30, 10], [30, 30], [10, 30]]
    sc = load_scenario("small", {"map.no_fly_zones_km": [zone]})
    grid = Grid.from_config(sc.map)
    prior = np.zeros(grid.shape)
    prior[2, 3] = 0.9  # y 10-15 km, x 15-20 km: 0.6-4.4 km inside the zone's south edge
    prior[0, 0] = 0.1
    share = ZoneRouter.for_scenario(sc).reach_share(grid, reach_m=0.5 * sc.sensor.sweep_width_m)
    obj = PlanObjective(sc, prior * share, bound_prior=prior)  # as the DE planner builds it
    x = obj.bounds.mean(axis=1)
    effort = obj.sweep_width_m * float(np.sum(obj.evaluate(x[None]).search_length_m))
    # back and forth along y = 9 km (1 km south of the zone), no longer than the plan's effort
    reps = max(1, int(effort / obj.sweep_width_m // 20000.0))
    path = [[10000.0 + 20000.0 * (k % 2), 9000.0] for k in range(reps + 1)]
    found = sampled_sweep(sc, grid, prior, [path])[0][0]
    assert obj.sweep_width_m * 20000.0 * reps <= effort
    assert found > 0.1  # it finds mass inside the zone
    assert found <= obj.upper_bound(x)


def test_zone_reach_is_refused_beyond_the_memory_limit():
    """The bounds' zone reach builds ``s x s`` sample points (and a shapely point each) for every
    cell under the zones: sized against the memory guard first, as the other large structures
    are (``limits.check_memory``: a ConfigError naming the field, the count and the limit).
    The 30 km zone's 2 x 2 hidden cells at s = 16 need 1,024 points, about 0.5 MiB: refused
    under a 0.1 MiB limit, accepted at s = 2 (16 points) under it (i24-terrainleft: before,
    no guard; 273 B a point measured)."""
    from poc_env import limits

    zone = {"map.no_fly_zones_km": [[[5, 5], [35, 5], [35, 35], [5, 35]]]}
    grid = Grid.from_config(load_scenario("small").map)
    prior = np.ones(grid.shape) / grid.shape[0] / grid.shape[1]
    fine = load_scenario("small", {**zone, "sensor.samples_per_cell": 16})
    coarse = load_scenario("small", {**zone, "sensor.samples_per_cell": 2})
    with limits.memory_limit_gb(0.1 / 1024):
        with pytest.raises(ConfigError, match=r"sensor\.samples_per_cell: got 16.*zone reach of"):
            zone_reach(fine, prior)
        mass, _ = zone_reach(coarse, prior)
    assert mass.sum() < prior.sum()  # the zone hides the cells deep inside it
    assert zone_reach(fine, prior)[0].sum() < prior.sum()  # the default limit holds it
