"""Checkpoints of a training run: atomic save, load, resume, and the generator states.

Files in the run folder
-----------------------
::

    checkpoints/step_<N>.zip         the model after N timesteps (SB3 zip: weights, Adam state, ...)
    checkpoints/step_<N>.state.json  generator states: every env's, torch's, numpy's, python's
    checkpoints/step_<N>.env.npz     shared and pilot recipes: the simulator state (episodes in
                                     flight)
    latest.json                      pointer to the newest complete checkpoint

Every file is written through :func:`poc_env.io.atomic_path` (a temporary file beside it,
flushed to disk, renamed over its name), and ``latest.json`` only after the checkpoint's files
are in place, so a run killed at any moment leaves complete files. Checkpoints are taken at
rollout boundaries (after a PPO update, before the next rollout), when the env's state matches
the model's last observation.

What a resume restores
----------------------
With the vector envs of the shared and pilot recipes, everything: the weights and Adam state,
SB3's last observation and episode-start flags, the simulator state of every env (episodes in
flight), each env's generator, and the global torch, numpy and python generators (PPO samples
actions from torch's and shuffles minibatches with numpy's). The resumed run then trains
exactly as the uninterrupted run would have, on the same torch build and thread count. With
the central recipe the generators are restored but the episodes in flight are not (they live
in gymnasium wrappers): the resumed run starts fresh episodes from each env's saved generator.
Wall-clock fields (``episode["t"]``, SB3's ``time/fps``) never match.

Model files are pickle-based
----------------------------
SB3 ``.zip`` files hold cloudpickled objects (schedules, policy classes, the last
observation): loading one runs code from it. Load only files you trust (your own runs, the
checkpoint shipped in this repository). The ``.state.json`` / ``.env.npz`` companions are
pickle-free (JSON, ``np.load(allow_pickle=False)``).
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import json
import os
import random
import time
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from poc_env.errors import ConfigError
from poc_env.io import atomic_path, write_text_atomic

if TYPE_CHECKING:
    from stable_baselines3 import PPO
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import VecEnv


class Checkpoint(NamedTuple):
    """The files of one checkpoint (``state`` and ``env`` may be missing: None)."""

    step: int
    model: Path
    state: Path | None
    env: Path | None


def write_json(path: Path, data: Any) -> Path:
    """Write ``data`` as indented JSON to ``path`` atomically."""
    return write_text_atomic(path, json.dumps(data, indent=1) + "\n")


def read_json(path: Path, what: str) -> Any:
    """The JSON in ``path``; a ConfigError names ``what`` if it cannot be read, is not JSON,
    is nested too deep or holds NaN / Infinity (:func:`poc_env.io.read_json`)."""
    from poc_env.io import read_json as _read

    return _read(path, what)


# -- generators and episodes in flight --------------------------------------------------------
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


def env_generators(env: VecEnv) -> list[list[np.random.Generator]]:
    """Every env's generators (per env: a list), for checkpoints.

    ``env`` is a :class:`~poc_env.envs.vector.SwarmVecEnv` (one generator per env), a
    ``DummyVecEnv`` whose envs offer ``generators()``
    (:class:`poc_env.agents.rl.train.CentralEnv`) or a
    :class:`~poc_env.agents.rl.mixed.MixedVecEnv` of SwarmVecEnvs."""
    from stable_baselines3.common.vec_env import DummyVecEnv

    from poc_env.envs.vector import SwarmVecEnv

    if isinstance(env, SwarmVecEnv):
        return [[g] for g in env.rngs]
    if isinstance(env, DummyVecEnv):
        out = []
        for e in env.envs:
            try:
                generators = e.get_wrapper_attr("generators")
            except AttributeError:
                raise ConfigError(
                    "env", e, "an env with generators() (poc_env.agents.rl.train.CentralEnv)"
                ) from None
            out.append(list(generators()))
        return out
    parts = getattr(env, "parts", None)
    if parts is not None:  # poc_env.agents.rl.mixed.MixedVecEnv: its parts' generators in order
        return [gs for p in parts for gs in env_generators(p)]
    raise ConfigError("env", env, "a VecEnv from poc_env.agents.rl.train.make_env")


#: A SwarmVecEnv's arrays beside its state, by their names in ``step_<N>.env.npz``: the
#: engine's episode priors and POC scales, the adapter's slot bookkeeping.
_ENV_ARRAYS = ("priors", "_poc_scale", "_active", "_returns", "_lengths")


def _env_array(env: Any, name: str) -> np.ndarray:
    if name == "priors":
        return env.engine.priors
    if name == "_poc_scale":
        return env.engine.poc_scale
    return getattr(env, name)


def env_snapshot(env: Any) -> dict[str, np.ndarray]:
    """A SwarmVecEnv's episodes in flight: simulator state and per-slot bookkeeping."""
    st = env.state
    out = {
        f"state.{f.name}": np.asarray(getattr(st, f.name))
        for f in dataclasses.fields(st)
        if getattr(st, f.name) is not None
    }
    out.update({name: np.array(_env_array(env, name)) for name in _ENV_ARRAYS})
    return out


