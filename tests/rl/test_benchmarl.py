"""BenchMARL on the registered tasks: :mod:`poc_env.agents.rl.benchmarl_task`.

The enum covers the registry; a task's specs are our spaces; a tiny MAPPO experiment (CPU,
2 envs x 100 frames, twice) collects its frames, logs the rewards, evaluates and checkpoints.
"""

from __future__ import annotations

import json
import re
import sys
import warnings
from pathlib import Path

import pytest

pytest.importorskip(
    "benchmarl", reason="needs the benchmarl extra: pip install 'poc-env[benchmarl]'"
)

from poc_env import tasks
from poc_env.agents.rl.frameworks import GROUP
from poc_env.errors import MissingExtraError

SHORT = {"env_kwargs": {"overrides": {"episode.horizon_steps": 30}}}
DOC = Path(__file__).resolve().parents[2] / "docs" / "FRAMEWORKS.md"


@pytest.fixture(autouse=True)
def _quiet():
    # TorchRL warns that it tests PettingZoo 1.24.3 only (we run 1.27)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="PettingZoo in TorchRL", category=UserWarning)
        yield


def test_every_registered_task_is_a_member(tmp_path):
    from poc_env.agents.rl.benchmarl_task import PocEnvTask

    assert {m.task_id for m in PocEnvTask} == set(tasks.TASKS)
    assert len(PocEnvTask) == len(tasks.TASKS)
    assert PocEnvTask.from_id("UAVSearch-Small-Heading-v1").name == "SMALL_HEADING_V1"
    t = PocEnvTask.from_id("UAVSearch-Small-Random-Waypoint-v0")
    assert t is PocEnvTask.SMALL_RANDOM_WAYPOINT
    assert t.get_task().config["task"] == "poc_env/UAVSearch-Small-Random-Waypoint-v0"
    assert PocEnvTask.SMALL_HEADING.get_from_yaml() == PocEnvTask.SMALL_HEADING.get_task()
    (tmp_path / "t.yaml").write_text("state: false\nenv_kwargs: {max_cycles: 9}\n")
    cfg = PocEnvTask.SMALL_HEADING.get_from_yaml(tmp_path / "t.yaml").config
    assert cfg == {
        "task": "poc_env/UAVSearch-Small-Heading-v0",
        "state": False,
        "env_kwargs": {"max_cycles": 9},
    }
    with pytest.raises(KeyError, match="unknown"):
        PocEnvTask.SMALL_HEADING.get_task({"n_uavs": 4})


@pytest.mark.parametrize("control,dim", [("Increments", 3), ("Heading", 2)])
def test_specs_are_our_spaces(control, dim):
    from poc_env.agents.rl.benchmarl_task import PocEnvTask

    member = PocEnvTask.from_id(f"UAVSearch-Small-{control}-v0")
    task = member.get_task()
    env = task.get_env_fun(num_envs=1, continuous_actions=True, seed=0, device="cpu")()
    pz = tasks.make_parallel(member.task_id)
    n = len(pz.possible_agents)
    assert task.group_map(env) == {GROUP: pz.possible_agents}
    assert task.max_steps(env) == pz.max_cycles
    obs = task.observation_spec(env)
    assert list(obs.keys(True, True)) == [(GROUP, "observation")]
    assert obs[GROUP, "observation"].shape == (n, *pz.observation_space("uav_0").shape)
    act = task.action_spec(env)[GROUP, "action"]
    assert act.shape == (n, dim) == (n, *pz.action_space("uav_0").shape)
    assert act.space.low.min().item() == -1.0 and act.space.high.max().item() == 1.0
    assert task.state_spec(env)["state"].shape == pz.state_space.shape
    assert (GROUP, "info", "posc") in task.info_spec(env).keys(True, True)
    assert task.action_mask_spec(env) is None
    assert task.supports_continuous_actions() and not task.supports_discrete_actions()
    # the envs of a worker get successive seeds, so random priors differ between them
    fun = task.get_env_fun(num_envs=2, continuous_actions=True, seed=5, device="cpu")
    assert [fun().seed, fun().seed] == [5, 6]


def test_mappo_experiment(tmp_path):
    """MAPPO with a centralised critic on the env's state: 2 iterations of 2 x 100 frames."""
    from benchmarl.algorithms import MappoConfig
    from benchmarl.experiment import Experiment, ExperimentConfig
    from benchmarl.models.mlp import MlpConfig

    from poc_env.agents.rl.benchmarl_task import PocEnvTask

    config = ExperimentConfig.get_from_yaml()
    config.max_n_frames = 400
    config.on_policy_collected_frames_per_batch = 200
    config.on_policy_n_envs_per_worker = 2
    config.on_policy_n_minibatch_iters = 1
    config.on_policy_minibatch_size = 100
    config.evaluation_interval = 400
    config.evaluation_episodes = 1
    config.loggers = ["csv"]
    config.save_folder = str(tmp_path)
    config.checkpoint_at_end = True
    model = MlpConfig.get_from_yaml()
    model.num_cells = [32, 32]
    exp = Experiment(
        task=PocEnvTask.SMALL_HEADING.get_task(SHORT),
        algorithm_config=MappoConfig.get_from_yaml(),
        model_config=model,
        critic_model_config=model,
        seed=0,
        config=config,
    )
    assert exp.group_map == {GROUP: ["uav_0", "uav_1", "uav_2"]}
    assert exp.max_steps == 30
    assert "state" in exp.state_spec
    exp.run()
    assert exp.total_frames == 400 and exp.n_iters_performed == 2

    folder = Path(exp.folder_name)
    assert list((folder / "checkpoints").glob("checkpoint_*.pt"))
    # the per-group rewards BenchMARL logs from the collected batches, as CSV columns
    logged = {p.stem for p in folder.rglob("*.csv")}
    assert {"collection_uav_reward_episode_reward_mean", "counters_total_frames"} <= logged, logged
    # the evaluation episodes of the run, in BenchMARL's JSON of results
    results = json.loads((folder / f"{exp.name}.json").read_text())
    runs = results["poc_env"]["small_heading"]["mappo"]
    (run,) = runs.values()
    steps = [k for k in run if k.startswith("step_")]
    assert steps and all("return" in run[k] for k in steps)


def test_missing_benchmarl_is_a_missing_extra_error(monkeypatch):
    monkeypatch.delitem(sys.modules, "poc_env.agents.rl.benchmarl_task", raising=False)
    for name in ("benchmarl", "benchmarl.environments", "benchmarl.environments.common"):
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(MissingExtraError) as err:
        import poc_env.agents.rl.benchmarl_task  # noqa: F401
    assert err.value.extra == "benchmarl"
    assert "pip install 'poc-env[benchmarl]'" in str(err.value)


def test_docs_example_runs(capsys):
    """The BenchMARL example of docs/FRAMEWORKS.md runs as written (a 400-frame run)."""
    doc = DOC.read_text("utf-8")
    blocks = [b for b in re.findall(r"```python\n(.*?)```", doc, flags=re.S) if "benchmarl" in b]
    assert len(blocks) == 1
    exec(compile(blocks[0], "docs/FRAMEWORKS.md", "exec"), {})
    out = capsys.readouterr().out
    assert "frames 400" in out
