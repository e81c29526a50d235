"""The residual policy on a planner (poc_env.agents.rl.residual, ``poc-env train
--residual-teacher``): the zero residual flies the teacher's episode exactly (training env and
``ppo:RUN``), the rule of :func:`combine`, a run's determinism per seed, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from poc_env.agents.rl.args import TrainArgs
from poc_env.agents.rl.checkpoint import load_policy
from poc_env.agents.rl.residual import ResidualVecEnv, combine
from poc_env.agents.rl.train import train
from poc_env.errors import ConfigError

SET = "UAVSearch-Small-Random-Set-Heading-v1"


def _args(run_dir: Path, **kw) -> TrainArgs:
    base = dict(
        task=SET,
        residual_teacher="allocation_plan",
        residual_pool=2,
        total_timesteps=512,
        n_envs=2,
        n_steps=64,
        batch_size=128,
        n_epochs=2,
        checkpoint_every=10**6,
        progress=False,
        run_dir=str(run_dir),
    )
    base.update(kw)
    return TrainArgs(**base)


def _episode(policy: str, env_prior: np.ndarray, seed: int = 0):
    """Every step's actions and the final POSC of ``policy`` on ``small`` with ``env_prior``."""
    from poc_env.agents.policies.registry import make_policy
    from poc_env.envs.parallel import UAVSearchParallelEnv

    env = UAVSearchParallelEnv("small")
    obs, _ = env.reset(seed=seed, options={"prior": env_prior})
    pol = make_policy(policy)
    pol.reset(env, seed)
    steps = []
    while env.agents:
        actions, _ = pol.predict(obs)
        steps.append({a: np.asarray(v, dtype=float) for a, v in actions.items()})
        obs, *_ = env.step(actions)
    return steps, float(env.sim_state.posc[0])


def test_combine_adds_speed_and_turn_and_leaves_homing_uavs_to_the_teacher():
    t = np.array([[0.2, -0.5, 0.3], [0.9, 0.1, -0.2]])
    out = combine(t, np.array([[0.5, -0.7], [0.5, 0.5]]), np.array([False, True]))
    np.testing.assert_allclose(out, [[0.7, -1.0, 0.3], [0.9, 0.1, -0.2]])  # clipped; homing
    np.testing.assert_array_equal(combine(t, np.zeros((2, 2)), np.zeros(2, bool)), t)


def test_the_zero_residual_env_flies_the_teachers_episodes():
    """ResidualVecEnv with zero actions: each env's episode scores what allocation_plan scores
    alone on that env's prior (planning there and flying through the same follower)."""
    env = ResidualVecEnv(
        "small", n_envs=2, seed=3, obs_type="set", random_priors=True,
        teacher="allocation_plan", pool=0,
    )  # fmt: skip
    obs = env.reset()
    assert obs.shape == (6, env.observation_space.shape[0])
    priors = env.priors.copy()
    posc: dict[int, float] = {}
    while len(posc) < 2:
        _, _, _, infos = env.step(np.zeros((env.num_envs, 2)))
        for i, info in enumerate(infos):
            if "episode" in info:
                posc.setdefault(i // env.n_agents, info["posc"])
    for e in range(2):
        _, teacher = _episode("allocation_plan", priors[e])
        assert posc[e] == pytest.approx(teacher, abs=1e-9)
    assert env.plans_made == 4  # pool 0: one plan per episode (2 first + 2 after auto-reset)


def test_a_residual_run_at_zero_flies_the_teacher_exactly_through_ppo(tmp_path):
    """--total-timesteps 0 saves the initial residual policy (mean 0): ppo:RUN flies
    allocation_plan's episode action for action."""
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.config import load_scenario

    run = train(_args(tmp_path / "zero", total_timesteps=0))
    prior = episode_prior(load_scenario("small"), 11)
    ours, p_ours = _episode(f"ppo:{run}", prior, seed=11)
    teach, p_teach = _episode("allocation_plan", prior, seed=11)
    assert len(ours) == len(teach) and p_ours == p_teach
    for a, b in zip(ours, teach, strict=True):
        assert a.keys() == b.keys()
        for k in a:
            np.testing.assert_array_equal(a[k], b[k])


def test_residual_runs_are_deterministic_per_seed_and_learn_something(tmp_path):
    a = train(_args(tmp_path / "a"))
    b = train(_args(tmp_path / "b"))
    c = train(_args(tmp_path / "c", seed=1))
    pa, pb, pc = (
        [p.detach().numpy().copy() for p in load_policy(r / "model.zip").policy.parameters()]
        for r in (a, b, c)
    )
    assert all(np.array_equal(x, y) for x, y in zip(pa, pb, strict=True))
    assert not all(np.array_equal(x, y) for x, y in zip(pa, pc, strict=True))
    act = load_policy(a / "model.zip").policy.action_net
    assert float(act.weight.detach().abs().sum()) > 0  # PPO moved the residual off zero


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        (dict(residual_teacher="greedy_bayes"), "residual_teacher"),  # not a plan
        (dict(residual_teacher="ppo:x"), "residual_teacher"),
        (dict(net="set"), "net"),
        (dict(bc_teacher="lawnmower"), "bc_teacher"),
        (dict(residual_pool=-1), "residual_pool"),
        (dict(task="UAVSearch-Small-Random-Heading-v0", residual_log_std=9.0), "residual_log_std"),
    ],
)
def test_bad_residual_options_name_the_field(tmp_path, kw, field):
    with pytest.raises(ConfigError) as err:
        _args(tmp_path / "bad", **kw)
    assert err.value.field == field


