"""Control levels (poc_env.sim.control): heading and waypoint flown by the eq. 19 autopilot."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

import poc_env
import poc_env._kernels.sensing as _sensing
from poc_env.envs.gymnasium_env import UAVSearchGym
from poc_env.errors import ConfigError
from poc_env.sim import control as ctl
from poc_env.sim.observations import CompassFeatures


def _fly(env, seed, policy):
    """Fly one episode with ``policy(rng, agents)``; record the increments the core received."""
    seen = []
    # what every step flies: the engine's kinematics, the single env's kinematics and sensing
    real = (_sensing.kinematics, _sensing.fly_sense)

    def spy(fn):
        def call(actions, *args):
            seen.append(np.asarray(actions).copy())
            return fn(actions, *args)

        return call

    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    infos: dict = {}
    posc = 0.0
    _sensing.kinematics, _sensing.fly_sense = map(spy, real)
    try:
        while env.agents:
            _, _, _, _, infos = env.step(policy(rng, env.agents))
            posc = max([posc, *(i["posc"] for i in infos.values())])
    finally:
        _sensing.kinematics, _sensing.fly_sense = real
    return np.concatenate(seen), env.sim_state, posc


@pytest.mark.parametrize("control", ["heading", "waypoint"])
def test_autopilot_keeps_eq19_limits_and_lands_every_uav(control):
    env = poc_env.parallel_env("small", obs_type="flat", control=control)
    assert env.action_space("uav_0").shape == (2,)
    for seed in range(2):
        inc, st, posc = _fly(
            env, seed, lambda rng, agents: {a: rng.uniform(-1, 1, 2) for a in agents}
        )
        assert np.abs(inc).max() <= 1.0 + 1e-6  # every increment within its eq. 19 limit
        assert st.landed.all() and not st.crashed.any()
        assert posc > 0


def test_without_auto_return_random_headings_do_not_all_land():
    """The landing above is the autopilot's doing: without it a random heading policy does not
    bring the fleet home."""
    env = poc_env.parallel_env("small", obs_type="flat", control="heading", auto_return=False)
    _, st, _ = _fly(env, 0, lambda rng, agents: {a: rng.uniform(-1, 1, 2) for a in agents})
    assert not st.landed.all()


def test_waypoint_action_names_the_operating_area_corners():
    env = poc_env.parallel_env("small", control="waypoint")
    x0, y0, x1, y1 = env.params.bounds
    goal = ctl.waypoint_goal(env.params, np.array([[-1, -1], [1, 1], [0, 0]]))
    assert np.allclose(goal, [[x0, y0], [x1, y1], [(x0 + x1) / 2, (y0 + y1) / 2]])


def test_heading_flies_the_commanded_direction():
    env = poc_env.parallel_env("small", obs_type="flat", control="heading", auto_return=False)
    env.reset(seed=0)
    start = env.sim_state.pos[0, :, :2].copy()
    for _ in range(30):
        env.step({a: np.array([1.0, 0.0]) for a in env.agents})  # due east
    moved = env.sim_state.pos[0, :, :2] - start
    assert (moved[:, 0] > 5 * np.abs(moved[:, 1])).all()


def test_increments_stay_the_default_and_unknown_levels_are_refused():
    assert poc_env.parallel_env("small").action_space("uav_0").shape == (3,)
    with pytest.raises(ConfigError, match=r"control.*heading"):
        poc_env.parallel_env("small", control="velocity")
    with pytest.raises(ConfigError, match="auto_return"):
        poc_env.parallel_env("small", control="heading", auto_return="yes")
    env = poc_env.parallel_env("small", control="heading")
    env.reset(seed=0)
    with pytest.raises(ConfigError, match=r"actions\[uav_0\].*2 finite"):
        env.step({a: np.zeros(3) for a in env.agents})


@pytest.mark.parametrize("control", ["heading", "waypoint"])
def test_api_checkers_pass_on_each_level(control):
    parallel_api_test(
        poc_env.parallel_env("small", obs_type="flat", control=control), num_cycles=30
    )
    env = UAVSearchGym(scenario="small", control=control)
    assert env.action_space.shape == (2 * len(env.par.possible_agents),)
    check_env(env, skip_render_check=True)


def test_compass_observation_is_the_pilot_features_of_the_dict_observation():
    """obs_type="compass" (a size-free Box) equals the pilot recipe's features of the same
    state's dict observation, so a heading policy trained on them runs on the env as is."""
    kw = {"control": "heading", "random_prior": True}
    env_c = poc_env.parallel_env("small", obs_type="compass", **kw)
    env_d = poc_env.parallel_env("small", obs_type="dict", **kw)
    space = env_c.observation_space("uav_0")
    assert space.shape == (63,)
    oc, _ = env_c.reset(seed=4)
    od, _ = env_d.reset(seed=4)
    feats = CompassFeatures(env_d.params)
    for _ in range(3):
        for k, a in enumerate(env_c.agents):
            want = feats(od[a]["raster"][None], od[a]["vector"][None], [k])[0]
            np.testing.assert_array_equal(oc[a], want)
            assert space.contains(oc[a])
        acts = {a: np.array([0.0, 1.0]) for a in env_c.agents}
        oc = env_c.step(acts)[0]
        od = env_d.step(acts)[0]
    parallel_api_test(poc_env.parallel_env("small", obs_type="compass"), num_cycles=20)
    check_env(UAVSearchGym(scenario="small", obs_type="compass", control="heading"))


def test_waypoint_action_is_the_inverse_of_waypoint_goal():
    env = poc_env.parallel_env("paper_6_2")
    a = np.random.default_rng(0).uniform(-1, 1, (20, 2))
    np.testing.assert_allclose(ctl.waypoint_action(env.params, ctl.waypoint_goal(env.params, a)), a)
    x0, _, _, y1 = env.params.bounds
    far = np.array([[x0 - 1e6, y1 + 1e6]])  # outside the area: its corner
    np.testing.assert_array_equal(ctl.waypoint_action(env.params, far), [[-1.0, 1.0]])
