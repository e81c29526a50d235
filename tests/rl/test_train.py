"""``poc-env train`` (poc_env.agents.rl.train, args, checkpoint, policy, curve): run folders,
checkpoints, resume, determinism, learning, ppo:PATH, the command line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from poc_env.agents.rl.args import TrainArgs, parse_train_args
from poc_env.agents.rl.checkpoint import checkpoint_steps, latest_checkpoint, load_policy
from poc_env.agents.rl.policy import PPOPolicy
from poc_env.agents.rl.train import make_env, make_model, seed_everything, train
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.io import atomic_path

# small: 3 UAVs, so one shared-recipe rollout with 2 envs and 16 steps is 96 transitions; the
# central recipe's is 32 (one slot per env). Horizon 12 < 16: every rollout ends episodes.
ROLLOUT = {"shared": 96, "central": 32, "pilot": 96}


def _args(recipe: str, run_dir: Path, **kw) -> TrainArgs:
    base = dict(
        scenario="small",
        overrides=["episode.horizon_steps=12"],
        recipe=recipe,
        total_timesteps=3 * ROLLOUT[recipe],
        seed=0,
        n_envs=2,
        n_steps=16,
        batch_size=32,
        n_epochs=2,
        checkpoint_every=1,  # one checkpoint per rollout
        keep_checkpoints=2,
        progress=False,
        run_dir=str(run_dir),
    )
    base.update(kw)
    return TrainArgs(**base)


class Interrupt(Exception):
    """Stands in for a kill in the middle of a rollout."""


def _killer(at: int):
    from stable_baselines3.common.callbacks import BaseCallback

    class Kill(BaseCallback):
        def _on_step(self) -> bool:
            if self.model.num_timesteps >= at:
                raise Interrupt
            return True

    return Kill()


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    """One complete tiny run per recipe."""
    root = tmp_path_factory.mktemp("runs")
    return {r: train(_args(r, root / r)) for r in ("shared", "central", "pilot")}


# -- run folder -------------------------------------------------------------------------------
@pytest.mark.parametrize("recipe", ["shared", "central", "pilot"])
def test_train_writes_the_run_folder(runs, recipe, same_weights):
    run = runs[recipe]
    total = 3 * ROLLOUT[recipe]
    cfg = json.loads((run / "config.json").read_text())
    args = TrainArgs.from_dict(cfg)
    assert args == _args(recipe, run)  # the resolved args, round-tripping
    sc = load_scenario(run / "scenario.yaml")
    assert sc.name == "small" and sc.episode.horizon_steps == 12  # overrides resolved
    events = list((run / "tb").glob("ppo_1/events.out.tfevents.*"))
    assert len(events) == 1 and b"rollout/posc_mean" in events[0].read_bytes()
    # one checkpoint per rollout, the newest two kept, latest.json -> the final one
    assert checkpoint_steps(run) == [2 * ROLLOUT[recipe], total]
    step, model_zip, state, env_npz = latest_checkpoint(run)
    assert step == total and model_zip == run / "checkpoints" / f"step_{total}.zip"
    saved = json.loads(state.read_text())
    assert saved["step"] == total and len(saved["env_generators"]) == 2
    assert (env_npz is not None) == (recipe != "central")  # episodes in flight: shared only
    assert not list(run.rglob("*.tmp"))  # atomic writes leave no temporary files
    assert not [p for p in run.rglob(".*") if "tb" not in p.relative_to(run).parts]
    model = load_policy(run / "model.zip")
    assert model.num_timesteps == total
    assert same_weights(run / "model.zip", model_zip)


def test_every_run_file_is_published_by_rename(tmp_path, monkeypatch):
    import os

    renamed = []
    real = os.replace

    def spy(src, dst):
        renamed.append(Path(dst))
        real(src, dst)

    monkeypatch.setattr(os, "replace", spy)
    run = train(_args("shared", tmp_path / "run", keep_checkpoints=0))
    files = {p for p in run.rglob("*") if p.is_file() and "tb" not in p.relative_to(run).parts}
    assert len(files) == 3 + 3 * 3 + 1  # config, scenario, model; 3 checkpoints; latest
    assert files <= set(renamed)
    assert renamed[-1] == run / "model.zip"
    assert renamed.count(run / "latest.json") == 3


def test_atomic_path_leaves_the_old_file_on_failure(tmp_path):
    target = tmp_path / "model.zip"
    target.write_text("old")

    with pytest.raises(RuntimeError), atomic_path(target, suffix=".zip") as tmp:
        tmp.write_text("half")
        raise RuntimeError("killed")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["model.zip"]


# -- determinism ------------------------------------------------------------------------------
@pytest.mark.parametrize("recipe", ["shared", "central", "pilot"])
def test_save_load_gives_identical_deterministic_actions(tmp_path, recipe):
    args = _args(recipe, tmp_path)
    env = make_env(args, load_scenario("small", {"episode.horizon_steps": 12}))
    model = make_model(args, env, None)
    model.learn(ROLLOUT[recipe])
    obs = env.reset()
    for _ in range(5):  # a few different observations
        obs, *_ = env.step(np.stack([env.action_space.sample() for _ in range(env.num_envs)]))
    model.save(tmp_path / "m.zip")
    loaded = load_policy(tmp_path / "m.zip", env)
    a, _ = model.predict(obs, deterministic=True)
    b, _ = loaded.predict(obs, deterministic=True)
    np.testing.assert_array_equal(a, b)
    assert np.unique(a.round(6), axis=0).shape[0] > 1  # not a degenerate constant policy


def test_same_seed_same_parameters_other_seed_others(runs, tmp_path, same_weights):
    again = train(_args("shared", tmp_path / "again"))
    other = train(_args("shared", tmp_path / "other", seed=1))
    ref = runs["shared"] / "model.zip"
    assert same_weights(again / "model.zip", ref)
    assert not same_weights(other / "model.zip", ref)


# -- resume -----------------------------------------------------------------------------------
@pytest.mark.parametrize("recipe", ["shared", "pilot"])
def test_resume_continues_bit_identically(runs, tmp_path, recipe, same_weights, capsys):
    run = tmp_path / "killed"
    with pytest.raises(Interrupt):  # killed in the middle of the second rollout
        train(_args(recipe, run), callback=_killer(ROLLOUT[recipe] + 54))
    assert checkpoint_steps(run) == [ROLLOUT[recipe]]
    assert not (run / "model.zip").exists()
    out = train(TrainArgs(resume=str(run), progress=False))
    assert out == run
    assert load_policy(run / "model.zip").num_timesteps == 3 * ROLLOUT[recipe]
    # the step count continued from the checkpoint (96 -> 192 -> 288), not from 0
    assert checkpoint_steps(run) == [2 * ROLLOUT[recipe], 3 * ROLLOUT[recipe]]
    assert [p.name for p in (run / "tb").iterdir()] == ["ppo_1"]  # the same TensorBoard run
    # its curve joins the killed attempt's event file (up to the checkpoint) and the resumed
    # one's (issue 27: poc-env curve showed the resumed part alone)
    from poc_env.agents.rl.curve import training_curve

    steps = training_curve(run)["rollout/posc_mean"][:, 0]
    np.testing.assert_array_equal(steps, [ROLLOUT[recipe] * k for k in (1, 2, 3)])
    # model, optimiser, env state and generators restored: the uninterrupted run's parameters
    assert same_weights(run / "model.zip", runs[recipe] / "model.zip")
    # resuming a finished run changes nothing, and says so
    before = (run / "model.zip").stat().st_mtime_ns, (run / "model.zip").read_bytes()
    train(TrainArgs(resume=str(run), progress=False))
    assert same_weights(run / "model.zip", runs[recipe] / "model.zip")
    assert ((run / "model.zip").stat().st_mtime_ns, (run / "model.zip").read_bytes()) == before
    assert "nothing to train" in capsys.readouterr().err


def test_resume_continues_the_step_count_central(tmp_path):
    run = tmp_path / "killed"
    with pytest.raises(Interrupt):
        train(_args("central", run), callback=_killer(ROLLOUT["central"] + 10))
    assert checkpoint_steps(run) == [ROLLOUT["central"]]
    saved = json.loads((run / "checkpoints" / "step_32.state.json").read_text())
    train(TrainArgs(resume=str(run), progress=False))
    model = load_policy(run / "model.zip")
    assert model.num_timesteps == 3 * ROLLOUT["central"]
    assert checkpoint_steps(run) == [2 * ROLLOUT["central"], 3 * ROLLOUT["central"]]
    # the env generators were restored from the checkpoint, then drawn from further
    after = json.loads((run / "checkpoints" / "step_64.state.json").read_text())
    assert after["env_generators"] != saved["env_generators"]


# -- bad input --------------------------------------------------------------------------------
def test_unknown_algo_and_recipe():
    with pytest.raises(ConfigError, match="ppo") as err:
        TrainArgs(algo="dqn")
    assert err.value.field == "algo" and err.value.value == "dqn"
    with pytest.raises(ConfigError) as err:
        TrainArgs(recipe="decentralised")
    assert err.value.field == "recipe" and "shared" in err.value.allowed
    with pytest.raises(ConfigError) as err:
        TrainArgs(batch_size=1)
    assert err.value.field == "batch_size"
    with pytest.raises(ConfigError) as err:
        TrainArgs(overrides=["episode.horizon_steps"])
    assert err.value.field == "overrides"


def test_resume_on_a_folder_that_is_not_a_run(tmp_path):
    with pytest.raises(ConfigError, match=r"config\.json") as err:
        train(TrainArgs(resume=str(tmp_path / "nowhere")))
    assert err.value.field == "resume"
    (tmp_path / "config.json").write_text(json.dumps({"scenario": "small", "lr": 1}))
    with pytest.raises(ConfigError, match="lr"):
        train(TrainArgs(resume=str(tmp_path)))


def test_checkpoint_for_another_number_of_uavs_or_grid(runs, tmp_path):
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.envs.vector import SwarmVecEnv

    two = load_scenario("small").with_uavs(2)
    central = runs["central"] / "model.zip"
    args = _args("central", tmp_path, n_envs=1)
    with pytest.raises(ConfigError, match=r"Box\(540,\).*Box\(810,\)") as err:
        load_policy(central, make_env(args, two))
    assert err.value.field == "checkpoint"
    pol = PPOPolicy(central)
    with pytest.raises(ConfigError, match="2 UAVs"):
        pol.reset(UAVSearchParallelEnv(two), seed=0)
    # the shared policy flies any number of UAVs on its grid, but not another grid
    PPOPolicy(runs["shared"]).reset(UAVSearchParallelEnv(two), seed=0)
    with pytest.raises(ConfigError, match=r"Box\(4, 30, 40\).*Box\(4, 8, 8\)"):
        load_policy(runs["shared"] / "model.zip", SwarmVecEnv("paper_6_2", n_envs=1))
    # missing and corrupt files
    with pytest.raises(ConfigError, match="existing"):
        load_policy(tmp_path / "missing.zip")
    (tmp_path / "bad.zip").write_bytes(b"not a zip")
    with pytest.raises(ConfigError, match="readable") as err:
        PPOPolicy(tmp_path / "bad.zip")
    assert err.value.field == "checkpoint"


def test_a_shared_checkpoint_from_before_the_layout_by_role_loads(
    tmp_path, monkeypatch, same_weights
):
    """Shared-recipe files pickle the extractor's class by module path; those written before
    the layout by role name ``agents.networks`` (now ``poc_env.agents.rl.networks``)."""
    import sys
    import types

    from stable_baselines3 import PPO

    from poc_env.agents.rl.networks import SwarmExtractor

    old = types.ModuleType("agents.networks")
    Old = type("SwarmExtractor", (SwarmExtractor,), {"__module__": "agents.networks"})
    old.SwarmExtractor = Old  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "agents.networks", old)
    env = make_env(_args("shared", tmp_path), load_scenario("small"))
    model = PPO(
        "MultiInputPolicy", env, policy_kwargs={"features_extractor_class": Old}, device="cpu"
    )
    model.save(tmp_path / "old.zip")
    monkeypatch.delitem(sys.modules, "agents.networks")
    with pytest.raises(ModuleNotFoundError, match=r"agents\.networks"):
        PPO.load(tmp_path / "old.zip", device="cpu")  # the file names the old module
    loaded = load_policy(tmp_path / "old.zip", env)
    assert loaded.policy_kwargs["features_extractor_class"] is SwarmExtractor
    assert same_weights(loaded, model)


# -- evaluation through ppo:PATH --------------------------------------------------------------
def test_ppo_path_evaluates_through_evaluate(runs):
    from poc_env.agents.experiments.evaluate import evaluate, make_policy

    names = [
        f"ppo:{runs['shared'] / 'model.zip'}",
        f"ppo:{runs['central']}",
        f"ppo:{runs['pilot']}",
    ]
    ev = evaluate("small", names, episodes=1, seed0=1000)
    rows = ev.rows()
    assert [r["policy"] for r in rows] == names
    assert all(r["episodes"] == 1 and 0.0 <= r["posc_mean"] <= 1.0 for r in rows)
    again = evaluate("small", names[:1], episodes=1, seed0=1000)  # deterministic actions
    assert again.episodes[0].posc_curve == ev.episodes[0].posc_curve
    with pytest.raises(ConfigError, match="ppo:PATH"):
        make_policy("ppo_v2")
    with pytest.raises(ConfigError):
        make_policy("ppo:")


# -- learning ---------------------------------------------------------------------------------
def test_ppo_learns_on_small(tmp_path):
    """Training raises the POSC a policy finds, measured against the same network untrained.

    The pilot recipe on ``small`` learns fast: over training seeds 0-7, 20,480 transitions
    (20 rollouts of 4 envs x 3 UAVs x 64 steps, a few seconds on one core) raised the mean
    POSC on these 8 evaluation episodes (random priors, seeds 1000-1007) from 0.00-0.21
    untrained to 0.28-0.39, a gain of at least 0.17 for every seed (0.37 for seed 0). The run
    is deterministic on one torch build, so the 0.1 margin only has to absorb other torch builds
    and BLAS kernels; a broken reward, observation, action mapping or update loses it all.
    """
    from poc_env.agents.experiments.evaluate import evaluate

    args = TrainArgs(
        scenario="small",
        recipe="pilot",
        seed=0,
        n_envs=4,
        n_steps=64,
        batch_size=128,
        total_timesteps=20_480,
        checkpoint_every=10**9,  # only the final checkpoint
        progress=False,
        run_dir=str(tmp_path / "run"),
    )
    seed_everything(args.seed)  # the same initial weights as the run's
    untrained = make_model(args, make_env(args, load_scenario("small")), None)
    untrained.save(tmp_path / "untrained.zip")
    run = train(args)
    names = [f"ppo:{tmp_path / 'untrained.zip'}", f"ppo:{run / 'model.zip'}"]
    ev = evaluate("small", names, episodes=8, seed0=1000, random_priors=True, progress=False)
    before, after = (r["posc_mean"] for r in ev.rows())
    assert after > before + 0.1, (before, after)


# -- training curve ---------------------------------------------------------------------------
def test_curve_reads_the_runs_logs_and_plots_them(runs, tmp_path, capsys):
    from poc_env.agents.rl.curve import training_curve
    from poc_env.cli import main

    data = training_curve(runs["pilot"])["rollout/posc_mean"]
    assert data.shape == (3, 2)  # one value per rollout
    np.testing.assert_array_equal(data[:, 0], [96, 192, 288])
    assert np.all((data[:, 1] >= 0) & (data[:, 1] <= 1))
    out = tmp_path / "curve.png"
    assert main(["curve", str(runs["pilot"]), "--out", str(out), "--until", "192"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["curve", str(tmp_path)]) == 2  # no TensorBoard logs
    assert "run_dir" in capsys.readouterr().err
    # before the first logged step nothing is left to plot: a clear error (was a ValueError)
    assert main(["curve", str(runs["pilot"]), "--out", str(out), "--until", "95"]) == 2
    assert "until: got 95" in capsys.readouterr().err


# -- command line -----------------------------------------------------------------------------
def _field_docs() -> dict[str, str]:
    """The docstring under each TrainArgs field, read from the source."""
    import ast
    import inspect
    import itertools
    import textwrap

    from poc_env.agents.rl import args as args_module

    tree = ast.parse(textwrap.dedent(inspect.getsource(args_module.TrainArgs)))
    body = tree.body[0].body  # type: ignore[attr-defined]
    return {
        a.target.id: " ".join(b.value.value.split())
        for a, b in itertools.pairwise(body)
        if isinstance(a, ast.AnnAssign) and isinstance(b, ast.Expr)
    }


def test_cli_options_come_from_trainargs(tmp_path, capsys, monkeypatch):
    import dataclasses

    from poc_env.cli import main

    docs = _field_docs()
    assert set(docs) == set(TrainArgs.__dataclass_fields__)  # a docstring under every field
    with pytest.raises(SystemExit) as stop:
        parse_train_args(["--help"])
    assert stop.value.code == 0
    helptext = " ".join(capsys.readouterr().out.replace("│", " ").split())
    for f in dataclasses.fields(TrainArgs):  # every field an option, its docstring the help
        assert "--" + f.name.replace("_", "-") in helptext
        assert docs[f.name][:40] in helptext
    assert parse_train_args([]) == TrainArgs()  # one place for the defaults
    got = parse_train_args(["--total-timesteps", "5", "--no-random-priors", "--overrides", "a.b=1"])
    assert (got.total_timesteps, got.random_priors, got.overrides) == (5, False, ["a.b=1"])
    # the README's training command, through `poc-env train` itself
    seen = []
    monkeypatch.setattr("poc_env.agents.rl.train.train", lambda a: seen.append(a) or tmp_path)
    readme = (
        "train --scenario paper_6_2 --recipe pilot --seed 1 --n-envs 16 --total-timesteps "
        "10002432 --approach-shaping 0.1 --overrides reward.alpha=100 reward.violation_penalty=0.5"
    )
    assert main(readme.split()) == 0
    assert seen == [
        TrainArgs(
            scenario="paper_6_2",
            recipe="pilot",
            seed=1,
            n_envs=16,
            total_timesteps=10_002_432,
            approach_shaping=0.1,
            overrides=["reward.alpha=100", "reward.violation_penalty=0.5"],
        )
    ]
    argv = ["--recipe", "central", "--net-arch", "64", "32", "--resume", "None"]
    assert parse_train_args(argv).net_arch == [64, 32]
    assert parse_train_args(["--resume", "R", "--no-progress"]) == TrainArgs(
        resume="R", progress=False
    )
    # bad values: `error: FIELD: got VALUE; allowed: ...`, exit status 2
    capsys.readouterr()
    assert main(["train", "--algo", "dqn"]) == 2
    assert main(["train", "--resume", str(tmp_path), "--n-envs", "3"]) == 2
    assert main(["train", "--gamma", "1.5"]) == 2
    err = capsys.readouterr().err
    assert "error: algo: got 'dqn'; allowed: one of ppo" in err and "--n-envs" in err
    assert "error: gamma: got 1.5; allowed: a number in [0, 1]" in err
    # malformed ones (not a number, unknown option): the parser's message, exit status 2
    for bad in (["--n-envs", "two"], ["--n-env", "3"]):
        with pytest.raises(SystemExit) as stop:
            main(["train", *bad])
        assert stop.value.code == 2
    assert seen == [seen[0]]  # nothing else was trained


def test_resume_skips_a_checkpoint_killed_between_model_and_state(
    runs, tmp_path, monkeypatch, same_weights
):
    """A kill after step_192.zip but before its state file: resume takes the last complete
    checkpoint (step_96, with its generators) and ends bit-identical to the uninterrupted run,
    instead of restoring the weights without the generators."""
    import poc_env.agents.rl.checkpoint as ckpt

    recipe = "shared"
    run = tmp_path / "killed"
    real = ckpt.write_json
    second = f"step_{2 * ROLLOUT[recipe]}.state.json"

    def killed(path, data):
        if Path(path).name == second:
            raise Interrupt
        return real(path, data)

    monkeypatch.setattr(ckpt, "write_json", killed)
    with pytest.raises(Interrupt):
        train(_args(recipe, run))
    monkeypatch.setattr(ckpt, "write_json", real)
    assert (run / "checkpoints" / f"step_{2 * ROLLOUT[recipe]}.zip").is_file()
    with pytest.warns(UserWarning, match="incomplete"):
        ck = latest_checkpoint(run)
    assert ck is not None and ck.step == ROLLOUT[recipe]
    with pytest.warns(UserWarning, match="incomplete"):
        train(TrainArgs(resume=str(run), progress=False))
    assert same_weights(run / "model.zip", runs[recipe] / "model.zip")


def test_latest_json_cannot_point_outside_the_run(runs, tmp_path):
    import shutil

    run = tmp_path / "copy"
    shutil.copytree(runs["shared"], run)
    pointer = json.loads((run / "latest.json").read_text())
    pointer["model"] = "../../elsewhere/evil.zip"
    (run / "latest.json").write_text(json.dumps(pointer))
    with pytest.raises(ConfigError, match=r"latest\.json"):
        latest_checkpoint(run)


def test_a_run_killed_before_its_first_checkpoint_can_be_resumed(runs, tmp_path, same_weights):
    """--resume on a run with config but no checkpoint trains it again from step 0 and ends
    where the uninterrupted run ends (it used to refuse, pointing at --run-dir, which refused)."""
    run = tmp_path / "early"
    with pytest.raises(Interrupt):
        train(_args("shared", run), callback=_killer(40))
    assert checkpoint_steps(run) == [] and (run / "config.json").is_file()
    with pytest.warns(UserWarning, match="no complete checkpoint"):
        train(TrainArgs(resume=str(run), progress=False))
    assert same_weights(run / "model.zip", runs["shared"] / "model.zip")


def test_a_run_killed_before_its_scenario_file_can_be_resumed(runs, tmp_path, same_weights):
    """Issue 27: a kill between config.json and scenario.yaml left a folder that --resume
    refused (no scenario.yaml) and --run-dir refused (it holds a run: use --resume). Now
    --resume rebuilds scenario.yaml from config.json and trains in the folder from step 0,
    ending where the uninterrupted run ends; --run-dir's refusal names the command."""
    run = tmp_path / "early"
    with pytest.raises(Interrupt):
        train(_args("shared", run), callback=_killer(40))
    (run / "scenario.yaml").unlink()
    with pytest.raises(ConfigError, match=rf"train --resume {run}") as err:
        train(_args("shared", run, seed=1))  # other options (its own command restarts it)
    assert err.value.field == "run_dir"
    with pytest.warns(UserWarning, match="no complete checkpoint"):
        train(TrainArgs(resume=str(run), progress=False))
    assert (run / "scenario.yaml").is_file()
    assert same_weights(run / "model.zip", runs["shared"] / "model.zip")