def test_a_killed_residual_run_resumes_from_its_checkpoint(tmp_path):
    """Killed after its first checkpoint, ``--resume`` continues to the total (new episodes:
    the followers in flight are not checkpointed), with the teacher's env again."""
    from stable_baselines3.common.callbacks import BaseCallback

    from poc_env.agents.rl.checkpoint import checkpoint_steps

    rollout = 64 * 6  # n_steps x (2 swarms x 3 UAVs)

    class Interrupt(Exception):
        pass

    class Kill(BaseCallback):
        def _on_step(self) -> bool:
            if self.model.num_timesteps >= rollout + 100:
                raise Interrupt
            return True

    run = tmp_path / "killed"
    with pytest.raises(Interrupt):
        train(_args(run, total_timesteps=3 * rollout, checkpoint_every=1), callback=Kill())
    assert checkpoint_steps(run) == [rollout]
    assert not (run / "checkpoints" / f"step_{rollout}.env.npz").exists()
    train(TrainArgs(resume=str(run), progress=False))
    assert load_policy(run / "model.zip").num_timesteps == 3 * rollout


DRIFT = "UAVSearch-Small-Drift-Heading-v1"


def _drift_scenario():
    from poc_env.tasks import get_task

    return get_task(DRIFT).load_scenario()


def _fly_alone(policy: str, scenario, seed: int, plan_seed: int) -> float:
    """``policy``'s POSC flown alone on ``scenario``'s parallel env reset with ``seed``."""
    from poc_env.agents.policies.registry import make_policy
    from poc_env.envs.parallel import UAVSearchParallelEnv

    env = UAVSearchParallelEnv(scenario)
    obs, _ = env.reset(seed=seed)
    pol = make_policy(policy)
    pol.reset(env, plan_seed)
    while env.agents:
        actions, _ = pol.predict(obs)
        obs, *_ = env.step(actions)
    return float(env.sim_state.posc[0])


@pytest.mark.parametrize("teacher", ["spacetime_plan", "spacetime_receding"])
def test_a_moving_target_teacher_flies_its_episode_in_the_zero_residual_env(teacher):
    """On a Drift task the teacher reads its env's drift, belief and clock (EnvView): the zero
    residual scores what the teacher scores alone on the same episode (same generator), and
    plans are made per episode (none pooled: a plan depends on the drift)."""
    sc = _drift_scenario()
    env = ResidualVecEnv(
        sc, n_envs=1, seed=0, obs_type="compass", random_priors=False, teacher=teacher
    )
    env.engine.seed([11])  # the generator the parallel env's reset(seed=11) makes
    env._seeds = [None]  # keep it through reset
    env.reset()
    assert np.linalg.norm(env.engine.current.drift[0]) > 0.1  # a moving target
    posc = None
    while posc is None:
        _, _, _, infos = env.step(np.zeros((env.num_envs, 2)))
        if "episode" in infos[0]:
            posc = infos[0]["posc"]
    assert env.plans_made == 2  # the first episode's and the next one's (auto-reset)
    assert posc == pytest.approx(_fly_alone(teacher, sc, 11, plan_seed=0), abs=1e-9)


def test_a_receding_residual_at_zero_flies_the_receding_planner_through_ppo(tmp_path):
    """--residual-teacher spacetime_receding on a Drift task, --total-timesteps 0: ppo:RUN
    flies spacetime_receding's episode action for action (its re-plans included)."""
    from poc_env.envs.parallel import UAVSearchParallelEnv

    run = train(
        _args(
            tmp_path / "zero_drift",
            task=DRIFT,
            residual_teacher="spacetime_receding",
            total_timesteps=0,
        )
    )
    sc = _drift_scenario()
    flights = []
    for policy in (f"ppo:{run}", "spacetime_receding"):
        from poc_env.agents.policies.registry import make_policy

        env = UAVSearchParallelEnv(sc)
        obs, _ = env.reset(seed=12)
        pol = make_policy(policy)
        pol.reset(env, 12)
        steps = []
        while env.agents:
            actions, _ = pol.predict(obs)
            steps.append({a: np.asarray(v, dtype=float) for a, v in actions.items()})
            obs, *_ = env.step(actions)
        flights.append((steps, float(env.sim_state.posc[0])))
    (ours, p_ours), (teach, p_teach) = flights
    assert len(ours) == len(teach) and p_ours == p_teach
    for a, b in zip(ours, teach, strict=True):
        assert a.keys() == b.keys()
        for k in a:
            np.testing.assert_array_equal(a[k], b[k])
