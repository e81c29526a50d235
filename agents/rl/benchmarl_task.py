"""The registered tasks as BenchMARL tasks (see docs/FRAMEWORKS.md, section BenchMARL).

:class:`PocEnvTask` is a BenchMARL task enum with one member per registered task
(:data:`poc_env.tasks.TASKS`): the id without the namespace, the ``UAVSearch-`` prefix and the
version, upper-cased with ``_`` for ``-`` (``UAVSearch-Small-Heading-v0`` is
``PocEnvTask.SMALL_HEADING``, ``UAVSearch-Paper61-Random-Waypoint-v0`` is
``PocEnvTask.PAPER61_RANDOM_WAYPOINT``; :meth:`PocEnvTask.from_id` takes an id). Each member
builds a :class:`PocEnvTaskClass`, whose env is
:func:`poc_env.agents.rl.frameworks.torchrl_env` (TorchRL's ``PettingZooWrapper`` over
:func:`poc_env.tasks.make_parallel`, with ``use_mask=True`` and ``done_on_any=False``, the
settings UAVs finishing at different times need), so BenchMARL trains on the same MDP as the
other frameworks::

    from benchmarl.algorithms import MappoConfig
    from benchmarl.experiment import Experiment, ExperimentConfig
    from benchmarl.models.mlp import MlpConfig

    from poc_env.agents.rl.benchmarl_task import PocEnvTask

    Experiment(
        task=PocEnvTask.SMALL_HEADING.get_task(),
        algorithm_config=MappoConfig.get_from_yaml(),
        model_config=MlpConfig.get_from_yaml(),
        critic_model_config=MlpConfig.get_from_yaml(),
        seed=0,
        config=ExperimentConfig.get_from_yaml(),
    ).run()

The task's configuration (``get_task(config={...})``; ``get_task()`` and ``get_from_yaml()``
give the defaults, ``get_from_yaml(path)`` reads a YAML file of the same keys over them):

- ``task``: the registered id (set by the member; do not change it);
- ``state`` (default True): the env's ``state()`` (POC raster + every UAV's vector) as
  ``"state"``, which BenchMARL's centralised critics (MAPPO, MASAC, ...) take instead of the
  concatenated observations;
- ``env_kwargs`` (default ``{}``): keyword arguments of :func:`poc_env.tasks.make_parallel`
  (``{"overrides": {"episode.horizon_steps": 30}}``); a task with them is no longer the
  registered MDP, so compare scores only between runs without them.

The UAVs are one group, ``"uav"``; actions are continuous only (``Box(-1, 1)``), so the
discrete-action algorithms (QMIX, VDN, ...) refuse these tasks. BenchMARL builds each of the
``n_envs_per_worker`` envs of a worker with the same seed; this task seeds them ``seed``,
``seed + 1``, ... instead, so they do not draw the same random priors (with
``parallel_collection=True`` the factory is copied to each process before it is called, and
they start from one seed again).

Needs the ``benchmarl`` extra (benchmarl, torchrl, tensordict, torch): importing this module
without it raises :class:`~poc_env.errors.MissingExtraError`.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path
from typing import Any

from poc_env import tasks
from poc_env.agents.rl.frameworks import torchrl_env
from poc_env.errors import MissingExtraError

try:
    from benchmarl.environments.common import Task, TaskClass
    from torchrl.data import Composite
    from torchrl.envs import EnvBase
except ModuleNotFoundError as exc:  # pragma: no cover - exercised by the test's import check
    if (exc.name or "").partition(".")[0] not in ("benchmarl", "torchrl", "tensordict", "torch"):
        raise
    raise MissingExtraError("benchmarl", "poc_env.agents.rl.benchmarl_task") from exc

#: The name BenchMARL gives this environment (its logs and run folders).
ENV_NAME = "poc_env"


def member_name(task_id: str) -> str:
    """The :class:`PocEnvTask` member of a registered task id (``"SMALL_HEADING"``)."""
    task = tasks.get_task(task_id)
    tid = task.id.split("/", 1)[1]  # UAVSearch-Small-Heading-v0
    stem = tid.removeprefix("UAVSearch-").rsplit("-v", 1)[0]
    version = "" if task.version == tasks.VERSION else f"_V{task.version}"  # first release: bare
    return stem.upper().replace("-", "_") + version


#: Member name -> registered task id, for every registered task.
TASK_IDS: dict[str, str] = {member_name(t): t for t in tasks.TASKS}


def default_config(task_id: str) -> dict[str, Any]:
    """The default configuration of a task (see the module docstring)."""
    return {"task": tasks.get_task(task_id).id, "state": True, "env_kwargs": {}}


class _EnvFactory:
    """Builds the task's TorchRL env; successive calls seed ``seed``, ``seed + 1``, ..."""

    def __init__(self, config: dict[str, Any], seed: int | None, device: Any) -> None:
        self.config = config
        self.seed = seed
        self.device = device
        self.calls = 0

    def __call__(self) -> EnvBase:
        seed = None if self.seed is None else self.seed + self.calls
        self.calls += 1
        return torchrl_env(
            self.config["task"],
            seed=seed,
            return_state=bool(self.config["state"]),
            device=self.device,
            **self.config["env_kwargs"],
        )


