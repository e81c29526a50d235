"""What a training run depends on (:class:`TrainArgs`) and the ``poc-env train`` command line.

Recipes (``--recipe``): ``shared`` flies every UAV with one policy (parameter sharing over
:class:`poc_env.envs.vector.SwarmVecEnv`, CNN+MLP
:class:`poc_env.agents.rl.networks.SwarmExtractor`);
``central`` is one agent over the joint observation and action (``poc_env/UAVSearch-v0``,
``MlpPolicy``); ``pilot`` lets PPO pick headings and an autopilot fly eq. 19
(:mod:`poc_env.agents.rl.pilot`).

Every option of ``poc-env train`` is a field of :class:`TrainArgs` (``--total-timesteps`` for
``total_timesteps``), with the docstring under the field as its help; :func:`parse_train_args`
builds the parser from the dataclass with `tyro <https://brentyi.github.io/tyro/>`_. The fields
come in groups (:data:`GROUPS`): the run's own options, PPO's hyper-parameters (both engines),
``sb3``, ``rllib`` and ``bc`` (the behaviour-cloning warm start); ``--help`` shows one box per
group, while the flags keep their plain names and :class:`TrainArgs` stays one flat record. The
resolved arguments are saved flat as ``config.json`` in the run folder, and ``--resume`` reads
them back with :meth:`TrainArgs.from_dict` (a field missing from an older run's file takes its
default).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Annotated, Any

from tyro.conf import arg as _arg

import poc_env.limits as limits
from poc_env.config import parse_overrides
from poc_env.errors import ConfigError, as_int, as_number
from poc_env.helptext import examples

ALGOS = ("ppo",)
ENGINES = ("sb3", "rllib")
RECIPES = ("shared", "central", "pilot")
NETS = ("mlp", "set")


@dataclass(frozen=True)
class TrainArgs:
    """Everything a training run depends on; saved as ``config.json`` in the run folder."""

    # -- the run --------------------------------------------------------------------------------
    scenario: Annotated[str, _arg(metavar="NAME")] = "paper_6_2"
    """Built-in scenario name or YAML path; the resolved scenario is saved as scenario.yaml."""
    overrides: Annotated[list[str], _arg(metavar="KEY=VALUE")] = field(default_factory=list)
    """Scenario overrides, dotted KEY=VALUE (VALUE is YAML), e.g. episode.horizon_steps=20."""
    engine: Annotated[str, _arg(metavar="|".join(ENGINES))] = "sb3"
    """sb3: stable-baselines3 on our VecEnvs (the recipes); rllib: RLlib multi-agent PPO on the
    task's PettingZoo env (poc_env.agents.rl.rllib), locally or on a Ray cluster (--address)."""
    task: Annotated[str | None, _arg(metavar="TASK_ID")] = None
    """A registered task (poc-env tasks), e.g. poc_env/UAVSearch-Small-Random-Heading-v0: its
    scenario, prior kind and control level, an MLP on its compass observation (sb3: shared over
    the UAVs by SwarmVecEnv). rllib without one: --scenario at the heading level."""
    also_task: Annotated[list[str], _arg(metavar="TASK_ID")] = field(default_factory=list)
    """sb3: more registered tasks, --also-task ID [ID ...] (the same observation and control
    level as --task, e.g. other fleet sizes) whose swarms fly in the same rollouts, n_envs
    swarms each, so one parameter-shared policy learns all of them at once (--net set)."""
    total_timesteps: int = 1_000_000
    """Agent transitions (central: joint steps) to train for; rounded up to whole rollouts.
    PPO's only: a BC warm start (--bc-teacher) comes on top, and 0 saves the BC policy alone."""
    seed: int = 0
    """Root seed of the env generators (SeedSequence) and the torch, numpy, python ones."""
    random_priors: bool = True
    """A fresh random Gaussian-mixture prior every episode instead of the scenario's."""
    run_dir: Annotated[str | None, _arg(metavar="DIR")] = None
    """Run folder; default runs/<scenario>-<algo>-s<seed>-<timestamp>."""
    resume: Annotated[str | None, _arg(metavar="RUN_DIR")] = None
    """Continue this run folder from its latest checkpoint and config (no other options)."""
    from_card: Annotated[str | None, _arg(metavar="NAME")] = None
    """Train with a shipped checkpoint's recipe, one command: the training options of its card
    (agents/checkpoints/NAME.json, e.g. ppo_set_increments_anysize) are this run's defaults,
    and every option given here replaces the card's value (a list too), e.g. --seed 2 --run-dir
    DIR. The card's model_step is the checkpoint that was shipped."""
    checkpoint_every: int = 50_000
    """Timesteps between checkpoints (taken at the next rollout boundary)."""
    torch_threads: int = 1
    """torch intra-op threads (small networks run fastest and reproducibly on one)."""
    progress: bool = True
    """Show a progress bar with the mean POSC of recent episodes."""
    # -- ppo: PPO's hyper-parameters (both engines) ------------------------------------------------
    n_steps: int = 256
    """PPO: steps per slot per rollout (rollout = n_steps x slots transitions)."""
    batch_size: int = 512
    """PPO: minibatch size."""
    n_epochs: int = 5
    """PPO: passes over each rollout."""
    learning_rate: float = 3e-4
    """PPO: Adam learning rate (constant)."""
    gamma: float = 0.99
    """PPO: discount factor."""
    gae_lambda: float = 0.95
    """PPO: GAE lambda."""
    ent_coef: float = 0.0
    """PPO: entropy bonus coefficient."""
    net_arch: list[int] = field(default_factory=lambda: [128, 128])
    """pilot and central recipes: hidden layers of the policy and value MLPs."""
    # -- sb3: --engine sb3 (stable-baselines3 on our VecEnvs) --------------------------------------
    algo: Annotated[str, _arg(metavar="|".join(ALGOS))] = "ppo"
    """RL algorithm: ppo (stable-baselines3 PPO)."""
    recipe: Annotated[str, _arg(metavar="|".join(RECIPES))] = "shared"
    """shared: one policy flies every UAV; central: one joint agent; pilot: headings + autopilot."""
    approach_shaping: float = 0.0
    """pilot: c of the approach term c (gamma Phi(s') - Phi(s)), Phi = -(km to the grid)."""
    n_envs: int = 4
    """Independent swarms simulated side by side (shared, pilot: n_envs x UAVs slots)."""
    net: Annotated[str, _arg(metavar="|".join(NETS))] = "mlp"
    """--task (sb3): the policy's encoder. mlp: SB3's MLP on the observation; set: DeepSets
    over the neighbour set + the ego features (poc_env.agents.rl.networks.SetExtractor), for
    the -Set tasks, one policy for any fleet size; net_arch is then its heads."""
    agent_index: bool = True
    """--task (sb3): the compass observation carries the UAV's index (one-hot), so a shared
    policy can tell UAVs of one airfield apart; --no-agent-index zeroes it (an ablation)."""
    return_autopilot: bool = False
    """--task at the increments level (sb3): the autopilot takes each UAV home and lands it
    once eq. 18 says so (its increments are ignored from then on), as at the autopilot levels;
    the policy flies the search. Recorded in config.json; ppo:RUN flies the same way."""
    keep_checkpoints: int = 5
    """Newest checkpoints to keep (0: keep all)."""
    # -- rllib: --engine rllib (RLlib multi-agent PPO) ---------------------------------------------
    rllib_policies: Annotated[str, _arg(metavar="shared|per_uav")] = "shared"
    """rllib: one policy shared by every UAV, or one policy per UAV."""
    num_env_runners: int = 0
    """rllib: Ray actors sampling episodes (0: sample in the driver)."""
    address: Annotated[str | None, _arg(metavar="ADDRESS")] = None
    """rllib: an existing Ray cluster (host:port, ray://host:10001, auto); default: a new local
    instance that is stopped at the end."""
    # -- bc: the behaviour-cloning warm start (sb3 with --task) ------------------------------------
    bc_teacher: Annotated[str | None, _arg(metavar="POLICY")] = None
    """--task, sb3: behaviour-cloning warm start from this registered classical policy
    (allocation_plan, greedy_bayes, lawnmower, ...; not ppo:/rllib:) before PPO
    (poc_env.agents.rl.bc):
    its demonstrations at the task's control level fit the policy mean and value head; bc.json
    in the run folder. A resumed run does not repeat it."""
    bc_episodes: int = 32
    """BC: teacher episodes to record (seeds and priors from their own stream of --seed)."""
    bc_epochs: int = 10
    """BC: passes over the demonstrations (Adam, learning rate 1e-3)."""
    bc_batch_size: int = 64
    """BC: minibatch size of the fit (smaller than PPO's: demonstrations are few)."""
    bc_log_std: float = -1.0
    """BC: the policy's log standard deviation after the fit (PPO explores around the teacher;
    -1.0: std 0.37)."""
    bc_dagger: int = 0
    """BC: DAgger iterations after the fit (0: none). Each flies the current policy (its mean,
    with the run's --return-autopilot) for --bc-dagger-episodes episodes, labels every state of
    a UAV the autopilot does not own with the teacher's action there (the teacher plans on the
    same prior and is asked at the learner's states), adds the rows to the data and refits;
    increments tasks with the compass observation. bc.json records each iteration."""
    bc_dagger_episodes: int = 16
    """BC: learner episodes per DAgger iteration (seeds and priors from their own stream)."""
    bc_dagger_epochs: int = 10
    """BC: passes over all the data so far after each DAgger iteration (from the current
    weights)."""
    bc_dagger_beta: float = 0.0
    """BC: DAgger's mixture: in iteration i each UAV flies the teacher's action instead of the
    policy's with probability beta**i at every step (0: the policy alone; on paper_6_2 0.5
    lifted allocation_plan's clone and 0 sank it: docs/rl.md, DAgger warm start)."""
    bc_all_tasks: bool = False
    """BC with --also-task: record --bc-episodes episodes of every task of the run (each from its
    own stream), not only of --task's, so the clone has seen every map and fleet size."""
    bc_coef: float = 0.0
    """BC: keep the teacher in the loss during PPO (poc_env.agents.rl.bcppo): every PPO
    minibatch update adds bc_coef_t x the BC actor loss (the mean squared error of the policy
    mean to the teacher's labels, as the warm start fits it) on a minibatch of the warm
    start's own demonstrations (the teacher's states, not DAgger's); 0: plain PPO, as
    before. The demonstrations are kept in the run folder (bc_demos.npz) for --resume."""
    bc_coef_filter: bool = False
    """BC: the filtered term (self-imitation, Oh et al. 2018): imitate only the demonstration
    rows whose discounted return (the teacher's, from that state) exceeds the critic's value of
    the state, i.e. where the teacher did better than the policy expects to; elsewhere the
    policy is free."""
    bc_coef_half_life: int = 0
    """BC: the half-life of --bc-coef in PPO transitions: bc_coef_t = bc_coef x
    0.5 ** (t / half-life), t the run's transitions so far (0: constant). Independent of
    --total-timesteps, so a run's checkpoint at t is the same whatever its budget."""
    # -- residual: a residual policy on a planner (sb3 with --task) ----------------------------
    residual_teacher: Annotated[str | None, _arg(metavar="POLICY")] = None
    """--task, sb3: learn a residual on this plan-then-fly policy (allocation_plan, de_plan,
    ...; poc_env.agents.rl.residual): it plans each episode and flies its routes, the policy
    sees the task's observation plus the teacher's eq. 19 action and adds (dv, d turn) to it;
    its mean starts at 0, i.e. at the teacher. ppo:RUN flies the checkpoint the same way. On a
    -Drift- task: spacetime_plan or spacetime_receding (the moving-target planners)."""
    residual_pool: int = 64
    """Residual: training priors come from a pool of this many random priors whose plans are
    made once (planning costs ~30x an episode's simulation on paper_6_2); 0: a fresh prior and plan
    every episode. Not used on a moving target or with spacetime_receding (a plan depends on
    the episode's drift: the teacher plans every episode)."""
    residual_log_std: float = -3.0
    """Residual: the policy's initial log standard deviation (-3.0: std 0.05; the residual is
    a fraction of eq. 19's per-step limits, 180 degrees of turn per step on paper_6_2, so BC's
    std 0.37 zigzags the teacher's routes: training episodes fell from 0.69 to 0.31-0.35)."""

    def __post_init__(self) -> None:
        if self.algo not in ALGOS:
            raise ConfigError("algo", self.algo, "one of " + ", ".join(ALGOS))
        if self.recipe not in RECIPES:
            raise ConfigError("recipe", self.recipe, "one of " + ", ".join(RECIPES))
        if self.engine not in ENGINES:
            raise ConfigError("engine", self.engine, "one of " + ", ".join(ENGINES))
        if self.rllib_policies not in ("shared", "per_uav"):
            raise ConfigError("rllib_policies", self.rllib_policies, "shared or per_uav")
        as_int("num_env_runners", self.num_env_runners, 0, limits.MAX_WORKERS)
        if self.task is not None:
            from poc_env.tasks import get_task

            task_scenario = get_task(self.task).scenario
            if self.scenario not in ("paper_6_2", task_scenario):  # the default, or the task's
                raise ConfigError(
                    "scenario", self.scenario, f"either --task or --scenario, not both (the "
                    f"task {self.task} trains on its scenario, {task_scenario})",
                )  # fmt: skip
            if self.engine == "sb3" and self.recipe != "shared":
                raise ConfigError(
                    "recipe", self.recipe, "shared (the default) with --task: the task's env "
                    "and an MLP on its compass observation replace the recipe",
                )  # fmt: skip
        self._check_net()
        if self.address is not None and self.engine != "rllib":
            raise ConfigError("address", self.address, "an address with --engine rllib only")
        for name, lo, hi in (
            ("total_timesteps", 0 if (self.bc_teacher or self.residual_teacher) else 1, 10**12),
            ("seed", 0, limits.MAX_SEED),
            ("n_envs", 1, limits.N_ENVS_MAX),
            ("checkpoint_every", 1, 10**12),
            ("keep_checkpoints", 0, 10**6),
            ("n_steps", 1, 10**6),
            ("batch_size", 2, 10**7),
            ("n_epochs", 1, 1000),
            ("torch_threads", 1, 256),
        ):
            as_int(name, getattr(self, name), lo, hi)
        # learning rate in (0, 10]: inf or 1e300 turn the weights to NaN in the first update
        as_number("learning_rate", self.learning_rate, 0.0, 10.0, lo_open=True)
        as_number("gamma", self.gamma, 0.0, 1.0)
        as_number("gae_lambda", self.gae_lambda, 0.0, 1.0)
        as_number("ent_coef", self.ent_coef, 0.0, 100.0)
        shaping = self.approach_shaping
        if isinstance(shaping, bool) or not isinstance(shaping, int | float):
            raise ConfigError("approach_shaping", shaping, "a finite number")
        if not math.isfinite(shaping):
            raise ConfigError("approach_shaping", shaping, "a finite number")
        if not isinstance(self.net_arch, list | tuple) or not all(
            isinstance(w, int) and not isinstance(w, bool) and w >= 1 for w in self.net_arch
        ):
            raise ConfigError("net_arch", self.net_arch, "a list of layer widths (integers >= 1)")
        if not isinstance(self.scenario, str):
            raise ConfigError("scenario", self.scenario, "a string")
        if self.from_card is not None and self.from_card not in card_names():
            raise ConfigError("from_card", self.from_card, _CARDS_ALLOWED + ", ".join(card_names()))
        for name in ("run_dir", "resume"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, str | os.PathLike):
                raise ConfigError(name, v, "a folder path or None")
        for name in ("random_priors", "progress", "agent_index", "return_autopilot"):
            if not isinstance(getattr(self, name), bool):
                raise ConfigError(name, getattr(self, name), "true or false")
        parse_overrides(self.overrides)
        self._check_bc()
        self._check_residual()

    def _check_net(self) -> None:
        """--net and --also-task: a set network needs a -Set task; the tasks trained together
        share one observation and control level."""
        if self.net not in NETS:
            raise ConfigError("net", self.net, "one of " + ", ".join(NETS))
        if not isinstance(self.also_task, list | tuple) or not all(
            isinstance(t, str) for t in self.also_task
        ):
            raise ConfigError("also_task", self.also_task, "a list of registered task ids")
        if self.task is None:
            if self.also_task:
                raise ConfigError("also_task", self.also_task, "[] without --task")
            return
        from poc_env.tasks import get_task

        task = get_task(self.task)
        if self.net == "set" and task.obs != "set":
            raise ConfigError(
                "net", self.net, f"mlp with {self.task} (set needs a -Set task: its obs_type "
                "'set' holds the neighbour rows the set network reads)",
            )  # fmt: skip
        for other in self.also_task:
            o = get_task(other)
            if (o.obs, o.kwargs["control"]) != (task.obs, task.kwargs["control"]):
                raise ConfigError(
                    "also_task", other, f"a task with the observation ({task.obs}) and control "
                    f"({task.kwargs['control']}) of --task {self.task}",
                )  # fmt: skip
            if self.engine != "sb3":
                raise ConfigError("also_task", other, "none with --engine rllib (sb3 only)")

    def _check_bc(self) -> None:
        """The behaviour-cloning fields (poc_env.agents.rl.bc)."""
        as_int("bc_episodes", self.bc_episodes, 1, limits.MAX_EPISODES)
        as_int("bc_epochs", self.bc_epochs, 1, 10_000)
        as_int("bc_batch_size", self.bc_batch_size, 1, 10**7)
        as_number("bc_log_std", self.bc_log_std, -20.0, 2.0)
        as_int("bc_dagger", self.bc_dagger, 0, 1000)
        as_int("bc_dagger_episodes", self.bc_dagger_episodes, 1, limits.MAX_EPISODES)
        as_int("bc_dagger_epochs", self.bc_dagger_epochs, 1, 10_000)
        as_number("bc_dagger_beta", self.bc_dagger_beta, 0.0, 1.0)
        as_number("bc_coef", self.bc_coef, 0.0, 1e6)
        as_int("bc_coef_half_life", self.bc_coef_half_life, 0, 10**12)
        if self.bc_teacher is None:
            if self.bc_coef > 0:
                raise ConfigError(
                    "bc_coef", self.bc_coef, "0 without --bc-teacher (the BC term imitates the "
                    "warm start's demonstrations)",
                )  # fmt: skip
            return
        check_teacher(self.bc_teacher)
        if self.task is None:
            raise ConfigError(
                "bc_teacher", self.bc_teacher, "None without --task (BC warm-starts task runs)"
            )
        if self.engine != "sb3":
            raise ConfigError(
                "bc_teacher", self.bc_teacher, "None with --engine rllib (BC is for sb3 runs)"
            )
        if self.bc_dagger > 0:
            from poc_env.tasks import get_task

            task = get_task(str(self.task))
            if (task.control, task.obs) != ("increments", "compass"):
                raise ConfigError(
                    "bc_dagger", self.bc_dagger, f"0 with {self.task} (DAgger relabels at the "
                    f"increments level with the compass observation, not {task.control} with "
                    f"{task.obs})",
                )  # fmt: skip
        if self.bc_all_tasks and not self.also_task:
            raise ConfigError("bc_all_tasks", self.bc_all_tasks, "False without --also-task")
        if self.bc_all_tasks and self.bc_dagger > 0:
            raise ConfigError(
                "bc_dagger", self.bc_dagger, "0 with --bc-all-tasks (DAgger relabels the "
                "episodes of --task only)",
            )  # fmt: skip

    def _check_residual(self) -> None:
        """The residual fields (poc_env.agents.rl.residual)."""
        as_int("residual_pool", self.residual_pool, 0, 100_000)
        as_number("residual_log_std", self.residual_log_std, -20.0, 2.0)
        if self.residual_teacher is None:
            return
        check_residual_teacher(self.residual_teacher)
        for name, bad, allowed in (
            ("task", self.task is None, "a task (the residual flies a task's scenario)"),
            ("engine", self.engine != "sb3", "sb3 with --residual-teacher"),
            ("net", self.net != "mlp", "mlp with --residual-teacher"),
            ("also_task", bool(self.also_task), "[] with --residual-teacher"),
            ("bc_teacher", self.bc_teacher is not None, "None with --residual-teacher"),
        ):
            if bad:
                raise ConfigError(name, getattr(self, name), allowed)
        from poc_env.tasks import get_task

        task = get_task(str(self.task))
        if task.obs not in ("compass", "set"):
            raise ConfigError(
                "residual_teacher", self.residual_teacher, f"None with {self.task} (a residual "
                f"needs a compass or set observation, not {task.obs})",
            )  # fmt: skip

    @classmethod
    def from_dict(cls, data: Any, where: str = "config") -> TrainArgs:
        """TrainArgs from a mapping (``config.json``); unknown keys are an error."""
        if not isinstance(data, dict):
            raise ConfigError(where, data, "a JSON object of TrainArgs fields")
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise ConfigError(f"{where}.{unknown[0]}", data[unknown[0]], "a TrainArgs field")
        return cls(**data)