def test_rerunning_the_command_of_a_run_killed_before_its_first_checkpoint(
    runs, tmp_path, same_weights
):
    """Issue 27, the documented way: the same command (options and --run-dir) after a kill
    before the first checkpoint trains the run again in its folder from step 0, ending where
    the uninterrupted run ends; other options, or a folder holding a finished run, are refused
    with the command that continues or flies it."""
    run = tmp_path / "early run"  # a space: the command shown is shell-quoted
    with pytest.raises(Interrupt):
        train(_args("shared", run), callback=_killer(40))
    with pytest.raises(ConfigError, match=r"train --resume '.*early run'") as err:
        train(_args("shared", run, seed=1))
    assert err.value.field == "run_dir"
    with pytest.warns(UserWarning, match="no complete checkpoint"):
        assert train(_args("shared", run)) == run
    assert same_weights(run / "model.zip", runs["shared"] / "model.zip")
    assert sorted(p.name for p in (run / "tb").iterdir()) == ["ppo_1", "ppo_2"]
    with pytest.raises(ConfigError, match=r"finished run.*evaluate --policies ppo:'"):
        train(_args("shared", run))


def test_curve_takes_the_newest_run_folder(tmp_path):
    """tb/ppo_10 is newer than tb/ppo_9 (a restart in place logs into the next K)."""
    from torch.utils.tensorboard import SummaryWriter

    from poc_env.agents.rl.curve import training_curve

    for k, value in ((9, 0.25), (10, 0.5)):
        with SummaryWriter(str(tmp_path / "tb" / f"ppo_{k}")) as w:
            w.add_scalar("rollout/posc_mean", value, 96)
    np.testing.assert_array_equal(training_curve(tmp_path)["rollout/posc_mean"], [[96, 0.5]])


