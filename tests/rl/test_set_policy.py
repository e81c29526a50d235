"""The any-size architecture end to end (issue 28, smoke-sized): one PPO policy with the
DeepSets network trained on two fleet sizes in the same rollouts (``--also-task``), saved,
then flown at 6 and 24 UAVs without retraining. A real run is the ``slow`` recipe of
docs/rl.md; this only checks the pieces fit."""

from __future__ import annotations

import json

import numpy as np
import pytest

from poc_env import spec, tasks
from poc_env.agents.experiments.evaluate import evaluate
from poc_env.agents.rl.args import TrainArgs
from poc_env.agents.rl.policy import PPOPolicy
from poc_env.agents.rl.train import make_env, train
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

N3 = "UAVSearch-Wide-N3-Random-Set-Heading-v1"
N6 = "UAVSearch-Wide-N6-Random-Set-Heading-v1"
N24 = "UAVSearch-Wide-N24-Random-Set-Heading-v1"
SHORT = ["episode.horizon_steps=12"]


def test_also_task_puts_every_fleet_size_in_one_rollout():
    args = TrainArgs(task=N3, also_task=[N6], net="set", n_envs=2, progress=False)
    env = make_env(args, load_scenario("wide_400").with_uavs(3))
    assert env.num_envs == 2 * 3 + 2 * 6
    assert [p.n_agents for p in env.parts] == [3, 6]
    obs = env.reset()
    assert obs.shape == (18, spec.SET_SIZE)
    np.testing.assert_array_equal(obs[6:], env.parts[1].engine.observe().reshape(12, -1))
    _, rew, done, infos = env.step(np.zeros((18, 2), np.float32))
    assert rew.shape == done.shape == (18,) and len(infos) == 18
    assert len(env.rngs) == 4  # each part's env generators, for checkpoints
    assert env.parts[0].rngs[0].random() != env.parts[1].rngs[0].random()  # own streams


def test_the_set_network_needs_a_set_task_and_also_tasks_match():
    with pytest.raises(ConfigError, match="net"):
        TrainArgs(task="UAVSearch-Small-Random-Heading-v1", net="set")
    with pytest.raises(ConfigError, match="also_task"):
        TrainArgs(task=N6, also_task=["UAVSearch-Small-Random-Heading-v1"])
    with pytest.raises(ConfigError, match="also_task"):
        TrainArgs(also_task=[N6])


def test_one_set_policy_trained_on_3_and_6_flies_6_and_24_uavs(tmp_path):
    run = train(
        TrainArgs(
            task=N3, also_task=[N6], net="set", n_envs=1, n_steps=16, batch_size=48,
            n_epochs=1, total_timesteps=300, overrides=SHORT, progress=False,
            run_dir=str(tmp_path / "run"),
        )
    )  # fmt: skip
    cfg = json.loads((run / "config.json").read_text())
    assert cfg["net"] == "set" and cfg["also_task"] == [N6]
    # a mixed run's checkpoint restores onto its rebuilt mixed env (every part's generators)
    state = json.loads(next((run / "checkpoints").glob("*.state.json")).read_text())
    assert len(state["env_generators"]) == 2 and not state["env"]
    assert train(TrainArgs(resume=str(run), progress=False)) == run
    pol = PPOPolicy(run)
    assert type(pol.model.policy.features_extractor).__name__ == "SetExtractor"
    assert pol.model.num_timesteps % (16 * 9) == 0  # whole rollouts of 3 + 6 slots
    for tid, n in ((N6, 6), (N24, 24)):
        env = tasks.make_parallel(tid, overrides={"episode.horizon_steps": 12})
        pol.reset(env, seed=0)
        assert (pol.mode, pol.control, len(pol._agents)) == ("set", "heading", n)
        obs, _ = env.reset(seed=0)
        acts, _ = pol.predict(obs)
        assert len(acts) == n and all(a.shape == (3,) for a in acts.values())
        # the policy reads exactly what the task observes, and its network decides the actions
        seen = pol._set.of_state(env.engine.current, env.engine.poc_scale)[0]
        np.testing.assert_array_equal(seen, np.stack([obs[a] for a in env.agents]))
        heading, _ = pol.model.predict(seen, deterministic=True)
        assert np.abs(heading).max() > 0
        sc = load_scenario("wide_400", {"episode.horizon_steps": 12}).with_uavs(n)
        ev = evaluate(sc, [f"ppo:{run}"], episodes=1, seed0=0, random_priors=True)
        assert 0.0 < ev.rows()[0]["posc_mean"] <= 1.0


def _recipe() -> list[str]:
    """The any-size recipe's ``poc-env train`` options, read from docs/rl.md."""
    import re
    import shlex
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "rl.md").read_text(encoding="utf-8")
    block = re.search(r"<!-- recipe:any-size -->\n```bash\n(.*?)```", text, re.DOTALL)
    assert block is not None
    argv = shlex.split(block.group(1).replace("\\\n", " "))
    assert argv[:2] == ["poc-env", "train"]
    return argv[2:]


def _size(task_id: str) -> int:
    """A task's fleet size (a -Wide-N task's own, else its scenario's)."""
    return tasks.get_task(task_id).load_scenario().n_uavs


def test_the_any_size_recipe_in_the_docs_is_a_valid_command():
    from poc_env.agents.rl.args import parse_train_args

    args = parse_train_args(_recipe())
    sizes = [_size(t) for t in [args.task, *args.also_task]]
    assert set(sizes) == {3, 6, 12, 24} and args.net == "set"
    slots = args.n_envs * sum(sizes)  # every task's swarms, two tasks of one size included
    assert args.total_timesteps % (args.n_steps * slots) == 0  # whole rollouts
    assert (args.n_steps * slots) % args.batch_size == 0


@pytest.mark.slow
def test_the_any_size_recipe_trains_and_flies_6_and_24_uavs(tmp_path):
    from poc_env.agents.rl.args import parse_train_args
    from poc_env.cli import main

    argv = _recipe()
    k = argv.index("--total-timesteps")
    args = parse_train_args(argv)
    slots = args.n_envs * sum(_size(t) for t in [args.task, *args.also_task])
    argv[k + 1] = str(2 * args.n_steps * slots)  # two rollouts: the command runs end to end
    argv += ["--run-dir", str(tmp_path / "run"), "--no-progress"]
    run = train(parse_train_args(argv))
    for n in (6, 24):
        tid = f"UAVSearch-Wide-N{n}-Random-Set-Heading-v1"
        assert main(["evaluate", "--task", tid, "--policies", f"ppo:{run}", "--episodes", "2",
                     "--quiet"]) == 0  # fmt: skip


def test_the_shipped_any_size_policy_flies_24_uavs_home():
    """ppo_set_anysize (its card's replay is in tests/rl/test_pilot.py) flies an unseen 24-UAV
    episode of wide_400 (a seed and prior neither training nor its evaluations used) with
    every UAV back and a POSC its 50 evaluation episodes at 24 UAVs never fell below."""
    import csv
    from pathlib import Path

    from poc_env.agents.experiments.evaluate import run_episode

    sc = tasks.get_task(N24).load_scenario()
    ep = run_episode(sc, "ppo:ppo_set_anysize", 987_654, random_priors=True)
    assert ep.landed == 24 and ep.crashed == 0
    rows = Path(__file__).resolve().parents[2] / "results/anysize/eval_wide_n24/episodes.csv"
    floor = min(float(r["posc"]) for r in csv.DictReader(rows.open())
                if r["policy"] == "ppo:ppo_set_anysize")  # fmt: skip
    assert ep.posc >= floor > 0.0
