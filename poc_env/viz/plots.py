"""Static figures of plans and surveys (matplotlib, imported lazily, Agg backend, no pyplot).

Nothing in the core imports this module: the environment and the planner run without
matplotlib loaded.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from poc_env.io import atomic_path


def _figure(figsize=(8.0, 6.0)):
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained")


def save_figure_atomic(fig, path: str | os.PathLike[str], dpi: int = 110) -> Path:
    """Save a matplotlib figure as PNG atomically (:func:`poc_env.io.atomic_path`)."""
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    return Path(path)


def draw_prior(ax, grid, prior, label: str = "prior POC per cell"):
    """Heat map of a (ny, nx) map in km, with a colour bar."""
    x0, y0, x1, y1 = grid.bounds
    im = ax.imshow(
        prior,
        origin="lower",
        extent=(x0 / 1e3, x1 / 1e3, y0 / 1e3, y1 / 1e3),
        cmap="viridis",
        interpolation="nearest",
    )
    ax.figure.colorbar(im, ax=ax, shrink=0.8, label=label)
    ax.set_xlabel("x / km")
    ax.set_ylabel("y / km")
    return im


def draw_airfields(ax, points, names=None):
    pts = np.asarray(points, dtype=float) / 1e3
    ax.scatter(pts[:, 0], pts[:, 1], marker="^", s=90, c="red", edgecolors="k", zorder=5)
    for k, p in enumerate(pts):
        if names is not None:
            ax.annotate(names[k], p, textcoords="offset points", xytext=(6, -10), color="red")


def plot_survey(result, scenario, plan, prior, path) -> Path:
    """Fig. 17 / 19 analog: prior, regions, tracks and airfields, one colour per UAV."""
    from poc_env.theory.probability_map import Grid

    grid = Grid.from_config(scenario.map)
    fig = _figure((9.0, 6.5))
    ax = fig.add_subplot()
    draw_prior(ax, grid, prior)
    colors = [f"C{k % 10}" for k in range(len(plan.regions))]
    for k, spec in enumerate(plan.regions):
        geom = spec.region().geometry
        xs, ys = geom.exterior.xy
        ax.plot(np.asarray(xs) / 1e3, np.asarray(ys) / 1e3, color="w", lw=1.5)
        wp = result.tracks[k] / 1e3
        ax.plot(wp[:, 0], wp[:, 1], color=colors[k], lw=0.8, label=f"UAV {spec.id}")
        c = geom.representative_point()
        ax.annotate(str(spec.id), (c.x / 1e3, c.y / 1e3), color="w", fontsize=14, weight="bold")
    pts = np.unique(np.asarray(result.takeoff_m + result.landing_m), axis=0)
    draw_airfields(ax, pts)
    x0, y0, x1, y1 = grid.bounds
    lo = min(y0, pts[:, 1].min()) / 1e3 - 10
    ax.set_xlim(min(x0, pts[:, 0].min()) / 1e3 - 10, max(x1, pts[:, 0].max()) / 1e3 + 10)
    ax.set_ylim(lo, y1 / 1e3 + 5)
    ax.set_title(
        f"{result.scenario} / {result.regions}: POS_C {result.posc:.4f} "
        f"(flown {result.posc_flown:.4f}, bound {result.bound:.4f})"
    )
    ax.legend(loc="upper right", fontsize=7, ncols=2)
    return save_figure_atomic(fig, path)
