"""The rule-aware bound without merged airfields (:mod:`poc_env.theory.split_bound`)."""

import numpy as np

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.theory.bound import rule_bound
from poc_env.theory.probability_map import Grid
from poc_env.theory.split_bound import _pairings, split_rule_bound


def _blobs(grid: Grid, centres_km, sigma_km: float) -> np.ndarray:
    ys, xs = np.mgrid[0 : grid.ny, 0 : grid.nx]
    c = grid.cell_m / 1e3
    x, y = xs * c + c / 2, ys * c + c / 2
    p = sum(np.exp(-((x - a) ** 2 + (y - b) ** 2) / (2 * sigma_km**2)) for a, b in centres_km)
    return p / p.sum()


def test_two_airfields_give_the_rule_bound():
    """paper_6_2 (two fields: ``rule_bound`` is exact there): the same bound."""
    sc = load_scenario("paper_6_2")
    prior = _blobs(Grid.from_config(sc.map), [(60, 90), (150, 60)], 15.0)
    sb = split_rule_bound(sc, prior)
    assert sb.how == "rule"
    assert sb.upper == sb.rule == rule_bound(sc, prior).upper


def test_pairings_cover_every_field_once():
    for n in range(1, 7):
        parts = _pairings(list(range(n)))
        assert parts and len({tuple(p) for p in parts}) == len(parts)
        for p in parts:
            assert sorted(f for b in p for f in b) == list(range(n))
            assert all(len(b) <= 2 for b in p)
            assert sum(len(b) == 1 for b in p) == n % 2


def test_three_airfields_tighter_and_still_above_a_plan():
    """large_400 on 20 km cells (three fields, 12 UAVs). A blob near the north field only: the
    merged relaxation credits the south-east field's UAVs the north field's reach, the split
    bound does not (at least 10 % lower). Three blobs, one near each field: the fleet's
    allocation plan (planned POS, the environment's detection model) stays below the split
    bound, which needs every block's share summed."""
    sc = load_scenario("large_400", {"map.cell_km": 20})
    grid = Grid.from_config(sc.map)
    north = _blobs(grid, [(200, 350)], 30.0)
    sb = split_rule_bound(sc, north)
    assert sb.upper <= sb.rule
    assert sb.upper < 0.9 * sb.rule, sb
    three = _blobs(grid, [(80, 60), (320, 60), (200, 350)], 30.0)
    sb3 = split_rule_bound(sc, three)
    plan = make_allocation_plan(sc, prior=three, refine=0)
    assert 0.0 < plan["posc"] <= sb3.upper <= sb3.rule
    assert plan["posc"] > 0.5 * sb3.upper, (plan["posc"], sb3)


def test_large_grids_split_into_single_fields():
    """On grids where ``rule_bound`` merges even two fields into one (more than
    sqrt(bound._MAX_PAIRS) cells: large_400 at 4 km cells, 100 x 100) the single fields' sum is
    tried too. Two fields, south-west and north, a blob near the north one: the merged bound
    credits the south-western UAVs the north field's reach, the split bound is at least 10 %
    lower and still above the north field's own bound."""
    import dataclasses

    sc = load_scenario("large_400", {"map.cell_km": 4})
    sc = dataclasses.replace(sc, fleet=(sc.fleet[0], sc.fleet[2]))
    grid = Grid.from_config(sc.map)
    assert (grid.nx * grid.ny) ** 2 > 50_000_000
    prior = _blobs(grid, [(200, 350)], 30.0)
    sb = split_rule_bound(sc, prior)
    alone = rule_bound(dataclasses.replace(sc, fleet=sc.fleet[1:]), prior).upper
    assert alone < sb.upper < 0.9 * sb.rule, (alone, sb)