_CARDS_ALLOWED = "the name of a shipped checkpoint with a card: "


def card_names() -> list[str]:
    """The shipped checkpoints that have a card (``agents/checkpoints/<name>.json``)."""
    import importlib.resources

    folder = importlib.resources.files("poc_env.agents").joinpath("checkpoints")
    return sorted(f.name[:-5] for f in folder.iterdir() if f.name.endswith(".json"))


def load_card(name: str) -> dict[str, Any]:
    """The card of the shipped checkpoint ``name`` (``agents/checkpoints/<name>.json``: its
    run's training options, ``model_step``, its evaluation)."""
    import importlib.resources
    import json

    if name not in card_names():
        raise ConfigError("from_card", name, _CARDS_ALLOWED + ", ".join(card_names()))
    ref = importlib.resources.files("poc_env.agents").joinpath("checkpoints", f"{name}.json")
    card: dict[str, Any] = json.loads(ref.read_text(encoding="utf-8"))
    return card


def card_options(name: str) -> dict[str, Any]:
    """The training options recorded in the card of the shipped checkpoint ``name``: its
    TrainArgs fields (a field the card predates takes its default, as on ``--resume``), without
    the run folder's own (``run_dir``, ``resume``, ``progress``); ``--from-card``'s defaults."""
    names = {f.name for f in dataclasses.fields(TrainArgs)} - {"run_dir", "resume", "progress"}
    return {k: v for k, v in load_card(name).items() if k in names}


