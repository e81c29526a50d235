"""Recorded episodes of the registered tasks: the versioning rule made mechanical.

For every task id of :data:`poc_env.tasks.TASKS` one episode is flown through the public API,
``gymnasium.make(task_id)``, from ``reset(seed=RESET_SEED)`` with fixed actions (drawn once from
``numpy.random.default_rng(ACTION_SEED)`` uniformly in the task's action space and stored with
the recording), for :func:`steps_of` steps or until the episode ends. Everything the agent sees
is stored: the observation after reset and after every step, the reward, ``terminated``,
``truncated`` and every numeric info key, as arrays stacked over time (float32 where the
environment gives float32, the info floats and rewards as float64) in one compressed ``.npz``
per task (:func:`path_of`).

``tests/envs/test_recorded.py`` replays every recording and compares it with a cross-CPU
tolerance; a registered task without a recording fails it. Any change to an observation, a
reward, the dynamics or the episode end therefore fails the test until the task's version is
bumped (a new id, recorded afresh) -- old ids keep their behaviour.

Record (atomically: a temporary file in the same folder, then renamed)::

    python -m poc_env.recorded --task poc_env/UAVSearch-Small-Heading-v0   # or --all
    poc-env record --all --dir tests/recorded
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from poc_env import tasks

#: The seed of the one ``reset`` of every recorded episode.
RESET_SEED = 2024
#: The seed of the generator the recorded actions are drawn from (once; they are stored).
ACTION_SEED = 7
#: The recorded actions (:func:`draw_actions`): eq. 19 increments (dv, d alpha, d beta) of this
#: size around zero (the UAVs start level, heading for the grid's centre; a small pitch noise
#: still crashes some of them: the episode end is recorded too); for the autopilot levels a
#: fixed heading or waypoint per UAV drawn uniformly once, jittered by this much each step.
NOISE_INCREMENTS = (0.3, 0.3, 0.03)
NOISE_TARGET = 0.3
#: Steps of a recorded episode: the ``small`` scenario's run to their end (81 steps at most),
#: the others 50 steps (past the transit: the sensors sweep the grid for 30 of them).
MAX_STEPS = {"small": 200}
DEFAULT_STEPS = 40
#: The folder of the recordings in the source tree.
DEFAULT_DIR = Path(__file__).resolve().parents[1] / "tests" / "recorded"


def steps_of(task_id: str) -> int:
    """The most steps the recorded episode of ``task_id`` runs for."""
    return MAX_STEPS.get(tasks.get_task(task_id).scenario, DEFAULT_STEPS)


def path_of(task_id: str, directory: str | os.PathLike | None = None) -> Path:
    """The recording of ``task_id``: ``<directory>/<id without namespace>.npz``."""
    name = tasks.get_task(task_id).id.split("/", 1)[1]
    return Path(DEFAULT_DIR if directory is None else directory) / f"{name}.npz"


def draw_actions(task_id: str) -> np.ndarray:
    """The fixed actions ``(steps_of(task_id), action size)`` float32 of a new recording."""
    import gymnasium

    env = gymnasium.make(task_id)
    try:
        shape = env.action_space.shape
        assert shape is not None
    finally:
        env.close()
    task = tasks.get_task(task_id)
    rng = np.random.default_rng(ACTION_SEED)
    noise = rng.uniform(-1.0, 1.0, (steps_of(task_id), *shape))
    if task.control == "increments":  # small increments around the initial flight to the grid
        actions = (noise.reshape(len(noise), -1, 3) * NOISE_INCREMENTS).reshape(noise.shape)
    else:  # a fixed direction / point per UAV, jittered
        actions = rng.uniform(-1.0, 1.0, shape) + NOISE_TARGET * noise
    wide = recorded_scale(task_id)  # a version whose rule acts outside the Box: drawn wider
    return np.clip(actions * wide, -wide, wide).astype(np.float32)


def recorded_scale(task_id: str) -> float:
    """How much wider than the Box the recorded actions of ``task_id`` are drawn: its version's
    :attr:`poc_env.spec.TaskVersion.recorded_scale` (1: inside the Box)."""
    from poc_env import spec

    task = tasks.get_task(task_id)
    part = next(text for text, level in tasks.CONTROL_NAMES.items() if level == task.control)
    return next(v.recorded_scale for v in spec.versions_of(part) if v.version == task.version)


def _info_dtype(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.dtype
    if isinstance(value, bool | np.bool_):
        return np.bool_
    if isinstance(value, int | np.integer):
        return np.int64
    return np.float64


def run(task_id: str, actions: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Fly the recorded episode of ``task_id`` with ``actions`` (default :func:`draw_actions`)
    until they run out or the episode ends; the arrays of a recording (module docstring)."""
    import gymnasium

    if actions is None:
        actions = draw_actions(task_id)
    env = gymnasium.make(task_id)
    try:
        obs, info = env.reset(seed=RESET_SEED)
        observations, infos = [obs], [info]
        rewards, terminated, truncated = [], [], []
        for action in actions:
            obs, reward, term, trunc, info = env.step(action)
            observations.append(obs)
            infos.append(info)
            rewards.append(reward)
            terminated.append(term)
            truncated.append(trunc)
            if term or trunc:
                break
    finally:
        env.close()
    t = len(rewards)
    out: dict[str, np.ndarray] = {
        "task": np.array(tasks.get_task(task_id).id),
        "reset_seed": np.array(RESET_SEED),
        "actions": np.asarray(actions[:t], dtype=np.float32),
        "observation": np.stack(observations),
        "reward": np.asarray(rewards, dtype=np.float64),
        "terminated": np.asarray(terminated, dtype=bool),
        "truncated": np.asarray(truncated, dtype=bool),
    }
    for key, value in infos[0].items():
        out[f"info_{key}"] = np.stack([np.asarray(i[key], dtype=_info_dtype(value)) for i in infos])
    return out


