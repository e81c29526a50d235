"""Benchmark-suite API (issue 11): numeric infos with fixed keys, random priors drawn in reset,
PettingZoo's ``max_cycles``, the Gymnasium view's Dict observation, the checkers on all of it."""

import functools
import types

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import api_test, max_cycles_test, parallel_api_test, parallel_seed_test

import poc_env
from poc_env import uav_search_v0
from poc_env.envs.parallel import REWARD_TERMS, UAVSearchParallelEnv
from poc_env.errors import ConfigError
from poc_env.sim.rewards import reward_terms
from poc_env.theory.probability_map import random_gaussian_mixture

SHORT = {"episode.horizon_steps": 25}


def _spec(value):
    """What a TorchRL-style spec records of an info value: kind, shape and dtype."""
    if isinstance(value, bool | np.bool_):
        return ("bool", (), None)
    if isinstance(value, int | np.integer):
        return ("int", (), None)
    if isinstance(value, float | np.floating):
        return ("float", (), None)
    assert isinstance(value, np.ndarray), f"not numeric: {value!r}"
    assert value.dtype.kind in "biuf", f"not numeric: {value.dtype}"
    return ("array", value.shape, value.dtype)


def _specs(info):
    return {k: _spec(v) for k, v in info.items()}


def _actions(rng, agents):
    return {a: rng.uniform(-1, 1, 3).astype(np.float32) for a in agents}


@pytest.mark.parametrize("obs_type", ["dict", "flat"])
@pytest.mark.parametrize("scenario", ["small", "paper_6_2"])
def test_parallel_infos_same_keys_all_numeric(scenario, obs_type):
    env = poc_env.parallel_env(scenario, obs_type=obs_type, random_prior=True, overrides=SHORT)
    _, infos = env.reset(seed=3)
    assert set(infos) == set(env.possible_agents)
    spec = _specs(infos["uav_0"])
    assert "posc" in spec and "links" in spec and "topology" in spec
    assert spec["links"] == ("array", (env.params.n_agents,), np.dtype(bool))
    rng = np.random.default_rng(0)
    steps = 0
    while env.agents:
        *_, infos = env.step(_actions(rng, env.agents))
        steps += 1
        for info in infos.values():
            assert _specs(info) == spec  # same keys, kinds, shapes and dtypes as at reset
    assert steps == 25


def test_reward_terms_are_the_info_keys():
    env = poc_env.parallel_env("small")
    env.reset(seed=0)
    *_, infos = env.step({a: [0.0, 0.0, 0.0] for a in env.agents})
    from poc_env.sim import core as sim

    env.reset(seed=0)
    ev = sim.step(env.params, env.sim_state, np.zeros((1, 3, 3)), [np.random.default_rng(0)])
    assert tuple(reward_terms(env.scenario.reward, ev)) == REWARD_TERMS
    assert {k for k in infos["uav_0"] if k.startswith("reward_")} == {
        f"reward_{t}" for t in REWARD_TERMS
    }


def test_step_infos_carry_the_step_values():
    """The numeric infos are not placeholders: POSC grows, flight time advances, the links row
    is the adjacency row, and the reward terms add up to the reward."""
    env = poc_env.parallel_env("small")
    _, infos0 = env.reset(seed=1)
    assert infos0["uav_0"]["posc"] == 0.0 and infos0["uav_0"]["time_to_detection_s"] == -1.0
    for _ in range(5):
        _, rew, _, _, infos = env.step({a: [0.0, 0.0, 0.0] for a in env.agents})
    info = infos["uav_1"]
    assert info["posc"] == pytest.approx(float(env.sim_state.posc[0])) and info["posc"] > 0
    assert info["flight_time_s"] == pytest.approx(float(env.sim_state.elapsed[0, 1]))
    np.testing.assert_array_equal(info["links"], env.sim_state.links[0, 1])
    total = sum(info[f"reward_{t}"] for t in REWARD_TERMS)
    assert total == pytest.approx(rew["uav_1"])
    assert env.topology == "auto" and info["topology"] == -1
    assert all(isinstance(p, tuple) and p[0] < p[1] for p in env.links)