def teachers() -> tuple[str, ...]:
    """The policies that may teach a BC warm start (:mod:`poc_env.agents.rl.bc`): every registered
    policy spelled by its name alone."""
    from poc_env.agents.policies.registry import REGISTRY

    return tuple(sorted(name for name, s in REGISTRY.items() if s.argument is None))


def check_teacher(name: Any, field: str = "bc_teacher") -> str:
    """``name`` if it is a registered classical policy (:func:`teachers`), else a ConfigError
    naming ``field`` and listing them (``ppo:PATH`` and ``rllib:PATH`` are refused)."""
    allowed = teachers()
    if not isinstance(name, str) or name not in allowed:
        raise ConfigError(
            field, name, "a registered classical policy (not ppo:/rllib:): " + ", ".join(allowed)
        )
    return name


#: Residual teachers that are not a plan made once but fly routes with a waypoint follower
#: (``follower``) and re-plan from the environment's state (:mod:`poc_env.agents.rl.residual`).
ROUTE_TEACHERS = ("spacetime_receding",)


def check_residual_teacher(name: Any, field: str = "residual_teacher") -> str:
    """``name`` if it is a registered plan-then-fly policy (a
    :class:`~poc_env.agents.policies.base.PlanPolicy`: it has routes and a follower) or a
    re-planning one (:data:`ROUTE_TEACHERS`), else a ConfigError naming ``field``."""
    from poc_env.agents.policies.base import PlanPolicy
    from poc_env.agents.policies.registry import make_policy

    plans = [t for t in teachers() if isinstance(make_policy(t), PlanPolicy) or t in ROUTE_TEACHERS]
    if not isinstance(name, str) or name not in plans:
        raise ConfigError(field, name, "a registered plan-then-fly policy: " + ", ".join(plans))
    return name


