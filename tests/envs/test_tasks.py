"""The registered benchmark tasks (poc_env.tasks) and the batched Gymnasium vector env."""

from __future__ import annotations

import functools
import types

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.env_registry.registration import make as pz_make
from pettingzoo.test import api_test, max_cycles_test, parallel_api_test, parallel_seed_test

import poc_env
from poc_env import tasks
from poc_env.envs.gym_vector import SwarmGymVectorEnv
from poc_env.errors import ConfigError
from poc_env.sim.control import ACTION_DIMS
from poc_env.sim.observations import FEATURES, SET_SIZE

SHORT = {"episode.horizon_steps": 25}
ALL = list(tasks.TASKS)


def test_the_table_of_tasks():
    # Increments v0, Heading v0 and v1, Waypoint v0; plus Drift-Heading v0 and v1; plus
    # Set-Heading v1 and Set-Increments v0 on every scenario and prior and on Wide at 4 fleet
    # sizes
    assert len(ALL) == 3 * 2 * 4 + 3 * 2 + 2 * (3 * 2 + 4)
    assert "poc_env/UAVSearch-Wide-N12-Random-Set-Increments-v0" in ALL
    assert f"poc_env/UAVSearch-Paper62-Drift-Heading-v{tasks.VERSION}" in ALL
    assert "poc_env/UAVSearch-Paper62-Drift-Heading-v1" in ALL
    assert f"poc_env/UAVSearch-Paper62-Random-Heading-v{tasks.VERSION}" in ALL
    assert f"poc_env/UAVSearch-Small-Increments-v{tasks.VERSION}" in ALL
    for tid in ALL:
        assert tid in gymnasium.registry
        spec = gymnasium.spec(tid)
        assert spec.vector_entry_point == tasks.VECTOR_ENTRY_POINT
        assert spec.kwargs == tasks.TASKS[tid].kwargs
        assert tid.endswith(f"-v{tasks.TASKS[tid].version}")
    rows = tasks.task_table()
    assert [r["id"] for r in rows] == ALL
    assert {(r["scenario"], r["n_uavs"]) for r in rows} == {
        ("small", 3),
        ("paper_6_2", 6),
        ("paper_6_1", 6),
        *(("wide_400", n) for n in (3, 6, 12, 24)),
    }


@pytest.mark.parametrize("tid", ALL)
def test_every_task_passes_the_four_checkers(tid):
    task = tasks.TASKS[tid]
    kw = {"overrides": SHORT}
    par = pz_make("parallel", tid, **kw)
    assert par.control == task.kwargs["control"] and par.random_prior == task.random_prior
    n = par.params.n_agents
    size = SET_SIZE if task.obs == "set" else FEATURES
    assert par.observation_space("uav_0").shape == (size,)
    assert par.action_space("uav_0").shape == (ACTION_DIMS[task.control],)
    parallel_api_test(par, num_cycles=30)
    api_test(pz_make("aec", tid, **kw), num_cycles=30)
    parallel_seed_test(functools.partial(tasks.make_parallel, tid, **kw), num_cycles=20)
    env = gymnasium.make(tid, **kw)
    assert env.observation_space.shape == (n * size,)
    check_env(env.unwrapped, skip_render_check=True)


@pytest.mark.parametrize("tid", [ALL[0], ALL[4], ALL[11]])
def test_max_cycles_on_tasks(tid):
    kw = {"overrides": {"uav.cruise_altitude_m": 4000.0}}  # no crash before the cut-off
    module = types.SimpleNamespace(
        env=functools.partial(tasks.make_aec, tid, **kw),
        parallel_env=functools.partial(tasks.make_parallel, tid, **kw),
    )
    max_cycles_test(module)


def test_random_tasks_draw_a_prior_per_seed_and_replay_a_seed():
    tid = f"poc_env/UAVSearch-Small-Random-Heading-v{tasks.VERSION}"
    priors = []
    for seed in (0, 1, 0):
        env = tasks.make_parallel(tid)
        env.reset(seed=seed)
        priors.append(env.sim_state.prior_fine[0].copy() if env.sim_state.prior_fine is not None
                      else env.sim_state.belief[0].copy())  # fmt: skip
    assert not np.allclose(priors[0], priors[1])
    np.testing.assert_array_equal(priors[0], priors[2])
    fixed = tasks.make_parallel(f"poc_env/UAVSearch-Small-Heading-v{tasks.VERSION}")
    fixed.reset(seed=0)
    b0 = fixed.sim_state.belief[0].copy()
    fixed.reset(seed=1)
    np.testing.assert_array_equal(b0, fixed.sim_state.belief[0])


