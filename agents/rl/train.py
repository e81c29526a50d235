"""Train RL policies in poc-env: ``poc-env train`` (stable-baselines3 PPO).

:func:`train` runs one :class:`~poc_env.agents.rl.args.TrainArgs` (or resumes a run folder); it
builds the training env with :func:`make_env` and the model with :func:`make_model`. Recipes:

``shared``
    One policy flies every UAV (parameter sharing): :class:`poc_env.envs.vector.SwarmVecEnv`
    shows each (env, UAV) pair to SB3 as one environment slot, the policy is
    ``MultiInputPolicy`` with :class:`poc_env.agents.rl.networks.SwarmExtractor` (CNN over the
    belief raster + MLP over the state vector). A checkpoint is independent of the number of UAVs
    (not of the grid).
``central``
    The centralised single-agent view ``gymnasium.make("poc_env/UAVSearch-v0")``: one agent
    sees every UAV's flat observation stacked and sets every UAV's action; plain
    ``MlpPolicy``. Simpler, but the network is tied to the number of UAVs.
``pilot``
    PPO picks where each UAV heads, an autopilot flies eq. 19 (:mod:`poc_env.agents.rl.pilot`);
    ``MlpPolicy`` over the pilot features.

With ``random_priors`` (default) every episode starts from a fresh seeded Gaussian-mixture
prior (:func:`~poc_env.theory.probability_map.random_gaussian_mixture`), so a policy is judged
on maps it has never seen.

Run folder
----------
Every run writes to its own folder (default ``runs/<scenario>-<algo>-s<seed>-<timestamp>``)::

    config.json      the resolved TrainArgs (``--resume`` reads it back)
    scenario.yaml    the resolved scenario (overrides applied); envs are built from it
    tb/ppo_1/        TensorBoard logs (SB3's, plus rollout/posc_mean)
    checkpoints/     atomic checkpoints and latest.json (:mod:`poc_env.agents.rl.checkpoint`)
    model.zip        the final model
    bc.json          with ``--bc-teacher``: the behaviour-cloning warm start (teacher POSC,
                     samples, losses; :mod:`poc_env.agents.rl.bc`); TensorBoard scalars in tb/bc/
    bc_demos.npz     with ``--bc-coef`` > 0: the warm start's demonstrations, which the BC term
                     imitates during PPO (:mod:`poc_env.agents.rl.bcppo`; read again on resume)

Checkpoints are taken at rollout boundaries once every ``checkpoint_every`` timesteps and at
the end; the newest ``keep_checkpoints`` are kept.

Resume
------
``poc-env train --resume RUN_DIR`` rebuilds the env from the run's ``config.json`` and
``scenario.yaml``, loads the checkpoint ``latest.json`` names and continues with
``reset_num_timesteps=False`` up to the saved ``total_timesteps``: the same step count, the
same learning-rate and clip-range schedule, the same TensorBoard run, and the checkpoint
numbering continues. With the shared and pilot recipes the resumed run is bit-identical to an
uninterrupted one (:mod:`poc_env.agents.rl.checkpoint` says what is restored).

A run killed before its first checkpoint (SB3 or RLlib) trains again from step 0 in its folder
with its ``config.json``: with ``--resume RUN_DIR``, or by rerunning its own command (the same
options and ``--run-dir``). ``--run-dir`` on a folder holding any other run is refused with the
command that continues or flies it.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import shlex
import sys
import time
import typing
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

from poc_env.agents.rl.args import TrainArgs, changed_fields, check_used, parse_overrides
from poc_env.agents.rl.checkpoint import (
    Checkpoint,
    checkpoint_callback,
    latest_checkpoint,
    read_json,
    restore_checkpoint,
    write_json,
)
from poc_env.errors import ConfigError, require_extra
from poc_env.io import atomic_path, safe_stem

if TYPE_CHECKING:
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import VecEnv

    from poc_env.config import Scenario


# -- environments ------------------------------------------------------------------------------
class CentralEnv(gym.Wrapper):
    """``poc_env/UAVSearch-v0`` for the central recipe: seeded from a SeedSequence at its first
    reset, and (with ``random_priors``) a fresh prior from its own generator every episode."""

    def __init__(self, scenario: Scenario, seed_seq: np.random.SeedSequence, random_priors: bool):
        from poc_env import ENV_ID

        super().__init__(gym.make(ENV_ID, scenario=scenario))
        env_ss, prior_ss = seed_seq.spawn(2)
        self._first_seed = int(env_ss.generate_state(1)[0])
        self._seeded = False
        self.prior_rng = np.random.default_rng(prior_ss)
        self.random_priors = random_priors
        #: The episode engine of the wrapped env (its generator draws targets, thresholds and
        #: link failures; the priors come from ``prior_rng``).
        self.engine = typing.cast(Any, self.env.unwrapped).par.engine

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        from poc_env.sim.engine import RandomPrior

        if seed is None and not self._seeded:
            seed = self._first_seed
        self._seeded = True
        if self.random_priors and "prior" not in (options or {}):
            prior = RandomPrior().draw(self.engine.params.grid, self.prior_rng)
            options = {**(options or {}), "prior": prior}
        return self.env.reset(seed=seed, options=options)

    def generators(self) -> list[np.random.Generator]:
        """The env's generators: the simulator's (targets, thresholds, links), the priors'."""
        if not self._seeded:  # what the first reset would do: seed the simulator's generator
            self.engine.seed([self._first_seed])
            self._seeded = True
        return [self.engine.rngs[0], self.prior_rng]


