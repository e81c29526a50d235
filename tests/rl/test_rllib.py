"""RLlib multi-agent PPO (poc_env.agents.rl.rllib) and Ray-distributed jobs
(poc_env.agents.rl.cluster, poc_env.agents.experiments.pool.ray_jobs): tiny runs on one local
Ray instance (2 CPUs, no dashboard)."""

from __future__ import annotations

import csv
import dataclasses
import sys
import time

import numpy as np
import pytest

pytest.importorskip("ray", reason="the rllib extra is not installed")

from poc_env.agents.experiments.evaluate import evaluate
from poc_env.agents.experiments.pool import ray_jobs, run_jobs
from poc_env.agents.policies.registry import make_policy
from poc_env.agents.rl import cluster
from poc_env.agents.rl.args import TrainArgs
from poc_env.agents.rl.rllib import RLlibPolicy
from poc_env.agents.rl.train import train
from poc_env.errors import ConfigError, MissingExtraError

TASK = "poc_env/UAVSearch-Small-Random-Heading-v0"
SHORT = ["episode.horizon_steps=30"]


@pytest.fixture(scope="module")
def ray_local():
    """One local Ray instance for the module (train and ray_jobs join it, leave it running)."""
    with cluster.ray_session(None, num_cpus=2) as ray:
        yield ray


def _args(tmp_path, name, **kw):
    base = {
        "engine": "rllib",
        "task": TASK,
        "overrides": SHORT,
        "total_timesteps": 200,
        "n_steps": 100,
        "batch_size": 100,
        "n_epochs": 1,
        "net_arch": [16],
        "run_dir": str(tmp_path / name),
        "progress": False,
    }
    base.update(kw)
    return TrainArgs(**base)