def test_make_overrides_the_tasks_arguments():
    env = gymnasium.make(f"poc_env/UAVSearch-Small-Heading-v{tasks.VERSION}", obs_type="dict")
    assert isinstance(env.observation_space, gymnasium.spaces.Dict)
    no_namespace = f"UAVSearch-Small-Heading-v{tasks.VERSION}"
    par = tasks.make_parallel(no_namespace, control="waypoint")
    assert par.control == "waypoint"


@pytest.mark.parametrize("bad", ["UAVSearch-Tiny-Heading-v0", "poc_env/UAVSearch-Small-v0", 3])
def test_unknown_task(bad):
    with pytest.raises(ConfigError, match=r"task: got .*allowed: a registered task id"):
        tasks.make_parallel(bad)


def test_poc_env_tasks_shows_the_observation_and_the_target(capsys):
    """Audit (i28-audit): ``poc-env tasks`` showed scenario, control, prior, UAVs and horizon,
    so a -Set task (another observation) and a -Drift task (a moving target) read as their
    plain siblings but for the id."""
    from poc_env.cli import main

    assert main(["tasks"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[-2:] == ["obs", "target"]
    row = {ln.split()[0]: ln.split()[-2:] for ln in lines[1:]}
    assert row["poc_env/UAVSearch-Small-Heading-v1"] == ["compass", "static"]
    assert row["poc_env/UAVSearch-Small-Random-Set-Heading-v1"] == ["set", "static"]
    assert row["poc_env/UAVSearch-Small-Drift-Heading-v1"] == ["compass", "drift"]
    assert len(row) == len(ALL)


@pytest.mark.parametrize(
    ("bad", "closest"),
    [
        ("UAVSearch-Smal-Heading-v1", "UAVSearch-Small-Heading-v1"),  # a typo
        ("Small-Random-Heading-v1", "UAVSearch-Small-Random-Heading-v1"),  # no UAVSearch-
        ("poc_env/UAVSearch-Small-Increments-v1", "UAVSearch-Small-Increments-v0"),  # a version
    ],
)
def test_a_wrong_task_id_names_the_closest_ids_first(bad, closest):
    """Audit (i28-audit): the error listed all 50 ids and no near match; the closest come
    first, then the whole list."""
    with pytest.raises(ConfigError) as err:
        tasks.get_task(bad)
    text = str(err.value)
    assert f"allowed: a registered task id, the closest {closest}" in text
    assert text.index(closest) < text.index("UAVSearch-Paper61-Increments-v0")


# -- gymnasium.make_vec: the batched core equals the sync vector env ---------------------------
def _run_both(tid, num_envs, steps, seed, **kw):
    v = gymnasium.make_vec(tid, num_envs=num_envs, vectorization_mode="vector_entry_point", **kw)
    s = gymnasium.make_vec(tid, num_envs=num_envs, vectorization_mode="sync", **kw)
    assert isinstance(v.unwrapped, SwarmGymVectorEnv)
    assert v.single_observation_space == s.single_observation_space
    assert v.action_space == s.action_space
    ov, iv = v.reset(seed=seed)
    os_, _ = s.reset(seed=seed)
    np.testing.assert_array_equal(ov, os_)
    keys = set(iv)
    rng = np.random.default_rng(seed)
    ends = 0
    held: list = []  # what the previous step returned, and a copy of it
    for t in range(steps):
        a = rng.uniform(-1, 1, v.action_space.shape).astype(np.float32)
        got, want = v.step(a), s.step(a)
        for arr, copy_ in held:  # arrays handed out are never written into later
            np.testing.assert_array_equal(arr, copy_, err_msg=f"step {t}: an earlier array changed")
        held = [(got[0], got[0].copy())] + [(x, np.array(x)) for x in got[4].values()]
        for j in range(4):
            np.testing.assert_array_equal(got[j], want[j], err_msg=f"step {t} item {j}")
        np.testing.assert_array_equal(got[4]["posc"], want[4]["posc"])
        assert set(got[4]) == keys
        assert all(np.asarray(x).dtype.kind in "biuf" for x in got[4].values())
        ends += int(got[2].sum() + got[3].sum())
    return ends


@pytest.mark.parametrize(
    "tid",
    [
        f"poc_env/UAVSearch-Small-Increments-v{tasks.VERSION}",
        f"poc_env/UAVSearch-Small-Random-Heading-v{tasks.VERSION}",
        f"poc_env/UAVSearch-Small-Random-Waypoint-v{tasks.VERSION}",
        poc_env.ENV_ID,
    ],
)
def test_make_vec_equals_the_sync_vector_env(tid):
    # a 12-step horizon: every env ends and autoresets (NEXT_STEP) twice within 40 steps
    ends = _run_both(tid, 3, 40, seed=5, overrides={"episode.horizon_steps": 12})
    assert ends >= 6


def test_make_vec_without_mode_uses_the_batched_core():
    v = gymnasium.make_vec(f"poc_env/UAVSearch-Small-Heading-v{tasks.VERSION}", num_envs=4)
    assert isinstance(v.unwrapped, SwarmGymVectorEnv)
    obs, info = v.reset(seed=[1, 2, 3, None])
    assert obs.shape == (4, 3 * FEATURES)
    assert info["landed"].shape == (4, 3) and info["posc"].shape == (4,)


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"num_envs": 0}, "num_envs"),
        ({"num_envs": 2, "render_mode": "rgb_array"}, "render_mode"),
        ({"num_envs": 2, "random_airfields": True}, "random_airfields"),
        ({"num_envs": 2, "control": "joystick"}, "control"),
    ],
)
def test_vector_env_bad_arguments(kw, field):
    with pytest.raises(ConfigError, match=field):
        SwarmGymVectorEnv(scenario="small", **kw)


