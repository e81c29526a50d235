"""SB3 PPO on a registered task (``poc-env train --task``): the task's env and control level,
and the trained policy flies at that level in evaluate."""

from __future__ import annotations

import json

import numpy as np
import pytest

import poc_env
from poc_env.agents.experiments.evaluate import evaluate
from poc_env.agents.rl.args import TrainArgs
from poc_env.agents.rl.policy import PPOPolicy
from poc_env.agents.rl.train import make_env, train
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.observations import FEATURES


def _tiny(tmp_path, **kw) -> TrainArgs:
    """A smoke-sized SB3 run into ``tmp_path / "run"`` (fields in ``kw`` win)."""
    base = dict(total_timesteps=96, n_steps=16, batch_size=48, n_envs=2, progress=False)
    return TrainArgs(**{**base, "run_dir": str(tmp_path / "run"), **kw})


@pytest.mark.parametrize(
    ("task", "dim"),
    [("UAVSearch-Small-Random-Waypoint-v0", 2), ("UAVSearch-Small-Increments-v0", 3)],
)
def test_task_env_is_the_tasks(task, dim):
    args = TrainArgs(task=task, n_envs=2, progress=False)
    env = make_env(args, load_scenario("small"))
    assert env.observation_space.shape == (FEATURES,)
    assert env.action_space.shape == (dim,)
    assert env.control == poc_env.tasks.get_task(task).control
    assert env.random_priors == ("Random" in task)


def test_trained_task_policy_flies_its_control_level(tmp_path):
    run = train(
        _tiny(
            tmp_path,
            task="UAVSearch-Small-Random-Waypoint-v0",
            total_timesteps=600,
            n_steps=32,
            batch_size=96,
        )
    )
    assert json.loads((run / "config.json").read_text())["task"].endswith("Waypoint-v0")
    pol = PPOPolicy(run)
    env = poc_env.parallel_env("small")
    pol.reset(env, seed=0)
    assert (pol.mode, pol.control) == ("compass", "waypoint")
    obs, _ = env.reset(seed=0)
    acts, _ = pol.predict(obs)
    # the waypoint autopilot's increments, within eq. 19's limits
    assert all(np.all(np.abs(a) <= 1.0 + 1e-9) and a.shape == (3,) for a in acts.values())
    ev = evaluate("small", [f"ppo:{run}"], episodes=1, seed0=0, random_priors=True)
    assert 0.0 <= ev.rows()[0]["posc_mean"] <= 1.0


def test_a_checkpoint_of_another_control_level_is_refused(tmp_path, capsys):
    from poc_env.cli import main

    run = train(_tiny(tmp_path, task="UAVSearch-Small-Waypoint-v0", total_timesteps=100, n_envs=1))
    argv = ["evaluate", "--policies", f"ppo:{run}", "--episodes", "1", "--quiet", "--task"]
    assert main([*argv, "UAVSearch-Small-Heading-v0"]) != 0
    err = capsys.readouterr().err
    assert "policies: got 'ppo:" in err and "trained at 'waypoint'" in err
    assert main([*argv, "UAVSearch-Small-Random-Waypoint-v0"]) == 0  # same level, other maps
    out = capsys.readouterr().out  # a transfer is allowed and said so, naming both tasks
    assert "was trained on poc_env/UAVSearch-Small-Waypoint-v0; flown here on " in out
    assert "poc_env/UAVSearch-Small-Random-Waypoint-v0 (a transfer" in out
    assert main([*argv, "UAVSearch-Small-Waypoint-v0"]) == 0
    assert "a transfer" not in capsys.readouterr().out


def test_a_transfer_note_names_the_observation_the_policy_reads(capsys):
    """Audit (i28-audit): ``ppo:ppo_set_anysize`` (trained on a ``-Set`` task) flown by
    ``evaluate --task`` on a compass task reads its own set observation; the note said
    "same control level and observation"."""
    from poc_env.cli import main

    argv = ["evaluate", "--policies", "ppo:ppo_set_anysize", "--episodes", "1", "--quiet"]
    argv += ["--overrides", "episode.horizon_steps=3"]
    assert main([*argv, "--task", "UAVSearch-Small-Random-Heading-v1"]) == 0
    out = capsys.readouterr().out
    assert "same control level and observation" not in out
    assert "its own 'set' observation" in out and "the task's 'compass'" in out
    assert main([*argv, "--task", "UAVSearch-Small-Random-Set-Heading-v1"]) == 0
    assert "(a transfer: same control level and observation)" in capsys.readouterr().out


