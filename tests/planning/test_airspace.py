"""Airspace (issue 24): plans and flights keep eq. 20 around no-fly zones, and every plan the
planners write is exported in every format."""

import json

import numpy as np
import pytest
import shapely

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.plan import write_plan
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.policies.allocation import AllocationPlanPolicy
from poc_env.agents.policies.de_plan import DEPlanPolicy
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import Grid

#: a zone across the middle of ``small``'s search area (km), named as an import names it.
ACROSS = {"map.no_fly_zones_km": [[[15, 10], [25, 10], [25, 30], [15, 30]]],
          "map.no_fly_names": ["range R-12"]}  # fmt: skip


def _crossings(plan, zones) -> int:
    polys = [shapely.Polygon(z) for z in zones]
    return sum(
        shapely.LineString([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]).intersects(z)
        for u in plan["uavs"]
        for z in polys
    )


def test_router_goes_around_and_stays_in_the_area():
    r = ZoneRouter([[(0, 0), (10, 0), (10, 10), (0, 10)]], (-20, -20, 30, 30), 1.0)
    p = r.path([-5, 5], [15, 5])
    assert p is not None and len(p) > 2
    line = shapely.LineString(p)
    assert not line.intersects(shapely.box(0, 0, 10, 10))
    assert line.length < 20 + 2 * 5 + 2 * np.pi  # around one side, not the long way
    assert np.all((p >= -20) & (p <= 30))
    # a zone touching the area's edge on both sides leaves no way round
    wall = ZoneRouter([[(0, -30), (10, -30), (10, 40), (0, 40)]], (-20, -20, 30, 30), 1.0)
    assert wall.path([-5, 5], [15, 5]) is None
    # search legs clipped: a line through the zone flies only outside it (plus the way round)
    pts = r.reroute([[-5, 5], [15, 5]])
    assert not shapely.LineString(pts).intersects(shapely.box(0, 0, 10, 10))


def test_reach_share_discounts_only_what_the_sensor_cannot_reach():
    sc = load_scenario("paper_6_2", {"map.no_fly_zones_km": [[[60, 20], [90, 20], [90, 120],
                                                                [60, 120]]]})  # fmt: skip
    share = ZoneRouter.for_scenario(sc).reach_share(Grid.from_config(sc.map), reach_m=2500.0)
    assert share[10, 14] == 0.0  # deep inside
    assert share[10, 5] == 1.0 and share[0, 30] == 1.0  # far away
    assert 0.0 < share[10, 11] < 1.0  # the rim: reached from outside in part


def test_planners_route_around_a_zone_across_the_search_area():
    sc = load_scenario("small", ACROSS)
    for plan in (make_allocation_plan(sc), make_plan(sc, popsize=16, maxiter=15)):
        assert _crossings(plan, sc.map.no_fly_zones_m) == 0
        assert plan["no_fly_zone_names"] == ["range R-12"]
        assert all(u["waypoints_m"] for u in plan["uavs"])
    # the zone matters: moving it changes the routes (issue 24: it did not)
    moved = load_scenario("small", {"map.no_fly_zones_km": [[[5, 5], [12, 5], [12, 12]]]})
    a = make_allocation_plan(sc)["uavs"][0]["waypoints_m"]
    assert make_allocation_plan(moved)["uavs"][0]["waypoints_m"] != a


@pytest.mark.parametrize("policy", ["allocation", "de"])
def test_flown_plans_have_no_no_fly_steps(policy, fly):
    sc = load_scenario("small", ACROSS)
    pol = AllocationPlanPolicy() if policy == "allocation" else DEPlanPolicy(16, 15)
    f = fly(sc, pol)
    assert (f.nofly_steps, f.oob_steps) == (0, 0)
    assert f.landed == sc.n_uavs


def test_zone_over_an_airfield_or_the_whole_area_is_named():
    with pytest.raises(ConfigError, match=r"no-fly zone 0 \('R-1'\)"):
        load_scenario("small", {"map.no_fly_zones_km": [[[15, -8], [25, -8], [25, 2]]],
                                "map.no_fly_names": ["R-1"]})  # fmt: skip
    with pytest.raises(ConfigError, match=r"no_fly_zones_km\[1\].*covers all"):
        load_scenario(
            "small",
            {
                "map.no_fly_zones_km": [
                    [[0, 0], [1, 0], [1, 1]],
                    [[-1, 0], [41, 0], [41, 41], [-1, 41]],
                ]
            },
        )


def test_plan_bounds_and_probabilities_are_in_0_1(tmp_path):
    # a prior concentrated in one cell: sums round to 1 + 2e-16 (issue 24)
    sc = load_scenario("small")
    prior = np.zeros((8, 8))
    prior[4, 3] = 1.0
    plan = make_allocation_plan(sc.with_uavs(6), prior=prior)
    for v in (plan["posc"], *plan["bounds"].values(), plan["bound_reach"]):
        assert 0.0 <= v <= 1.0
    path = write_plan(plan, tmp_path / "plan.json")
    assert json.loads(path.read_text())["bounds"]["honest"] <= 1.0
    export_plan(path, "geojson", origin=(46.5, 7.9))