def test_aec_infos_same_keys_all_numeric():
    env = poc_env.env("small", random_prior=True, overrides=SHORT)
    env.reset(seed=2)
    spec = _specs(env.infos["uav_0"])
    rng = np.random.default_rng(1)
    seen = 0
    for agent in env.agent_iter():
        assert _specs(env.infos[agent]) == spec
        _, _, term, trunc, _ = env.last()
        env.step(None if term or trunc else rng.uniform(-1, 1, 3).astype(np.float32))
        seen += 1
    assert seen > 25


@pytest.mark.parametrize("obs_type", ["flat", "dict"])
def test_gymnasium_infos_same_keys_all_numeric(obs_type):
    env = gymnasium.make(
        poc_env.ENV_ID, scenario="small", obs_type=obs_type, random_prior=True, max_cycles=20
    )
    _, info = env.reset(seed=4)
    spec = _specs(info)
    n = 3
    assert spec["posc"] == ("float", (), None)
    assert spec["pos"] == ("array", (n,), np.dtype(np.float64))
    assert spec["landed"] == ("array", (n,), np.dtype(bool))
    assert spec["topology"] == ("array", (n,), np.dtype(np.int64))
    assert spec["links"] == ("array", (n, n), np.dtype(bool))
    done, steps = False, 0
    while not done:
        _, _, term, trunc, info = env.step(env.action_space.sample())
        assert _specs(info) == spec
        done, steps = term or trunc, steps + 1
    assert steps <= 20 and info["posc"] == pytest.approx(float(env.unwrapped.par.sim_state.posc[0]))


# -- random priors -----------------------------------------------------------------------------
def _trace(env, seed, n_steps=12):
    rng = np.random.default_rng(99)  # the same action sequence for every seed
    obs, infos = env.reset(seed=seed)
    out = [(obs, infos)]
    for _ in range(n_steps):
        if not env.agents:
            break
        acts = {a: rng.uniform(-1, 1, 3) for a in env.possible_agents if a in env.agents}
        out.append(env.step(acts))
    return out


def _flatten(x):
    if isinstance(x, dict):
        return [y for k in sorted(x) for y in _flatten(x[k])]
    if isinstance(x, tuple | list):
        return [y for v in x for y in _flatten(v)]
    return [np.asarray(x)]


def _identical(a, b):
    fa, fb = _flatten(a), _flatten(b)
    return len(fa) == len(fb) and all(
        x.shape == y.shape and x.dtype == y.dtype and x.tobytes() == y.tobytes()
        for x, y in zip(fa, fb)
    )


def test_random_prior_same_seed_identical_episode():
    t1 = _trace(poc_env.parallel_env("small", random_prior=True), 7)
    t2 = _trace(poc_env.parallel_env("small", random_prior=True), 7)
    assert len(t1) == 13 and _identical(t1, t2)  # bit-identical observations, rewards, infos
    t3 = _trace(poc_env.parallel_env("small", random_prior=True), 8)
    assert not _identical(t1, t3)


def test_random_prior_seed_changes_the_prior_and_the_rewards():
    env = poc_env.parallel_env("small", random_prior=True)
    priors, returns = [], []
    for seed in range(5):
        env.reset(seed=seed)
        priors.append(env.sim_state.belief[0].copy())
        trace = _trace(env, seed)
        returns.append(sum(sum(step[1].values()) for step in trace[1:]))
    for i in range(5):
        for j in range(i):
            assert not np.allclose(priors[i], priors[j])
    assert len(set(returns)) == 5  # a fixed action sequence scores differently per seed
    # the prior is the RL training's family, drawn from the reset seed's generator
    grid = env.params.grid
    env.reset(seed=11)
    coarse = grid.coarsen(env.sim_state.belief[0], env.params.s)
    expected = random_gaussian_mixture(grid, np.random.default_rng(11))
    np.testing.assert_allclose(coarse, expected, rtol=1e-9, atol=1e-15)