def test_a_task_trained_with_also_task_is_not_called_a_transfer(capsys):
    """Audit (i28-audit): ``ppo_set_anysize`` trained on Paper62 with the four ``Wide`` sizes
    as ``--also-task``; ``evaluate --task`` of one of them called it a transfer."""
    from poc_env.cli import main

    argv = ["evaluate", "--policies", "ppo:ppo_set_anysize", "--episodes", "1", "--quiet"]
    argv += ["--overrides", "episode.horizon_steps=2"]
    assert main([*argv, "--task", "UAVSearch-Wide-N3-Random-Set-Heading-v1"]) == 0
    out = capsys.readouterr().out
    assert "a transfer" not in out
    assert "UAVSearch-Wide-N3-Random-Set-Heading-v1 is one of its --also-task tasks" in out


def test_no_agent_index_trains_and_flies_without_it(tmp_path):
    """--no-agent-index: the training env's features and the checkpoint's, flown by
    PPOPolicy, both have the index block at zero."""
    from poc_env.sim.observations import N_IDS

    args = _tiny(tmp_path, task="UAVSearch-Small-Random-Heading-v0", agent_index=False)
    env = make_env(args, load_scenario("small"))
    assert env.agent_index is False and not env.reset()[:, -N_IDS:].any()
    pol = PPOPolicy(train(args))
    penv = poc_env.parallel_env("small")
    penv.reset(seed=0)
    pol.reset(penv, seed=0)
    assert pol._features.agent_index is False
    with pytest.raises(ConfigError, match="agent_index"):
        TrainArgs(task="UAVSearch-Small-Heading-v0", agent_index="no")


@pytest.mark.parametrize(
    ("task", "net", "mode"),
    [
        ("UAVSearch-Small-Random-Increments-v0", "mlp", "compass"),
        ("UAVSearch-Small-Random-Set-Increments-v0", "set", "set"),  # any fleet size
    ],
)
def test_return_autopilot_trains_and_flies_the_same_way(tmp_path, task, net, mode):
    """--return-autopilot at the increments level: recorded in config.json, and PPOPolicy
    replaces the increments of home-bound UAVs by the autopilot's, as the training env did
    (the compass and the set observation alike)."""
    from poc_env.sim.control import return_home
    from poc_env.sim.observations import decode_vector, split_observation

    run = train(_tiny(tmp_path, task=task, net=net, return_autopilot=True))
    assert json.loads((run / "config.json").read_text())["return_autopilot"] is True
    pol = PPOPolicy(run)
    net = pol.model.policy.action_net  # level flight (zero increments) until the way home
    net.weight.data.zero_()
    net.bias.data.zero_()
    env = poc_env.parallel_env("small")
    obs, _ = env.reset(seed=0)
    pol.reset(env, seed=0)
    assert pol._return and (pol.mode, pol.control) == (mode, "increments")
    plain = PPOPolicy(run)
    plain.reset(env, seed=0)
    plain._return = False
    took_over = False
    while env.agents:
        acts, _ = pol.predict(obs)
        raw, _ = plain.predict(obs)
        live = list(acts)
        vec = np.stack([split_observation(obs[a], env.params.grid.shape)[1] for a in live])
        k = np.array([env.possible_agents.index(a) for a in live])
        want = return_home(env.params, decode_vector(env.params, vec), np.stack(
            [raw[a] for a in live]), k)  # fmt: skip
        np.testing.assert_allclose(np.stack([acts[a] for a in live]), want, atol=1e-6)
        took_over |= any(not np.allclose(acts[a], raw[a]) for a in live)
        obs, *_ = env.step(acts)
    assert took_over and env.sim_state.landed[0].all()  # the autopilot brought them home


def test_a_checkpoint_of_another_observation_is_refused(tmp_path, capsys):
    """A shared-recipe checkpoint (raster + vector observation) is not a task policy."""
    from poc_env.cli import main

    run = train(
        _tiny(
            tmp_path,
            scenario="small",
            overrides=["episode.horizon_steps=8"],
            total_timesteps=48,
            n_steps=8,
            batch_size=24,
            n_envs=1,
        )
    )
    argv = ["evaluate", "--policies", f"ppo:{run}", "--episodes", "1", "--quiet", "--task"]
    assert main([*argv, "UAVSearch-Small-Increments-v0"]) != 0
    err = capsys.readouterr().err
    assert "compass observation" in err and "'shared' recipe" in err