def test_curve_joins_attempts_in_the_order_they_started(tmp_path):
    """A resumed attempt's event file can sort before the killed one's by name (the name's
    time is in whole seconds, then the process id and a writer count compared as text: ``.10``
    before ``.9``); the killed attempt's points then replaced the resumed ones, which made
    test_resume_continues_bit_identically flaky under xdist. The files are joined by their first
    event's wall time."""
    from torch.utils.tensorboard import SummaryWriter

    from poc_env.agents.rl.curve import training_curve

    folder = tmp_path / "tb" / "ppo_1"
    for name, points in (
        ("killed", [(96, 0.125), (192, 0.25)]),
        ("resumed", [(192, 0.375), (288, 0.5)]),
    ):
        with SummaryWriter(str(tmp_path / name)) as w:
            for step, value in points:
                w.add_scalar("rollout/posc_mean", value, step)
        (log,) = (tmp_path / name).glob("events.out.tfevents.*")
        folder.mkdir(parents=True, exist_ok=True)
        # names in the wrong order: the resumed attempt's sorts first as text
        count = 9 if name == "killed" else 10
        log.rename(folder / f"events.out.tfevents.1700000000.host.7.{count}")
    np.testing.assert_array_equal(
        training_curve(tmp_path)["rollout/posc_mean"], [[96, 0.125], [192, 0.375], [288, 0.5]]
    )


