"""Issue 24, any size: the greedy rectangle baseline, the planned POS against the flown one at
several cell sizes, and no UAV left idle on a large map."""

import numpy as np
import pytest

import poc_env
from poc_env.agents.planning.allocation import (
    _reserve,
    make_allocation_plan,
    plan_speeds,
    sampled_sweep,
)
from poc_env.agents.planning.greedy_rectangles import make_greedy_rectangles_plan
from poc_env.agents.planning.refine import route_fits
from poc_env.agents.policies.greedy_rectangles import GreedyRectanglesPolicy
from poc_env.agents.policies.registry import make_policy, registered
from poc_env.config import load_scenario
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior


def _fly(sc, policy, seed=0):
    env = poc_env.parallel_env(sc)
    obs, _ = env.reset(seed=seed)
    pol = make_policy(policy)
    pol.reset(env, seed)
    while env.agents:
        obs, *_ = env.step(pol.predict(obs)[0])
    return env, pol


def test_greedy_rectangles_routes_fit_and_take_the_best_remaining_boxes():
    """Every UAV of paper_6_2 gets lawnmower lines inside the map that it flies whole under
    eq. 18; the first UAV's box holds more mass than the next one's at the same field (the
    mass it took is gone), and every UAV finds some of what the ones before it left."""
    sc = load_scenario("paper_6_2")
    plan = make_greedy_rectangles_plan(sc)
    grid = Grid.from_config(sc.map)
    v = plan_speeds(sc, "max")
    heading = takeoff_heading(grid.bounds, np.asarray(sc.takeoff_m, dtype=float))
    x0, y0, x1, y1 = grid.bounds
    for k, u in enumerate(plan["uavs"]):
        wps = np.asarray(u["waypoints_m"])
        assert len(wps) >= 2 and len(wps) % 2 == 0
        assert np.all((wps >= [x0, y0]) & (wps <= [x1, y1]))
        path = np.vstack([u["takeoff_m"], wps, u["landing_m"]])
        assert route_fits(
            path, v, sc.uav.max_turn_rate_rad_s, sc.uav.usable_endurance_s, _reserve(sc), heading[k]
        )
    prior = build_prior(sc.map)
    paths = [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] for u in plan["uavs"]]
    pos, _ = sampled_sweep(sc, grid, prior, paths)
    assert plan["posc"] > 0.5 * sum(pos) and pos[0] > pos[1]
    assert min(pos) > 0.02 * sum(pos)  # every UAV finds mass the ones before left


def test_greedy_rectangles_policy_flies_and_lands():
    assert "greedy_rectangles" in registered()
    env, pol = _fly("small", "greedy_rectangles")
    assert isinstance(pol, GreedyRectanglesPolicy)
    st = env.sim_state
    assert st.landed[0].all() and not st.crashed[0].any()
    assert float(st.posc[0]) > 0.3


@pytest.mark.parametrize("cell_km", [5.0, 10.0])
def test_planned_pos_matches_the_flown_one_at_any_cell_size(cell_km):
    """Issue 24: the allocation plan's POS_C was W x length per cell (eq. 10 per cell):
    planned 0.6097 against 0.5861 flown at 5 km cells, 0.6548 against 0.5851 at 10 km on
    paper_6_2. It is now the environment's detection on the sample points along the whole
    path (sampled_sweep): within 3 % of what the follower flies."""
    sc = load_scenario("paper_6_2", {"map.cell_km": cell_km})
    env, pol = _fly(sc, "allocation_plan")
    flown = float(env.sim_state.posc[0])
    assert abs(pol.plan["posc"] / flown - 1.0) <= 0.03
    assert pol.plan["posc"] == pytest.approx(sum(u["pos"] for u in pol.plan["uavs"]))
    assert all(0.0 <= u["pod"] <= 1.0 for u in pol.plan["uavs"])


def test_no_uav_is_left_idle_on_a_large_map():
    """large_400 (400 x 400 km, 12 UAVs from 3 airfields) at 10 km cells: every UAV is
    planned a share of the POS (issue 24: one UAV found 0.001-0.003 and stayed near its
    field), and the plan is never below the greedy rectangle plan it may start from (at
    10 km cells it is that plan: the refinement, scored per cell, is not kept)."""
    sc = load_scenario("large_400", {"map.cell_km": 10})
    plan = make_allocation_plan(sc)
    pos = np.array([u["pos"] for u in plan["uavs"]])
    assert len(pos) == 12 and pos.min() > 0.2 * pos.mean()
    greedy = make_greedy_rectangles_plan(sc)
    paths = [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] for u in greedy["uavs"]]
    grid = Grid.from_config(sc.map)
    assert plan["posc"] >= sum(sampled_sweep(sc, grid, build_prior(sc.map), paths)[0]) - 1e-12


@pytest.mark.slow
def test_no_uav_is_left_idle_on_the_large_map_at_5_km_cells():
    """large_400 at its own 5 km cells (80 x 80): every UAV finds at least 30 % of the mean
    share (before the greedy start: the first UAV of field A found 0.0066 against a mean of
    0.031, 21 %)."""
    plan = make_allocation_plan("large_400")
    pos = np.array([u["pos"] for u in plan["uavs"]])
    assert pos.min() > 0.3 * pos.mean()