def test_without_random_prior_the_prior_is_fixed():
    env = poc_env.parallel_env("small")
    env.reset(seed=0)
    a = env.sim_state.belief[0].copy()
    env.reset(seed=1)
    np.testing.assert_array_equal(a, env.sim_state.belief[0])


def test_given_prior_wins_over_random_prior():
    env = poc_env.parallel_env("small", random_prior=True)
    env.reset(seed=0)
    ref = poc_env.parallel_env("small")
    ref.reset(seed=0)
    env.reset(seed=0, options={"prior": ref.params.prior})
    np.testing.assert_allclose(env.sim_state.belief[0], ref.sim_state.belief[0], rtol=1e-12)
    env.reset(seed=0)
    assert not np.allclose(env.sim_state.belief[0], ref.sim_state.belief[0])


def test_gymnasium_registration_takes_random_prior():
    env = gymnasium.make(poc_env.ENV_ID, scenario="small", random_prior=True)
    beliefs = []
    for seed in (0, 1, 0):
        env.reset(seed=seed)
        beliefs.append(env.unwrapped.par.sim_state.belief[0].copy())
    assert not np.allclose(beliefs[0], beliefs[1])
    np.testing.assert_array_equal(beliefs[0], beliefs[2])


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_bad_random_prior(value):
    with pytest.raises(ConfigError, match="random_prior"):
        poc_env.parallel_env("small", random_prior=value)


def test_random_prior_with_map_file_is_an_error(tmp_path):
    env = poc_env.parallel_env("small")
    path = tmp_path / "prior.npy"
    np.save(path, env.params.prior)
    with pytest.raises(ConfigError, match="random_prior"):
        poc_env.parallel_env("small", map_file=str(path), random_prior=True)


# -- max_cycles --------------------------------------------------------------------------------
def _module(**kw):
    """``uav_search_v0`` with keyword arguments bound, for the module-taking checkers.

    v0's defaults fail ``max_cycles_test`` (``uav_search_v1``'s pass, below): it flies
    uniformly random actions and requires most UAVs alive after 4 steps. At the paper's 1000 m
    cruise altitude a random pitch command reaches the 15 degree limit in one 60 s step
    (1 deg/s), a 776 m drop per step, so random flight hits the ground within 2-4 steps (the
    plain module failed 6 of 20 runs). From 4000 m no UAV can reach the ground in 4 steps (at
    most 4 x 776 m), so the test is deterministic; the max_cycles logic it checks is the same."""
    kw = {"uav__cruise_altitude_m": 4000.0, **kw}
    return types.SimpleNamespace(
        env=functools.partial(uav_search_v0.env, **kw),
        parallel_env=functools.partial(uav_search_v0.parallel_env, **kw),
    )


def test_max_cycles_passes_pettingzoo_test():
    max_cycles_test(_module())


def test_v1_module_passes_pettingzoo_tests_with_its_defaults():
    """Issue 27: ``max_cycles_test(uav_search_v0)`` failed (v0's increments control flies a
    random pitch into the ground); ``uav_search_v1`` defaults to the heading autopilot and
    passes with no argument. The test draws unseeded random actions, so it runs ten times: v0
    in its place fails about 6 runs in 20."""
    from poc_env import uav_search_v1

    for _ in range(10):
        max_cycles_test(uav_search_v1)
    parallel_api_test(uav_search_v1.parallel_env(), num_cycles=40)
    parallel_seed_test(uav_search_v1.parallel_env, num_cycles=20)
    api_test(uav_search_v1.env(), num_cycles=20)