def _central_env(scenario: Scenario, random_priors: bool, seed_seq: np.random.SeedSequence):
    from stable_baselines3.common.monitor import Monitor

    return Monitor(CentralEnv(scenario, seed_seq, random_priors), info_keywords=("posc",))


def make_env(args: TrainArgs, scenario: Scenario) -> VecEnv:
    """The training VecEnv of ``args.recipe``; env ``e``'s generators come from
    ``SeedSequence(args.seed).spawn(args.n_envs)[e]``."""
    if args.task is not None:  # the task's env: its control level and observation
        from poc_env.envs.vector import SwarmVecEnv
        from poc_env.tasks import get_task

        def task_env(tid: str, sc: Scenario, seed: int) -> SwarmVecEnv:
            task = get_task(tid)
            if args.residual_teacher is not None:  # the planner flies, the policy adds to it
                from poc_env.agents.rl.residual import ResidualVecEnv

                return ResidualVecEnv(
                    sc,
                    n_envs=args.n_envs,
                    seed=seed,
                    obs_type=task.obs,
                    random_priors=task.random_prior,
                    teacher=args.residual_teacher,
                    pool=args.residual_pool,
                    agent_index=args.agent_index,
                )
            return SwarmVecEnv(
                sc,
                n_envs=args.n_envs,
                seed=seed,
                obs_type=task.obs,
                random_priors=task.random_prior,
                control=task.kwargs["control"],  # the task version's rule (heading_clip at v1)
                agent_index=args.agent_index,
                return_autopilot=args.return_autopilot,
            )

        first = task_env(args.task, scenario, args.seed)
        if not args.also_task:
            return first
        from poc_env.agents.rl.mixed import MixedVecEnv

        more = []  # each further task's envs: its own seed stream, (seed, k) for the k-th task
        for k, tid in enumerate(args.also_task, start=1):
            seed = int(np.random.SeedSequence([args.seed, k]).generate_state(1)[0])
            sc = get_task(tid).load_scenario(parse_overrides(args.overrides))
            more.append(task_env(tid, sc, seed))
        return MixedVecEnv([first, *more])
    if args.recipe == "pilot":
        from poc_env.agents.rl.pilot import PilotVecEnv

        return PilotVecEnv(
            scenario,
            n_envs=args.n_envs,
            seed=args.seed,
            random_priors=args.random_priors,
            approach_shaping=args.approach_shaping,
            gamma=args.gamma,
        )
    if args.recipe == "shared":
        from poc_env.envs.vector import SwarmVecEnv

        return SwarmVecEnv(
            scenario,
            n_envs=args.n_envs,
            seed=args.seed,
            obs_type="dict",
            random_priors=args.random_priors,
        )
    from stable_baselines3.common.vec_env import DummyVecEnv

    seqs = np.random.SeedSequence(args.seed).spawn(args.n_envs)
    return DummyVecEnv(
        [functools.partial(_central_env, scenario, args.random_priors, s) for s in seqs]
    )