def load(task_id: str, directory: str | os.PathLike | None = None) -> dict[str, np.ndarray]:
    """The stored recording of ``task_id`` (FileNotFoundError if it was never recorded)."""
    with np.load(path_of(task_id, directory), allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


def replay(recording: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The episode of ``recording`` flown again today with its stored actions."""
    return run(str(recording["task"]), recording["actions"])


def write(task_id: str, directory: str | os.PathLike | None = None) -> Path:
    """Record ``task_id`` and write it atomically (:func:`poc_env.io.atomic_path`)."""
    from poc_env.io import atomic_path

    path = path_of(task_id, directory)
    arrays = run(task_id)
    with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]
    return path


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The recorder's options (``python -m poc_env.recorded`` and ``poc-env record``)."""
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--task", action="append", help="a registered task id (repeatable)")
    which.add_argument("--all", action="store_true", help="every registered task")
    p.add_argument("--dir", default=None, help=f"output folder (default {DEFAULT_DIR})")


def main_args(args: argparse.Namespace) -> int:
    """Record the tasks ``args`` name (:func:`add_arguments`), one line per file written."""
    from poc_env.errors import ConfigError
    from poc_env.io import atomic_dir, check_out

    ids = list(tasks.TASKS) if args.all else [tasks.get_task(t).id for t in args.task]
    if args.dir is None and not DEFAULT_DIR.is_dir():  # a wheel install: no source tree
        raise ConfigError(
            "dir",
            None,
            f"--dir FOLDER (the default {DEFAULT_DIR} is the "
            "tests/recorded/ folder of a source checkout; this install has none)",
        )
    folder = Path(DEFAULT_DIR if args.dir is None else args.dir)
    check_out("dir", folder, "folder")  # before any episode is flown
    lines = []
    with atomic_dir(folder, "dir") as stage:  # every recording in place, or none
        for tid in ids:
            path = write(tid, stage)
            lines.append(f"{tid}: {folder / path.name} ({path.stat().st_size} bytes)")
    print(*lines, sep="\n")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m poc_env.recorded", description=__doc__)
    add_arguments(p)
    return main_args(p.parse_args(argv))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
