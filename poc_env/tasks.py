"""The registered benchmark tasks: one id per (scenario, prior, control level).

Every task is registered with Gymnasium (``gymnasium.make(id)``: the centralised view,
:class:`~poc_env.envs.gymnasium_env.UAVSearchGym`; ``gymnasium.make_vec(id, num_envs)``: the
batched :class:`~poc_env.envs.gym_vector.SwarmGymVectorEnv`) and with PettingZoo's registry
(``pettingzoo.env_registry.registration.make("parallel" | "aec", id)``); :func:`make_parallel`
and :func:`make_aec` are the same without the registry. Keyword arguments given at ``make``
override the task's (``obs_type="dict"``, ``overrides={...}``, ``max_cycles=...``).

Ids: ``poc_env/UAVSearch-<Scenario>[-<Size>][-Random][-<Motion>][-Set]-<Control>-v<version>``.
Scenario: ``Small`` (``small``, quick), ``Paper62`` (``paper_6_2``, the paper's section 6.2
case), ``Paper61`` (``paper_6_1``, section 6.1) or, with a size ``N3`` .. ``N24``, ``Wide``
(``wide_400``); ``-Random``: a fresh seeded Gaussian-mixture prior at every reset
(``random_prior=True``); Control: ``Increments`` (eq. 19), ``Heading`` or ``Waypoint`` (flown
by the autopilot). The table of parts and their meanings is
:data:`poc_env.spec.SCENARIO_PARTS`, :data:`~poc_env.spec.RANDOM_PARTS`,
:data:`~poc_env.spec.CONTROL_PARTS`, :data:`~poc_env.spec.OBS_PARTS` and
:data:`~poc_env.spec.SIZE_PARTS`, which this module registers and ``docs/environment.md``
renders with each scenario's size and fleet read from its file (``poc-env spec
--write``).

Every task observes ``obs_type="compass"`` (a 63-value Box per UAV, the same size on every map:
:class:`~poc_env.sim.observations.CompassFeatures`), which default MLP encoders of SB3 and RLlib
take as they are, and flies with ``auto_return=True`` for the autopilot levels; the ``-Set``
tasks observe ``obs_type="set"`` instead (:class:`~poc_env.sim.observations.SetFeatures`: no
index width, the nearest UAVs as a padded set, for any fleet size), on every scenario and on
``wide_400`` at the fleet sizes of :data:`poc_env.spec.SIZE_PARTS`
(``UAVSearch-Wide-N24-Random-Set-Heading-v1``). The first
release's id ``poc_env/UAVSearch-v0`` (``paper_6_2``, increments, the ``dict`` observation in
PettingZoo, ``flat`` in Gymnasium) stays registered unchanged.

Versioning rule
---------------
A task id names a fixed MDP. Any change that can change what an agent observes, what it is
rewarded, how the swarm moves or when an episode ends (observations, rewards, dynamics,
constraints, scenario files, the random-prior generator, the task's keyword arguments) bumps the
version of every task it touches (``-v0`` to ``-v1``); scores are compared only between equal
ids. Speed-ups that leave every transition bit-identical (the test suite's equivalence tests
decide) keep the version. Each control part carries its own versions, in one place,
:data:`poc_env.spec.TASK_VERSIONS` (the version history: ``...-Heading-v1`` clips out-of-Box
headings, ``...-Heading-v0`` keeps normalising them); :data:`VERSION` is the first release's,
at which every task is registered.

The rule is mechanical: every registered id has a recorded episode (:mod:`poc_env.recorded`,
``tests/recorded/<id>.npz``: observations, rewards, terminations, truncations and infos of a
fixed-seed, fixed-action episode), and ``tests/envs/test_recorded.py`` replays each one. Any
change to an observation, a reward, the dynamics or the episode end fails those tests until the
version is bumped (new ids) and the episodes recorded anew (``poc-env record --all``, removing
the old ids' files with their ids); a new task fails until it is recorded. An id is never
reused: old ids keep their behaviour or leave the registry.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from poc_env import spec
from poc_env.errors import ConfigError

#: The first release's version (every task is registered at it): :data:`poc_env.spec.TASK_VERSION`.
#: Later versions: :data:`poc_env.spec.TASK_VERSIONS`.
VERSION = spec.TASK_VERSION
NAMESPACE = "poc_env"
#: Task-name part -> built-in scenario (:data:`poc_env.spec.SCENARIO_PARTS`).
SCENARIOS = {p.text: str(p.value) for p in spec.SCENARIO_PARTS}
#: Task-name part -> control level (:data:`poc_env.spec.CONTROL_PARTS`).
CONTROL_NAMES = {p.text: str(p.value) for p in spec.CONTROL_PARTS}
#: The Gymnasium entry points of every task.
ENTRY_POINT = "poc_env.envs.gymnasium_env:UAVSearchGym"
VECTOR_ENTRY_POINT = "poc_env.envs.gym_vector:SwarmGymVectorEnv"


@dataclass(frozen=True)
class Task:
    """One registered task: its id and the environment keyword arguments it stands for."""

    id: str
    scenario: str
    control: str
    random_prior: bool
    extra: dict[str, Any] = field(default_factory=dict)
    #: The id's version (:data:`poc_env.spec.TASK_VERSIONS`).
    version: int = VERSION
    #: how the target moves (:data:`poc_env.spec.MOTION_PARTS`; its scenario overrides are
    #: keyword overrides, ``target__model=...``, so a ``make(overrides=...)`` keeps them)
    motion: str = "static"
    #: what each UAV observes (:data:`poc_env.spec.OBS_PARTS`: ``"compass"`` or ``"set"``)
    obs: str = "compass"
    #: the fleet size of a size task (:data:`poc_env.spec.SIZE_PARTS`; its ``fleet`` keyword
    #: override), None: the scenario's fleet
    n_uavs: int | None = None

    def load_scenario(self, overrides: dict[str, Any] | None = None):
        """The task's resolved :class:`~poc_env.config.Scenario`: its own scenario overrides
        (a moving-target task's ``target`` section, :data:`~poc_env.spec.MOTION_OVERRIDES`),
        then ``overrides`` (dotted keys), and a size task's fleet -- the scenario its
        environments fly, so ``evaluate --task`` and ``train --task`` fly the task itself."""
        from poc_env.config import load_scenario
        from poc_env.sim.engine import resolve_overrides

        own = {k: v for k, v in self.kwargs.items() if "__" in k}  # the env's keyword overrides
        sc = load_scenario(self.scenario, {**resolve_overrides(None, own), **(overrides or {})})
        return sc if self.n_uavs is None else sc.with_uavs(self.n_uavs)

    @property
    def kwargs(self) -> dict[str, Any]:
        """Keyword arguments of the PettingZoo env / Gymnasium view for this task."""
        out: dict[str, Any] = {
            "scenario": self.scenario,
            "control": self.control,
            "random_prior": self.random_prior,
            "obs_type": self.obs,
        }
        if self.n_uavs is not None:
            out["fleet"] = spec.fleet_of(self.n_uavs)
        out.update(spec.MOTION_OVERRIDES[self.motion])
        out.update(self.extra)
        return out


def task_id(
    scenario: str,
    control: str,
    random_prior: bool,
    version: int = VERSION,
    motion: str = "",
    obs: str = "",
    size: str = "",
) -> str:
    """The id of a task from its name parts (``"Small"``, ``"Heading"``, ``"Drift"``,
    ``"Set"``, ``"N12"``, ...)."""
    rand = "-Random" if random_prior else ""
    move = f"-{motion}" if motion else ""
    seen = f"-{obs}" if obs else ""
    fleet = f"-{size}" if size else ""
    return f"{NAMESPACE}/UAVSearch-{scenario}{fleet}{rand}{move}{seen}-{control}-v{version}"


def _build() -> dict[str, Task]:
    out = {}
    for s_name, scenario in SCENARIOS.items():
        for rand in (bool(p.value) for p in spec.RANDOM_PARTS):
            for c_name, control in CONTROL_NAMES.items():
                for v in spec.versions_of(c_name):
                    tid = task_id(s_name, c_name, rand, v.version)
                    extra = {} if v.env_control == control else {"control": v.env_control}
                    out[tid] = Task(tid, scenario, control, rand, extra, v.version)
    for m in spec.MOTION_PARTS[1:]:  # moving targets: the fixed prior, some control levels
        for s_name, scenario in SCENARIOS.items():
            for c_name in spec.MOTION_CONTROLS[str(m.value)]:
                control = CONTROL_NAMES[c_name]
                for v in spec.versions_of(c_name):
                    tid = task_id(s_name, c_name, False, v.version, motion=m.text)
                    extra = {} if v.env_control == control else {"control": v.env_control}
                    out[tid] = Task(
                        tid, scenario, control, False, extra, v.version, motion=str(m.value)
                    )
    for o in spec.OBS_PARTS[1:]:  # other observations: the control parts and versions listed
        for v in spec.obs_versions(str(o.value)):
            control = CONTROL_NAMES[v.control]
            extra = {} if v.env_control == control else {"control": v.env_control}
            for s_name, scenario in SCENARIOS.items():
                for rand in (bool(p.value) for p in spec.RANDOM_PARTS):
                    tid = task_id(s_name, v.control, rand, v.version, obs=o.text)
                    out[tid] = Task(
                        tid, scenario, control, rand, extra, v.version, obs=str(o.value)
                    )
            for size in spec.SIZE_PARTS:  # the fleet sizes: random priors on the size scenario
                tid = task_id(
                    spec.SIZE_SCENARIO.text, v.control, True, v.version, obs=o.text, size=size.text
                )
                out[tid] = Task(
                    tid, str(spec.SIZE_SCENARIO.value), control, True, extra, v.version,
                    obs=str(o.value), n_uavs=int(size.value),
                )  # fmt: skip
    return out


#: Every registered task, by id (in the order of the table above).
TASKS: dict[str, Task] = _build()


def get_task(task: str) -> Task:
    """The task of id ``task`` (the ``poc_env/`` namespace may be left out)."""
    if isinstance(task, str):
        key = task if "/" in task else f"{NAMESPACE}/{task}"
        if key in TASKS:
            return TASKS[key]
    ids = [t.split("/", 1)[1] for t in TASKS]
    closest = ""
    if isinstance(task, str):  # a typo, a missing UAVSearch- or a version: the nearest ids first
        import difflib

        asked = task.split("/", 1)[-1]
        asked = asked if asked.startswith("UAVSearch-") else f"UAVSearch-{asked}"
        near = difflib.get_close_matches(asked, ids, n=3, cutoff=0.6)
        closest = f", the closest {', '.join(near)}" if near else ""
    names = ", ".join(ids)
    raise ConfigError(
        "task", task, f"a registered task id{closest}; all {len(ids)}: {names} (poc-env tasks)"
    )


def task_kwargs(task: str, **overrides: Any) -> dict[str, Any]:
    """The task's keyword arguments with ``overrides`` on top."""
    kw = get_task(task).kwargs
    kw.update(overrides)
    return kw


def make_parallel(task: str, **overrides: Any):
    """The PettingZoo parallel env of ``task`` (keyword arguments override the task's)."""
    from poc_env.envs.parallel import UAVSearchParallelEnv

    return UAVSearchParallelEnv(**task_kwargs(task, **overrides))


def make_aec(task: str, **overrides: Any):
    """The PettingZoo AEC env of ``task`` (the parallel env through ``parallel_to_aec``)."""
    from pettingzoo.utils.conversions import parallel_to_aec

    return parallel_to_aec(make_parallel(task, **overrides))


def register_tasks() -> None:
    """Register every task with Gymnasium and PettingZoo (idempotent)."""
    import gymnasium

    for tid, task in TASKS.items():
        if tid not in gymnasium.registry:
            gymnasium.register(
                tid,
                entry_point=ENTRY_POINT,
                vector_entry_point=VECTOR_ENTRY_POINT,
                kwargs=task.kwargs,
            )
    try:
        from pettingzoo.env_registry.registration import _get_registry, register
    except ImportError:  # PettingZoo < 1.27 has no registry
        return
    for kind, entry in (("parallel", "parallel_env"), ("aec", "env")):
        reg = _get_registry(kind)
        for tid, task in TASKS.items():
            if tid not in reg:
                entry_point = f"poc_env.uav_search_v0:{entry}"
                register(kind, tid, entry_point=entry_point, kwargs=task.kwargs)


def task_table() -> list[dict[str, Any]]:
    """One row per task (id, scenario, control, random prior, agents, horizon, observation,
    target motion): the rows of ``poc-env tasks``."""
    rows = []
    for tid, task in TASKS.items():
        sc = task.load_scenario()
        rows.append(
            {
                "id": tid,
                "scenario": task.scenario,
                "control": task.control,
                "random_prior": task.random_prior,
                "n_uavs": sc.n_uavs,
                "horizon_steps": sc.horizon_steps,
                "obs": task.obs,
                "motion": task.motion,
            }
        )
    return rows