# -- models ------------------------------------------------------------------------------------
def make_model(args: TrainArgs, env: VecEnv, tb_dir: Path | None) -> PPO:
    """A fresh PPO of ``args`` on ``env`` (CPU)."""
    from stable_baselines3 import PPO

    policy_kwargs: dict[str, Any] | None = None
    if args.recipe == "shared" and args.task is None:
        from poc_env.agents.rl.networks import SwarmExtractor

        policy, policy_kwargs = "MultiInputPolicy", {"features_extractor_class": SwarmExtractor}
    elif args.task is not None and args.net == "set":
        from poc_env.agents.rl.networks import SetExtractor

        policy = "MlpPolicy"
        policy_kwargs = {"features_extractor_class": SetExtractor, "net_arch": list(args.net_arch)}
    else:
        policy = "MlpPolicy"
        policy_kwargs = {"net_arch": list(args.net_arch)}
    return PPO(
        policy,
        env,
        n_steps=args.n_steps,
        batch_size=args.batch_size,
        n_epochs=args.n_epochs,
        learning_rate=args.learning_rate,
        gamma=args.gamma,
        gae_lambda=args.gae_lambda,
        ent_coef=args.ent_coef,
        policy_kwargs=policy_kwargs,
        tensorboard_log=None if tb_dir is None else str(tb_dir),
        seed=args.seed,
        device="cpu",
        verbose=0,
    )


def seed_everything(seed: int) -> None:
    """The seeding block: everything random in a run derives from ``seed``.

    * envs: numpy ``SeedSequence(seed).spawn(n_envs)``, one generator (tree) per env, inside
      :func:`make_env`: priors, targets, thresholds, link failures;
    * torch: initial weights and PPO's action sampling;
    * SB3: python ``random``, numpy's global generator (minibatch shuffling) and torch again;
      ``PPO(seed=seed)`` repeats ``set_random_seed`` and seeds the action space.
    """
    import torch as th
    from stable_baselines3.common.utils import set_random_seed

    th.manual_seed(seed)
    set_random_seed(seed)


# -- sizes checked before anything is allocated ------------------------------------------------
#: Bytes per float32 value of a rollout: SB3 keeps each observation, action, reward, value,
#: log-probability, advantage and return as float32, and copies each minibatch to torch.
_F32 = 4
#: Bytes per network parameter: the weight, its gradient and Adam's two moments (float32).
_PARAM_BYTES = 16


