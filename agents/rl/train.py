"""Train RL policies in poc-env: ``poc-env train`` (stable-baselines3 PPO).

Two recipes
-----------
``shared`` (default)
    One policy flies every UAV (parameter sharing): :class:`poc_env.envs.vector.SwarmVecEnv` shows
    each (env, UAV) pair to SB3 as one environment slot, the policy is ``MultiInputPolicy``
    with :class:`agents.rl.networks.SwarmExtractor` (CNN over the belief raster + MLP over the
    state vector). A checkpoint is independent of the number of UAVs (not of the grid).
``central``
    The centralised single-agent view ``gymnasium.make("poc_env/UAVSearch-v0")``: one agent
    sees every UAV's flat observation stacked and sets every UAV's action; plain
    ``MlpPolicy``. Simpler, but the network is tied to the number of UAVs.

With ``random_priors`` (default) every episode starts from a fresh seeded Gaussian-mixture
prior (:func:`~poc_env.theory.probability_map.random_gaussian_mixture`), so a policy is judged
on maps it has never seen.

Run folder
----------
Every run writes to its own folder (default ``runs/<scenario>-<algo>-s<seed>-<timestamp>``)::

    config.json                  the resolved TrainArgs (``--resume`` reads it back)
    scenario.yaml                the resolved scenario (overrides applied); envs are built from it
    tb/ppo_1/                    TensorBoard logs (SB3's, plus rollout/posc_mean)
    checkpoints/step_<N>.zip     the model after N timesteps (SB3 zip: weights, Adam state, ...)
    checkpoints/step_<N>.state.json  generator states: every env's, torch's, numpy's, python's
    checkpoints/step_<N>.env.npz     shared recipe: the simulator state (episodes in flight)
    latest.json                  pointer to the newest complete checkpoint
    model.zip                    the final model

Every file is written to a temporary file in its folder and renamed over its name
(``os.replace``), and ``latest.json`` only after the checkpoint's files are in place, so a run
killed at any moment leaves complete files. Checkpoints are taken at rollout boundaries (after
a PPO update, before the next rollout) once every ``checkpoint_every`` timesteps, and at the
end; the newest ``keep_checkpoints`` are kept.

Resume
------
``poc-env train --resume RUN_DIR`` rebuilds the env from the run's ``config.json`` and
``scenario.yaml``, loads the checkpoint ``latest.json`` names and continues with
``reset_num_timesteps=False`` up to the saved ``total_timesteps``: the same step count, the
same learning-rate and clip-range schedule, the same TensorBoard run, and the checkpoint
numbering continues.

What is bit-identical after a resume: with the **shared** recipe, everything. The checkpoint
holds the weights and Adam state, SB3's last observation and episode-start flags, the
simulator state of every env (episodes in flight), each env's generator, and the global torch,
numpy and python generators (PPO samples actions from torch's and shuffles minibatches with
numpy's); the resumed run then trains exactly as the uninterrupted run would have (tested), on
the same torch build and thread count. With the **central** recipe the generators are restored
but the episodes in flight are not (they live in gymnasium wrappers): the resumed run starts
fresh episodes from each env's saved generator, so it continues the same episode streams but
drops the partial episodes, and its parameters differ from an uninterrupted run's. Wall-clock
fields (``episode["t"]``, SB3's ``time/fps``) never match.

Model files are pickle-based
----------------------------
SB3 ``.zip`` files hold cloudpickled objects (schedules, policy classes, the last
observation): loading one runs code from it. Load only files you trust (your own runs, the
checkpoint shipped in this repository). The ``.state.json`` / ``.env.npz`` companions are
pickle-free (JSON, ``np.load(allow_pickle=False)``).

Benchmark
---------
``poc-env bench train`` (``python -m agents.rl.train [--scenario paper_6_2] [--iterations 2]``)
prints PPO agent transitions per second on ``paper_6_2`` with the shipped network and default
hyper-parameters, and the shares of wall time spent in the environment (``VecEnv.step_wait``),
in the network during rollouts (action sampling and values) and in the PPO updates; one torch
thread.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import functools
import inspect
import json
import os
import random
import sys
import tempfile
import textwrap
import time
import typing
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

from agents.policies.base import Policy
from poc_env.errors import ConfigError
from poc_env.io import publish_atomic, write_text_atomic

if TYPE_CHECKING:
    from stable_baselines3 import PPO
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import VecEnv

    from poc_env.config import Scenario

ALGOS = ("ppo",)
RECIPES = ("shared", "central", "pilot")


@dataclass
class TrainArgs:
    """Everything a training run depends on; saved as ``config.json`` in the run folder."""

    scenario: str = "paper_6_2"
    """Built-in scenario name or YAML path; the resolved scenario is saved as scenario.yaml."""
    overrides: list[str] = field(default_factory=list)
    """Scenario overrides as dotted KEY=VALUE pairs (VALUE is YAML), e.g.
    episode.horizon_steps=20."""
    algo: str = "ppo"
    """RL algorithm: ppo (stable-baselines3 PPO)."""
    recipe: str = "shared"
    """shared: one policy for every UAV (parameter sharing over SwarmVecEnv, CNN+MLP
    SwarmExtractor); central: one agent over the joint observation and joint action
    (poc_env/UAVSearch-v0, MlpPolicy)."""
    approach_shaping: float = 0.0
    """pilot recipe: coefficient of the potential-based approach term c (gamma Phi(s') -
    Phi(s)), Phi = -(km from the UAV to the grid) (agents.rl.pilot)."""
    net_arch: list[int] = field(default_factory=lambda: [128, 128])
    """pilot and central recipes: hidden layers of the policy and value MLPs."""
    total_timesteps: int = 1_000_000
    """Timesteps to train for: agent transitions (shared) or joint steps (central), summed over
    envs; rounded up to whole rollouts of n_steps x slots."""
    seed: int = 0
    """Root seed: env generators (numpy SeedSequence), torch, numpy and python generators."""
    n_envs: int = 4
    """Independent swarms simulated side by side (shared: n_envs x UAVs slots)."""
    random_priors: bool = True
    """Draw a fresh random Gaussian-mixture prior every episode instead of the scenario's."""
    run_dir: str | None = None
    """Run folder; default runs/<scenario>-<algo>-s<seed>-<timestamp>."""
    resume: str | None = None
    """Continue the run in this folder from its latest checkpoint, with its saved config (no
    other options may be given)."""
    checkpoint_every: int = 50_000
    """Timesteps between checkpoints (taken at the next rollout boundary)."""
    keep_checkpoints: int = 5
    """Newest checkpoints to keep (0: keep all)."""
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
    torch_threads: int = 1
    """torch intra-op threads (small networks run fastest and reproducibly on one)."""
    progress: bool = True
    """Show a progress bar with the mean POSC of recent episodes."""

    def __post_init__(self) -> None:
        if self.algo not in ALGOS:
            raise ConfigError("algo", self.algo, "one of " + ", ".join(ALGOS))
        if self.recipe not in RECIPES:
            raise ConfigError("recipe", self.recipe, "one of " + ", ".join(RECIPES))
        for name, lo in (
            ("total_timesteps", 1),
            ("seed", 0),
            ("n_envs", 1),
            ("checkpoint_every", 1),
            ("keep_checkpoints", 0),
            ("n_steps", 1),
            ("batch_size", 2),
            ("n_epochs", 1),
            ("torch_threads", 1),
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                raise ConfigError(name, v, f"an integer >= {lo}")
        bounds: tuple[tuple[str, float, float], ...] = (
            ("learning_rate", 0.0, float("inf")),
            ("gamma", 0.0, 1.0),
            ("gae_lambda", 0.0, 1.0),
            ("ent_coef", 0.0, float("inf")),
        )
        for name, low, high in bounds:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not low <= v <= high:
                raise ConfigError(name, v, f"a number in [{low}, {high}]")
        if (
            isinstance(self.approach_shaping, bool)
            or not isinstance(self.approach_shaping, int | float)
            or not np.isfinite(self.approach_shaping)
        ):
            raise ConfigError("approach_shaping", self.approach_shaping, "a finite number")
        if not isinstance(self.net_arch, list | tuple) or not all(
            isinstance(w, int) and not isinstance(w, bool) and w >= 1 for w in self.net_arch
        ):
            raise ConfigError("net_arch", self.net_arch, "a list of layer widths (integers >= 1)")
        if self.learning_rate == 0:
            raise ConfigError("learning_rate", self.learning_rate, "a number > 0")
        for name in ("scenario",):
            if not isinstance(getattr(self, name), str):
                raise ConfigError(name, getattr(self, name), "a string")
        for name in ("run_dir", "resume"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, str | os.PathLike):
                raise ConfigError(name, v, "a folder path or None")
        for name in ("random_priors", "progress"):
            if not isinstance(getattr(self, name), bool):
                raise ConfigError(name, getattr(self, name), "true or false")
        parse_overrides(self.overrides)

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


def parse_overrides(items: Sequence[str]) -> dict[str, Any]:
    """``["a.b=1", ...]`` -> ``{"a.b": 1}`` (values parsed as YAML)."""
    import yaml

    if isinstance(items, str) or not isinstance(items, list | tuple):
        raise ConfigError("overrides", items, "a list of KEY=VALUE strings")
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = str(item).partition("=")
        if not sep or not key.strip():
            raise ConfigError("overrides", item, "KEY=VALUE, e.g. episode.horizon_steps=20")
        try:
            out[key.strip()] = yaml.safe_load(value)
        except yaml.YAMLError as err:
            raise ConfigError("overrides", item, f"a YAML value after '=' ({err})") from None
    return out


# -- the command line, generated from TrainArgs ------------------------------------------------
def field_docs(cls: type) -> dict[str, str]:
    """The docstring under each field of a dataclass (read from its source), one line each."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    except (OSError, TypeError, SyntaxError):
        return {}
    node = tree.body[0]
    if not isinstance(node, ast.ClassDef):
        return {}
    out = {}
    for a, b in zip(node.body, node.body[1:]):
        if (
            isinstance(a, ast.AnnAssign)
            and isinstance(a.target, ast.Name)
            and isinstance(b, ast.Expr)
            and isinstance(b.value, ast.Constant)
            and isinstance(b.value.value, str)
        ):
            out[a.target.id] = " ".join(b.value.value.split())
    return out


def _default(f: dataclasses.Field) -> Any:
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return None


_METAVARS = {
    "scenario": "NAME",
    "algo": "|".join(ALGOS),
    "recipe": "|".join(RECIPES),
    "run_dir": "DIR",
    "resume": "RUN_DIR",
}


def add_train_arguments(parser: argparse.ArgumentParser) -> None:
    """One option per TrainArgs field (``--total-timesteps`` for ``total_timesteps``), its
    docstring as help. Options left out are absent from the namespace (``SUPPRESS``), so
    :func:`args_from_namespace` knows what was given and TrainArgs holds the defaults."""
    hints = typing.get_type_hints(TrainArgs)
    docs = field_docs(TrainArgs)
    for f in dataclasses.fields(TrainArgs):
        tp = hints[f.name]
        args = [t for t in typing.get_args(tp) if t is not type(None)]
        base = args[0] if args and typing.get_origin(tp) is not list else tp
        default = _default(f)
        shown = "none" if default is None else default
        text = f"{docs.get(f.name, '')} (default: {shown})".replace("%", "%%").strip()
        flag = "--" + f.name.replace("_", "-")
        kw: dict[str, Any] = {"dest": f.name, "default": argparse.SUPPRESS, "help": text}
        if base is bool:
            parser.add_argument(flag, action=argparse.BooleanOptionalAction, **kw)
        elif typing.get_origin(base) is list:
            item = typing.get_args(base)[0]
            meta = "N" if item is int else "KEY=VALUE"
            parser.add_argument(flag, nargs="*", type=item, metavar=meta, **kw)
        else:
            metavar = _METAVARS.get(f.name) or {int: "N", float: "X"}.get(base, "VALUE")
            parser.add_argument(flag, type=base, metavar=metavar, **kw)


def args_from_namespace(ns: argparse.Namespace) -> TrainArgs:
    """TrainArgs from the options given on the command line (the rest: defaults).

    With ``--resume`` the run's saved config is used, so other options (except
    ``--progress/--no-progress``) are an error rather than silently ignored."""
    given = {f.name: getattr(ns, f.name) for f in dataclasses.fields(TrainArgs) if f.name in ns}
    if given.get("resume") is not None:
        extra = sorted(set(given) - {"resume", "progress"})
        if extra:
            flags = ", ".join("--" + k.replace("_", "-") for k in extra)
            raise ConfigError(
                "resume",
                given["resume"],
                f"no other training options (a resumed run keeps its config.json); got {flags}",
            )
    return TrainArgs(**given)


# -- atomic files ----------------------------------------------------------------------------
def write_atomic(path: Path, write: Callable[[str], None]) -> Path:
    """``write(tmp)`` to a temporary file beside ``path``, flush it to disk, rename it over
    ``path``; on any error the temporary file is removed and ``path`` is untouched."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        publish_atomic(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def _write_json(path: Path, data: Any) -> Path:
    return write_text_atomic(path, json.dumps(data, indent=1) + "\n")


def _read_json(path: Path, what: str) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ConfigError(what, str(path), f"a readable JSON file ({err})") from None


# -- generators ------------------------------------------------------------------------------
def global_rng_states() -> dict[str, Any]:
    """The torch, numpy-global and python generator states, as JSON-able data."""
    import torch as th

    np_state = np.random.get_state(legacy=False)  # noqa: NPY002  (SB3 shuffles with it)
    assert isinstance(np_state, dict)
    np_json = dict(np_state)
    np_json["state"] = {
        "key": np.asarray(np_state["state"]["key"]).tolist(),
        "pos": int(np_state["state"]["pos"]),
    }
    version, internal, gauss = random.getstate()
    return {
        "torch": th.get_rng_state().tolist(),
        "numpy": np_json,
        "python": [version, list(internal), gauss],
    }


def set_global_rng_states(states: dict[str, Any]) -> None:
    """Inverse of :func:`global_rng_states`."""
    import torch as th

    th.set_rng_state(th.tensor(states["torch"], dtype=th.uint8))
    np_state = dict(states["numpy"])
    np_state["state"] = {
        "key": np.asarray(np_state["state"]["key"], dtype=np.uint32),
        "pos": int(np_state["state"]["pos"]),
    }
    np.random.set_state(np_state)  # noqa: NPY002
    version, internal, gauss = states["python"]
    random.setstate((version, tuple(internal), gauss))


# -- environments ----------------------------------------------------------------------------
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
        self._par: Any = typing.cast(Any, self.env.unwrapped).par

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        from poc_env.theory.probability_map import random_gaussian_mixture

        if seed is None and not self._seeded:
            seed = self._first_seed
        self._seeded = True
        if self.random_priors and "prior" not in (options or {}):
            prior = random_gaussian_mixture(self._par.params.grid, self.prior_rng)
            options = {**(options or {}), "prior": prior}
        return self.env.reset(seed=seed, options=options)

    def generators(self) -> list[np.random.Generator]:
        """The env's generators: the simulator's (targets, thresholds, links), the priors'."""
        if not self._seeded:  # what the first reset would do: seed the simulator's generator
            self._par._rng = np.random.default_rng(self._first_seed)
            self._seeded = True
        return [self._par._rng, self.prior_rng]


def _central_env(scenario: Scenario, random_priors: bool, seed_seq: np.random.SeedSequence):
    from stable_baselines3.common.monitor import Monitor

    return Monitor(CentralEnv(scenario, seed_seq, random_priors), info_keywords=("posc",))


def make_env(args: TrainArgs, scenario: Scenario) -> VecEnv:
    """The training VecEnv of ``args.recipe``; env ``e``'s generators come from
    ``SeedSequence(args.seed).spawn(args.n_envs)[e]``."""
    if args.recipe == "pilot":
        from agents.rl.pilot import PilotVecEnv

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


def env_generators(env: VecEnv) -> list[list[np.random.Generator]]:
    """Every env's generators (per env: a list), for checkpoints."""
    from stable_baselines3.common.vec_env import DummyVecEnv

    from poc_env.envs.vector import SwarmVecEnv

    if isinstance(env, SwarmVecEnv):
        return [[g] for g in env.rngs]
    if isinstance(env, DummyVecEnv):
        out = []
        for e in env.envs:
            inner = e
            while not isinstance(inner, CentralEnv) and isinstance(inner, gym.Wrapper):
                inner = inner.env
            if not isinstance(inner, CentralEnv):
                raise ConfigError("env", e, "a CentralEnv (from agents.rl.train.make_env)")
            out.append(inner.generators())
        return out
    raise ConfigError("env", env, "a VecEnv from agents.rl.train.make_env")


_ENV_ARRAYS = ("priors", "_poc_scale", "_active", "_returns", "_lengths")


def env_snapshot(env: Any) -> dict[str, np.ndarray]:
    """A SwarmVecEnv's episodes in flight: simulator state and per-slot bookkeeping."""
    st = env.state
    out = {
        f"state.{f.name}": np.asarray(getattr(st, f.name))
        for f in dataclasses.fields(st)
        if getattr(st, f.name) is not None
    }
    out.update({name: np.asarray(getattr(env, name)) for name in _ENV_ARRAYS})
    return out


def restore_env_snapshot(env: Any, arrays: Any) -> None:
    """Inverse of :func:`env_snapshot`."""
    from poc_env.sim import core as sim

    names = set(arrays.files) if hasattr(arrays, "files") else set(arrays)
    state = {n[len("state.") :]: np.array(arrays[n]) for n in names if n.startswith("state.")}
    new = sim.State(**state)
    for name in _ENV_ARRAYS:
        value = np.array(arrays[name])
        if value.shape != np.shape(getattr(env, name)):
            raise ValueError(f"{name}: shape {value.shape} != {np.shape(getattr(env, name))}")
        setattr(env, name, value)
    env.state = new


# -- models ----------------------------------------------------------------------------------
def make_model(args: TrainArgs, env: VecEnv, tb_dir: Path | None) -> PPO:
    """A fresh PPO of ``args`` on ``env`` (CPU)."""
    from stable_baselines3 import PPO

    policy_kwargs: dict[str, Any] | None = None
    if args.recipe == "shared":
        from agents.rl.networks import SwarmExtractor

        policy, policy_kwargs = "MultiInputPolicy", {"features_extractor_class": SwarmExtractor}
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


def describe_space(space: Any) -> str:
    """A short description of a space: its kind and shapes."""
    from gymnasium import spaces

    if isinstance(space, spaces.Dict):
        return "Dict(" + ", ".join(f"{k}={describe_space(v)}" for k, v in space.items()) + ")"
    if isinstance(space, spaces.Box):
        return f"Box{tuple(space.shape)}"
    return repr(space)


def model_path(path: str | os.PathLike[str]) -> Path:
    """A model file: ``path`` itself, or in a run folder its ``model.zip`` or else its latest
    checkpoint."""
    p = Path(path)
    if p.is_dir():
        if (p / "model.zip").is_file():
            return p / "model.zip"
        latest = latest_checkpoint(p)
        if latest is not None:
            return latest[1]
        raise ConfigError(
            "checkpoint", str(p), "a model .zip file or a run folder with model.zip or checkpoints"
        )
    if not p.is_file():
        raise ConfigError("checkpoint", str(p), "an existing PPO model file (.zip)")
    return p


def _load_ppo(path: Path) -> PPO:
    from stable_baselines3 import PPO

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return PPO.load(path, device="cpu")
    except Exception as err:  # corrupt, truncated or foreign files fail in many ways
        raise ConfigError(
            "checkpoint",
            str(path),
            f"a readable stable-baselines3 PPO .zip (loading failed: {type(err).__name__}: {err})",
        ) from None


def load_policy(path: str | os.PathLike[str], env: VecEnv | None = None, **kwargs: Any) -> PPO:
    """Load a PPO model (CPU) and, given ``env``, attach it after checking that the model was
    trained for ``env``'s observation and action spaces (a ConfigError names both otherwise:
    another grid, number of UAVs or recipe). ``kwargs`` go to ``set_env`` (``force_reset``).

    Model files are pickle-based: load only trusted files."""
    from stable_baselines3 import PPO

    p = model_path(path)
    model = _load_ppo(p)
    if env is None:
        return model
    for what, mine, theirs in (
        ("observation", model.observation_space, env.observation_space),
        ("action", model.action_space, env.action_space),
    ):
        if mine != theirs:
            raise ConfigError(
                "checkpoint",
                str(p),
                f"a model for this env's {what} space {describe_space(theirs)}, but the file "
                f"was trained for {describe_space(mine)} (another grid, number of UAVs or "
                f"recipe?)",
            )
    if env.num_envs == model.n_envs:
        model.set_env(env, **kwargs)
    else:
        model = PPO.load(p, env=env, device="cpu", **kwargs)
    return model


# -- checkpoints -----------------------------------------------------------------------------
def _ckpt_files(folder: Path, step: int) -> tuple[Path, Path, Path]:
    return (
        folder / f"step_{step}.zip",
        folder / f"step_{step}.state.json",
        folder / f"step_{step}.env.npz",
    )


def save_checkpoint(model: BaseAlgorithm, env: VecEnv, run_dir: Path, keep: int = 0) -> Path:
    """Checkpoint ``model`` and ``env`` as ``checkpoints/step_<N>.*``, then point
    ``latest.json`` at it and prune to the newest ``keep`` (0: keep all). Call it at a rollout
    boundary (the env snapshot must match the model's last observation)."""
    from poc_env.envs.vector import SwarmVecEnv

    step = int(model.num_timesteps)
    folder = run_dir / "checkpoints"
    zpath, spath, epath = _ckpt_files(folder, step)
    write_atomic(zpath, model.save)
    state = {
        "step": step,
        "rng": global_rng_states(),
        "env_generators": [[g.bit_generator.state for g in gs] for gs in env_generators(env)],
    }
    _write_json(spath, state)
    has_env = isinstance(env, SwarmVecEnv) and env.state is not None
    if has_env:
        arrays = env_snapshot(env)

        def _savez(tmp: str) -> None:
            with open(tmp, "wb") as fh:
                np.savez(fh, allow_pickle=False, **arrays)

        write_atomic(epath, _savez)
    latest = {
        "step": step,
        "model": zpath.relative_to(run_dir).as_posix(),
        "state": spath.relative_to(run_dir).as_posix(),
        "env": epath.relative_to(run_dir).as_posix() if has_env else None,
        "time": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    _write_json(run_dir / "latest.json", latest)
    if keep > 0:
        steps = sorted(checkpoint_steps(run_dir))
        for old in steps[:-keep]:
            if old != step:
                for f in _ckpt_files(folder, old):
                    f.unlink(missing_ok=True)
    return zpath


def checkpoint_steps(run_dir: Path) -> list[int]:
    """Step counts of the checkpoints present in ``run_dir/checkpoints``."""
    out = []
    for f in (run_dir / "checkpoints").glob("step_*.zip"):
        num = f.name[len("step_") : -len(".zip")]
        if num.isdigit():
            out.append(int(num))
    return sorted(out)


def latest_checkpoint(run_dir: Path) -> tuple[int, Path, Path | None, Path | None] | None:
    """(step, model, state json or None, env npz or None) of the newest checkpoint: the one
    ``latest.json`` names, else the highest-numbered one on disk; None if there is none."""
    pointer = run_dir / "latest.json"
    if pointer.is_file():
        data = _read_json(pointer, "latest.json")
        try:
            step = int(data["step"])
            model = run_dir / data["model"]
            state = run_dir / data["state"]
            env = run_dir / data["env"] if data.get("env") else None
        except (KeyError, TypeError, ValueError):
            raise ConfigError(
                "latest.json", str(pointer), "a checkpoint pointer written by poc-env train"
            ) from None
        if model.is_file():
            return step, model, state if state.is_file() else None, env
    steps = checkpoint_steps(run_dir)
    if not steps:
        return None
    zpath, spath, epath = _ckpt_files(run_dir / "checkpoints", steps[-1])
    return (
        steps[-1],
        zpath,
        spath if spath.is_file() else None,
        epath if epath.is_file() else None,
    )


# -- callbacks -------------------------------------------------------------------------------
def _callbacks(
    run_dir: Path, env: VecEnv, args: TrainArgs, start_step: int
) -> tuple[BaseCallback, BaseCallback]:
    """(checkpointer, progress bar); built here so that importing this module stays light."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Checkpointer(BaseCallback):
        """Atomic checkpoints at rollout boundaries every ``checkpoint_every`` and at the end."""

        def __init__(self) -> None:
            super().__init__()
            self.last = start_step

        def _save(self) -> None:
            save_checkpoint(self.model, env, run_dir, args.keep_checkpoints)
            self.last = self.model.num_timesteps

        def _on_rollout_start(self) -> None:
            n, every = self.model.num_timesteps, args.checkpoint_every
            if n // every > self.last // every:
                self._save()

        def _on_step(self) -> bool:
            return True

        def _on_training_end(self) -> None:
            if self.model.num_timesteps != self.last:
                self._save()

    class Progress(BaseCallback):
        """tqdm bar over timesteps; postfix: mean POSC of the episodes in SB3's info buffer
        (the last 100 episode records); also logged to TensorBoard as rollout/posc_mean."""

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
                    desc=f"{args.algo} {args.recipe} {Path(run_dir).name}",
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

    return Checkpointer(), Progress()


# -- training --------------------------------------------------------------------------------
def _new_run_dir(args: TrainArgs, scenario_name: str) -> Path:
    if args.run_dir is not None:
        p = Path(args.run_dir)
        if (p / "config.json").exists():
            raise ConfigError(
                "run_dir", str(p), "a new or empty folder (this one holds a run: use --resume)"
            )
        return p
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = Path("runs") / f"{scenario_name}-{args.algo}-s{args.seed}-{stamp}"
    p, k = base, 1
    while p.exists():
        k += 1
        p = base.with_name(f"{base.name}-{k}")
    return p


def _seed_everything(seed: int) -> None:
    """The seeding block: everything random in a run derives from ``seed``."""
    import torch as th
    from stable_baselines3.common.utils import set_random_seed

    # ---- seeding ------------------------------------------------------------------------
    # envs: numpy SeedSequence(seed).spawn(n_envs), one generator (tree) per env, inside
    #       make_env (SwarmVecEnv / CentralEnv): priors, targets, thresholds, link failures;
    # torch: initial weights and PPO's action sampling;
    # SB3: python `random`, numpy's global generator (minibatch shuffling) and torch again;
    #      PPO(seed=seed) repeats set_random_seed and seeds the action space.
    th.manual_seed(seed)
    set_random_seed(seed)
    # --------------------------------------------------------------------------------------


def train(args: TrainArgs, callback: BaseCallback | None = None) -> Path:
    """Train according to ``args`` (or resume ``args.resume``); return the run folder.

    ``callback``: an extra SB3 callback, called after the checkpointer and the progress bar."""
    if args.resume is not None:
        return _resume(Path(args.resume), args.progress, callback)
    from poc_env.config import load_scenario, save_scenario

    sc = load_scenario(args.scenario, parse_overrides(args.overrides))
    run_dir = _new_run_dir(args, sc.name)
    args = dataclasses.replace(args, run_dir=str(run_dir))
    run_dir.mkdir(parents=True, exist_ok=True)
    _write_json(run_dir / "config.json", dataclasses.asdict(args))
    save_scenario(sc, run_dir / "scenario.yaml")
    sc = load_scenario(run_dir / "scenario.yaml")  # resumed runs build their env from it too
    return _run(args, sc, run_dir, callback, checkpoint=None)


def _resume(run_dir: Path, progress: bool, callback: BaseCallback | None) -> Path:
    from poc_env.config import load_scenario

    if not (run_dir / "config.json").is_file():
        raise ConfigError(
            "resume",
            str(run_dir),
            "a run folder written by poc-env train (with config.json, scenario.yaml and "
            "checkpoints/)",
        )
    args = TrainArgs.from_dict(_read_json(run_dir / "config.json", "config.json"), "config.json")
    args = dataclasses.replace(args, run_dir=str(run_dir), resume=None, progress=progress)
    ck = latest_checkpoint(run_dir)
    if ck is None:
        raise ConfigError(
            "resume",
            str(run_dir),
            "a run with at least one checkpoint in checkpoints/ (this one has none: it stopped "
            "before its first checkpoint; start it again)",
        )
    sc = load_scenario(run_dir / "scenario.yaml")
    return _run(args, sc, run_dir, callback, checkpoint=ck)


def _run(
    args: TrainArgs,
    sc: Scenario,
    run_dir: Path,
    callback: BaseCallback | None,
    checkpoint: tuple[int, Path, Path | None, Path | None] | None,
) -> Path:
    import torch as th
    from stable_baselines3.common.callbacks import CallbackList

    threads = th.get_num_threads()
    th.set_num_threads(args.torch_threads)
    try:
        _seed_everything(args.seed)
        env = make_env(args, sc)
        if checkpoint is None:
            model = make_model(args, env, run_dir / "tb")
        else:
            model = _restore(checkpoint, env, run_dir)
        start = int(model.num_timesteps)
        remaining = args.total_timesteps - start
        if remaining > 0:
            ckpt, bar = _callbacks(run_dir, env, args, start)
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
                    f"poc-env train --resume {run_dir}",
                    file=sys.stderr,
                )
                raise
            finally:
                bar.close()  # type: ignore[attr-defined]
        write_atomic(run_dir / "model.zip", model.save)
        env.close()
    finally:
        th.set_num_threads(threads)
    return run_dir


def _restore(
    checkpoint: tuple[int, Path, Path | None, Path | None], env: VecEnv, run_dir: Path
) -> PPO:
    """Load a checkpoint for resuming: model, generators and (shared) the episodes in flight."""
    step, zpath, spath, epath = checkpoint
    model = load_policy(zpath, env, force_reset=False)
    model.tensorboard_log = str(run_dir / "tb")
    in_flight = False
    if spath is not None:
        state = _read_json(spath, "checkpoint state")
        set_global_rng_states(state["rng"])
        gens = env_generators(env)
        saved = state["env_generators"]
        if len(saved) == len(gens):
            for gs, ss in zip(gens, saved):
                for g, s in zip(gs, ss):
                    g.bit_generator.state = s
        else:
            warnings.warn(
                f"{spath}: {len(saved)} env generators for {len(gens)} envs; not restored",
                stacklevel=2,
            )
        if epath is not None:
            try:
                with np.load(epath, allow_pickle=False) as arrays:
                    restore_env_snapshot(env, arrays)
                in_flight = True
            except (OSError, KeyError, TypeError, ValueError) as err:
                warnings.warn(f"{epath}: episodes in flight not restored ({err})", stacklevel=2)
    if not in_flight:
        model._last_obs = None  # type: ignore[assignment]  # -> env.reset() in learn()
    if model.num_timesteps != step:
        raise ConfigError(
            "checkpoint", str(zpath), f"a model at step {step} (it holds {model.num_timesteps})"
        )
    return model


# -- evaluation through the Policy interface -------------------------------------------------
_MODELS: dict[tuple[str, int, int], Any] = {}


def _cached_model(path: Path) -> PPO:
    st = path.stat()
    key = (str(path.resolve()), st.st_mtime_ns, st.st_size)
    if key not in _MODELS:
        if len(_MODELS) >= 8:
            _MODELS.clear()
        _MODELS[key] = _load_ppo(path)
    return _MODELS[key]


def _flat(obs: Any) -> np.ndarray:
    """One agent's flat observation (raster then vector, as ``obs_type="flat"``)."""
    if isinstance(obs, dict):
        return np.concatenate([np.ravel(obs["raster"]), np.ravel(obs["vector"])]).astype(np.float32)
    return np.asarray(obs, dtype=np.float32)


def _flat_space(space: Any) -> Any:
    from gymnasium import spaces

    if isinstance(space, spaces.Dict):
        ras, vec = space["raster"], space["vector"]
        assert isinstance(ras, spaces.Box) and isinstance(vec, spaces.Box)
        low = np.concatenate([ras.low.ravel(), vec.low])
        high = np.concatenate([ras.high.ravel(), vec.high])
        return spaces.Box(low, high, dtype=np.float32)
    return space


def _split(env: Any, obs: Any) -> tuple[np.ndarray, np.ndarray]:
    """(raster, vector) of one agent's ``dict`` or ``flat`` observation."""
    from poc_env.sim.observations import RASTER_CHANNELS, VECTOR_SIZE

    if isinstance(obs, dict):
        return np.asarray(obs["raster"]), np.asarray(obs["vector"])
    flat = np.asarray(obs)
    g = env.params.grid
    return flat[:-VECTOR_SIZE].reshape(RASTER_CHANNELS, g.ny, g.nx), flat[-VECTOR_SIZE:]


class PPOPolicy(Policy):
    """A PPO checkpoint flying through the :class:`agents.policies.base.Policy` interface.

    ``PPOPolicy(path)`` loads ``path`` (a ``.zip``, or a run folder: its ``model.zip`` or latest
    checkpoint) on the CPU; :meth:`reset` checks it against the env and picks the recipe from
    the model's observation space: the per-agent space (shared recipe: the live agents'
    observations go through ``model.predict`` as one batch) or the joint flat space (central:
    finished agents keep their last observation, as in ``UAVSearch-v0``). Actions are
    deterministic by default. ``agents.experiments.evaluate`` makes one from ``"ppo:PATH"``::

        from agents.rl.train import PPOPolicy
        policy = PPOPolicy("runs/.../model.zip"); policy.reset(env, seed=0)
        actions, _ = policy.predict(observations)

    Model files are pickle-based: load only trusted files.
    """

    def __init__(self, path: str | os.PathLike[str], name: str | None = None) -> None:
        self.path = model_path(path)
        self.name = name or f"ppo:{path}"
        self.model = _cached_model(self.path)
        self.mode = ""
        self._last: dict[str, np.ndarray] = {}

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        from gymnasium import spaces

        agents = list(env.possible_agents)
        agent_space = env.observation_space(agents[0])
        joint = _flat_space(agent_space)
        assert isinstance(joint, spaces.Box)
        joint = spaces.Box(
            np.tile(joint.low, len(agents)), np.tile(joint.high, len(agents)), dtype=np.float32
        )
        m_obs, m_act = self.model.observation_space, self.model.action_space
        one_act = spaces.Box(-1.0, 1.0, (3,), np.float32)
        joint_act = spaces.Box(-1.0, 1.0, (3 * len(agents),), np.float32)
        from agents.rl import pilot

        if m_obs == pilot.OBSERVATION_SPACE and m_act == pilot.ACTION_SPACE:
            self.mode = "pilot"
            self._features = pilot.PilotFeatures(env.params)
        elif m_obs == agent_space and m_act == one_act:
            self.mode = "shared"
        elif m_obs == _flat_space(agent_space) and m_act == one_act:
            self.mode = "shared_flat"
        elif m_obs == joint and m_act == joint_act:
            self.mode = "central"
        else:
            raise ConfigError(
                "checkpoint",
                str(self.path),
                f"a model for this env ({len(agents)} UAVs; per-agent observation "
                f"{describe_space(agent_space)}, joint {describe_space(joint)}), but the file "
                f"was trained for observation {describe_space(m_obs)} and action "
                f"{describe_space(m_act)} (another grid, number of UAVs or recipe?)",
            )
        self._agents = agents
        self._last = {}

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        if not observations:
            return {}, state
        live = [a for a in self._agents if a in observations]
        if self.mode == "central":
            self._last.update({a: _flat(observations[a]) for a in live})
            joint = np.concatenate([self._last[a] for a in self._agents])
            act, _ = self.model.predict(joint, deterministic=deterministic)
            act = np.asarray(act, dtype=np.float32).reshape(len(self._agents), 3)
            return {a: act[self._agents.index(a)] for a in live}, state
        batch: Any
        if self.mode == "pilot":
            from agents.rl.pilot import pilot_actions

            ras, vec = zip(*(_split(self.env, observations[a]) for a in live), strict=True)
            k = np.array([self._agents.index(a) for a in live])
            feats = self._features(np.stack(ras), np.stack(vec), k)
            act, _ = self.model.predict(feats, deterministic=deterministic)
            inc = pilot_actions(self.env.params, np.stack(vec), np.asarray(act), k)
            return {a: inc[j] for j, a in enumerate(live)}, state
        if self.mode == "shared":
            batch = {
                k: np.stack([np.asarray(observations[a][k]) for a in live])
                for k in ("raster", "vector")
            }
        else:
            batch = np.stack([_flat(observations[a]) for a in live])
        act, _ = self.model.predict(batch, deterministic=deterministic)
        act = np.asarray(act, dtype=np.float32).reshape(len(live), 3)
        return {a: act[k] for k, a in enumerate(live)}, state


# -- benchmark -------------------------------------------------------------------------------
def bench_train(
    scenario: str = "paper_6_2",
    recipe: str = "shared",
    n_envs: int | None = None,
    iterations: int = 2,
    seed: int = 0,
) -> dict[str, float]:
    """PPO transitions per second with the default TrainArgs (the shipped network and
    hyper-parameters) and where the time goes, after one warm-up iteration; one torch thread.

    Returns ``{"transitions_per_s", "env_share", "rollout_net_share", "update_share",
    "wall_s", "transitions"}``; transitions are agent transitions (a central joint step counts
    once per UAV). env = ``VecEnv.step_wait`` (simulator, observations, rewards,
    resets), rollout_net = the rest of ``collect_rollouts`` (policy forward passes, buffer),
    update = ``PPO.train`` (forward and backward passes over the rollout)."""
    import torch as th

    from poc_env.config import load_scenario

    threads = th.get_num_threads()
    th.set_num_threads(1)
    try:
        base = TrainArgs(scenario=scenario, recipe=recipe, seed=seed, progress=False)
        if n_envs is not None:
            base = dataclasses.replace(base, n_envs=n_envs)
        _seed_everything(seed)
        env = make_env(base, load_scenario(scenario))
        model = make_model(base, env, None)
        clock = {"env": 0.0, "collect": 0.0, "train": 0.0}

        def timed(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
            def wrapper(*a: Any, **kw: Any) -> Any:
                t0 = time.perf_counter()
                try:
                    return fn(*a, **kw)
                finally:
                    clock[name] += time.perf_counter() - t0

            return wrapper

        env.step_wait = timed("env", env.step_wait)  # type: ignore[method-assign]
        model.collect_rollouts = timed("collect", model.collect_rollouts)  # type: ignore[method-assign]
        model.train = timed("train", model.train)  # type: ignore[method-assign]
        rollout = base.n_steps * env.num_envs
        model.learn(rollout)  # warm-up: allocations, first-call overheads
        for k in clock:
            clock[k] = 0.0
        t0 = time.perf_counter()
        model.learn(iterations * rollout, reset_num_timesteps=False)
        wall = time.perf_counter() - t0
    finally:
        th.set_num_threads(threads)
    n = iterations * rollout
    per_step = 1 if recipe in ("shared", "pilot") else load_scenario(scenario).n_uavs
    return {
        "transitions_per_s": n * per_step / wall,
        "env_share": clock["env"] / wall,
        "rollout_net_share": (clock["collect"] - clock["env"]) / wall,
        "update_share": clock["train"] / wall,
        "wall_s": wall,
        "transitions": float(n * per_step),
    }


def main(argv: Sequence[str] | None = None) -> dict[str, float]:
    """``poc-env bench train``: print the figures of :func:`bench_train`."""
    ap = argparse.ArgumentParser(
        prog="poc-env bench train",
        description="PPO training speed: agent transitions/s and env vs network time shares",
    )
    ap.add_argument("--scenario", default="paper_6_2")
    ap.add_argument("--recipe", default="shared", choices=RECIPES)
    ap.add_argument("--n-envs", type=int, default=None, help="default: TrainArgs.n_envs")
    ap.add_argument("--iterations", type=int, default=2, help="timed PPO iterations")
    ns = ap.parse_args(argv)
    r = bench_train(ns.scenario, ns.recipe, ns.n_envs, ns.iterations)
    d = TrainArgs()
    print(
        f"PPO {ns.recipe} on {ns.scenario}: {r['transitions_per_s']:,.0f} agent transitions/s "
        f"({int(r['transitions'])} in {r['wall_s']:.1f} s; n_steps={d.n_steps}, "
        f"batch_size={d.batch_size}, n_epochs={d.n_epochs}, 1 torch thread)"
    )
    print(
        f"time shares: env {r['env_share']:.0%}, network in rollouts "
        f"{r['rollout_net_share']:.0%}, PPO updates {r['update_share']:.0%} "
        f"(network total {r['rollout_net_share'] + r['update_share']:.0%})",
        flush=True,
    )
    return r


if __name__ == "__main__":  # pragma: no cover
    main()
    sys.exit(0)


# -- training curve --------------------------------------------------------------------------
def training_curve(run_dir: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Steps and values of ``rollout/posc_mean`` and ``rollout/ep_rew_mean`` from a run's
    TensorBoard logs."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    logs = sorted(Path(run_dir).glob("tb/*/events.out.tfevents.*"))
    if not logs:
        raise ConfigError("run_dir", str(run_dir), "a run folder with TensorBoard logs (tb/)")
    out: dict[str, np.ndarray] = {}
    for log in logs:
        acc = EventAccumulator(str(log), size_guidance={"scalars": 0})
        acc.Reload()
        for tag in ("rollout/posc_mean", "rollout/ep_rew_mean"):
            if tag in acc.Tags()["scalars"]:
                ev = acc.Scalars(tag)
                out[tag] = np.array([[e.step, e.value] for e in ev], dtype=float)
    if "rollout/posc_mean" not in out:
        raise ConfigError("run_dir", str(run_dir), "a run whose logs hold rollout/posc_mean")
    return out


def plot_training_curve(
    run_dir: str | os.PathLike[str], path: str | os.PathLike[str], until: int | None = None
) -> Path:
    """PNG of the mean POSC of recent training episodes against timesteps (up to ``until``)."""
    from poc_env.viz.plots import _figure, save_figure_atomic

    data = training_curve(run_dir)["rollout/posc_mean"]
    if until is not None:
        data = data[data[:, 0] <= until]
    fig = _figure((7.0, 4.0))
    ax = fig.add_subplot()
    ax.plot(data[:, 0] / 1e6, data[:, 1], lw=0.8, alpha=0.5, color="C0", label="per rollout")
    k = max(1, len(data) // 40)
    smooth = np.convolve(data[:, 1], np.ones(k) / k, mode="valid")
    ax.plot(data[k - 1 :, 0] / 1e6, smooth, color="C0", lw=2, label=f"mean of {k} rollouts")
    ax.set_xlabel("agent transitions (millions)")
    ax.set_ylabel("POSC of recent training episodes")
    ax.set_title(f"PPO training: {Path(run_dir).name}")
    ax.legend()
    return save_figure_atomic(fig, path)