@pytest.mark.parametrize(
    ("kw", "field", "said"),
    [
        (
            {"recipe": "central", "net_arch": [10**6, 10**6]},
            "net_arch",
            "policy and value networks",
        ),
        ({"n_steps": 10**6, "n_envs": 1024, "batch_size": 64}, "n_steps", "rollout buffer"),
        ({"batch_size": 10**7}, "batch_size", "at most the rollout"),
        ({"recipe": "central", "n_steps": 1, "n_envs": 1, "batch_size": 2}, "n_steps", ">= 2"),
    ],
)
def test_train_sizes_are_checked_before_anything_is_allocated(tmp_path, kw, field, said):
    """Issue 27: sizes that passed validation and then allocated tens of GB (a huge network,
    a rollout buffer of 10^9 transitions) or failed inside SB3 (an assertion on a rollout of
    one transition; a minibatch larger than the rollout was silently cut) end in a ConfigError
    naming the field, before the run folder is made."""
    run = tmp_path / "r"
    with pytest.raises(ConfigError, match=said) as err:
        train(_args(kw.pop("recipe", "shared"), run, **kw))
    assert err.value.field == field
    assert not run.exists()


@pytest.mark.parametrize(
    "fields,name",
    [
        ({"engine": "rllib", "task": "UAVSearch-Paper62-Random-Set-Heading-v1", "net": "set"},
         "net"),  # RLlib's own model flies a set task: --net set was silently ignored
        ({"task": "UAVSearch-Small-Heading-v0", "num_env_runners": 3}, "num_env_runners"),
        ({"scenario": "small", "recipe": "shared", "n_envs": 2, "engine": "rllib"}, "n_envs"),
    ],
)  # fmt: skip
def test_train_from_python_refuses_fields_its_run_would_ignore(tmp_path, fields, name, monkeypatch):
    """The CLI refuses an option its run would ignore (``USED_WHEN``); from Python,
    ``train(TrainArgs(engine="rllib", net="set", ...))`` trained RLlib's own model and said
    nothing. A fresh run now refuses any field set away from its default that the run would
    ignore, naming it, before its folder is made."""
    import poc_env.agents.rl.train as train_mod

    def made(*_a, **_k):
        raise AssertionError("the run was started")

    monkeypatch.setattr(train_mod, "_new_run_dir", made)  # nothing trains, whatever happens
    run = tmp_path / "run"
    with pytest.raises(ConfigError, match="would ignore it") as err:
        train(TrainArgs(**fields, run_dir=str(run), progress=False))
    assert err.value.field == name
    assert not run.exists()