def slots_and_obs(args: TrainArgs, sc: Scenario) -> tuple[int, int, int]:
    """``(slots, obs_size, act_size)`` of the training env of ``args`` on ``sc``: SB3 sees
    ``slots`` envs of observations of ``obs_size`` float32 values (computed from the scenario,
    without building the env)."""
    from poc_env import spec

    n = sc.n_uavs
    cells = sc.map.nx * sc.map.ny
    dict_obs = len(spec.RASTER) * cells + len(spec.VECTOR)
    if args.task is not None:
        from poc_env.sim.control import ACTION_DIMS
        from poc_env.tasks import get_task

        task = get_task(args.task)
        act = ACTION_DIMS[task.control]
        sizes = [n if task.n_uavs is None else task.n_uavs]
        sizes += [get_task(tid).load_scenario().n_uavs for tid in args.also_task]
        obs = spec.SET_SIZE if task.obs == "set" else spec.COMPASS_SIZE
        if args.residual_teacher is not None:
            from poc_env.agents.rl.residual import RESIDUAL_DIMS, TEACHER_DIMS

            obs, act = obs + TEACHER_DIMS, RESIDUAL_DIMS
        return args.n_envs * sum(sizes), obs, act
    if args.recipe == "central":
        return args.n_envs, n * dict_obs, 3 * n
    if args.recipe == "pilot":
        return args.n_envs * n, spec.COMPASS_SIZE, 2  # about the pilot features' size
    return args.n_envs * n, dict_obs, 3


def check_sizes(args: TrainArgs, sc: Scenario) -> None:
    """ConfigError naming the field before training starts, instead of a failure deep inside
    SB3 or an allocation of tens of GB: a rollout of fewer than 2 transitions (SB3 asserts),
    a minibatch larger than the rollout (SB3 would silently train on the whole rollout), and
    a rollout buffer or network larger than the memory guard
    (:func:`poc_env.limits.check_memory`)."""
    import poc_env.limits as limits

    slots, obs, act = slots_and_obs(args, sc)
    rollout = args.n_steps * slots
    if args.engine == "sb3":
        if rollout < 2:
            raise ConfigError(
                "n_steps", args.n_steps, f"a rollout of at least 2 transitions: n_steps x "
                f"{slots} slot(s) (n_envs {args.n_envs}) >= 2",
            )  # fmt: skip
        if args.batch_size > rollout:
            raise ConfigError(
                "batch_size", args.batch_size, f"at most the rollout, n_steps x slots = "
                f"{args.n_steps} x {slots} = {rollout} transitions (n_envs {args.n_envs})",
            )  # fmt: skip
    per_transition = (obs + act + 8) * _F32
    limits.check_memory(
        "n_steps", args.n_steps, 2.0 * rollout * per_transition,
        f"rollout buffer (n_steps x {slots} slots x {obs} observation values)",
    )  # fmt: skip
    widths = [obs, *args.net_arch, act]
    params = 2 * sum(a * b + b for a, b in itertools.pairwise(widths))  # pi and vf
    batch = min(args.batch_size, rollout)
    activations = 3.0 * batch * sum(widths) * _F32  # forward values, gradients, a copy
    limits.check_memory(
        "net_arch", list(args.net_arch), params * _PARAM_BYTES + activations,
        f"policy and value networks ({params:,} parameters, minibatches of {batch})",
    )  # fmt: skip


