"""The training curve of a run (``poc-env curve``): mean POSC of recent episodes over timesteps.

Read from the run's TensorBoard logs, where the progress callback of
:func:`poc_env.agents.rl.train.train`
records ``rollout/posc_mean`` (the mean POSC of the last 100 finished episodes) once per rollout.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from poc_env.errors import ConfigError


def training_curve(run_dir: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """``{tag: array (n, 2) of (step, value)}`` for ``rollout/posc_mean`` and
    ``rollout/ep_rew_mean`` from a run's TensorBoard logs."""
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