# -- the command line --------------------------------------------------------------------------
PROG = "poc-env train"
DESCRIPTION = (
    "Train PPO on a scenario; the run folder gets config.json, scenario.yaml, TensorBoard logs "
    "(tb/), atomic checkpoints and model.zip. Model files are pickle-based: load only trusted "
    "files.\n\n"
    + examples(
        "poc-env train --task poc_env/UAVSearch-Small-Heading-v1 --total-timesteps 20000 "
        "--run-dir runs/small",
        "poc-env train --resume runs/small",
        "poc-env train --from-card ppo_set_increments_anysize --seed 2 --run-dir runs/s2",
        "poc-env train --scenario small --overrides episode.horizon_steps=40 --recipe pilot "
        "--total-timesteps 4096 --n-envs 2",
        "poc-env train --engine rllib --task poc_env/UAVSearch-Small-Heading-v1 "
        "--total-timesteps 8000 --num-env-runners 0",
    )
)


#: The option groups of ``poc-env train --help``: group -> (its heading, its TrainArgs fields).
#: Fields in no group are the run's own options; a group's options keep their plain names
#: (``--n-steps``, not ``--ppo.n-steps``), so a group changes the help's layout, not the flags.
GROUPS: dict[str, tuple[str, tuple[str, ...]]] = {
    "ppo": (
        "PPO's hyper-parameters (both engines).",
        (
            "n_steps",
            "batch_size",
            "n_epochs",
            "learning_rate",
            "gamma",
            "gae_lambda",
            "ent_coef",
            "net_arch",
        ),
    ),
    "sb3": (
        "The sb3 engine (--engine sb3): stable-baselines3 on our VecEnvs (the recipes, or "
        "--task's env).",
        (
            "algo",
            "recipe",
            "approach_shaping",
            "n_envs",
            "net",
            "agent_index",
            "return_autopilot",
            "keep_checkpoints",
        ),
    ),
    "rllib": (
        "The rllib engine (--engine rllib): RLlib multi-agent PPO (poc_env.agents.rl.rllib), "
        "locally or on a Ray cluster.",
        ("rllib_policies", "num_env_runners", "address"),
    ),
    "bc": (
        "Behaviour-cloning warm start before PPO (sb3 with --task; poc_env.agents.rl.bc).",
        (
            "bc_teacher",
            "bc_episodes",
            "bc_epochs",
            "bc_batch_size",
            "bc_log_std",
            "bc_dagger",
            "bc_dagger_episodes",
            "bc_dagger_epochs",
            "bc_dagger_beta",
            "bc_all_tasks",
            "bc_coef",
            "bc_coef_half_life",
            "bc_coef_filter",
        ),
    ),
    "residual": (
        "A residual policy on a planner (sb3 with --task; poc_env.agents.rl.residual).",
        ("residual_teacher", "residual_pool", "residual_log_std"),
    ),
}