def test_vector_env_bad_actions_and_seeds():
    v = SwarmGymVectorEnv(2, scenario="small", control="heading")
    with pytest.raises(ConfigError, match="seed"):
        v.reset(seed=[1, 2, 3])
    v.reset(seed=0)
    with pytest.raises(ConfigError, match=r"actions: .*shape \(2, 6\)"):
        v.step(np.zeros((2, 9)))
    with pytest.raises(ConfigError, match="actions"):
        v.step(np.full((2, 6), np.nan))


@pytest.mark.parametrize("wild", [1e308, 5.0, -3.0])
def test_heading_v1_clips_out_of_box_actions_v0_keeps_normalising(wild):
    """Issue 27: a heading action outside its Box was normalised (a component of 1e308
    flies due east whatever the other says). ``-Heading-v1`` clips each component to [-1, 1]
    first, as the other levels clip; ``-Heading-v0`` keeps its behaviour (an old id)."""
    action = np.array([wild, 0.8], dtype=np.float64)
    clipped = np.clip(action, -1.0, 1.0)

    def first_step(tid, a):
        env = gymnasium.make(tid, disable_env_checker=True)
        env.reset(seed=3)
        n = env.unwrapped.par.engine.n_agents
        obs, *_ = env.step(np.tile(a, n).astype(np.float64))
        env.close()
        return obs

    v1 = "poc_env/UAVSearch-Small-Heading-v1"
    v0 = "poc_env/UAVSearch-Small-Heading-v0"
    np.testing.assert_array_equal(first_step(v1, action), first_step(v1, clipped))
    np.testing.assert_array_equal(first_step(v1, clipped), first_step(v0, clipped))
    assert not np.array_equal(first_step(v0, action), first_step(v0, clipped))


@pytest.mark.parametrize("tid", list(tasks.TASKS))
def test_a_tasks_scenario_is_the_one_its_environment_flies(tid):
    """``Task.load_scenario`` (what ``evaluate --task``, ``train --task`` and the baselines fly
    the task's policies on) is the scenario of the task's registered environment: a Drift
    task's moving target included (it was the static scenario, so ``evaluate --task
    ...-Drift-...`` scored a target standing still)."""
    from poc_env.envs.parallel import UAVSearchParallelEnv

    task = tasks.get_task(tid)
    env = UAVSearchParallelEnv(**task.kwargs)
    assert task.load_scenario() == env.scenario