def test_v0_module_keeps_its_defaults_and_v1_changes_only_the_control():
    from poc_env import uav_search_v1

    v0, v1 = uav_search_v0.parallel_env(), uav_search_v1.parallel_env()
    assert (v0.control, v0.metadata["name"]) == ("increments", "uav_search_v0")
    assert (v1.control, v1.metadata["name"]) == ("heading", "uav_search_v1")
    assert UAVSearchParallelEnv.metadata["name"] == "uav_search_v0"  # the class is untouched
    same = uav_search_v1.parallel_env(control="increments")  # v0's episode, step for step
    o0, _ = v0.reset(seed=3)
    o1, _ = same.reset(seed=3)
    rng = np.random.default_rng(0)
    for _ in range(5):
        acts = {a: rng.uniform(-1, 1, 3) for a in v0.agents}
        o0, r0, *_ = v0.step(acts)
        o1, r1, *_ = same.step(acts)
        assert r0 == r1
        for a in o0:
            np.testing.assert_array_equal(o0[a]["raster"], o1[a]["raster"])


@pytest.mark.parametrize("n", [1, 7])
def test_max_cycles_truncates_after_n_steps(n):
    env = poc_env.parallel_env("small", max_cycles=n)
    assert env.max_cycles == n and env.scenario.horizon_steps == n
    env.reset(seed=0)
    for _ in range(n):
        assert env.agents
        _, _, term, trunc, _ = env.step({a: [0.0, 0.0, 0.0] for a in env.agents})
    assert env.agents == [] and all(trunc.values()) and not any(term.values())


@pytest.mark.parametrize("value", [0, -3, 2.5, "10", True, 10**8])
def test_bad_max_cycles(value):
    with pytest.raises(ConfigError, match="max_cycles"):
        poc_env.parallel_env("small", max_cycles=value)


def test_max_cycles_must_agree_with_horizon():
    with pytest.raises(ConfigError, match=r"max_cycles.*horizon_steps \(5\)"):
        poc_env.parallel_env("small", max_cycles=4, episode__horizon_steps=5)
    env = poc_env.parallel_env("small", max_cycles=5, episode__horizon_steps=5)
    assert env.max_cycles == 5


# -- Gymnasium view observation types ----------------------------------------------------------
def test_gymnasium_dict_observation_is_kept():
    env = gymnasium.make(poc_env.ENV_ID, scenario="small", obs_type="dict")
    space = env.observation_space
    assert isinstance(space, gymnasium.spaces.Dict)
    assert space["raster"].shape == (3, 4, 8, 8) and space["vector"].shape == (3, 14)
    obs, _ = env.reset(seed=0)
    assert space.contains(obs)
    flat = gymnasium.make(poc_env.ENV_ID, scenario="small")
    fobs, _ = flat.reset(seed=0)
    assert isinstance(flat.observation_space, gymnasium.spaces.Box)
    # the same numbers, agent by agent: raster then vector
    joined = np.concatenate(
        [np.concatenate([obs["raster"][i].ravel(), obs["vector"][i]]) for i in range(3)]
    )
    np.testing.assert_array_equal(joined, fobs)


def test_gymnasium_bad_obs_type():
    with pytest.raises(ConfigError, match="obs_type: got 'pixels'; allowed: 'flat'"):
        gymnasium.make(poc_env.ENV_ID, scenario="small", obs_type="pixels")


# -- the four checkers with random priors ------------------------------------------------------
def test_checkers_with_random_prior():
    kw = {"scenario": "small", "random_prior": True}
    parallel_api_test(uav_search_v0.parallel_env(**kw), num_cycles=60)
    parallel_seed_test(lambda: uav_search_v0.parallel_env(**kw), num_cycles=40)
    api_test(uav_search_v0.env(**kw), num_cycles=40)
    max_cycles_test(_module(random_prior=True))
    for obs_type in ("flat", "dict"):
        check_env(gymnasium.make(poc_env.ENV_ID, obs_type=obs_type, **kw).unwrapped)


# -- random airfields --------------------------------------------------------------------------
ZONE = {"map.no_fly_zones_km": [[[0, 0], [30, 0], [30, 30], [0, 30]]]}  # most of small's grid