def restore_env_snapshot(env: Any, arrays: Any) -> None:
    """Inverse of :func:`env_snapshot`."""
    from poc_env.sim import core as sim

    names = set(arrays.files) if hasattr(arrays, "files") else set(arrays)
    state = {n[len("state.") :]: np.array(arrays[n]) for n in names if n.startswith("state.")}
    new = sim.State(**state)
    for name in _ENV_ARRAYS:
        value = np.array(arrays[name])
        dst = _env_array(env, name)
        if value.shape != np.shape(dst):
            raise ValueError(f"{name}: shape {value.shape} != {np.shape(dst)}")
        if name in ("priors", "_poc_scale"):
            dst[...] = value  # the engine's arrays, in place
        else:
            setattr(env, name, value)
    env.state = new


# -- model files -------------------------------------------------------------------------------
def describe_space(space: Any) -> str:
    """A short description of a space: its kind and shapes."""
    from gymnasium import spaces

    if isinstance(space, spaces.Dict):
        return "Dict(" + ", ".join(f"{k}={describe_space(v)}" for k, v in space.items()) + ")"
    if isinstance(space, spaces.Box):
        return f"Box{tuple(space.shape)}"
    return repr(space)


def shipped_checkpoints() -> list[str]:
    """Names of the PPO checkpoints shipped inside the package (``agents/checkpoints``)."""
    folder = importlib.resources.files("poc_env.agents").joinpath("checkpoints")
    return sorted(f.name[:-4] for f in folder.iterdir() if f.name.endswith(".zip"))


def model_path(path: str | os.PathLike[str]) -> Path:
    """A model file: ``path`` itself, in a run folder its ``model.zip`` or else its latest
    checkpoint, or the name of a shipped checkpoint (:func:`shipped_checkpoints`, e.g.
    ``ppo_pilot_paper_6_2``), read from the installed package."""
    p = Path(path)
    if not p.exists() and str(path) in shipped_checkpoints():
        ref = importlib.resources.files("poc_env.agents").joinpath("checkpoints", f"{path}.zip")
        return Path(str(ref))
    if p.is_dir():
        if (p / "model.zip").is_file():
            return p / "model.zip"
        latest = latest_checkpoint(p)
        if latest is not None:
            return latest.model
        raise ConfigError(
            "checkpoint", str(p), "a model .zip file or a run folder with model.zip or checkpoints"
        )
    if not p.is_file():
        raise ConfigError(
            "checkpoint",
            str(p),
            "an existing PPO model file (.zip), a run folder, or a shipped checkpoint: "
            + ", ".join(shipped_checkpoints()),
        )
    return p


#: Where the shared recipe's extractor lived before the layout by role. Its checkpoints name
#: that module in their cloudpickled ``policy_kwargs``; they are loaded with the class from
#: its current module instead.
_OLD_NETWORKS = "agents.networks"


def _load_ppo(path: Path, **kwargs: Any) -> PPO:
    from stable_baselines3 import PPO

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                return PPO.load(path, device="cpu", **kwargs)
            except ModuleNotFoundError as err:
                if err.name != _OLD_NETWORKS:
                    raise
                from poc_env.agents.rl.networks import SwarmExtractor

                kw = {"features_extractor_class": SwarmExtractor}
                custom = {"policy_kwargs": kw}
                return PPO.load(path, device="cpu", custom_objects=custom, **kwargs)
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
        model = _load_ppo(p, env=env, **kwargs)
    return model


