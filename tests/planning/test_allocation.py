"""The allocation planner: routes from the reach-aware allocation, within the bounds and 0.85 T."""

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from poc_env.agents.planning.allocation import REFINE, make_allocation_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.bound import honest_optimum, reach_bound
from poc_env.theory.probability_map import Grid, build_prior


def _small(**over):
    return load_scenario("small", over or None)


@pytest.mark.parametrize("refine", [0, REFINE])
def test_small_plan_is_flyable_and_inside_the_map(refine):
    sc = _small()
    plan = make_allocation_plan(sc, refine=refine)
    assert plan["reason"] is None
    grid = Grid.from_config(sc.map)
    x0, y0, x1, y1 = grid.bounds
    flown = 0
    for u in plan["uavs"]:
        assert u["flight_time_s"] <= sc.uav.usable_endurance_s
        assert u["feasible"]
        assert u["transit_waypoints"] in (0, 1)  # a dog-leg out of the shared field
        wps = np.asarray(u["waypoints_m"]).reshape(-1, 2)[u["transit_waypoints"] :]
        if not refine:
            assert len(wps) % 2 == 0  # search lines: start and end
        flown += len(wps)
        if len(wps):
            assert np.all(wps[:, 0] >= x0) and np.all(wps[:, 0] <= x1)
            assert np.all(wps[:, 1] >= y0) and np.all(wps[:, 1] <= y1)
    assert flown > 0
    assert 0 < plan["posc"] <= plan["bound_reach"]
    assert plan["posc"] == pytest.approx(sum(u["pos"] for u in plan["uavs"]), abs=1e-9)
    assert plan["bounds"]["reach"] == plan["bound_reach"] <= plan["bounds"]["honest"] + 1e-9
    json.dumps(plan)  # plan.json-able


def test_make_plan_dispatches_to_the_allocation_planner():
    plan = make_plan("small", planner="allocation")
    assert plan["planner"] == "allocation"
    assert plan["posc"] == pytest.approx(make_allocation_plan("small")["posc"])
    with pytest.raises(ConfigError, match="planner"):
        make_plan("small", planner="bogus")


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**31 - 1))
def test_planned_posc_never_above_either_bound(seed):
    sc = _small()
    grid = Grid.from_config(sc.map)
    prior = np.random.default_rng(seed).gamma(0.5, size=grid.shape)
    prior /= prior.sum()
    plan = make_allocation_plan(sc, prior=prior)
    assert plan["posc"] <= reach_bound(sc, prior).upper + 1e-12
    assert plan["posc"] <= honest_optimum(sc, prior).pos + 1e-12
    assert plan["posc"] <= plan["upper_bound"] + 1e-12  # the allocation it was built from


def test_zero_mass_gives_an_empty_plan_with_a_reason():
    sc = _small()
    plan = make_allocation_plan(sc, prior=np.zeros(Grid.from_config(sc.map).shape))
    assert plan["reason"] == "the prior has no mass on the map"
    assert plan["posc"] == 0 and all(u["waypoints_m"] == [] for u in plan["uavs"])


def test_no_uav_reaches_any_mass_gives_an_empty_plan():
    sc = _small(**{"uav.endurance_h": 0.05})  # 0.85 T = 153 s: 9 km out and back at most
    plan = make_allocation_plan(sc)
    assert "no UAV can reach any mass" in plan["reason"]
    assert plan["posc"] == 0 and all(u["waypoints_m"] == [] for u in plan["uavs"])


def test_an_empty_plan_says_why_its_bounds_stay_above_zero():
    """G4 (results/audit/dayaudit2): beside "no search planned: ..." the rule-aware bound could
    print 0.2000 with no word of why; the summary now says the bounds are relaxations. A plan
    whose bounds are 0 prints no such line, nor does a plan with routes."""
    from poc_env.agents.planning.planner import plan_table

    sc = _small(**{"uav.endurance_h": 0.05})
    plan = make_allocation_plan(sc)
    assert plan["reason"]
    said = "the bounds are relaxations"
    assert said in plan_table({**plan, "bound_rule": 0.2})
    assert said in plan_table({**plan, "bound_rule": 0.0, "bounds": {"honest": 1.0, "reach": 0.3}})
    assert said not in plan_table({**plan, "bound_rule": 0.0, "bounds": None})
    routed = make_allocation_plan(_small())
    assert said not in plan_table({**routed, "bound_rule": 0.5})


def test_mass_only_outside_reach_gives_an_empty_plan():
    sc = _small(**{"uav.endurance_h": 0.3})  # 0.85 T = 918 s: ~28 km out and back
    grid = Grid.from_config(sc.map)
    prior = np.zeros(grid.shape)
    prior[-1, -1] = 1.0  # the far corner, > 40 km from the field at (20, -5) km
    plan = make_allocation_plan(sc, prior=prior)
    assert plan["reason"] is not None and plan["posc"] == 0


def test_bad_input_is_a_config_error():
    sc = _small()
    with pytest.raises(ConfigError, match="safety_distance"):
        make_allocation_plan(
            _small(**{"constraints.safety_distance_km": 1000, "comms.range_km": 1000})
        )
    with pytest.raises(ConfigError, match="prior"):
        make_allocation_plan(sc, prior=np.ones((3, 3)))
    bad = build_prior(sc.map).copy()
    bad[0, 0] = -1.0
    with pytest.raises(ConfigError, match="prior"):
        make_allocation_plan(sc, prior=bad)
    with pytest.raises(ConfigError, match="levels"):
        make_allocation_plan(sc, levels=0)


