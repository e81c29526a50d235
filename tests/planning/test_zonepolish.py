"""The polish on maps with no-fly zones (i24-zonepolish): every candidate keeps eq. 20."""

import numpy as np
import pytest
import shapely

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.polish import polish_for, zone_guard
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import build_prior

#: a 10 x 20 km zone across the middle of ``small`` (the prior's two blobs either side)
ZONE = {"map.no_fly_zones_km": [[[15, 10], [25, 10], [25, 30], [15, 30]]]}


def _paths(sc, routes) -> list[np.ndarray]:
    return [
        np.array([sc.takeoff_m[k], *r, sc.landing_m[k]], dtype=float)
        for k, r in enumerate(routes)
        if r
    ]


def _entering(sc, routes) -> tuple[int, int]:
    """(routes that meet a zone, legs that cross the router's obstacle: zones grown by c)."""
    router = ZoneRouter.for_scenario(sc)
    zones = shapely.union_all([shapely.Polygon(z) for z in sc.map.no_fly_zones_m])
    paths = _paths(sc, routes)
    meet = sum(bool(shapely.LineString(p).intersects(zones)) for p in paths)
    return meet, sum(int(router.crosses(p[:-1], p[1:]).sum()) for p in paths)


def test_polish_with_zones_keeps_every_leg_out_and_moves():
    """The polish with the router: it keeps moves (the routes change, the planned POS rises)
    and no leg of the polished routes meets the zone or cuts the router's clearance ring; the
    same polish without the router (as the moves see the map) does enter the zone here, so
    the check is what keeps the routes out."""
    sc = load_scenario("small", ZONE)
    prior = build_prior(sc.map)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
    assert _entering(sc, routes) == (0, 0)
    _, before, _ = polish_for(sc, routes, prior, 0)
    router = ZoneRouter.for_scenario(sc)
    out, value, stats = polish_for(sc, routes, prior, 2, router=router)
    assert stats["moves"] > 0 and out != routes and value > before + 1e-3
    assert _entering(sc, out) == (0, 0)
    blind, _, _ = polish_for(sc, routes, prior, 2)
    assert _entering(sc, blind)[0] > 0


def test_standard_effort_polishes_maps_with_zones_and_the_option_skips_it():
    """The planner polishes with zones (``polish_zones``, default True): moves kept, more
    planned POS than the default plan, every route out of the zone; ``polish_zones=False``
    is the plan before (the polish skipped, the settings say why)."""
    sc = load_scenario("small", ZONE)
    base = make_allocation_plan(sc)
    std = make_allocation_plan(sc, options=PlanOptions.preset("standard"))
    pol = std["optimizer"]["settings"]["polish"]
    assert "skipped" not in pol and pol["moves"] > 0
    assert std["posc"] > base["posc"] + 1e-3
    assert _entering(sc, [u["waypoints_m"] for u in std["uavs"]]) == (0, 0)
    off = PlanOptions(polish=2, polish_zones=False)
    skip = make_allocation_plan(sc, options=off)
    assert [u["waypoints_m"] for u in skip["uavs"]] == [u["waypoints_m"] for u in base["uavs"]]
    assert skip["optimizer"]["settings"]["polish"]["skipped"] == "no-fly zones"


def test_zone_guard_rejects_entering_and_deepening_legs_only():
    """``zone_guard``: a leg through the zone is rejected, one clear of the ring is not, and a
    window already crossing the clearance ring may keep (not add) such legs; no guard without
    zones."""
    sc = load_scenario("small", ZONE)
    bad = zone_guard(ZoneRouter.for_scenario(sc))
    assert bad is not None
    west, east = np.array([5e3, 20e3]), np.array([35e3, 20e3])
    south = np.array([20e3, 2e3])
    through = np.array([west, east])
    around = np.array([west, [5e3, 2e3], south, [35e3, 2e3], east])
    assert bad(around, through)
    assert not bad(through, around)
    ring = np.array([west, [14.5e3, 20e3], [14.5e3, 2e3]])  # 0.5 km from the zone: in the ring
    assert not bad(ring, ring) and bad(around, ring)
    assert zone_guard(ZoneRouter.for_scenario(load_scenario("small"))) is None
    assert zone_guard(None) is None


@pytest.mark.parametrize("bad", [1, "yes", None])
def test_polish_zones_option_is_checked(bad):
    with pytest.raises(ConfigError, match=r"options\.polish_zones"):
        PlanOptions(polish_zones=bad)