def _pettingzoo_env(env: EnvBase) -> Any:
    """Our PettingZoo env inside ``env`` (TorchRL transforms and batches unwrapped)."""
    while not hasattr(env, "_env") or not hasattr(env._env, "possible_agents"):
        inner = getattr(env, "base_env", None)
        if inner is None or inner is env:
            raise TypeError(f"no poc-env PettingZoo env inside {type(env).__name__}")
        env = inner
    return env._env


def _keep(spec: Composite, groups: list[str], key: str) -> Composite:
    """``spec`` with, under each group, only ``key`` (and no root-level ``state``)."""
    out = spec.clone()
    for group in groups:
        for k in list(out[group].keys()):
            if k != key:
                del out[group][k]
    if "state" in out:
        del out["state"]
    return out


class PocEnvTaskClass(TaskClass):
    """A registered task for BenchMARL (see the module docstring); built by :class:`PocEnvTask`."""

    def get_env_fun(
        self,
        num_envs: int,
        continuous_actions: bool,
        seed: int | None,
        device: Any,
    ) -> Callable[[], EnvBase]:
        # one unbatched env per call: BenchMARL batches it with SerialEnv/ParallelEnv(num_envs)
        return _EnvFactory(copy.deepcopy(self.config), seed, device)

    def supports_continuous_actions(self) -> bool:
        return True

    def supports_discrete_actions(self) -> bool:
        return False

    def has_state(self) -> bool:
        return bool(self.config.get("state", True))

    def has_render(self, env: EnvBase) -> bool:
        return False  # rendering needs the plot extra and a render_mode; not in training runs

    def max_steps(self, env: EnvBase) -> int:
        return int(_pettingzoo_env(env).max_cycles)

    def group_map(self, env: EnvBase) -> dict[str, list[str]]:
        return dict(env.group_map)

    def observation_spec(self, env: EnvBase) -> Composite:
        return _keep(env.observation_spec, list(self.group_map(env)), "observation")

    def info_spec(self, env: EnvBase) -> Composite | None:
        return _keep(env.observation_spec, list(self.group_map(env)), "info")

    def state_spec(self, env: EnvBase) -> Composite | None:
        if "state" not in env.observation_spec:
            return None
        return Composite({"state": env.observation_spec["state"].clone()})

    def action_mask_spec(self, env: EnvBase) -> Composite | None:
        return None  # continuous actions; a finished UAV is marked by ("uav", "mask") instead

    def action_spec(self, env: EnvBase) -> Composite:
        return env.full_action_spec

    @staticmethod
    def env_name() -> str:
        return ENV_NAME


class _PocEnvTasks(Task):
    """The members' behaviour; :data:`PocEnvTask` holds one member per registered task."""

    @staticmethod
    def associated_class() -> type[PocEnvTaskClass]:
        return PocEnvTaskClass

    @property
    def task_id(self) -> str:
        """The registered id of this member (``poc_env/UAVSearch-Small-Heading-v0``)."""
        if self.name not in TASK_IDS:
            raise KeyError(f"{self.name} is not a registered task (poc-env tasks)")
        return TASK_IDS[self.name]

    @classmethod
    def from_id(cls, task_id: str) -> _PocEnvTasks:
        """The member of a registered task id (the ``poc_env/`` namespace may be left out)."""
        return cls.__members__[member_name(task_id)]

    def get_task(self, config: dict[str, Any] | None = None) -> PocEnvTaskClass:
        """The task with ``config`` over the defaults (see the module docstring)."""
        full = default_config(self.task_id)
        if config:
            unknown = sorted(set(config) - set(full))
            if unknown:
                raise KeyError(f"unknown {self.name} config keys {unknown}; known: {sorted(full)}")
            if config.get("task", full["task"]) != full["task"]:
                raise ValueError(f"{self.name} is {full['task']}, not {config['task']}")
            full.update(copy.deepcopy(config))
        return PocEnvTaskClass(name=self.name, config=full)

    def get_from_yaml(self, path: str | Path | None = None) -> PocEnvTaskClass:
        """The defaults, or the YAML file ``path`` over them (BenchMARL has no YAML of ours)."""
        if path is None:
            return self.get_task()
        import yaml

        config = yaml.safe_load(Path(path).read_text(encoding="utf-8")) or {}
        config.pop("defaults", None)  # a Hydra defaults list, as in BenchMARL's task files
        return self.get_task(config)


#: One member per registered task, named after its id (``SMALL_HEADING`` for
#: ``poc_env/UAVSearch-Small-Heading-v0``, ``SMALL_HEADING_V1`` for its v1,
#: ``PAPER62_DRIFT_HEADING`` for a moving-target task): made from the task registry, so a new
#: task or version is a member without an edit here.
#: ``PocEnvTask.SMALL_HEADING.get_task()`` is a :class:`PocEnvTaskClass`.
PocEnvTask = _PocEnvTasks(  # type: ignore[call-arg]
    "PocEnvTask",
    [(name, k + 1) for k, name in enumerate(TASK_IDS)],
    module=__name__,
    qualname="PocEnvTask",
)