def test_shared_policy_trains_saves_and_flies(ray_local, tmp_path):
    run = train(_args(tmp_path, "shared", num_env_runners=1))  # sampling on a Ray actor
    assert (run / "checkpoint" / "learner_group").is_dir()
    rows = list(csv.DictReader((run / "metrics.csv").open()))
    assert rows and int(rows[-1]["env_steps"]) >= 200
    assert int(float(rows[-1]["agent_steps"])) == 3 * int(rows[-1]["env_steps"])
    from poc_env.agents.rl.policy import checkpoint_control

    assert checkpoint_control(f"rllib:{run}") == "heading"  # from the run's task
    policy = make_policy(f"rllib:{run}")
    assert isinstance(policy, RLlibPolicy) and set(policy.modules) == {"shared"}
    ev = evaluate("small", [f"rllib:{run}"], episodes=2, seed0=0)
    posc = [r["posc_mean"] for r in ev.rows()]
    assert 0.0 <= posc[0] <= 1.0
    # issue 27: TensorBoard scalars under SB3's tags, one per iteration at its agent steps, so
    # poc-env curve reads an RLlib run as it reads an SB3 run
    from poc_env.agents.rl.curve import training_curve
    from poc_env.cli import main

    curve = training_curve(run)
    assert [p.name for p in (run / "tb").iterdir()] == ["rllib_1"]
    steps = [float(r["agent_steps"]) for r in rows]  # every iteration (horizon 30) ends episodes
    for tag in ("rollout/posc_mean", "rollout/ep_rew_mean"):
        np.testing.assert_array_equal(curve[tag][:, 0], steps)
    assert np.all((curve["rollout/posc_mean"][:, 1] > 0) & (curve["rollout/posc_mean"][:, 1] <= 1))
    png = tmp_path / "curve.png"
    assert main(["curve", str(run), "--out", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_rllib_run_of_a_set_task_flies_on_its_observation(ray_local, tmp_path):
    """Audit (i28-audit): RLlib trains on a ``-Set`` task (the 116-value set observation), but
    its policy read the 63-value compass, so ``evaluate`` crashed in torch (``mat1 and mat2
    shapes cannot be multiplied (3x63 and 116x128)``). It reads the set observation of the
    env's swarm, which is the task's own observation of the same state."""
    import poc_env
    from poc_env.tasks import make_parallel

    set_task = "poc_env/UAVSearch-Small-Random-Set-Heading-v1"
    run = train(_args(tmp_path, "set", task=set_task))
    policy = make_policy(f"rllib:{run}")
    env = make_parallel(set_task, overrides={"episode.horizon_steps": 5})
    obs, _ = env.reset(seed=3)
    policy.reset(env, seed=3)
    acts, _ = policy.predict(obs)
    assert set(acts) == set(env.agents) and all(np.isfinite(a).all() for a in acts.values())
    np.testing.assert_array_equal(  # the policy's features are the env's observation
        policy._set.of_state(env.engine.current, env.engine.poc_scale)[0],
        np.stack([obs[a] for a in env.agents]),
    )
    ev = evaluate(
        poc_env.tasks.get_task(set_task).load_scenario({"episode.horizon_steps": 20}),
        [f"rllib:{run}"],
        episodes=1,
        seed0=0,
    )
    assert 0.0 <= ev.rows()[0]["posc_mean"] <= 1.0


def test_one_policy_per_uav(ray_local, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # relative run folders (RLlib itself needs absolute URIs)
    train(dataclasses.replace(_args(tmp_path, "x", rllib_policies="per_uav"), run_dir="per_uav"))
    policy = RLlibPolicy("per_uav")
    assert set(policy.modules) == {"uav_0", "uav_1", "uav_2"}
    import poc_env

    with pytest.raises(ConfigError, match="one policy per UAV for 6 UAVs"):
        policy.reset(poc_env.parallel_env("paper_6_2"), seed=0)


def test_a_long_run_keeps_its_newest_checkpoint_and_curve(ray_local, tmp_path, monkeypatch):
    """Every --checkpoint-every env steps the checkpoint and metrics.csv are rewritten, so a
    run stopped midway keeps them (here: seen at each save, before the run ends)."""
    import poc_env.agents.rl.rllib as rl

    seen: list[int] = []
    real = rl._save

    def save(algo, dest):
        real(algo, dest)
        metrics = dest.parent / "metrics.csv"
        seen.append(len(list(csv.DictReader(metrics.open()))) if metrics.exists() else 0)

    monkeypatch.setattr(rl, "_save", save)
    run = train(_args(tmp_path, "long", total_timesteps=300, checkpoint_every=100))
    # two saves midway (metrics.csv then holds 0 and 1 rows: it is written after the save),
    # then the final one; every iteration is in the final curve
    assert seen[:2] == [0, 1] and len(seen) == 3
    assert len(list(csv.DictReader((run / "metrics.csv").open()))) == 3


def test_ray_jobs_equal_local_jobs(ray_local):
    # the same episodes, as Ray tasks on 2 workers and in this process: identical results
    names = ["lawnmower", "random", "greedy_bayes"]
    local = evaluate("small", names, episodes=4, seed0=7, random_priors=True)
    with ray_jobs(None):
        remote = evaluate("small", names, episodes=4, seed0=7, workers=2, random_priors=True)
    assert local.to_csv() == remote.to_csv()
    assert np.ptp([e.posc for e in local.episodes if e.policy == "lawnmower"]) > 0  # seeds vary


def test_a_jobs_error_comes_back_as_itself(ray_local):
    with ray_jobs(None), pytest.raises(ConfigError, match="episodes"):
        run_jobs(_bad_job, [1, 2])


def _bad_job(x):
    raise ConfigError("episodes", x, "a test error")


_RACE = """
import time
from poc_env.agents.experiments.pool import ray_jobs, run_jobs
from poc_env.errors import ConfigError

def bad(x):
    time.sleep(0.05 * x)
    raise ConfigError("episodes", x, "a test error")

if __name__ == "__main__":
    with ray_jobs(None):
        for _ in range(25):
            for jobs in ([1, 1], [1, 2, 3, 4], [0, 1, 2, 3]):
                try:
                    run_jobs(bad, jobs)
                except ConfigError:
                    pass
            time.sleep(0.3)  # the replies of the other jobs arrive
    print("survived")
"""


def test_jobs_failing_together_do_not_crash_the_driver(tmp_path):
    """Stop 32's CI worker crashed: when one Ray job failed, run_jobs cancelled the others, and
    Ray 2.60 aborts the driver (``Check failed: ... Tried to complete task that was not
    pending``) when a cancel races with the reply of a job that is finishing, here the other
    jobs failing at the same moment. In a subprocess, so a crash fails this test only."""
    import subprocess

    script = tmp_path / "race.py"
    script.write_text(_RACE)
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=tmp_path
    )
    assert done.returncode == 0 and "survived" in done.stdout, done.stderr[-2000:]


def test_unreachable_address_fails_fast():
    t0 = time.perf_counter()
    with (
        pytest.raises(ConfigError, match=r"address: got '127.0.0.1:1'.*nothing answered"),
        cluster.ray_session("127.0.0.1:1"),
    ):
        pass
    assert time.perf_counter() - t0 < 60  # a clear error, not Ray's minutes of retries
    for bad in ("nohost", "host:port", "ray://:0", ""):
        with pytest.raises(ConfigError, match="address"), cluster.ray_session(bad):
            pass


def test_cli_errors(tmp_path, capsys):
    from poc_env.cli import main

    assert main(["evaluate", "--scenario", "small", "--episodes", "1", "--ray", "127.0.0.1:1"]) != 0
    assert "ray: got '127.0.0.1:1'" in capsys.readouterr().err  # the option evaluate takes
    with pytest.raises(ConfigError, match="task: got 'poc_env/Nope-v0'"):
        _args(tmp_path, "x", task="poc_env/Nope-v0")
    with pytest.raises(ConfigError, match=r"recipe: got 'pilot'.*with --task"):
        _args(tmp_path, "x", engine="sb3", recipe="pilot")
    with pytest.raises(ConfigError, match="rllib_policies"):
        _args(tmp_path, "x", rllib_policies="each")


def test_missing_ray_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(MissingExtraError, match=r"poc-env\[rllib\]"):
        cluster.require_ray("--ray")


def test_the_probe_passes_a_real_ray_gcs(ray_local):
    """The handshake probe (tests/rl/test_cluster.py refuses services that are not Ray)
    accepts Ray's own GCS port."""
    address = ray_local.get_runtime_context().gcs_address
    cluster.probe(address, timeout_s=5.0)


def test_an_rllib_run_killed_before_its_first_checkpoint_resumes(ray_local, tmp_path):
    """Issue 27: --resume refused rllib runs ("an rllib run starts anew") while --run-dir
    refused the folder ("holds a run: use --resume"). A run with config.json and no checkpoint
    now trains in its folder when its own command is run again (or with --resume, the same
    code); other options get an error naming --resume; once it has a checkpoint, each
    refusal names what to do instead."""
    from tensorboardX import SummaryWriter

    from poc_env.agents.rl.checkpoint import write_json
    from poc_env.agents.rl.curve import training_curve

    args = _args(tmp_path, "early")
    run = tmp_path / "early"
    run.mkdir()
    write_json(run / "config.json", dataclasses.asdict(args))  # a kill after one iteration:
    with SummaryWriter(str(run / "tb" / "rllib_1")) as killed:  # its scalars, and no checkpoint
        killed.add_scalar("rollout/posc_mean", 5.0, 300)
    with pytest.raises(ConfigError, match=rf"train --resume {run}") as err:
        train(dataclasses.replace(args, seed=1))  # other options than the folder's run
    assert err.value.field == "run_dir"
    with pytest.warns(UserWarning, match="no checkpoint"):
        assert train(args) == run  # its own command again: trains in place from step 0
    assert (run / "checkpoint" / "learner_group").is_dir()
    curve = training_curve(run)["rollout/posc_mean"]  # the new attempt's, not the killed one's
    assert sorted(p.name for p in (run / "tb").iterdir()) == ["rllib_1", "rllib_2"]
    assert np.all(curve[:, 1] <= 1.0) and curve[0, 0] > 0
    with pytest.raises(ConfigError, match=rf"rllib:{run}.*--run-dir NEW") as err:
        train(TrainArgs(resume=str(run), progress=False))
    assert err.value.field == "resume"
    with pytest.raises(ConfigError, match=rf"evaluate --policies rllib:{run}") as err:
        train(args)
    assert err.value.field == "run_dir"


@pytest.mark.parametrize(
    "damage",
    ["module_state.pkl", "no_modules", "config"],  # (RLlib reads the module from its state)
)
def test_a_damaged_checkpoint_is_a_clear_error(tmp_path, damage):
    """Issue 27: a damaged RLlib checkpoint folder (a truncated pickle, garbage metadata, no
    module, a config.json nested 1,000 deep) ends in a ConfigError naming the checkpoint,
    not a traceback from deep inside RLlib."""
    import shutil
    from importlib import resources

    src = resources.files("poc_env.agents") / "checkpoints" / "rllib_heading_paper_6_2"
    run = tmp_path / "run"
    shutil.copytree(str(src), run)
    shared = run / "checkpoint" / "learner_group" / "learner" / "rl_module" / "shared"
    if damage == "no_modules":
        shutil.rmtree(shared)
    elif damage == "config":
        (run / "config.json").write_text("[" * 1000 + "]" * 1000)
    else:
        (shared / damage).write_bytes(b"\x80\x04garbage")
    with pytest.raises(ConfigError) as err:
        RLlibPolicy(run)
    assert err.value.field in ("checkpoint", "config.json")


def test_an_rllib_run_of_a_heading_v1_task_flies_that_task(tmp_path, capsys):
    """Audit (i28-audit): ``train --engine rllib --task ...-Heading-v1`` (the help's own
    example) wrote a run that ``evaluate --task`` of the same id refused ("trained at
    'heading_clip'", the v1 variant, not the level). The run's level is ``heading``; a run
    folder without modules then fails on its checkpoint, not on its control level."""
    import json

    from poc_env.agents.rl.policy import checkpoint_control
    from poc_env.cli import main

    run = tmp_path / "run"
    (run / "checkpoint" / "learner_group").mkdir(parents=True)
    args = TrainArgs(engine="rllib", task="UAVSearch-Small-Heading-v1", progress=False)
    (run / "config.json").write_text(json.dumps(dataclasses.asdict(args)))
    assert checkpoint_control(f"rllib:{run}") == "heading"
    argv = ["evaluate", "--policies", f"rllib:{run}", "--episodes", "1", "--quiet"]
    assert main([*argv, "--task", "UAVSearch-Small-Heading-v1"]) != 0
    err = capsys.readouterr().err
    assert "trained at" not in err and "has no RLModule folder" in err


def test_an_rllib_transfer_is_noted_as_a_ppo_one(tmp_path, capsys):
    """Audit (i28-audit): ``evaluate --task`` said nothing when an RLlib run flew a task other
    than its own (a ``ppo:`` run gets a note naming both tasks and the observation read)."""
    import json

    from poc_env.cli import main

    run = tmp_path / "run"
    (run / "checkpoint" / "learner_group").mkdir(parents=True)
    own = "poc_env/UAVSearch-Small-Random-Set-Heading-v1"
    args = TrainArgs(engine="rllib", task=own, progress=False)
    (run / "config.json").write_text(json.dumps(dataclasses.asdict(args)))
    argv = ["evaluate", "--policies", f"rllib:{run}", "--episodes", "1", "--quiet", "--task"]
    main([*argv, "UAVSearch-Small-Random-Heading-v1"])
    out = capsys.readouterr().out
    assert f"was trained on {own}; flown here on poc_env/UAVSearch-Small-Random-Heading-v1" in out
    assert "its own 'set' observation, not the task's 'compass'" in out
    # a run without a task (the scenario at the heading level, the compass) is not a recipe's
    args = TrainArgs(engine="rllib", scenario="small", progress=False)
    (run / "config.json").write_text(json.dumps(dataclasses.asdict(args)))
    main([*argv, "UAVSearch-Small-Random-Heading-v1"])
    assert "recipe's observation" not in capsys.readouterr().err