# -- progress ----------------------------------------------------------------------------------
def _progress_callback(args: TrainArgs, env: VecEnv, run_dir: Path) -> BaseCallback:
    """tqdm bar over timesteps; postfix: mean POSC of the episodes in SB3's info buffer (the
    last 100 episode records), also logged to TensorBoard as ``rollout/posc_mean``."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Progress(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.bar: Any = None

        def posc_mean(self) -> float | None:
            buf = self.model.ep_info_buffer or ()
            vals = [ep["posc"] for ep in buf if "posc" in ep]
            return float(np.mean(vals)) if vals else None

        def _on_training_start(self) -> None:
            if args.progress:
                from tqdm import tqdm

                rollout = args.n_steps * env.num_envs  # SB3 trains whole rollouts
                self.bar = tqdm(
                    total=-(-args.total_timesteps // rollout) * rollout,
                    initial=self.model.num_timesteps,
                    unit="step",
                    unit_scale=True,
                    desc=f"{args.algo} {args.recipe} {run_dir.name}",
                    dynamic_ncols=True,
                )

        def _on_step(self) -> bool:
            if self.bar is not None:
                self.bar.update(self.model.num_timesteps - self.bar.n)
                if any("episode" in info for info in self.locals.get("infos", ())):
                    m = self.posc_mean()
                    if m is not None:
                        self.bar.set_postfix(posc=f"{m:.4f}", refresh=False)
            return True

        def _on_rollout_end(self) -> None:
            m = self.posc_mean()
            if m is not None:
                self.logger.record("rollout/posc_mean", m)

        def _on_training_end(self) -> None:
            self.close()

        def close(self) -> None:
            if self.bar is not None:
                self.bar.close()
                self.bar = None

    return Progress()


# -- training ----------------------------------------------------------------------------------
def _new_run_dir(args: TrainArgs, scenario_name: str) -> Path:
    if args.run_dir is not None:
        p = Path(args.run_dir)
        if (p / "config.json").exists():
            raise ConfigError("run_dir", str(p), f"a new or empty folder ({_what_holds(p)})")
        return p
    stamp = time.strftime("%Y%m%d-%H%M%S")
    # the scenario's name is the user's text: one safe component under runs/, never a path
    name = safe_stem(f"{scenario_name}-{args.engine}-{args.algo}-s{args.seed}-{stamp}", 128)
    base = Path("runs") / name
    p, k = base, 1
    while p.exists():
        k += 1
        p = base.with_name(f"{base.name}-{k}")
    return p


def _has_checkpoint(run_dir: Path) -> bool:
    """True when ``run_dir`` holds a model or checkpoint of either engine (a damaged
    ``latest.json`` counts as one: never restarted over)."""
    if (run_dir / "checkpoint").exists() or (run_dir / "model.zip").exists():
        return True
    try:
        return latest_checkpoint(run_dir) is not None
    except ConfigError:
        return True


def _what_holds(run_dir: Path) -> str:
    """What the run folder ``run_dir`` holds, and the command that continues or uses it."""
    q = shlex.quote(str(run_dir))
    if (run_dir / "checkpoint").exists():
        return (
            "this one holds an rllib run with a checkpoint, which is not continued: fly it "
            f"with poc-env evaluate --policies rllib:{q}, or train into a new folder"
        )
    if (run_dir / "model.zip").exists():
        return (
            f"this one holds a finished run: fly it with poc-env evaluate --policies ppo:{q}, "
            "or train into a new folder"
        )
    if _has_checkpoint(run_dir):
        return f"this one holds a run: continue it with poc-env train --resume {q}"
    try:
        TrainArgs.from_dict(read_json(run_dir / "config.json", "config.json"), "config.json")
    except ConfigError as err:
        return f"this one holds a config.json that is not a run's ({err}): pick a new folder"
    return (
        "this one holds a run killed before its first checkpoint, with other options than "
        f"these: poc-env train --resume {q} trains it again from step 0 with its own options "
        "(so does its own command with this --run-dir)"
    )


def _same_run_killed_early(args: TrainArgs) -> bool:
    """True when ``args.run_dir`` holds a run of exactly these options (its config.json) that
    was killed before its first checkpoint: rerunning its command trains it again in place."""
    if args.run_dir is None:
        return False
    p = Path(args.run_dir)
    if not (p / "config.json").is_file() or _has_checkpoint(p):
        return False
    try:
        stored = TrainArgs.from_dict(read_json(p / "config.json", "config.json"), "config.json")
    except ConfigError:
        return False

    def comparable(a: TrainArgs) -> TrainArgs:
        if a.task is not None and a.engine == "sb3":  # train() records the task's scenario
            from poc_env.tasks import get_task

            a = dataclasses.replace(a, scenario=get_task(a.task).scenario)
        return dataclasses.replace(a, run_dir=str(p), resume=None, progress=False)

    return comparable(stored) == comparable(args)


def train(args: TrainArgs, callback: BaseCallback | None = None) -> Path:
    """Train according to ``args`` (or resume ``args.resume``); return the run folder.

    ``callback``: an extra SB3 callback, called after the checkpointer and the progress bar.
    Needs the ``rl`` extra (checked before anything is written)."""
    if args.resume is not None:  # the run's own config.json says which engine
        return _resume(Path(args.resume), args.progress, callback)
    if _same_run_killed_early(args):  # the same command again after a kill: as --resume does
        return _resume(Path(str(args.run_dir)), args.progress, callback)
    check_used(args, changed_fields(args))  # as the CLI refuses options the run would ignore
    if args.engine == "rllib":
        from poc_env.agents.rl.rllib import train_rllib

        name = args.task.rsplit("/", 1)[-1] if args.task else args.scenario
        check_sizes(args, _scenario_of(args))
        run_dir = _new_run_dir(args, Path(name).stem)
        return train_rllib(dataclasses.replace(args, run_dir=str(run_dir)), run_dir)
    require_extra("rl", "poc-env train", "torch", "stable_baselines3", "tensorboard")
    from poc_env.config import load_scenario, save_scenario

    if args.task is not None:
        from poc_env.tasks import get_task

        args = dataclasses.replace(args, scenario=get_task(args.task).scenario)
    sc = _scenario_of(args)
    check_sizes(args, sc)
    run_dir = _new_run_dir(args, args.task.rsplit("/", 1)[-1] if args.task else sc.name)
    args = dataclasses.replace(args, run_dir=str(run_dir))
    run_dir.mkdir(parents=True, exist_ok=True)
    write_json(run_dir / "config.json", dataclasses.asdict(args))
    save_scenario(sc, run_dir / "scenario.yaml")
    sc = load_scenario(run_dir / "scenario.yaml")  # resumed runs build their env from it too
    return _run(args, sc, run_dir, callback, checkpoint=None)


def _resume(run_dir: Path, progress: bool, callback: BaseCallback | None) -> Path:
    """Continue ``run_dir`` from its newest checkpoint. A run killed before its first one
    (even before it wrote scenario.yaml) trains again from step 0 in the same folder with its
    config.json, so ``--resume`` and ``--run-dir`` never send the user to each other; rerunning
    the run's own command (the same options and ``--run-dir``) does the same."""
    from poc_env.config import load_scenario, save_scenario

    if not (run_dir / "config.json").is_file():
        raise ConfigError(
            "resume",
            str(run_dir),
            "a run folder written by poc-env train (with config.json; a folder without one "
            "starts a new run with --run-dir)",
        )
    args = TrainArgs.from_dict(read_json(run_dir / "config.json", "config.json"), "config.json")
    args = dataclasses.replace(args, run_dir=str(run_dir), resume=None, progress=progress)
    if args.engine == "rllib":
        return _resume_rllib(args, run_dir)
    require_extra("rl", "poc-env train", "torch", "stable_baselines3", "tensorboard")
    if not (run_dir / "scenario.yaml").is_file():  # killed between config.json and it
        if latest_checkpoint(run_dir) is not None:
            raise ConfigError(
                "resume", str(run_dir), "a run folder with its scenario.yaml beside its "
                "checkpoints (this one lost it: its checkpoints cannot be matched to a scenario)",
            )  # fmt: skip
        sc = _scenario_of(args)
        save_scenario(sc, run_dir / "scenario.yaml")
    ck = latest_checkpoint(run_dir)
    if ck is not None and ck.step >= args.total_timesteps and (run_dir / "model.zip").is_file():
        print(
            f"{run_dir}: finished (step {ck.step} of {args.total_timesteps}); nothing to train. "
            "Train longer with a new run: poc-env train --run-dir NEW ...",
            file=sys.stderr,
        )
        return run_dir
    if ck is None:  # killed before its first checkpoint: the same run again, from step 0
        warnings.warn(
            f"{run_dir}: no complete checkpoint; training again from step 0 with its config",
            stacklevel=2,
        )
    sc = load_scenario(run_dir / "scenario.yaml")
    return _run(args, sc, run_dir, callback, checkpoint=ck)


