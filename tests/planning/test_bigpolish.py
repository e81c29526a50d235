"""The polish on maps above the cell limit, within a work budget (i24-bigpolish)."""

import dataclasses

import numpy as np
import pytest
import shapely

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.polish import polish_for
from poc_env.agents.testing.routes import assert_flyable_inside
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import Grid, build_prior

#: a 10 x 20 km zone across the middle of ``small`` (8 x 8 cells; the prior's two blobs either
#: side), as tests/planning/test_zonepolish.py's
ZONE = {"map.no_fly_zones_km": [[[15, 10], [25, 10], [25, 30], [15, 30]]]}
#: ``standard`` with a cell limit below ``small``'s 8 cells a side: ``small`` is a big map
BIG = dataclasses.replace(
    PlanOptions.preset("standard"), polish_max_cells=7, polish_big_work=40_000, polish_big_lines=4
)


def _routes(plan: dict) -> list:
    return [u["waypoints_m"] for u in plan["uavs"]]


def _fields(sc) -> tuple[np.ndarray, np.ndarray]:
    return (np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2),
            np.asarray(sc.landing_m, dtype=float).reshape(-1, 2))  # fmt: skip


def test_the_big_map_polish_engages_above_the_cell_limit_and_keeps_the_rules():
    """Above ``polish_max_cells`` with a work budget the polish runs (it was skipped): moves
    kept, more planned POS than the default plan, the budget's steps recorded; every route
    fits eq. 17-18 with its new waypoints inside the map and keeps out of the zone (eq. 20);
    the same plan twice (a count, not a clock). Without a budget the polish is skipped there,
    as before."""
    sc = load_scenario("small", ZONE)
    base = make_allocation_plan(sc)
    big = make_allocation_plan(sc, options=BIG)
    pol = big["optimizer"]["settings"]["polish"]
    assert "skipped" not in pol and pol["moves"] > 0
    assert pol["work"] > 0 and isinstance(pol["spent"], bool)
    assert big["posc"] > base["posc"] + 1e-3
    takeoff, landing = _fields(sc)
    assert_flyable_inside(sc, Grid.from_config(sc.map), takeoff, landing, _routes(big),
                          _routes(base))  # fmt: skip
    zones = shapely.union_all([shapely.Polygon(z) for z in sc.map.no_fly_zones_m])
    for k, r in enumerate(_routes(big)):  # eq. 20: no leg meets the zone
        assert not r or not shapely.LineString([takeoff[k], *r, landing[k]]).intersects(zones)
    again = make_allocation_plan(sc, options=BIG)
    assert _routes(again) == _routes(big) and again["posc"] == big["posc"]
    off = make_allocation_plan(sc, options=dataclasses.replace(BIG, polish_big_work=0))
    assert _routes(off) == _routes(base)
    assert off["optimizer"]["settings"]["polish"]["skipped"] == "map larger than polish_max_cells"


def test_the_budget_stops_the_search_where_the_unbounded_one_was():
    """``work``: the polish scores candidate steps until the budget is spent; what it keeps is
    the unbounded search's first moves (the traces agree up to the stop), fewer of them, and
    the planned POS lies between the routes' and the unbounded polish's; a budget of 0 keeps
    the routes; a budget above the unbounded search's work is that search, bit for bit."""
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    routes = _routes(make_allocation_plan(sc, prior=prior))
    _, before, _ = polish_for(sc, routes, prior, 0)

    def run(**kw):
        seen: list = []
        out = polish_for(sc, routes, prior, 3, moves=("move", "shift", "grade", "block"),
                         trace=lambda *a: seen.append(a), **kw)  # fmt: skip
        return (*out, seen)

    full, v_full, s_full, t_full = run()
    _, _, s_all, _ = run(work=10**9)
    whole = s_all["work"]
    again, v_again, s_again, t_again = run(work=whole)
    assert (again, v_again, t_again) == (full, v_full, t_full) and not s_again["spent"]
    _, v_cut, s_cut, t_cut = run(work=whole // 3)
    assert s_cut["spent"] and whole // 3 <= s_cut["work"] < whole
    assert 0 < s_cut["moves"] < s_full["moves"]
    assert t_cut == t_full[: len(t_cut)]
    assert before < v_cut < v_full
    zero, v_zero, s_zero, _ = run(work=0)
    assert zero == routes and v_zero == before and s_zero["moves"] == 0 and s_zero["spent"]


def test_big_lines_passes_reach_the_second_polish_on_big_maps_only():
    """``polish_big_lines`` sets the second polish's passes above the cell limit (more passes
    than ``polish_lines``' one there), and changes nothing at or below it."""
    sc = load_scenario("small")
    one = dataclasses.replace(BIG, polish=1, polish_lines=1, polish_big_lines=0,
                              polish_big_work=10**9)  # fmt: skip
    more = dataclasses.replace(one, polish_big_lines=4)
    p_one = make_allocation_plan(sc, options=one)["optimizer"]["settings"]["polish"]
    p_more = make_allocation_plan(sc, options=more)["optimizer"]["settings"]["polish"]
    assert p_one["passes"] <= 2 < p_more["passes"]
    assert p_more["lines_moves"] > p_one["lines_moves"]
    for opt in (one, more):  # at the cell limit: the options' own passes, no budget
        here = dataclasses.replace(opt, polish_max_cells=8)
        plain = dataclasses.replace(here, polish_big_work=0, polish_big_lines=0)
        a, b = make_allocation_plan(sc, options=here), make_allocation_plan(sc, options=plain)
        assert _routes(a) == _routes(b) and "work" not in a["optimizer"]["settings"]["polish"]


@pytest.mark.parametrize(
    ("field", "bad"),
    [("polish_big_work", -1), ("polish_big_work", 1.5), ("polish_big_work", True),
     ("polish_big_lines", -1), ("polish_big_lines", 101), ("polish_big_lines", 2.0)],
)  # fmt: skip
def test_big_polish_options_are_checked(field, bad):
    with pytest.raises(ConfigError, match=f"options.{field}"):
        PlanOptions(**{field: bad})


@pytest.mark.parametrize("bad", [-1, 2.5, True, "10"])
def test_the_work_argument_is_checked(bad):
    sc = load_scenario("small")
    with pytest.raises(ConfigError, match="work"):
        polish_for(sc, [[] for _ in sc.takeoff_m], build_prior(sc.map), 1, work=bad)


def test_the_plan_summary_says_when_the_budget_stopped_the_polish():
    """``effort_skip_note`` (plan's and replan's summary) names the stop at the work budget;
    a polish that ended by itself or by its passes is not noted."""
    from poc_env.agents.planning.planner import effort_skip_note

    sc = load_scenario("small")
    tight = make_allocation_plan(sc, options=dataclasses.replace(BIG, polish_big_work=5_000))
    note = effort_skip_note(tight, "standard")
    assert note is not None and "stopped its polish at its work budget" in note
    assert f"{tight['optimizer']['settings']['polish']['work']:,} candidate steps" in note
    loose = make_allocation_plan(sc, options=dataclasses.replace(BIG, polish_big_work=10**9))
    assert not loose["optimizer"]["settings"]["polish"]["spent"]
    assert effort_skip_note(loose, "standard") is None
