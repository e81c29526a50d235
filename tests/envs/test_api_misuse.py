"""Misuse of the environment API ends in a ConfigError naming the field, never a raw exception."""

import pickle

import numpy as np
import pytest

import poc_env
from poc_env.envs.gymnasium_env import UAVSearchGym
from poc_env.errors import ConfigError


@pytest.fixture
def env():
    e = poc_env.parallel_env("small")
    e.reset(seed=3)
    return e


@pytest.mark.parametrize("actions", [None, [[0.0, 0.0, 0.0]], np.zeros((6, 3)), "go", 5])
def test_actions_must_be_a_dict(env, actions):
    with pytest.raises(ConfigError, match=r"(?s)^actions: got .*allowed: a dict"):
        env.step(actions)


@pytest.mark.parametrize(
    "bad",
    [
        ["a", "b", "c"],
        ["1", "0", "0"],  # numeric strings are not numbers
        [1j, 0, 0],
        [[1.0, 2.0], [3.0]],
        [0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
        None,
        {"dv": 0},
        [np.nan, 0, 0],
        [np.inf, 0, 0],
    ],
    ids=repr,
)
def test_bad_action_names_the_agent(env, bad):
    acts = {a: [0.0, 0.0, 0.0] for a in env.agents}
    acts["uav_0"] = bad
    with pytest.raises(ConfigError, match=r"^actions\[uav_0\]: got .*allowed: .*3 finite"):
        env.step(acts)


def test_valid_action_types_give_the_same_step():
    runs = []
    for make in (
        lambda a: a,
        lambda a: np.asarray(a, dtype=np.float32),
        lambda a: tuple(a),
        lambda a: np.asarray(a, dtype=np.float64),
    ):
        e = poc_env.parallel_env("small")
        e.reset(seed=7)
        out = [e.step({a: make([0.5, -0.25, 0.0]) for a in e.agents}) for _ in range(3)]
        runs.append([o[1] for o in out])
    assert all(r == runs[0] for r in runs)
    e = poc_env.parallel_env("small")
    e.reset(seed=7)
    ints = e.step({a: [1, -1, 0] for a in e.agents})[1]
    e.reset(seed=7)
    floats = e.step({a: [1.0, -1.0, 0.0] for a in e.agents})[1]
    assert ints == floats


@pytest.mark.parametrize("seed", [-1, 1.5, "abc", True, [1]])
def test_reset_seed_is_checked(env, seed):
    with pytest.raises(ConfigError, match=r"^seed: got .*allowed: None, an integer >= 0"):
        env.reset(seed=seed)
    gym_env = UAVSearchGym(scenario="small")
    with pytest.raises(ConfigError, match=r"^seed: "):
        gym_env.reset(seed=seed)


def test_reset_accepts_numpy_seeds(env):
    a = env.reset(seed=np.int64(4))[0]
    b = env.reset(seed=4)[0]
    c = env.reset(seed=np.random.SeedSequence(4))[0]
    np.testing.assert_array_equal(a["uav_0"]["vector"], b["uav_0"]["vector"])
    assert set(c) == set(a)


@pytest.mark.parametrize("map_file", [5, 1.5, ["a.npy"], b"x"])
def test_map_file_must_be_a_path(map_file):
    with pytest.raises(ConfigError, match=r"^map_file: got .*allowed: None or a path"):
        poc_env.parallel_env("small", map_file=map_file)


def test_options_must_be_a_dict(env):
    with pytest.raises(ConfigError, match=r"^options: "):
        env.reset(seed=1, options=[("prior", None)])


@pytest.mark.parametrize(
    "action",
    [
        np.zeros(5),
        np.zeros(100),
        ["a"] * 9,
        np.full(9, 1j),
        ["1"] * 9,
        [[0.0] * 3, [0.0]],
        None,
        "x",
    ],
    ids=lambda a: repr(a)[:30],
)
def test_gymnasium_action_is_checked(action):
    env = UAVSearchGym(scenario="small")
    env.reset(seed=0)
    n = 3 * len(env.par.possible_agents)
    with pytest.raises(ConfigError, match=rf"(?s)^action: got .*allowed: {n} finite real numbers"):
        env.step(action)


def test_gymnasium_valid_action_shapes_unchanged():
    env = UAVSearchGym(scenario="small")
    n = len(env.par.possible_agents)
    env.reset(seed=2)
    flat = env.step(np.full(3 * n, 0.5, dtype=np.float32))
    env.reset(seed=2)
    grid = env.step([[0.5, 0.5, 0.5]] * n)
    np.testing.assert_array_equal(flat[0], grid[0])
    assert flat[1] == grid[1]


def test_pickle_after_render():
    env = poc_env.parallel_env("small", render_mode="rgb_array")
    env.reset(seed=5)
    env.step({a: [0.1, 0.2, 0.0] for a in env.agents})
    assert env.render() is not None
    clone = pickle.loads(pickle.dumps(env))
    acts = {a: [0.3, -0.4, 0.0] for a in env.agents}
    assert env.step(acts)[1] == clone.step(acts)[1]
    assert clone.render().shape == env.render().shape
    env.close()
    clone.close()
