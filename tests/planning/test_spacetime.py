"""The space-time allocation planner (poc_env.agents.planning.spacetime)."""

import numpy as np
import pytest

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.spacetime import (
    airborne_poc,
    airborne_scenario,
    choose_routes,
    comoving_poc,
    comoving_route,
    intercept,
    replan,
    spacetime_plan,
)
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import Grid, build_prior


def _fine(prior, s):
    return np.repeat(np.repeat(prior, s, axis=0), s, axis=1) / (s * s)


def test_intercept_meets_the_drifting_points():
    """Each ground waypoint is the co-moving one carried by v for the time it is reached, and
    every leg is flown at its speed."""
    rng = np.random.default_rng(0)
    wps = rng.uniform(-5e4, 5e4, (6, 2))
    v = np.array([5.0, -3.0])
    speeds = [60.0] + [50.0] * 5
    start = np.array([1000.0, -2000.0])
    g, t = intercept(start, wps, v, speeds)
    np.testing.assert_allclose(g - v * t[:, None], wps, atol=1e-6)
    legs = np.hypot(*np.diff(np.vstack([start, g]), axis=0).T)
    np.testing.assert_allclose(legs, np.diff(np.r_[0.0, t]) * speeds, rtol=1e-12)
    g0, _ = intercept(start, wps, (0.0, 0.0), speeds)  # no drift: the points themselves
    np.testing.assert_allclose(g0, wps)
    with pytest.raises(ValueError, match="drift"):
        intercept(start, wps, (70.0, 0.0), speeds)


def test_comoving_poc_of_a_static_target_is_the_prior():
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    poc = comoving_poc(sc, _fine(prior, 4), (0.0, 0.0), 4, 1800.0)
    np.testing.assert_allclose(poc, prior, atol=1e-15)


def test_comoving_poc_follows_a_pure_drift():
    """No diffusion, a drift of 5 m/s: in the co-moving frame the mass stays where it was, up to
    the upwind scheme's smearing (none leaves the map here)."""
    sc = load_scenario("small", {"target.model": "drift", "target.current_kmh": [18.0, 0.0],
                                 "target.diffusion_m2_s": 0.0})  # fmt: skip
    grid = Grid.from_config(sc.map)
    prior = np.zeros(grid.shape)
    prior[4, 1] = 1.0
    poc = comoving_poc(sc, _fine(prior, 4), (5.0, 0.0), 4, 1800.0)  # 9 km: two cells east
    assert np.unravel_index(np.argmax(poc), poc.shape) == (4, 1)
    assert poc[4, 3] < 0.1 * poc[4, 1]  # where the mass is at the end, in the fixed frame


def test_spacetime_plan_without_drift_is_the_allocation_plan():
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    st = spacetime_plan(sc, _fine(prior, 4), (0.0, 0.0), 4)
    al = make_allocation_plan(sc, prior=prior)
    for a, b in zip(st["uavs"], al["uavs"], strict=True):
        np.testing.assert_allclose(a["waypoints_m"], b["waypoints_m"], atol=1e-6)
    assert st["planner"] == "spacetime"


def test_spacetime_plan_moves_the_routes_downstream():
    """An eastward drift: every ground waypoint lies east of its co-moving point, by v t."""
    sc = load_scenario("small", {"target.model": "drift", "target.current_kmh": [30.0, 0.0]})
    prior = build_prior(sc.map)
    v = (30.0 / 3.6, 0.0)
    plan = spacetime_plan(sc, _fine(prior, 4), v, 4)
    co = make_allocation_plan(sc, prior=comoving_poc(sc, _fine(prior, 4), v, 4,
                                                     sc.uav.usable_endurance_s))  # fmt: skip
    for u, c in zip(plan["uavs"], co["uavs"], strict=True):
        t = np.asarray(u["meet_times_s"])
        assert np.all(np.diff(t) > 0) and len(t) > 0
        shift = np.asarray(u["waypoints_m"]) - np.asarray(c["waypoints_m"])
        np.testing.assert_allclose(shift, np.outer(t, v), atol=1e-6)


def test_replan_takes_off_from_where_the_uavs_are():
    sc = load_scenario("small", {"target.model": "drift"})
    pos = np.array([[10e3, 10e3], [30e3, 20e3]])
    air = airborne_scenario(sc, pos, 600.0, [0, 2])
    np.testing.assert_allclose(air.takeoff_m, pos)
    assert air.uav.usable_endurance_s == pytest.approx(sc.uav.usable_endurance_s - 600.0)
    prior = build_prior(sc.map)
    plan = replan(sc, _fine(prior, 4), (0.0, 0.0), 4, pos, 600.0, [0, 2])
    assert len(plan["uavs"]) == 2


def test_comoving_route_inverts_the_intercept():
    rng = np.random.default_rng(1)
    wps = rng.uniform(-5e4, 5e4, (5, 2))
    v, speeds, start = np.array([-4.0, 6.0]), [60.0] + [45.0] * 4, np.array([3e3, 1e3])
    g, _ = intercept(start, wps, v, speeds)
    np.testing.assert_allclose(comoving_route(start, g, v, speeds), wps, atol=1e-6)
    assert comoving_route(start, np.zeros((0, 2)), v, speeds).shape == (0, 2)