def field_help() -> dict[str, str]:
    """The docstring under each :class:`TrainArgs` field (``inspect.cleandoc``), read from the
    source as tyro reads a dataclass's: the help of its option."""
    import ast
    import inspect
    import itertools
    import textwrap

    tree = ast.parse(textwrap.dedent(inspect.getsource(TrainArgs)))
    body = tree.body[0].body  # type: ignore[attr-defined]
    return {
        a.target.id: inspect.cleandoc(b.value.value)
        for a, b in itertools.pairwise(body)
        if isinstance(a, ast.AnnAssign) and isinstance(a.target, ast.Name)
        if isinstance(b, ast.Expr) and isinstance(b.value, ast.Constant)
        if isinstance(b.value.value, str)
    }


@functools.cache
def _parser_type() -> type:
    """The dataclass tyro parses: TrainArgs' fields (types, metavars, defaults, docstrings as
    help) with each group of :data:`GROUPS` nested under its name (one help box per group, no
    prefix on its flags). Its values are not validated: tyro reports a ``ValueError`` raised
    while it builds the dataclass in its own format, so :func:`parse_train_args` validates by
    building :class:`TrainArgs` afterwards, and a bad value ends like every other poc-env input
    error (``error: FIELD: got VALUE; allowed: ...``)."""
    import typing

    from tyro.conf import OmitArgPrefixes

    fields = {f.name: f for f in dataclasses.fields(TrainArgs)}
    grouped = [n for _, names in GROUPS.values() for n in names]
    if len(set(grouped)) != len(grouped) or not set(grouped) <= set(fields):
        raise AssertionError(f"GROUPS must name TrainArgs fields once each: {grouped}")
    hints = typing.get_type_hints(TrainArgs, include_extras=True)
    helps = field_help()

    def option(name: str) -> tuple[str, Any, Any]:
        f = fields[name]
        default = (
            field(default=f.default)
            if f.default is not dataclasses.MISSING
            else field(default_factory=f.default_factory)
        )
        factory: Any = f.default_factory
        made = f.default if f.default is not dataclasses.MISSING else factory()
        hint = "" if made is None or made == [] else None  # no "(default: None)" noise
        arg = _arg(help=helps[name], help_behavior_hint=hint)
        return name, Annotated[hints[name], arg], default

    top = [option(n) for n in fields if n not in grouped]
    for group, (heading, names) in GROUPS.items():
        cls = dataclasses.make_dataclass(
            f"TrainArgs_{group}", [option(n) for n in names], frozen=True
        )
        nested: Any = Annotated[cls, _arg(help=heading)]  # the heading of its help box
        top.append((group, OmitArgPrefixes[nested], field(default_factory=cls)))  # type: ignore[misc]
    return dataclasses.make_dataclass("TrainArgsOptions", top, frozen=True)


