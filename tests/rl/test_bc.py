"""Behaviour-cloning warm start (poc_env.agents.rl.bc, ``poc-env train --task ID --bc-teacher``):
demonstrations, the fit, determinism, resume, bad input, and the BC policy flown in evaluate."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch as th

from poc_env.agents.rl.args import TrainArgs, parse_train_args
from poc_env.agents.rl.bc import DEMO_KEY, FIT_KEY, _label, collect_demos, pretrain
from poc_env.agents.rl.checkpoint import checkpoint_steps, load_policy
from poc_env.agents.rl.train import make_env, make_model, seed_everything, train
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

INC = "UAVSearch-Small-Random-Increments-v0"
HEAD = "UAVSearch-Small-Random-Heading-v0"
# small: 3 UAVs; 2 envs x 3 UAVs = 6 slots, 128 steps per slot: rollouts of 768 transitions
ROLLOUT = 768


def _args(run_dir: Path, **kw) -> TrainArgs:
    base = dict(
        task=INC,
        bc_teacher="greedy_bayes",
        bc_episodes=2,
        bc_epochs=3,
        total_timesteps=2048,  # 3 rollouts
        n_envs=2,
        n_steps=128,
        batch_size=256,
        n_epochs=2,
        checkpoint_every=1,  # one checkpoint per rollout
        keep_checkpoints=0,
        progress=False,
        run_dir=str(run_dir),
    )
    base.update(kw)
    return TrainArgs(**base)


@pytest.fixture(scope="module")
def bc_run(tmp_path_factory) -> Path:
    """One complete tiny BC + PPO run."""
    return train(_args(tmp_path_factory.mktemp("bc") / "run"))


# -- demonstrations ----------------------------------------------------------------------------
def test_demos_see_the_compass_observation_and_carry_discounted_returns():
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.theory.probability_map import random_gaussian_mixture

    sc = load_scenario("small")
    ss = np.random.SeedSequence(7, spawn_key=DEMO_KEY)
    demos = collect_demos(sc, INC, "lawnmower", 2, ss, gamma=0.9)
    n = demos.samples
    assert n > 0 and demos.obs.shape == (n, 63) and demos.labels.shape == (n, 3)
    assert np.all(np.abs(demos.labels) <= 1.0) and len(demos.posc) == 2
    assert set(demos.episode.tolist()) == {0, 1} and set(demos.uav.tolist()) == {0, 1, 2}
    # episode 0 replayed: the same seed and prior from the stream, the compass env's first
    # observation is each UAV's first demo row (what PPO sees in SwarmVecEnv)
    rng = np.random.default_rng(np.random.SeedSequence(7, spawn_key=DEMO_KEY))
    seed = int(rng.integers(0, 2**31))
    env = UAVSearchParallelEnv(scenario=sc, obs_type="compass")
    prior = random_gaussian_mixture(env.params.grid, rng)
    obs, _ = env.reset(seed=seed, options={"prior": prior})
    assert demos.seeds[0] == seed
    for i in range(3):
        first = np.flatnonzero((demos.episode == 0) & (demos.uav == i))[0]
        np.testing.assert_array_equal(demos.obs[first], obs[f"uav_{i}"])
    # G_t = r_t + gamma G_{t+1} along each UAV's trajectory; G = r at its last step
    same = (demos.episode[1:] == demos.episode[:-1]) & (demos.uav[1:] == demos.uav[:-1])
    g, r = demos.returns.astype(float), demos.rewards.astype(float)
    np.testing.assert_allclose(g[:-1][same], r[:-1][same] + 0.9 * g[1:][same], atol=1e-5)
    last = np.append(~same, True)
    np.testing.assert_allclose(g[last], r[last], atol=1e-6)
    assert np.any(r != 0)


def test_labels_of_the_autopilot_levels():
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.sim.control import waypoint_goal

    params = UAVSearchParallelEnv("small").params
    xy0, xy1 = np.array([1000.0, 2000.0]), np.array([4000.0, -2000.0])
    np.testing.assert_allclose(_label("heading", params, None, xy0, xy1), [0.6, -0.8])
    assert _label("heading", params, None, xy0, xy0) is None  # no displacement: no label
    wp = _label("waypoint", params, None, xy0, xy1)
    np.testing.assert_allclose(waypoint_goal(params, wp)[0], xy1)  # its inverse
    np.testing.assert_array_equal(_label("increments", params, [2.0, -0.5, -3.0], xy0, xy1),
                                  [1.0, -0.5, -1.0])  # fmt: skip


def test_demo_stream_is_neither_a_training_nor_an_evaluation_stream():
    import poc_env.limits as limits
    from poc_env.agents.experiments.evaluate import EVAL_PRIOR_STREAM

    seed = 3
    streams = [
        np.random.SeedSequence(seed, spawn_key=k).generate_state(4) for k in (DEMO_KEY, FIT_KEY)
    ]
    assert not np.array_equal(*streams)
    training = np.random.SeedSequence(seed).spawn(limits.N_ENVS_MAX)
    evaluation = np.random.SeedSequence([seed, EVAL_PRIOR_STREAM])
    for other in [*training, evaluation]:
        for s in streams:
            assert not np.array_equal(s, other.generate_state(4))


# -- the fit -----------------------------------------------------------------------------------
@pytest.mark.parametrize(("task", "epochs", "factor"), [(HEAD, 30, 5.0), (INC, 100, 2.0)])
def test_pretrain_moves_the_policy_to_the_labels_and_the_values_to_the_returns(
    task, epochs, factor
):
    """Heading labels (directions) are cloned closely. Increment labels are sparse impulses
    (the teacher's increments are 0 on most steps and turn now and then, so even the
    untrained policy's near-zero mean is close to them): their error falls by a smaller
    factor, after more updates."""
    sc = load_scenario("small")
    args = TrainArgs(task=task, n_envs=1, n_steps=128, batch_size=128)
    demos = collect_demos(
        sc, task, "greedy_bayes", 3, np.random.SeedSequence(0, spawn_key=DEMO_KEY)
    )
    seed_everything(0)
    model = make_model(args, make_env(args, sc), None)

    def errors():
        act, _ = model.predict(demos.obs, deterministic=True)
        with th.no_grad():
            v = model.policy.predict_values(th.as_tensor(demos.obs)).numpy()[:, 0]
        return np.mean((act - demos.labels) ** 2), np.mean((v - demos.returns) ** 2)

    act0, val0 = errors()
    out = pretrain(model, demos, epochs=epochs, batch_size=32, seed=0, log_std=-1.5)
    act1, val1 = errors()
    print(f"{task}: action MSE {act0:.4f} -> {act1:.4f}, value MSE {val0:.4f} -> {val1:.4f}")
    assert act1 * factor < act0 and val1 * 20 < val0
    assert out["after"]["action_mse"] == pytest.approx(act1, rel=1e-5)
    assert out["before"]["value_mse"] == pytest.approx(val0, rel=1e-5)
    assert len(out["epochs_actor_mse"]) == epochs
    np.testing.assert_array_equal(model.policy.log_std.detach().numpy(), -1.5)


# -- runs: bc.json, determinism, resume --------------------------------------------------------
def test_a_bc_run_writes_bc_json_and_counts_ppo_steps_only(bc_run):
    bc = json.loads((bc_run / "bc.json").read_text())
    assert bc["teacher"] == "greedy_bayes" and bc["control"] == "increments"
    assert bc["episodes"] == 2 and len(bc["teacher_posc"]) == 2 and bc["samples"] > 0
    assert 0.0 < bc["teacher_posc_mean"] <= 1.0
    assert bc["after"]["value_mse"] < bc["before"]["value_mse"]
    assert load_policy(bc_run / "model.zip").num_timesteps == 3 * ROLLOUT  # PPO's transitions
    assert checkpoint_steps(bc_run) == [ROLLOUT, 2 * ROLLOUT, 3 * ROLLOUT]
    assert sorted(p.name for p in (bc_run / "tb").iterdir()) == ["bc", "ppo_1"]
    assert list((bc_run / "tb" / "bc").glob("events.out.tfevents.*"))


def test_bc_runs_are_reproducible(bc_run, tmp_path, same_weights):
    again = train(_args(tmp_path / "again"))
    other = train(_args(tmp_path / "other", seed=1))
    ref = bc_run / "model.zip"
    assert same_weights(again / "model.zip", ref)
    assert not same_weights(other / "model.zip", ref)
    a, b = (json.loads((r / "bc.json").read_text()) for r in (bc_run, again))
    assert a["after"] == b["after"] and a["seeds"] == b["seeds"]


def test_a_resumed_bc_run_continues_bit_identically_without_bc_again(
    bc_run, tmp_path, monkeypatch, same_weights
):
    from stable_baselines3.common.callbacks import BaseCallback

    class Interrupt(Exception):
        pass

    class Kill(BaseCallback):
        def _on_step(self) -> bool:
            if self.model.num_timesteps >= ROLLOUT + 300:
                raise Interrupt
            return True

    run = tmp_path / "killed"
    with pytest.raises(Interrupt):  # killed in the middle of the second rollout
        train(_args(run), callback=Kill())
    assert checkpoint_steps(run) == [ROLLOUT]
    bc_before = (run / "bc.json").read_bytes()

    def no_bc(*a, **k):
        raise AssertionError("BC repeated on resume")

    monkeypatch.setattr("poc_env.agents.rl.bc.warm_start", no_bc)
    train(TrainArgs(resume=str(run), progress=False))
    assert load_policy(run / "model.zip").num_timesteps == 3 * ROLLOUT
    assert same_weights(run / "model.zip", bc_run / "model.zip")
    assert (run / "bc.json").read_bytes() == bc_before


# -- bad input ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kw",
    [
        {"task": INC, "bc_teacher": "nobody"},
        {"task": INC, "bc_teacher": "ppo:runs/x"},
        {"task": INC, "bc_teacher": "rllib:runs/x"},
        {"task": INC, "bc_teacher": "ppo"},
        {"bc_teacher": "lawnmower"},  # no --task
        {"task": INC, "bc_teacher": "lawnmower", "engine": "rllib"},
    ],
)
def test_bad_teachers_name_bc_teacher(kw):
    with pytest.raises(ConfigError) as err:
        TrainArgs(**kw)
    assert err.value.field == "bc_teacher"
    if kw.get("bc_teacher") == "nobody":
        assert "allocation_plan" in str(err.value) and "lawnmower" in str(err.value)


@pytest.mark.parametrize(
    ("field", "value"),
    [("bc_episodes", 0), ("bc_epochs", 0), ("bc_batch_size", 0), ("bc_log_std", float("nan"))],
)
def test_bad_bc_numbers(field, value):
    with pytest.raises(ConfigError) as err:
        TrainArgs(task=INC, bc_teacher="lawnmower", **{field: value})
    assert err.value.field == field


def test_bc_options_on_the_command_line():
    argv = ["--task", INC, "--bc-teacher", "lawnmower", "--bc-episodes", "3", "--bc-epochs", "4"]
    args = parse_train_args([*argv, "--bc-log-std", "-0.5", "--total-timesteps", "0"])
    assert (args.bc_teacher, args.bc_episodes, args.bc_epochs, args.bc_log_std) == (
        "lawnmower", 3, 4, -0.5,
    )  # fmt: skip
    assert args.total_timesteps == 0  # BC alone
    with pytest.raises(ConfigError) as err:
        TrainArgs(task=INC, total_timesteps=0)  # PPO needs steps without a teacher
    assert err.value.field == "total_timesteps"


# -- the BC policy flies -----------------------------------------------------------------------
def test_the_bc_increments_policy_beats_random_through_evaluate(tmp_path):
    """BC alone (no PPO step) from 3 greedy_bayes episodes, flown as ppo:RUN on 10 held-out
    priors: its mean POSC exceeds random's by more than the two 95 % half-widths together."""
    from poc_env.agents.experiments.evaluate import evaluate

    run = train(
        _args(
            tmp_path / "bc",
            bc_episodes=3,
            bc_epochs=100,
            bc_batch_size=32,
            total_timesteps=0,
        )
    )
    assert not (run / "checkpoints").exists() or checkpoint_steps(run) == []
    assert load_policy(run / "model.zip").num_timesteps == 0
    ev = evaluate("small", [f"ppo:{run}", "random"], episodes=10, seed0=0, random_priors=True)
    bc, rnd = ev.rows()
    assert bc["posc_mean"] - rnd["posc_mean"] > bc["posc_ci95"] + rnd["posc_ci95"], ev.table()


# -- the set observation (-Set tasks, --net set) -----------------------------------------------
SET = "UAVSearch-Small-Random-Set-Heading-v1"


def test_set_task_demos_see_the_set_observation_and_clone_with_the_set_network():
    """A -Set task records the set observation its env computes (not the compass), and BC
    with ``--net set`` moves the set network's actions towards the teacher's labels."""
    from poc_env import spec
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.theory.probability_map import random_gaussian_mixture

    sc = load_scenario("small")
    ss = np.random.SeedSequence(5, spawn_key=DEMO_KEY)
    demos = collect_demos(sc, SET, "greedy_bayes", 3, ss)
    n = demos.samples
    assert n > 0 and demos.obs.shape == (n, spec.SET_SIZE) and demos.labels.shape == (n, 2)
    # episode 0 replayed in the set env: each UAV's first demo row is its first observation
    rng = np.random.default_rng(np.random.SeedSequence(5, spawn_key=DEMO_KEY))
    seed = int(rng.integers(0, 2**31))
    env = UAVSearchParallelEnv(scenario=sc, obs_type="set")
    prior = random_gaussian_mixture(env.params.grid, rng)
    obs, _ = env.reset(seed=seed, options={"prior": prior})
    for i in range(3):
        first = np.flatnonzero((demos.episode == 0) & (demos.uav == i))[0]
        np.testing.assert_array_equal(demos.obs[first], obs[f"uav_{i}"])
    args = TrainArgs(task=SET, net="set", n_envs=1, n_steps=128, batch_size=128)
    seed_everything(0)
    model = make_model(args, make_env(args, sc), None)

    def action_mse():
        act, _ = model.predict(demos.obs, deterministic=True)
        return float(np.mean((act - demos.labels) ** 2))

    fresh = action_mse()
    pretrain(model, demos, epochs=30, batch_size=32, seed=0)
    cloned = action_mse()
    print(f"set net: action MSE {fresh:.4f} -> {cloned:.4f}")
    assert cloned * 3 < fresh


def test_a_set_bc_run_is_reproducible(tmp_path, same_weights):
    """``--bc-teacher`` with a -Set task and ``--net set`` through train(): bc.json, and the
    same weights from the same seed."""
    kw = dict(task=SET, net="set", bc_teacher="lawnmower", total_timesteps=0)
    a = train(_args(tmp_path / "a", **kw))
    b = train(_args(tmp_path / "b", **kw))
    bc = json.loads((a / "bc.json").read_text())
    assert bc["samples"] > 0 and bc["after"]["actor_mse"] < bc["before"]["actor_mse"]
    assert same_weights(a / "model.zip", b / "model.zip")


# -- every task of a mixed run (--bc-all-tasks) --------------------------------------------------
def test_bc_all_tasks_records_every_task_and_keeps_the_first_tasks_stream(tmp_path):
    """``--bc-all-tasks``: ``--bc-episodes`` teacher episodes of each task of the run, the
    first task's from the stream it had without the flag (so its rows are the same)."""
    kw = dict(task="UAVSearch-Small-Random-Set-Increments-v0", net="set", bc_teacher="lawnmower",
              bc_episodes=1, total_timesteps=0,
              also_task=["UAVSearch-Wide-N3-Random-Set-Increments-v0"])  # fmt: skip
    both = json.loads(
        (train(_args(tmp_path / "all", bc_all_tasks=True, **kw)) / "bc.json").read_text()
    )
    first = json.loads((train(_args(tmp_path / "first", **kw)) / "bc.json").read_text())
    assert [t["task"] for t in both["tasks"]] == [kw["task"], *kw["also_task"]]
    assert "tasks" not in first and both["episodes"] == 2 and first["episodes"] == 1
    assert both["samples"] == sum(t["samples"] for t in both["tasks"]) > first["samples"]
    assert both["tasks"][0]["samples"] == first["samples"]
    assert both["teacher_posc"][0] == first["teacher_posc"][0]
    assert both["tasks"][1]["samples"] > 0  # the wide_400 episode's rows are in the fit


def test_concat_demos_renumbers_episodes_and_refuses_mixed_teachers():
    from poc_env.agents.rl.bc import concat_demos

    sc = load_scenario("small")
    a = collect_demos(sc, INC, "lawnmower", 2, np.random.SeedSequence(1, spawn_key=DEMO_KEY))
    b = collect_demos(sc, INC, "lawnmower", 1, np.random.SeedSequence(2, spawn_key=DEMO_KEY))
    c = concat_demos([a, b])
    assert c.samples == a.samples + b.samples and c.posc == a.posc + b.posc
    np.testing.assert_array_equal(c.episode, np.concatenate([a.episode, b.episode + 2]))
    np.testing.assert_array_equal(c.obs[a.samples :], b.obs)
    g = collect_demos(sc, INC, "greedy_bayes", 1, np.random.SeedSequence(2, spawn_key=DEMO_KEY))
    with pytest.raises(ConfigError) as err:
        concat_demos([a, g])
    assert err.value.field == "demos"


def test_bc_all_tasks_needs_also_task():
    with pytest.raises(ConfigError) as err:
        TrainArgs(task=INC, bc_teacher="lawnmower", bc_all_tasks=True)
    assert err.value.field == "bc_all_tasks"
