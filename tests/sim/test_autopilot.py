"""A scripted lawnmower flown through step() reproduces eq. 10; the follower keeps its limits."""

import numpy as np
import pytest

import poc_env
from poc_env.sim.autopilot import WaypointFollower
from poc_env.theory.search_theory import pod_parallel

ONE_UAV = {
    "map.width_km": 60,
    "map.height_km": 60,
    "map.prior": {"kind": "gaussian_mixture", "background": 1.0, "components": []},
    "fleet": [{"takeoff": "A", "count": 1}],
    "airfields": [{"name": "A", "position_km": [0, -15]}],
    "sensor.sweep_width_km": 5,
    "uav.endurance_h": 20,
    "episode.dt_s": 60,
}


def _lawnmower(spacing, x_hi, y_lo, y_hi):
    wps = []
    for k, x in enumerate(np.arange(spacing / 2, x_hi, spacing)):
        ys = (y_lo, y_hi) if k % 2 == 0 else (y_hi, y_lo)
        wps += [(x, ys[0]), (x, ys[1])]
    return np.array(wps)


def test_lawnmower_through_step_reproduces_eq10_within_2_percent():
    env = poc_env.parallel_env("small", overrides=ONE_UAV)
    obs, _ = env.reset(seed=0)
    w = env.scenario.sensor.sweep_width_m
    track = _lawnmower(w, 60e3, -12e3, 72e3)
    pol = WaypointFollower(env.params, [track], env.possible_agents)
    prior = env.params.prior
    while env.agents and pol.index[0] < len(track):
        acts, _ = pol.predict(obs)
        obs, *_ = env.step(acts)
    grid, s = env.params.grid, env.params.s
    left = grid.coarsen(env.sim_state.belief[0], s)
    pod = 1.0 - left / prior
    inner = pod[2:-2, 2:-2].mean()  # cells away from the swept area's edges
    assert inner == pytest.approx(float(pod_parallel(w, w)), rel=0.02)


def test_follower_actions_stay_within_limits_and_land():
    env = poc_env.parallel_env("small")
    obs, _ = env.reset(seed=1)
    tracks = [np.array([[10e3, 10e3], [30e3, 10e3]]) + np.array([0.0, 8e3 * k]) for k in range(3)]
    pol = WaypointFollower(env.params, tracks, env.possible_agents)
    landed = set()
    for _ in range(env.params.horizon):
        acts, _ = pol.predict(obs)
        for a in acts.values():
            assert np.all(np.abs(a) <= 1.0)
        obs, _, term, _, infos = env.step(acts)
        landed |= {a for a in term if infos[a]["landed"]}
        if not env.agents:
            break
    assert landed == set(env.possible_agents)


def test_a_uav_with_no_waypoints_leaves_its_field_and_lands():
    """A plan that gives a UAV nothing to search (greedy_rectangles on a 2 x 2 map of 20 km
    cells, where no whole cell fits the endurance) left it circling inside its field's landing
    radius, which it must leave before it may land: every UAV crashed at T, every step a
    violation (config-audit). The follower flies it out of the radius and back to land."""
    env = poc_env.parallel_env("small", obs_type="flat", overrides={"map.cell_km": 20})
    obs, _ = env.reset(seed=0)
    follower = WaypointFollower(env.params, [np.empty((0, 2))] * 3, env.possible_agents)
    while env.agents:
        obs, *_ = env.step(follower.predict(obs)[0])
    st = env.sim_state
    assert st.landed.all() and not st.crashed.any()


def _fly_counting_collisions_away(env, follower) -> int:
    """Collision UAV-steps (eq. 21) of a flight farther than ``d_s / sin FAN_DEG`` from the
    UAV's fields (within it field-mates taking off together are together anyway)."""
    from poc_env.sim.autopilot import FAN_DEG

    obs, _ = env.reset(seed=0)
    follower.reset()
    p = env.params
    near = env.scenario.constraints.safety_distance_m / np.sin(np.radians(FAN_DEG))
    count = 0
    while env.agents:
        obs, _, _, _, infos = env.step(follower.predict(obs)[0])
        xy = env.sim_state.pos[0, :, :2]
        away = (np.hypot(*(xy - p.takeoff).T) > near) & (np.hypot(*(xy - p.landing).T) > near)
        for a, i in infos.items():
            count += int(i["violation_collision"] and away[int(a.rsplit("_", 1)[1])])
    return count


def test_field_mates_given_nothing_hop_out_apart():
    """Field-mates a plan gives nothing all flew one point out of the field at the same time
    (eq. 21 collisions on every step of the hop: all of the deconfliction's ``mono2`` flown
    collisions away from the fields, i24-flownsep). Each now hops out on its own bearing, at
    least FAN_DEG from its field-mates' (a routed one's first waypoint among them): no
    collision step away from the field, and every UAV lands."""
    env = poc_env.parallel_env("small", overrides={"fleet": [{"takeoff": "A", "count": 4}]})
    centre = np.array([[20e3, 20e3], [20e3, 35e3]])  # UAV 0 flies out towards the centre
    follower = WaypointFollower(env.params, [centre] + [np.empty((0, 2))] * 3, env.possible_agents)
    from poc_env.sim.autopilot import FAN_DEG

    out = np.array([w[0] for w in follower.waypoints]) - np.asarray(env.params.takeoff)
    bearing = np.arctan2(out[:, 1], out[:, 0])
    apart = np.abs((bearing[:, None] - bearing[None] + np.pi) % (2 * np.pi) - np.pi)
    assert apart[~np.eye(4, dtype=bool)].min() >= np.radians(FAN_DEG) - 1e-9
    assert _fly_counting_collisions_away(env, follower) == 0
    assert env.sim_state.landed.all() and not env.sim_state.crashed.any()