def test_random_airfields_follow_the_seed_and_the_fleet():
    env = poc_env.parallel_env("paper_6_2", random_airfields=True, random_prior=True)
    base = np.asarray(env.scenario.takeoff_m)
    fields = {}
    for seed in (0, 1, 0):
        env.reset(seed=seed)
        p = env.params
        # UAVs of a fleet group share their field; the two groups' fields differ
        assert (p.takeoff[:3] == p.takeoff[0]).all() and (p.takeoff[3:] == p.takeoff[3]).all()
        assert not np.array_equal(p.takeoff[0], p.takeoff[3])
        np.testing.assert_array_equal(p.landing, p.takeoff)  # each group lands where it left
        np.testing.assert_array_equal(env.sim_state.pos[0, :, :2], p.takeoff)  # start there
        x0, y0, x1, y1 = p.grid.bounds
        assert ((p.takeoff >= [x0, y0]) & (p.takeoff <= [x1, y1])).all()
        assert not np.allclose(p.takeoff, base)
        fields.setdefault(seed, []).append(p.takeoff.copy())
    np.testing.assert_array_equal(fields[0][0], fields[0][1])
    assert not np.allclose(fields[0][0], fields[1][0])
    assert env.params.prior is env.engine.base_params.prior  # only the airfields move


def test_random_airfields_keep_out_of_no_fly_zones():
    env = poc_env.parallel_env("small", random_airfields=True, overrides=ZONE)
    clearance = env.scenario.episode.landing_radius_m
    for seed in range(20):
        env.reset(seed=seed)
        assert float(env.params.zones.distance(env.params.takeoff[0])) >= clearance


def test_random_airfields_same_seed_identical_episode_and_checkers():
    kw = {"scenario": "small", "random_airfields": True}
    t1 = _trace(poc_env.parallel_env(**kw), 5)
    t2 = _trace(poc_env.parallel_env(**kw), 5)
    assert _identical(t1, t2)
    assert not _identical(t1, _trace(poc_env.parallel_env(**kw), 6))
    parallel_api_test(uav_search_v0.parallel_env(**kw), num_cycles=40)
    parallel_seed_test(lambda: uav_search_v0.parallel_env(**kw), num_cycles=30)
    check_env(gymnasium.make(poc_env.ENV_ID, **kw).unwrapped)


def test_without_random_airfields_the_fields_are_the_scenarios():
    env = poc_env.parallel_env("paper_6_2", random_prior=True)
    env.reset(seed=3)
    np.testing.assert_array_equal(env.params.takeoff, np.asarray(env.scenario.takeoff_m))


def test_bad_random_airfields():
    with pytest.raises(ConfigError, match="random_airfields"):
        poc_env.parallel_env("small", random_airfields="yes")
    # two zones that leave only a 0.2 km strip of the grid flyable: no room for an airfield
    # (a zone over the whole grid is refused when the scenario loads, issue 24)
    strips = [
        [[-1, -1], [41, -1], [41, 19.9], [-1, 19.9]],
        [[-1, 20.1], [41, 20.1], [41, 41], [-1, 41]],
    ]
    env = poc_env.parallel_env(
        "small", random_airfields=True, overrides={"map.no_fly_zones_km": strips}
    )
    with pytest.raises(ConfigError, match="random_airfields"):
        env.reset(seed=0)


def test_infos_stack_into_tensors_over_an_episode():
    """What a TorchRL-style wrapper does with infos: one tensor per key, stacked over the steps
    (reset included) and agents; this needs every value numeric with one shape and dtype."""
    torch = pytest.importorskip("torch")
    env = poc_env.parallel_env("small", random_prior=True, max_cycles=15)
    _, infos = env.reset(seed=0)
    rows = [infos["uav_2"]]
    rng = np.random.default_rng(2)
    while "uav_2" in env.agents:
        *_, infos = env.step(_actions(rng, env.agents))
        rows.append(infos["uav_2"])
    for key in rows[0]:
        stacked = torch.stack([torch.as_tensor(r[key]) for r in rows])
        assert stacked.shape[0] == len(rows) > 2
        assert stacked.dtype in (torch.float32, torch.float64, torch.int64, torch.bool)
