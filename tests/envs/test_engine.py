"""The batched episode engine (:mod:`poc_env.sim.engine`) and the adapters that only convert it:
``gymnasium.make_vec`` returns the sync vector env's infos key for key, the rewards averaged
over live agents equal numpy's mean of the live values, sub-batch resets and steps leave the
other envs alone, and bad input names its field."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import poc_env  # (also registers the tasks)
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.errors import ConfigError
from poc_env.sim import core as sim
from poc_env.sim import engine as engine_mod
from poc_env.sim.engine import Engine, RandomPrior, make_engine


@pytest.mark.parametrize(
    ("tid", "overrides"),
    [
        ("poc_env/UAVSearch-Small-Random-Heading-v0", {"episode.horizon_steps": 9}),
        (
            "poc_env/UAVSearch-Small-Increments-v0",
            {"episode.detection_ends_episode": True, "constraints.violation": "terminate"},
        ),
    ],
)
def test_make_vec_infos_equal_the_sync_vector_env(tid, overrides):
    kw = {"num_envs": 3, "overrides": overrides}
    v = gymnasium.make_vec(tid, vectorization_mode="vector_entry_point", **kw)
    s = gymnasium.make_vec(tid, vectorization_mode="sync", **kw)

    def same(got, want, where):
        assert set(got) == set(want), where
        for key in want:
            g, w = np.asarray(got[key]), np.asarray(want[key])
            assert g.dtype == w.dtype and g.shape == w.shape, (where, key)
            np.testing.assert_array_equal(g, w, err_msg=f"{where} {key}")

    got, want = v.reset(seed=7), s.reset(seed=7)
    same(got[1], want[1], "reset")
    assert "target_detected" in got[1] and "violations" in got[1]
    rng = np.random.default_rng(7)
    ends = 0
    for t in range(30):
        a = rng.uniform(-1, 1, v.action_space.shape).astype(np.float32)
        got, want = v.step(a), s.step(a)
        for j in range(4):
            np.testing.assert_array_equal(got[j], want[j], err_msg=f"step {t} item {j}")
        same(got[4], want[4], f"step {t}")
        ends += int(got[2].sum() + got[3].sum())
    assert ends >= 3  # autoresets included


def test_mean_over_is_numpys_mean_of_the_live_values():
    rng = np.random.default_rng(0)
    for n in (3, 8, 9, 17):
        values = rng.normal(size=(40, n)) * 10.0 ** rng.integers(-6, 3, (40, n))
        some = rng.random((40, n)) < 0.7
        some[0] = False
        two = np.argsort(rng.random((40, n)), axis=1) < 2  # two live agents in every row
        # the general grouping, every agent live, one count for every row
        for mask in (some, np.ones((40, n), dtype=bool), two):
            got = engine_mod.mean_over(values, mask)
            want = [
                float(np.mean(values[k][mask[k]].tolist())) if mask[k].any() else 0.0
                for k in range(40)
            ]
            assert got.tolist() == want


def test_mean_over_short_rows_bit_for_bit():
    """Rows of fewer than 8 agents (summed column by column, the masked values as 0.0): every
    mean is numpy's mean of the row's live values to the bit, the sign of a zero included
    (NaN's sign aside): special values, rows without a live agent, every agent live."""
    rng = np.random.default_rng(1)
    specials = np.array([0.0, -0.0, 1e300, -1e300, 5e-324, np.inf, -np.inf, 0.1, -1.0, 1 / 3])
    for trial in range(3000):
        n, e = int(rng.integers(1, 8)), int(rng.integers(1, 30))
        if trial % 2:
            values = rng.choice(specials, (e, n))
        else:
            values = rng.normal(size=(e, n)) * 10.0 ** rng.integers(-6, 6, (e, n))
        mask = rng.random((e, n)) < (1.0 if trial % 5 == 0 else rng.random())
        got = engine_mod.mean_over(values, mask)
        for k in range(e):
            with np.errstate(invalid="ignore"):
                want = np.mean(values[k][mask[k]]) if mask[k].any() else 0.0
            if np.isnan(want):
                assert np.isnan(got[k])
            else:
                assert got[k] == want and np.signbit(got[k]) == np.signbit(want), (k, trial)


def test_engine_seeds_give_the_parallel_envs_episodes():
    eng = make_engine(2, scenario="small", random_prior=True, seeds=[4, 9])
    obs, info = eng.reset()
    for k, seed in enumerate((4, 9)):
        par = UAVSearchParallelEnv("small", random_prior=True)
        par.reset(seed=seed)
        np.testing.assert_array_equal(eng.priors[k], par.engine.priors[0])
        np.testing.assert_array_equal(eng.current.target[k], par.sim_state.target[0])
        np.testing.assert_array_equal(obs["raster"][k], par.engine.observe()["raster"][0])
    assert set(info) == {"posc", "violations", *engine_mod.AGENT_INFO_KEYS}


def test_sub_batch_reset_and_step_leave_the_other_envs_alone():
    eng = Engine("small", 3, prior_source=RandomPrior(), seeds=[1, 2, 3])
    eng.reset()
    acts = np.zeros((3, eng.n_agents, 3))
    eng.step(acts)
    before = sim.take_envs(eng.current, np.array([0, 2]))
    eng.reset([1])
    assert int(eng.current.step[1]) == 0
    after = sim.take_envs(eng.current, np.array([0, 2]))
    np.testing.assert_array_equal(before.belief, after.belief)
    tr = eng.step(acts[:1], [1])
    assert tr.reward.shape == (1, eng.n_agents) and tr.info["posc"].shape == (1,)
    np.testing.assert_array_equal(eng.current.step, [1, 1, 1])


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"n_envs": 0}, "n_envs"),
        ({"n_envs": 2, "random_airfields": True}, "random_airfields"),
        ({"seeds": [1, 2]}, "seeds"),
        ({"obs_type": "image"}, "obs_type"),
        ({"control": "joystick"}, "control"),
        ({"agent_index": "yes"}, "agent_index"),
    ],
)
def test_engine_bad_arguments(kw, field):
    with pytest.raises(ConfigError, match=field):
        Engine("small", **kw)


@pytest.mark.parametrize(
    ("scenario", "kw"),
    [
        ("paper_6_2", {}),
        ("small", {"overrides": {"episode.detection_ends_episode": True}}),
        ("small", {"random_airfields": True, "control": "waypoint", "target__model": "drift"}),
    ],
)
def test_single_env_infos_are_the_info_arrays_row_by_row(scenario, kw):
    """The PettingZoo env builds its per-agent infos from ``info_parts`` directly: each value is
    the agent's entry of the engine's info arrays, with the type and key order of the spec."""
    env = UAVSearchParallelEnv(scenario, **kw)
    rng = np.random.default_rng(5)
    for ep in range(2):
        _, infos = env.reset(seed=ep)
        arrays = env.info_arrays
        for t in range(40):
            for a, row in infos.items():
                i = env._index[a]
                assert list(row)[: len(engine_mod.AGENT_INFO_KEYS) + 1] == list(
                    poc_env.spec.info_keys()
                )
                for k, v in row.items():
                    want = arrays[k][0] if k == "posc" else arrays[k][0, i]
                    if isinstance(v, np.ndarray):
                        assert v.dtype == want.dtype and v.tobytes() == want.tobytes(), (t, k)
                    else:
                        assert type(v) is type(want.item()) and v == want.item(), (t, k)
            if not env.agents:
                break
            acts = {a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents}
            *_, infos = env.step(acts)
            arrays = env.info_arrays
            assert env.transition.info is arrays