def _flat(parsed: Any) -> dict[str, Any]:
    """TrainArgs' field values from a parsed :func:`_parser_type` instance."""
    values = {n: getattr(parsed, n) for n in vars(parsed) if n not in GROUPS}
    for group in GROUPS:
        values |= vars(getattr(parsed, group))
    return values


def given_options(argv: Sequence[str]) -> list[str]:
    """The TrainArgs fields whose option appears in ``argv`` (``--n-envs 3``, ``--n-envs=3``,
    ``--no-progress``), in order of appearance."""
    names = {f.name for f in dataclasses.fields(TrainArgs)}
    out: list[str] = []
    for token in argv:
        if token == "--":
            break
        if not token.startswith("--"):
            continue
        name = token[2:].partition("=")[0].replace("-", "_")
        if name not in names and name.startswith("no_"):
            name = name[3:]
        if name in names and name not in out:
            out.append(name)
    return out


#: When each option is used by a run (a predicate of its TrainArgs); an option given on the
#: command line for a run that does not use it is refused, not silently ignored.
USED_WHEN: dict[str, tuple[Any, str]] = {
    "scenario": (lambda a: a.task is None, "without --task (a task brings its scenario)"),
    "random_priors": (
        lambda a: a.task is None,
        "without --task (a task's id says whether its priors are random)",
    ),
    "recipe": (lambda a: a.engine == "sb3" and a.task is None, "with --engine sb3, no --task"),
    "algo": (lambda a: a.engine == "sb3", "with --engine sb3"),
    "n_envs": (lambda a: a.engine == "sb3", "with --engine sb3 (rllib: --num-env-runners)"),
    "keep_checkpoints": (lambda a: a.engine == "sb3", "with --engine sb3"),
    "approach_shaping": (
        lambda a: a.engine == "sb3" and a.task is None and a.recipe == "pilot",
        "with --recipe pilot",
    ),
    "net_arch": (
        lambda a: not (a.engine == "sb3" and a.task is None and a.recipe == "shared"),
        "with --task, --recipe central or pilot, or --engine rllib (the shared recipe's "
        "network is the CNN of poc_env.agents.rl.networks)",
    ),
    "agent_index": (lambda a: a.engine == "sb3" and a.task is not None, "with --task, sb3"),
    "net": (lambda a: a.engine == "sb3" and a.task is not None, "with --task, sb3"),
    "also_task": (lambda a: a.engine == "sb3" and a.task is not None, "with --task, sb3"),
    "return_autopilot": (
        lambda a: a.engine == "sb3" and a.task is not None,
        "with --task at the increments level, sb3",
    ),
    "rllib_policies": (lambda a: a.engine == "rllib", "with --engine rllib"),
    "num_env_runners": (lambda a: a.engine == "rllib", "with --engine rllib"),
    **{
        f"bc_{k}": (lambda a: a.bc_teacher is not None, "with --bc-teacher")
        for k in ("episodes", "epochs", "batch_size", "log_std", "dagger", "all_tasks", "coef")
    },
    **{
        f"bc_coef_{k}": (
            lambda a: a.bc_teacher is not None and a.bc_coef > 0,
            "with --bc-teacher and --bc-coef C > 0",
        )
        for k in ("half_life", "filter")
    },
    **{
        f"bc_dagger_{k}": (
            lambda a: a.bc_teacher is not None and a.bc_dagger > 0,
            "with --bc-teacher and --bc-dagger N > 0",
        )
        for k in ("episodes", "epochs", "beta")
    },
    **{
        f"residual_{k}": (lambda a: a.residual_teacher is not None, "with --residual-teacher")
        for k in ("pool", "log_std")
    },
}


