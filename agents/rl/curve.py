"""The training curve of a run (``poc-env curve``): mean POSC of recent episodes over timesteps.

Read from the run's TensorBoard logs, ``tb/<name>_<K>/``: an SB3 run's progress callback
(:func:`poc_env.agents.rl.train.train`) records ``rollout/posc_mean`` (the mean POSC of the last
100 finished episodes) once per rollout in ``tb/ppo_K/``; an RLlib run
(:func:`poc_env.agents.rl.rllib.train_rllib`) records the same tags once per training iteration
in ``tb/rllib_K/``. Both count steps in agent transitions (env steps x UAVs).

A run restarted in its folder after a kill before its first checkpoint trains from step 0 into
the next ``K``: the curve is the newest ``K``'s. A run resumed from a checkpoint appends a new
event file to the same folder, starting at the checkpoint's step: the files are joined in
order, each later file replacing the points of the earlier ones from its first step on (the
steps the killed attempt took after its checkpoint were done again).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from poc_env.errors import ConfigError

TAGS = ("rollout/posc_mean", "rollout/ep_rew_mean")


def _run_order(folder: Path) -> tuple[int, str]:
    """Sort key of ``tb/<name>_<K>``: K as a number (``ppo_10`` after ``ppo_9``), then the name."""
    k = folder.name.rpartition("_")[2]
    return (int(k) if k.isdigit() else -1, folder.name)


def _read(log: Path) -> tuple[float, dict[str, np.ndarray]]:
    """When the log's writer started (its first event's wall time) and its curves.

    Not the file name's order: the name holds the start time in whole seconds, then the host,
    the process id and a per-process writer count, so a resumed attempt started within the same
    second as the killed one sorted by process id and by the count as text (``.10`` before
    ``.9``), and the killed attempt's points replaced the resumed ones (a flaky CI test)."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    acc = EventAccumulator(str(log), size_guidance={"scalars": 0})
    acc.Reload()
    have = acc.Tags()["scalars"]
    try:
        started = float(acc.FirstEventTimestamp())
    except ValueError:  # an empty file: no event at all
        started = float("inf")
    return started, {
        tag: np.array([[e.step, e.value] for e in acc.Scalars(tag)], dtype=float).reshape(-1, 2)
        for tag in TAGS
        if tag in have
    }


def training_curve(run_dir: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """``{tag: array (n, 2) of (step, value)}`` for ``rollout/posc_mean`` and
    ``rollout/ep_rew_mean`` from a run's TensorBoard logs (module docstring: which logs)."""
    folders = sorted({p.parent for p in Path(run_dir).glob("tb/*/events.out.tfevents.*")})
    if not folders:
        raise ConfigError("run_dir", str(run_dir), "a run folder with TensorBoard logs (tb/)")
    for folder in sorted(folders, key=_run_order, reverse=True):  # the newest run first
        out: dict[str, np.ndarray] = {}
        logs = [(*_read(log), log.name) for log in folder.glob("events.out.tfevents.*")]
        for _, read, _ in sorted(logs, key=lambda r: (r[0], r[2])):  # as the attempts started
            for tag, data in read.items():
                if tag in out and len(data):
                    out[tag] = np.concatenate([out[tag][out[tag][:, 0] < data[0, 0]], data])
                elif len(data):
                    out[tag] = data
        if "rollout/posc_mean" in out:
            return out
    raise ConfigError("run_dir", str(run_dir), "a run whose logs hold rollout/posc_mean")


def plot_training_curve(
    run_dir: str | os.PathLike[str], path: str | os.PathLike[str], until: int | None = None
) -> Path:
    """PNG of the mean POSC of recent training episodes against timesteps (up to ``until``)."""
    from poc_env.viz.plots import _figure, save_figure_atomic

    data = training_curve(run_dir)["rollout/posc_mean"]
    data = data[np.isfinite(data).all(axis=1)]  # a damaged log's NaN or infinite values
    if until is not None:
        if len(data) and until < data[0, 0]:
            raise ConfigError(
                "until", until, f"a step at or after the run's first logged one, {data[0, 0]:g}"
            )
        data = data[data[:, 0] <= until]
    if not len(data):
        raise ConfigError("run_dir", str(run_dir), "a run whose logs hold finite POSC values")
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
