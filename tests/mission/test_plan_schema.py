"""plan.json schema 2: the flown strip, its rule, the bounds, route plans; schema 1 still loads."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from poc_env.agents.mission.crs import to_local
from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.plan import (
    READ_SCHEMAS,
    RECTANGLE_RULE,
    SCHEMA,
    load_plan,
    search_rings,
    write_plan,
)
from poc_env.agents.planning.planner import make_plan, plan_table
from poc_env.errors import ConfigError
from poc_env.theory.timing import flight_time_s

ORIGIN = (45.75, 126.65)


@pytest.fixture(scope="module")
def plan():
    return make_plan("small", seed=3, popsize=12, maxiter=6, origin_deg=ORIGIN)


def test_a_new_plan_is_schema_2_with_flown_strips_rule_and_bounds(plan, tmp_path):
    assert plan["schema"] == SCHEMA == 2 and 1 in READ_SCHEMAS
    assert plan["rectangle_rule"] == RECTANGLE_RULE
    for u in plan["uavs"]:
        fr = u["flown_rectangle"]
        assert fr["strip_width_m"] > 0 and fr["line_length_m"] > 0
    b = plan["bounds"]
    # the plan flies at v_s for at most 0.85 T: it cannot beat either bound of the environment
    assert 0 < plan["posc"] <= b["reach"] <= b["honest"] * (1 + 1e-9) <= 1 + 1e-9
    assert "reach-aware" in plan_table(plan)
    path = write_plan(plan, tmp_path / "plan.json")
    assert load_plan(path)["uavs"][0]["flown_rectangle"] == plan["uavs"][0]["flown_rectangle"]


def test_reflying_the_exported_strip_gives_the_plans_flight_time(plan, tmp_path, usual_lawnmower):
    """Issue 12: the GeoJSON search strip, flown by the usual ceil(E/d) lawnmower at the plan's
    spacing, takes the plan's own eq. 17 time (coordinates are rounded to 1e-6 deg, ~0.1 m)."""
    path = write_plan(plan, tmp_path / "plan.json")
    (gj,) = export_plan(path, "geojson")
    feats = json.loads(gj.read_text())["features"]
    strips = {f["properties"]["id"]: f for f in feats if f["properties"]["kind"] == "search_strip"}
    assert sorted(strips) == [u["id"] for u in plan["uavs"]]
    assert not [f for f in feats if f["properties"]["kind"] == "search_rectangle"]
    fl = plan["flight"]
    for u in plan["uavs"]:
        ring = strips[u["id"]]["geometry"]["coordinates"][0]
        c = np.asarray(to_local([(lat, lon) for lon, lat in ring[:4]], plan["crs"]))
        alpha = np.arctan2(*(c[1] - c[0])[::-1])
        length, strip = np.hypot(*(c[1] - c[0])), np.hypot(*(c[3] - c[0]))
        heading = strips[u["id"]]["properties"]["lines_heading_deg"]
        assert np.degrees(alpha) % 360 == pytest.approx(heading, abs=0.006)  # 2 decimals
        start = u["takeoff_m"]
        n, wps = usual_lawnmower(c.mean(axis=0), length, strip, alpha, u["spacing_m"], start)
        assert n == max(1, round(strip / u["spacing_m"]))  # the rule's strip_width / spacing
        t = flight_time_s(
            u["takeoff_m"], wps, u["landing_m"], fl["cruise_speed_mps"], fl["search_speed_mps"]
        )
        assert t == pytest.approx(u["flight_time_s"], rel=1e-5)


def test_schema_1_still_loads_and_draws_its_rectangle(plan, tmp_path):
    old = copy.deepcopy(plan)
    old["schema"] = 1
    for key in ("rectangle_rule", "bounds"):
        old.pop(key)
    for u in old["uavs"]:
        u.pop("flown_rectangle")
    path = write_plan(old, tmp_path / "old.json")
    (gj,) = export_plan(path, "geojson")
    kinds = [f["properties"]["kind"] for f in json.loads(gj.read_text())["features"]]
    assert kinds.count("search_rectangle") == len(plan["uavs"])
    assert "search_strip" not in kinds


def test_route_plans_have_no_rectangle_but_areas(plan, tmp_path):
    route = copy.deepcopy(plan)
    for u in route["uavs"]:
        u["rectangle"] = None
        u.pop("flown_rectangle")
        x, y = u["waypoints_m"][0]
        u["areas_m"] = [[[x, y], [x + 1e3, y], [x + 1e3, y + 1e3], [x, y + 1e3]]]
    kinds = [k for u in route["uavs"] for k, _, _ in search_rings(u)]
    assert kinds == ["search_area"] * len(route["uavs"])
    path = write_plan(route, tmp_path / "route.json")
    for fmt in ("geojson", "kml", "qgc"):
        assert export_plan(path, fmt)
    assert "search area" in (tmp_path / "route.kml").read_text()
    route["schema"] = 1  # schema 1 requires the rectangle
    path = write_plan(route, tmp_path / "route1.json")
    with pytest.raises(ConfigError, match=r"uavs\[0\]\.rectangle"):
        load_plan(path)


@pytest.mark.parametrize(
    ("where", "value", "field"),
    [
        ("schema", 3, "plan.schema"),
        ("schema", True, "plan.schema"),
        ("bounds", {"honest": 0.5}, "plan.bounds"),
        ("bounds", {"honest": 0.5, "reach": 1.5}, "plan.bounds.reach"),
        ("rectangle_rule", 7, "plan.rectangle_rule"),
        ("flown", {"center_m": [0, 0]}, r"uavs\[0\]\.flown_rectangle"),
        ("theta", float("nan"), r"uavs\[0\]\.flown_rectangle\.lines_theta_rad"),
        ("areas", [[[0, 0], [1, 1]]], r"uavs\[0\]\.areas_m\[0\]"),
    ],
)
def test_bad_schema_2_fields_name_the_field(plan, tmp_path, where, value, field):
    bad = copy.deepcopy(plan)
    if where == "flown":
        bad["uavs"][0]["flown_rectangle"] = value
    elif where == "theta":
        bad["uavs"][0]["flown_rectangle"]["lines_theta_rad"] = value
    elif where == "areas":
        bad["uavs"][0]["areas_m"] = value
    else:
        bad[where] = value
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad))
    with pytest.raises(ConfigError, match=field):
        load_plan(path)


@pytest.mark.parametrize("planner", ["de", "allocation"])
def test_bounds_are_the_planned_fleets(planner):
    # uavs=n plans n UAVs: plan.json's bounds are that fleet's, not the scenario's
    from poc_env.config import load_scenario
    from poc_env.theory.bound import reach_bound
    from poc_env.theory.probability_map import build_prior

    sc = load_scenario("small")
    prior = build_prior(sc.map)
    kw = {"popsize": 4, "maxiter": 1} if planner == "de" else {}
    one = make_plan("small", uavs=1, planner=planner, **kw)
    assert len(one["uavs"]) == 1
    assert one["bounds"]["reach"] == pytest.approx(reach_bound(sc.with_uavs(1), prior).upper)
    assert one["bounds"]["reach"] < reach_bound(sc, prior).upper