def test_cli_plan_with_the_allocation_planner(tmp_path, capsys):
    from poc_env.cli import main

    out = tmp_path / "plan.json"
    assert (
        main(
            ["plan", "--scenario", "small", "--planner", "allocation", "--out", str(out), "--quiet"]
        )
        == 0
    )
    plan = json.loads(out.read_text())
    assert plan["planner"] == "allocation" and plan["bound_reach"] > plan["posc"] > 0
    straight = tmp_path / "straight.json"
    args = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet"]
    assert main([*args, "--speed", "paper", "--refine", "0", "--out", str(straight)]) == 0
    flat = json.loads(straight.read_text())
    assert flat["speed_rule"] == "paper" and flat["optimizer"]["settings"]["refine"] == 0
    assert flat["posc"] < plan["posc"]  # v_s and no refinement find less
    capsys.readouterr()
    bad = tmp_path / "bad.json"
    assert main([*args, "--speed", "fast", "--out", str(bad)]) == 2
    assert "speed: got 'fast'; allowed: max or paper" in capsys.readouterr().err
    assert main(["plan", "--scenario", "small", "--refine", "2", "--out", str(bad)]) == 2
    assert "refine: got 2; allowed: only with planner allocation" in capsys.readouterr().err
    assert not bad.exists()


def test_lines_follow_an_elongated_prior():
    """Step 2 (the lines of the allocation's start, before any refinement) lays straight lines
    along the prior. (The boxes' start may chain a short box across the row before its lines
    along it: test_coverage_boxes.py.)"""
    sc = _small()
    grid = Grid.from_config(sc.map)
    for axis in (0, 1):
        prior = np.zeros(grid.shape)
        if axis == 0:
            prior[3, :] = 1.0  # one row of cells: lines along x
        else:
            prior[:, 3] = 1.0  # one column: lines along y
        prior /= prior.sum()
        plan = make_allocation_plan(sc, prior=prior, refine=0, greedy_start=False, box_start=False)
        assert plan["start"] == "allocation"
        assert plan["lines_along"] == ("x" if axis == 0 else "y")
        for u in plan["uavs"]:
            lines = np.asarray(u["waypoints_m"][u["transit_waypoints"] :]).reshape(-1, 2, 2)
            across = 1 if axis == 0 else 0
            assert np.allclose(lines[:, 0, across], lines[:, 1, across])  # straight lines
            assert u["flight_time_s"] <= sc.uav.usable_endurance_s
        assert plan["posc"] <= reach_bound(sc, prior).upper + 1e-12


def test_the_plans_rule_bound_is_the_plans_not_a_short_episodes():
    """``episode.horizon_steps`` cuts the environment's episodes, not a plan (the planners plan
    the endurance): with 2 steps the plan.json's ``bound_rule`` was the 2-step episode's bound,
    0.023 under a planned POS_C of 0.59 (config-audit). The plan's bound is its own."""
    sc = _small(**{"episode.horizon_steps": 2})
    plan = make_allocation_plan(sc, refine=0)
    assert plan["posc"] <= plan["bound_rule"] * 1.02
    assert plan["bound_rule"] == make_allocation_plan(_small(), refine=0)["bound_rule"]


def test_an_operating_area_beyond_plan_json_is_refused_naming_the_scenario():
    """A 2,000 km map (the largest side a scenario takes) grows by the 20 km boundary margin
    past plan.json's +-2,000 km: the plan was made, then refused naming its own
    ``plan.operating_area_m[1]`` (config-audit). Refused naming the margin; without it the
    plan is written."""
    big = {"map.cell_km": 2000, "map.width_km": 2000, "map.height_km": 2000}
    with pytest.raises(ConfigError, match=r"episode\.boundary_margin_km: got 20(\.0)?; allowed"):
        make_allocation_plan(_small(**big), refine=0)
    make_allocation_plan(_small(**big, **{"episode.boundary_margin_km": 0}), refine=0)


@pytest.mark.parametrize("refine", [0, None])
def test_field_mates_dog_legs_stay_inside_the_operating_area(refine):
    """config-audit, left for the lead: with ``episode.boundary_margin_km: 0`` the airfield of
    ``small`` sits on eq. 20's boundary, and a field-mate's fan-out dog-leg (``_spread``) was
    laid 0.55 km outside it, on the spread bearing; the flight breaks eq. 20 and the QGC export
    refuses the geofence. Every waypoint is now inside the operating area."""
    from poc_env.sim.core import operating_area

    ov = {"episode.boundary_margin_km": 0.0, "map.cell_km": 5.0, "map.height_km": 5.0,
          "map.width_km": 45.0}  # fmt: skip
    sc = load_scenario("small", ov)
    x0, y0, x1, y1 = operating_area(sc)
    plan = make_allocation_plan(sc, refine=refine)
    wps = np.array([w for u in plan["uavs"] for w in u["waypoints_m"]])
    assert len(wps) > 0
    assert np.all((wps[:, 0] >= x0) & (wps[:, 0] <= x1) & (wps[:, 1] >= y0) & (wps[:, 1] <= y1))