def check_used(args: TrainArgs, given: Sequence[str]) -> None:
    """ConfigError for the first option in ``given`` that ``args``'s run would ignore
    (:data:`USED_WHEN`)."""
    for name in given:
        rule = USED_WHEN.get(name)
        if rule is not None and not rule[0](args):
            raise ConfigError(
                name, getattr(args, name), f"this option only {rule[1]}; this run would ignore it"
            )


def changed_fields(args: TrainArgs) -> list[str]:
    """The TrainArgs fields set away from their defaults (what a Python caller "gave"; the
    CLI's counterpart is :func:`given_options`). A ``scenario`` equal to ``task``'s own is not
    counted: a run's config.json and a card record it so (``--from-card ppo_drift_small``)."""
    out = []
    for f in dataclasses.fields(TrainArgs):
        default = f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default
        if getattr(args, f.name) != default:
            out.append(f.name)
    if "scenario" in out and args.task is not None:
        from poc_env.tasks import get_task

        if args.scenario == get_task(args.task).scenario:
            out.remove("scenario")
    return out


def parse_train_args(argv: Sequence[str] | None = None) -> TrainArgs:
    """TrainArgs from ``poc-env train`` options (the rest: the dataclass defaults).

    ``--help`` prints every option with its field's docstring and exits. Bad values raise
    :class:`~poc_env.errors.ConfigError`; malformed ones (``--n-envs two``, unknown options)
    end with tyro's message and exit status 2. With ``--resume`` the run's saved config is used,
    so other options (except ``--progress/--no-progress``) are an error rather than silently
    ignored."""
    import sys

    import tyro

    argv = list(sys.argv[1:] if argv is None else argv)
    parsed: Any = tyro.cli(_parser_type(), args=argv, prog=PROG, description=DESCRIPTION)
    values = _flat(parsed)
    if values["resume"] is not None:
        extra = [k for k in given_options(argv) if k not in ("resume", "progress")]
        if extra:
            flags = ", ".join("--" + k.replace("_", "-") for k in extra)
            raise ConfigError(
                "resume",
                values["resume"],
                f"no other training options (a resumed run keeps its config.json); got {flags}",
            )
    given = given_options(argv)
    if values["from_card"] is not None:
        values = card_options(values["from_card"]) | {k: values[k] for k in given}
    args = TrainArgs(**values)
    check_used(args, given)
    return args
