"""The tour-charged bound of one flight (poc_env.theory.tour_bound, issue 24)."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.agents.planning.coverage_boxes import cut_lines
from poc_env.agents.planning.flight_rules import path_coverage, plan_speeds, reserve_s
from poc_env.agents.planning.greedy_rectangles import _lines
from poc_env.agents.planning.refine import route_fits
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import pod_from_coverage
from poc_env.theory.tour_bound import tour_bound

KM = 1000.0
#: two blobs 160 km apart, 190 and 250 km from the UAV's field at (20, -60) km: the rule-aware
#: bound shares the effort between them; no flight of 0.85 T (612 km) can search both
BLOBS_KM = ((20.0, 130.0), (180.0, 130.0))
SIGMA_KM = 10.0


def _case(keeps: tuple[int, ...]):
    sc = load_scenario("paper_6_2", {"map.cell_km": 10}).with_uavs(1)
    grid = Grid.from_config(sc.map)
    x, y = _centres(grid)
    prior = sum(
        np.exp(-((x - cx * KM) ** 2 + (y - cy * KM) ** 2) / (2 * (SIGMA_KM * KM) ** 2))
        for cx, cy in BLOBS_KM
    )
    prior = prior / prior.sum()
    env_b = tour_bound(sc, prior, block_km=30.0, keeps=keeps)
    plan_b = tour_bound(sc, prior, block_km=30.0, keeps=keeps, spill_m=0.0)
    return sc, grid, prior, env_b, plan_b


@pytest.fixture(scope="module")
def case():
    return _case((4,))


@pytest.fixture(scope="module")
def flights():
    """Random rule-keeping flights and the allocation planner's lone plan of :func:`_case`."""
    sc, grid, prior, _, _ = _case(())
    plans = _random_plans(sc, np.random.default_rng(7), 60)
    lone = make_allocation_plan(sc, prior=prior)
    plans.append(np.vstack([sc.takeoff_m[0], lone["uavs"][0]["waypoints_m"], sc.landing_m[0]]))
    law = sc.sensor.law
    w = sc.sensor.sweep_width_m
    model = [
        float(np.sum(prior * pod_from_coverage(path_coverage(p, grid, w), law))) for p in plans
    ]
    flown = [sampled_sweep(sc, grid, prior, [p])[0][0] for p in plans]
    return max(model), max(flown)


def _centres(grid: Grid):
    ox, oy = grid.origin_m
    xs = ox + grid.cell_m * (np.arange(grid.nx) + 0.5)
    ys = oy + grid.cell_m * (np.arange(grid.ny) + 0.5)
    return np.meshgrid(xs, ys)


def _random_plans(sc, rng, count: int):
    """Rule-keeping lawnmowers: one or two chained boxes near the blobs (random size, spacing
    and place), the last lines cut until eq. 18 holds (the planners' own rule)."""
    speeds = plan_speeds(sc, "max")
    u = sc.uav
    s = np.asarray(sc.takeoff_m[0], dtype=float)
    land = np.asarray(sc.landing_m[0], dtype=float)
    w = sc.sensor.sweep_width_m

    def fits(q):
        return route_fits(
            np.vstack([s, q, land]), speeds, u.max_turn_rate_rad_s, u.usable_endurance_s,
            reserve_s(sc),
        )  # fmt: skip

    plans = []
    for _ in range(count):
        order = rng.permutation(len(BLOBS_KM))[: rng.integers(1, 3)]
        wps = np.zeros((0, 2))
        frm = s
        for b in order:
            c = np.array(BLOBS_KM[b]) * KM + rng.normal(0, 8 * KM, 2)
            half = rng.uniform(8, 30, 2) * KM
            lo, hi = c - half, c + half
            box = _lines(lo, hi, rng.choice([1.0, 1.5, 2.0, 3.0]) * w, frm)
            wps = np.vstack([wps, box])
            frm = wps[-1]
        wps, _ = cut_lines(wps, fits, w)
        if len(wps):
            plans.append(np.vstack([s, wps, land]))
    return plans


def _check(case, flights, tight: float) -> None:
    _, _, _, env_b, plan_b = case
    model, flown = flights
    assert model <= plan_b.upper
    assert flown <= env_b.upper
    # the bound bites: the travel between the blobs is charged ...
    assert plan_b.upper < plan_b.rule - 0.01
    assert env_b.upper < env_b.rule - 0.005
    # ... and it is not loose for the best of these flights
    assert model >= tight * plan_b.upper


def test_rule_keeping_flights_stay_below_the_tour_bound(case, flights):
    """Random rule-keeping flights (one blob, or both in either order) and the allocation
    planner's own lone plan: their POS in the planners' coverage model (W x length per cell,
    no spill) stays below the bound with rho = 0, their POS by the environment's detection
    model (sampled, the sensor's spill) below the bound with the sensor's spill. The bound
    charges the travel between the blobs, so it is well below the rule-aware bound here (4
    valuable blocks of 30 km: a quick program), and not far above the best flight found."""
    _check(case, flights, 0.75)


def test_tour_bound_takes_the_least_and_checks_its_input(case):
    sc, _, prior, env_b, _ = case
    assert env_b.upper == min([env_b.rule, *env_b.by_keep.values()])
    for k, dual in env_b.by_keep.items():
        assert env_b.primal[k] <= dual + 1e-7
    two = sc.with_uavs(2)
    with pytest.raises(ConfigError, match="fleet"):
        tour_bound(two, prior)
    with pytest.raises(ConfigError, match="prior"):
        tour_bound(sc, prior[:-1])
    with pytest.raises(ConfigError, match="block_km"):
        tour_bound(sc, prior, block_km=0.0)
    with pytest.raises(ConfigError, match="spill_m"):
        tour_bound(sc, prior, spill_m=-1.0)


def test_one_blob_gives_the_rule_aware_bound_back():
    """One blob near the field: one flight can spend its effort as the rule-aware bound does,
    so the program (travel charged, tangents of each cell's POD) is the rule-aware bound up to
    the tangents (above it by under 1 %); mis-scaled tangents or travel move it off."""
    sc = load_scenario("paper_6_2", {"map.cell_km": 10}).with_uavs(1)
    grid = Grid.from_config(sc.map)
    x, y = _centres(grid)
    cx, cy = BLOBS_KM[0]
    prior = np.exp(-((x - cx * KM) ** 2 + (y - (cy - 80.0) * KM) ** 2) / (2 * (20 * KM) ** 2))
    prior = prior / prior.sum()
    for spill in (None, 0.0):
        b = tour_bound(sc, prior, block_km=30.0, keeps=(4,), spill_m=spill)
        assert b.rule - 1e-7 <= b.by_keep[4] <= 1.01 * b.rule
