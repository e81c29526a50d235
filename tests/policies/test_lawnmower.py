"""The lawnmower baseline flown through the environment."""

import numpy as np
from shapely.geometry import Point, box

import poc_env
from poc_env.agents.policies.lawnmower import lawnmower_policy, lawnmower_waypoints
from poc_env.sim.core import make_params


def test_lawnmower_strips_cover_the_grid_at_spacing_w():
    params = make_params(poc_env.load_scenario("paper_6_2"))
    wps = lawnmower_waypoints(params)
    x0, y0, x1, y1 = params.grid.bounds
    area = box(x0, y0, x1, y1).buffer(1e-6)
    assert len(wps) == params.n_agents
    xs = np.unique(np.round(np.concatenate([w[:, 0] for w in wps]), 6))
    np.testing.assert_allclose(np.diff(xs), params.scenario.sensor.sweep_width_m)
    assert all(area.contains(Point(p)) for w in wps for p in w)


def test_lawnmower_flies_and_finds_more_than_random():
    def run(policy_factory):
        env = poc_env.parallel_env("small")
        obs, _ = env.reset(seed=0)
        pol = policy_factory(env)
        while env.agents:
            obs, *_ = env.step(pol(obs))
        return env.sim_state.posc[0]

    def lawn(env):
        p = lawnmower_policy(env.params, env.possible_agents)
        return lambda obs: p.predict(obs)[0]

    def rand(env):
        rng = np.random.default_rng(0)
        return lambda obs: {a: rng.uniform(-1, 1, 3) * [1, 1, 0] for a in obs}

    assert run(lawn) > run(rand) > 0


def test_lawnmower_returns_to_land_within_the_usable_endurance():
    """The strips are too long for 3 h: the follower breaks off in time and every UAV lands."""
    env = poc_env.parallel_env("paper_6_2")
    obs, _ = env.reset(seed=0)
    pol = lawnmower_policy(env.params, env.possible_agents)
    while env.agents:
        obs, *_ = env.step(pol.predict(obs)[0])
    st = env.sim_state
    assert st.landed.all() and not st.crashed.any()
    assert st.elapsed.max() <= env.scenario.uav.usable_endurance_s + env.params.dt


def test_more_uavs_than_lines_share_the_lines():
    """A 5 km wide map at W = 5 km has one line for three UAVs: the split gave two UAVs an
    empty strip, a zero-area polygon and an error with nothing of what is allowed
    (config-audit). With fewer lines than UAVs each block is one line, shared by neighbouring
    UAVs: every UAV searches, and lands."""
    one_line = {"map.width_km": 5, "sensor.sweep_width_km": 5, "episode.horizon_steps": 400}
    env = poc_env.parallel_env(poc_env.load_scenario("small", one_line))
    obs, _ = env.reset(seed=0)
    wps = lawnmower_waypoints(env.params)
    assert all(len(w) > 0 for w in wps)
    pol = lawnmower_policy(env.params, env.possible_agents)
    while env.agents:
        obs, *_ = env.step(pol.predict(obs)[0])
    st = env.sim_state
    assert st.landed.all() and not st.crashed.any() and st.posc[0] > 0