def test_zone_reach_option_reaches_the_objective_on_maps_with_zones_only():
    """``zone_reach`` (the zone credit's reach, sweep widths; default the W/2 discount, which
    flew best on the validation maps: docs/PLANNER.md, "Polish and credit with no-fly zones"):
    with a sighting just inside a zone, crediting the interior within 4 W of the outside
    changes the plan (its allocation; the default is ``0.5``); without zones nothing
    changes."""
    sc = load_scenario("small", ZONE)
    prior = np.full((8, 8), 1e-4)
    prior[3, 3] = 1.0  # the cell 15-20 km x 15-20 km: inside the zone's west edge
    prior /= prior.sum()
    base = make_allocation_plan(sc, prior=prior)
    same = make_allocation_plan(sc, prior=prior, options=PlanOptions(zone_reach=0.5))
    wide = make_allocation_plan(sc, prior=prior, options=PlanOptions(zone_reach=4.0))
    assert same["uavs"] == base["uavs"] and same["allocation_pos"] == base["allocation_pos"]
    assert wide["allocation_pos"] > base["allocation_pos"] + 1e-3
    assert _entering(sc, [u["waypoints_m"] for u in wide["uavs"]]) == (0, 0)
    free = load_scenario("small")
    plain = make_allocation_plan(free, prior=prior)
    assert (
        make_allocation_plan(free, prior=prior, options=PlanOptions(zone_reach=4.0))["uavs"]
        == plain["uavs"]
    )


@pytest.mark.parametrize("bad", [0, -1.0, 17.0, "2", True, float("nan")])
def test_zone_reach_option_is_checked(bad):
    with pytest.raises(ConfigError, match=r"options\.zone_reach"):
        PlanOptions(zone_reach=bad)


#: two 30 x 40 km zones on ``paper_6_2`` where its default routes run beside them
TWO_ZONES = {
    "map.no_fly_zones_km": [
        [[60, 50], [90, 50], [90, 90], [60, 90]],
        [[120, 80], [150, 80], [150, 120], [120, 120]],
    ]
}


def test_the_regrade_keeps_its_runs_out_of_the_zones():
    """The regrade with the router (i24-smallfix): no leg of a regraded route meets a zone or
    cuts the clearance ring, and it still keeps moves; without the router the same regrade
    enters the zones here (so the check is what keeps it out). The planner regrades on maps
    with zones (``options.regrade``), no longer skipping it."""
    from poc_env.agents.planning.regrade import regrade_routes

    sc = load_scenario("paper_6_2", TWO_ZONES)
    prior = build_prior(sc.map)
    routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
    assert _entering(sc, routes) == (0, 0)
    blind, _, _ = polish_for(sc, routes, prior, 2, routine=regrade_routes)
    assert _entering(sc, blind)[0] > 0
    router = ZoneRouter.for_scenario(sc)
    out, _, stats = polish_for(sc, routes, prior, 2, routine=regrade_routes, router=router)
    assert stats["moves"] > 0 and out != routes
    assert _entering(sc, out) == (0, 0)
    plan = make_allocation_plan(sc, prior=prior, options=PlanOptions(regrade=1))
    settings = plan["optimizer"]["settings"]["polish"]
    assert "regrade_skipped" not in settings and settings["regrade_moves"] > 0
    assert _entering(sc, [u["waypoints_m"] for u in plan["uavs"]]) == (0, 0)


def test_one_zone_discount_for_the_greedy_rectangles_and_its_start(monkeypatch):
    """i24-smallfix: the greedy rectangle planner counts the prior near the zones by the
    allocation's ``zone_reach`` (``geography.zone_prior``), not a W/2 of its own: its default
    is the option's default, another reach changes its planned POS, and the allocation's
    greedy start is planned at the allocation's own ``zone_reach``."""
    from poc_env.agents.planning import greedy_rectangles

    sc = load_scenario("paper_6_2", TWO_ZONES)
    prior = build_prior(sc.map)
    plan = greedy_rectangles.make_greedy_rectangles_plan
    default = plan(sc, prior=prior)["posc"]
    assert plan(sc, prior=prior, zone_reach=PlanOptions.zone_reach)["posc"] == default
    assert abs(plan(sc, prior=prior, zone_reach=2.0)["posc"] - default) > 1e-3
    with pytest.raises(ConfigError, match=r"zone_reach"):
        plan(sc, prior=prior, zone_reach=-1.0)
    seen = []

    def spy(*a, **kw):
        seen.append(kw.get("zone_reach"))
        return plan(*a, **kw)

    monkeypatch.setattr(greedy_rectangles, "make_greedy_rectangles_plan", spy)
    make_allocation_plan(sc, prior=prior, options=PlanOptions(zone_reach=1.5, refine=0))
    assert seen == [1.5]