def _scenario_of(args: TrainArgs) -> Scenario:
    """The scenario a run trains on, with the run's overrides: its task's (a fleet-size task's
    fleet included), else ``args.scenario``."""
    from poc_env.config import load_scenario

    overrides = parse_overrides(args.overrides)
    if args.task is not None:
        from poc_env.tasks import get_task

        return get_task(args.task).load_scenario(overrides)
    return load_scenario(args.scenario, overrides)


def _resume_rllib(args: TrainArgs, run_dir: Path) -> Path:
    """``--resume`` of an RLlib run: one killed before its first checkpoint trains in its folder
    from step 0; one with a checkpoint is complete up to it and is not continued (RLlib runs
    start anew), and the error says what to do instead."""
    from poc_env.agents.rl.rllib import train_rllib

    if (run_dir / "checkpoint").exists():
        raise ConfigError(
            "resume", str(run_dir), "an sb3 run, or an rllib run killed before its first "
            "checkpoint (this rllib run has one: fly it with evaluate --policies "
            f"rllib:{run_dir}, or train a new run with --run-dir NEW)",
        )  # fmt: skip
    warnings.warn(
        f"{run_dir}: no checkpoint; training again from step 0 with its config", stacklevel=2
    )
    return train_rllib(args, run_dir)


def _run(
    args: TrainArgs,
    sc: Scenario,
    run_dir: Path,
    callback: BaseCallback | None,
    checkpoint: Checkpoint | None,
) -> Path:
    import torch as th
    from stable_baselines3.common.callbacks import CallbackList

    threads = th.get_num_threads()
    th.set_num_threads(args.torch_threads)
    try:
        seed_everything(args.seed)
        env = make_env(args, sc)
        if checkpoint is None:
            model = make_model(args, env, run_dir / "tb")
            if args.bc_teacher is not None:  # warm start; a resumed run has it in its weights
                from poc_env.agents.rl.bc import warm_start

                warm_start(args, sc, model, run_dir)
            if args.residual_teacher is not None:  # the residual starts at 0: at the teacher
                from poc_env.agents.rl.residual import init_policy

                init_policy(model, args.residual_log_std)
        else:
            model = restore_checkpoint(checkpoint, env, run_dir)
        if args.bc_coef > 0:  # the teacher kept in the loss: the warm start's saved demos
            from poc_env.agents.rl.bc import DEMOS_FILE, load_demos
            from poc_env.agents.rl.bcppo import attach

            demos = load_demos(run_dir / DEMOS_FILE)
            model = attach(
                model, demos, args.bc_coef, args.bc_coef_half_life, args.seed, args.bc_coef_filter
            )
        start = int(model.num_timesteps)
        remaining = args.total_timesteps - start
        if remaining > 0:
            ckpt = checkpoint_callback(
                run_dir, env, args.checkpoint_every, args.keep_checkpoints, start
            )
            bar = _progress_callback(args, env, run_dir)
            extra = [] if callback is None else [callback]
            try:
                model.learn(
                    remaining,
                    callback=CallbackList([ckpt, bar, *extra]),
                    tb_log_name="ppo",
                    reset_num_timesteps=checkpoint is None,
                )
            except KeyboardInterrupt:
                bar.close()  # type: ignore[attr-defined]
                print(
                    f"\ninterrupted at step {model.num_timesteps}; continue with: "
                    f"poc-env train --resume {shlex.quote(str(run_dir))}",
                    file=sys.stderr,
                )
                raise
            finally:
                bar.close()  # type: ignore[attr-defined]
        with atomic_path(run_dir / "model.zip", suffix=".zip") as tmp:
            model.save(tmp)
        env.close()
    finally:
        th.set_num_threads(threads)
    return run_dir