def test_switch_rule_never_takes_a_worse_scored_plan():
    """The routes being flown are candidate 0; a re-plan is taken only if it scores more by the
    margin. A real re-plan against no routes at all, in either role."""
    sc = load_scenario("small", {"target.model": "drift"})
    pos = np.array([[12e3, 15e3], [25e3, 22e3]])
    ks, v, s = [0, 2], np.array([6.0, 1.0]), 4
    fine = _fine(build_prior(sc.map), s)
    poc = airborne_poc(sc, fine, v, s, pos, 900.0, ks)
    plan = replan(sc, fine, v, s, pos, 900.0, ks, poc=poc)
    u = plan["speeds_mps"]
    good = [np.asarray(x["waypoints_m"]).reshape(-1, 2) for x in plan["uavs"]]
    good_v = [[u["out"]] + [u["line"]] * len(w) for w in good]
    none = [np.zeros((0, 2))] * 2
    none_v: list[list[float]] = [[], []]

    def pick(cands, margin=0.0):
        return choose_routes(sc, fine, v, s, pos, 900.0, ks, cands, margin, poc=poc)

    i, scores = pick([(none, none_v), (good, good_v)])
    assert scores[1] > scores[0] + 0.01  # the re-plan finds something, no routes nothing
    assert i == 1
    i, scores2 = pick([(good, good_v), (none, none_v)])  # flying the better routes: keep them
    assert i == 0 and scores2 == [scores[1], scores[0]]
    gap = scores[1] - scores[0]
    assert pick([(none, none_v), (good, good_v)], margin=gap + 1e-6)[0] == 0
    assert pick([(none, none_v), (good, good_v)], margin=gap - 1e-6)[0] == 1
    assert pick([(good, good_v)])[0] == 0


def test_a_drift_faster_than_the_uavs_is_a_config_error_naming_the_current():
    """Issue 25 audit: a current faster than the UAVs (accepted up to 400 km/h) stopped
    ``poc-env evaluate --policies spacetime_plan`` with a bare ValueError traceback; it is a
    ConfigError naming ``target.current_kmh``, the drift in km/h and the UAVs' speed."""
    sc = load_scenario("small", {"target.model": "drift", "target.current_kmh": [300.0, 0.0]})
    prior = build_prior(sc.map)
    with pytest.raises(ConfigError) as err:
        spacetime_plan(sc, _fine(prior, 4), (300.0 / 3.6, 0.0), 4)
    assert err.value.field == "target.current_kmh"
    assert err.value.value == pytest.approx(300.0)
    assert "km/h" in str(err.value)


def test_ground_waypoints_stay_in_the_operating_area():
    """Issue 25 audit: with a fast current (100 km/h south, within the documented range) the
    intercept put waypoints up to 25 km beyond eq. 20's operating area, where the mass had
    drifted off the map: ``spacetime_plan`` flew 8 out-of-bounds steps. Waypoints outside the
    area are now dropped (each kept one keeps its meet time)."""
    from poc_env.sim.core import operating_area

    over = {"target.model": "drift", "target.current_kmh": [0.0, -100.0]}
    sc = load_scenario("small", {**over, "target.diffusion_m2_s": 50.0})
    prior = build_prior(sc.map)
    v = (0.0, -100.0 / 3.6)
    plan = spacetime_plan(sc, _fine(prior, 4), v, 4)
    x0, y0, x1, y1 = operating_area(sc)
    n = 0
    for u in plan["uavs"]:
        w = np.asarray(u["waypoints_m"], dtype=float).reshape(-1, 2)
        n += len(w)
        assert np.all((w[:, 0] >= x0) & (w[:, 0] <= x1) & (w[:, 1] >= y0) & (w[:, 1] <= y1))
        assert len(u.get("meet_times_s", [])) == len(w)
    assert n > 0  # routes are left to fly


def test_meet_times_after_a_dropped_waypoint_are_when_it_is_reached():
    """drift-recede: a ground waypoint outside eq. 20's area is dropped and the route flies
    straight on, so the later waypoints are reached before the intercept's times (and before
    their co-moving points pass there). ``meet_times_s`` kept the intercept's times; they are
    the times the follower reaches each kept waypoint at the plan's speeds, and the co-moving
    points those times give (:func:`comoving_route`, what the switch rule scores) are the plan's
    up to the first drop."""
    from poc_env.agents.planning.spacetime import ground_plan

    wps = np.array([[0.0, 0.0], [8e3, 0.0], [8e3, 6e3], [0.0, 6e3], [-4e3, 9e3]])
    v, start = np.array([4.0, 0.0]), np.array([-1e4, 0.0])
    speeds = {"out": 60.0, "line": 40.0}
    plan = {"uavs": [{"waypoints_m": wps.tolist()}], "speeds_mps": speeds}
    full = ground_plan(plan, [start], v)["uavs"][0]
    x1 = float(np.asarray(full["waypoints_m"])[1, 0]) - 1.0  # the second one is outside
    cut = ground_plan(plan, [start], v, area=(-2e4, -2e4, x1, 2e4))
    g = np.asarray(cut["uavs"][0]["waypoints_m"], dtype=float).reshape(-1, 2)
    assert cut["cut_outside_area"] >= 1 and len(g) >= 2
    flown = [speeds["out"]] + [speeds["line"]] * (len(g) - 1)
    legs = np.hypot(*np.diff(np.vstack([start, g]), axis=0).T)
    reached = np.cumsum(legs / flown)
    np.testing.assert_allclose(cut["uavs"][0]["meet_times_s"], reached)
    kept = np.isin(np.asarray(full["waypoints_m"])[:, 0], g[:, 0])
    assert np.all(reached[1:] < np.asarray(full["meet_times_s"])[kept][1:])  # early after it
    np.testing.assert_allclose(comoving_route(start, g, v, flown)[:1], wps[:1], atol=1e-6)