# -- checkpoints -------------------------------------------------------------------------------
def _files(folder: Path, step: int) -> tuple[Path, Path, Path]:
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
    zpath, spath, epath = _files(folder, step)
    state = {
        "step": step,
        "rng": global_rng_states(),
        "env_generators": [[g.bit_generator.state for g in gs] for gs in env_generators(env)],
    }
    with atomic_path(zpath, suffix=".zip") as tmp:
        model.save(tmp)
    # a SwarmVecEnv's episodes in flight (not a residual env's: its followers are not saved)
    has_env = isinstance(env, SwarmVecEnv) and env.state is not None
    has_env = has_env and getattr(env, "snapshots", True)
    if has_env:
        with atomic_path(epath, suffix=".npz") as tmp, open(tmp, "wb") as fh:
            np.savez(fh, allow_pickle=False, **env_snapshot(env))
    # the state file is written last: its presence marks the checkpoint complete
    write_json(spath, {**state, "env": has_env})
    latest = {
        "step": step,
        "model": zpath.relative_to(run_dir).as_posix(),
        "state": spath.relative_to(run_dir).as_posix(),
        "env": epath.relative_to(run_dir).as_posix() if has_env else None,
        "time": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    write_json(run_dir / "latest.json", latest)
    if keep > 0:
        for old in checkpoint_steps(run_dir)[:-keep]:
            if old != step:
                for f in _files(folder, old):
                    f.unlink(missing_ok=True)
    return zpath


def checkpoint_steps(run_dir: Path) -> list[int]:
    """Step counts of the checkpoints present in ``run_dir/checkpoints``, ascending."""
    out = []
    for f in (run_dir / "checkpoints").glob("step_*.zip"):
        num = f.name[len("step_") : -len(".zip")]
        if num.isdigit():
            out.append(int(num))
    return sorted(out)


def _complete(run_dir: Path, step: int) -> Checkpoint | None:
    """Checkpoint ``step`` if all its files are there, else None. The state file is written last
    (:func:`save_checkpoint`), so a model without it is a checkpoint interrupted mid-way."""
    zpath, spath, epath = _files(run_dir / "checkpoints", step)
    if not (zpath.is_file() and spath.is_file()):
        return None
    try:
        wants_env = bool(read_json(spath, "checkpoint state").get("env", False))
    except (ConfigError, AttributeError):
        return None
    if wants_env and not epath.is_file():
        return None
    return Checkpoint(step, zpath, spath, epath if epath.is_file() else None)


def latest_checkpoint(run_dir: Path) -> Checkpoint | None:
    """The newest complete checkpoint (model, state and env snapshot all present); None if there
    is none.

    ``latest.json`` names the newest one; it must point inside ``run_dir/checkpoints``. A
    checkpoint cut off by a kill (a model file without its state) is skipped with a warning:
    resuming from it would restore the weights without the generators and silently diverge.
    """
    pointer = run_dir / "latest.json"
    folder = (run_dir / "checkpoints").resolve()
    if pointer.is_file():
        data = read_json(pointer, "latest.json")
        try:
            step = int(data["step"])
            named = [(run_dir / data[k]).resolve() for k in ("model", "state")]
        except (KeyError, TypeError, ValueError):
            raise ConfigError(
                "latest.json", str(pointer), "a checkpoint pointer written by poc-env train"
            ) from None
        if any(p.parent != folder for p in named) or named[0] != _files(folder, step)[0]:
            raise ConfigError(
                "latest.json",
                {k: data.get(k) for k in ("model", "state")},
                f"paths of checkpoints/step_{step}.* inside the run folder {run_dir}",
            )
        found = _complete(run_dir, step)
        if found is not None and all(found.step >= s for s in checkpoint_steps(run_dir)):
            return found
    steps = checkpoint_steps(run_dir)
    for step in reversed(steps):
        found = _complete(run_dir, step)
        if found is not None:
            return found
        warnings.warn(
            f"{run_dir}/checkpoints/step_{step}: incomplete (interrupted while being written); "
            "skipped",
            stacklevel=2,
        )
    return None


def restore_checkpoint(checkpoint: Checkpoint, env: VecEnv, run_dir: Path) -> PPO:
    """Load a checkpoint for resuming on ``env``: the model, every generator and (vector envs)
    the episodes in flight. Without the latter, SB3 resets ``env`` when training resumes."""
    step, zpath, spath, epath = checkpoint
    model = load_policy(zpath, env, force_reset=False)
    model.tensorboard_log = str(run_dir / "tb")
    in_flight = False
    if spath is not None:
        state = read_json(spath, "checkpoint state")
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


def checkpoint_callback(
    run_dir: Path, env: VecEnv, every: int, keep: int, start_step: int
) -> BaseCallback:
    """An SB3 callback that checkpoints at the first rollout boundary after every ``every``
    timesteps (counted from 0, so a resumed run keeps the same checkpoint steps) and at the end
    of training, keeping the newest ``keep``."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Checkpointer(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.last = start_step

        def _save(self) -> None:
            save_checkpoint(self.model, env, run_dir, keep)
            self.last = self.model.num_timesteps

        def _on_rollout_start(self) -> None:
            if self.model.num_timesteps // every > self.last // every:
                self._save()

        def _on_step(self) -> bool:
            return True

        def _on_training_end(self) -> None:
            if self.model.num_timesteps != self.last:
                self._save()

    return Checkpointer()
