"""The rule-aware bound with more than two airfields (:func:`poc_env.theory.bound.rule_bound`:
the least of the merged relaxations and of sums over blocks of at most two fields)."""

import dataclasses

import numpy as np
import pytest

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.theory import bound
from poc_env.theory.bound import _pairings, _rule_relaxation, env_limits, rule_bound
from poc_env.theory.probability_map import Grid


def _blobs(grid: Grid, centres_km, sigma_km: float) -> np.ndarray:
    ys, xs = np.mgrid[0 : grid.ny, 0 : grid.nx]
    c = grid.cell_m / 1e3
    x, y = xs * c + c / 2, ys * c + c / 2
    p = sum(np.exp(-((x - a) ** 2 + (y - b) ** 2) / (2 * sigma_km**2)) for a, b in centres_km)
    return p / p.sum()


@pytest.mark.parametrize("name", ["paper_6_2", "small"])
def test_at_most_two_airfields_give_the_relaxation_bit_for_bit(name):
    """One or two fields on a grid where the relaxation is exact: the very same bits (values
    and coverage) as the single relaxation, with and without a spill."""
    sc = load_scenario(name)
    prior = _blobs(Grid.from_config(sc.map), [(60, 90), (150, 60)], 15.0)
    for spill in (None, 0.0):
        rb = rule_bound(sc, prior, spill_m=spill)
        rho = env_limits(sc).spill_m if spill is None else spill
        one = _rule_relaxation(sc, prior, rho)
        assert rb.how == "exact"
        assert (rb.upper, rb.pos, rb.merged) == (one.upper, one.pos, one.upper)
        assert np.array_equal(rb.coverage, one.coverage)


def test_pairings_cover_every_field_once():
    for n in range(1, 7):
        parts = _pairings(list(range(n)))
        assert parts and len({tuple(p) for p in parts}) == len(parts)
        for p in parts:
            assert sorted(f for b in p for f in b) == list(range(n))
            assert all(len(b) <= 2 for b in p)
            assert sum(len(b) == 1 for b in p) == n % 2


def _orders_only(sc, prior) -> float:
    """The least of the merged relaxations with each field first (no block sums)."""
    rho = env_limits(sc).spill_m
    fields = list(dict.fromkeys(g.takeoff for g in sc.fleet))
    return min(
        _rule_relaxation(
            dataclasses.replace(sc, fleet=tuple(sorted(sc.fleet, key=lambda g: g.takeoff != f))),
            prior,
            rho,
        ).upper
        for f in fields
    )


def test_three_airfields_tighter_and_still_above_a_plan():
    """large_400 on 20 km cells (three fields, 12 UAVs). A blob near the north field only: the
    merged relaxation credits the south-east field's UAVs the north field's reach, the bound
    does not (at least 10 % lower). Blobs near the south-west and north fields: the sum over
    the blocks (SW, N) + (SE) is below every merged relaxation (fails if the block sums are
    dropped). Three blobs, one near each field: the fleet's allocation plan (planned POS, the
    environment's detection model) stays below the bound, which needs every block's share
    summed."""
    sc = load_scenario("large_400", {"map.cell_km": 20})
    grid = Grid.from_config(sc.map)
    north = _blobs(grid, [(200, 350)], 30.0)
    rb = rule_bound(sc, north)
    assert rb.upper <= rb.merged
    assert rb.upper < 0.9 * rb.merged, rb
    two = _blobs(grid, [(80, 60), (200, 350)], 30.0)
    rb2 = rule_bound(sc, two)
    assert rb2.how == "blocks=(0, 1)+(2,)"
    assert rb2.upper < 0.995 * _orders_only(sc, two), rb2
    three = _blobs(grid, [(80, 60), (320, 60), (200, 350)], 30.0)
    rb3 = rule_bound(sc, three)
    plan = make_allocation_plan(sc, prior=three, refine=0)
    assert 0.0 < plan["posc"] <= rb3.upper <= rb3.merged
    assert plan["posc"] > 0.5 * rb3.upper, (plan["posc"], rb3)


def test_large_grids_split_into_single_fields():
    """On grids where the relaxation merges even two fields into one (more than
    sqrt(bound._MAX_PAIRS) cells: large_400 at 4 km cells, 100 x 100) the single fields' sum is
    tried too. Two fields, south-west and north, a blob near the north one: the merged
    relaxation credits the south-western UAVs the north field's reach, the bound is at least
    10 % lower and still above the north field's own bound; ``spill_m`` reaches the parts."""
    sc = load_scenario("large_400", {"map.cell_km": 4})
    sc = dataclasses.replace(sc, fleet=(sc.fleet[0], sc.fleet[2]))
    grid = Grid.from_config(sc.map)
    assert (grid.nx * grid.ny) ** 2 > bound._MAX_PAIRS
    prior = _blobs(grid, [(200, 350)], 30.0)
    rb = rule_bound(sc, prior)
    alone = rule_bound(dataclasses.replace(sc, fleet=sc.fleet[1:]), prior).upper
    assert alone < rb.upper < 0.9 * rb.merged, (alone, rb)
    assert rb.how == "blocks=(0,)+(1,)"
    rb0 = rule_bound(sc, prior, spill_m=0.0)
    alone0 = rule_bound(dataclasses.replace(sc, fleet=sc.fleet[1:]), prior, spill_m=0.0).upper
    assert alone0 < rb0.upper < rb.upper


def test_flown_allocation_plans_stay_below_the_bound_with_three_airfields():
    """large_400 on 20 km cells, random priors whose bound is a block sum (seed 12, 0.80 of the
    merged relaxation) and a reordered merge (seed 13): the allocation plan flown in the
    environment (the sensor's spill included) stays below the bound."""
    from poc_env.agents.benchmarks.plan_scale import _flown
    from poc_env.agents.experiments.evaluate import episode_prior

    sc = load_scenario("large_400", {"map.cell_km": 20})
    hows = []
    for seed in (12, 13):
        prior = episode_prior(sc, seed)
        rb = rule_bound(sc, prior)
        posc, _ = _flown(sc, "allocation_plan", seed, prior)
        assert 0.0 < posc <= rb.upper < 0.95 * rb.merged, (seed, posc, rb)
        hows.append(rb.how.split("=")[0])
    assert hows == ["blocks", "first"]
