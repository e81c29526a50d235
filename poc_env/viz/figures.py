"""Figures of poc-env. matplotlib is imported lazily, inside the functions, with the Agg backend."""

from __future__ import annotations

import math
import pathlib
from typing import Any

import numpy as np
from shapely.geometry import LineString, Point, Polygon
from shapely.geometry.base import BaseGeometry
from shapely.geometry.polygon import orient

from poc_env.geometry import rectangle_polygon
from poc_env.theory.patterns import (
    Track,
    expanding_square,
    horizontal_line_search,
    parallel_line_search,
    parallel_search,
    sector_search,
    spiral_search,
)

__all__ = ["pattern_gallery"]


def _geometry_path(geom: BaseGeometry) -> Any:
    """A matplotlib Path of a (multi)polygon, holes included (non-zero winding rule)."""
    from matplotlib.path import Path

    polys = [g for g in getattr(geom, "geoms", [geom]) if isinstance(g, Polygon) and not g.is_empty]
    rings = []
    for p in polys:
        p = orient(p, 1.0)  # exterior counter-clockwise, holes clockwise
        rings.append(Path(np.asarray(p.exterior.coords), closed=True))
        rings.extend(Path(np.asarray(h.coords), closed=True) for h in p.interiors)
    return Path.make_compound_path(*rings)


def _draw(ax: Any, region: BaseGeometry, track: Track, sweep_width_m: float, title: str) -> None:
    from matplotlib.patches import PathPatch

    swath = LineString(track.waypoints).buffer(sweep_width_m / 2.0)
    ax.add_patch(
        PathPatch(_geometry_path(swath), facecolor="#9ecae1", edgecolor="none", alpha=0.45)
    )
    ax.add_patch(
        PathPatch(_geometry_path(region), facecolor="none", edgecolor="black", linewidth=1.5)
    )
    wp = track.waypoints
    ax.plot(wp[:, 0], wp[:, 1], color="#d62728", linewidth=0.9)
    # arrow at the start, pointing along the first leg
    d = wp[1] - wp[0]
    span = max(np.ptp(wp[:, 0]), np.ptp(wp[:, 1]), 1e-9)
    d = d / max(np.hypot(*d), 1e-12) * 0.08 * span
    ax.annotate(
        "",
        xy=wp[0] + d,
        xytext=wp[0],
        arrowprops={"arrowstyle": "-|>", "color": "#08306b", "linewidth": 2.0},
    )
    ax.plot(*wp[0], marker="o", color="#08306b", markersize=5)
    ax.set_title(title, fontsize=9)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, linewidth=0.3, alpha=0.5)


def pattern_gallery(out_dir: str | pathlib.Path, *, dpi: int = 110) -> list[pathlib.Path]:
    """Write one PNG per §2.2 search pattern into ``out_dir`` and return their paths.

    Each figure shows the region outline (black), the swept swath (the whole track buffered by
    W/2, round caps, light blue), the track (red) and an arrow at its start. Example
    parameters are fixed and printed in the titles.
    """
    from matplotlib.figure import Figure  # no pyplot: no global backend switch needed

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    deg = math.degrees

    holed = Polygon(
        [(0, 0), (6000, 0), (6500, 4000), (3500, 5500), (2500, 3000), (0, 4500)],
        [[(2000, 800), (3500, 800), (3500, 1800), (2000, 1800)]],
    )
    s_par, th = 400.0, math.radians(30)
    center, length, width, rt, s_rect = (0.0, 0.0), 6000.0, 3000.0, math.radians(20), 500.0
    rect = rectangle_polygon(center, length, width, rt)
    r_c, w_c = 1000.0, 150.0
    circle = Point(0.0, 0.0).buffer(r_c, quad_segs=64)

    sector = sector_search((0, 0), r_c, spacing_m=600.0)
    square = expanding_square((0, 0), 200.0, 800.0)
    cases = [
        (
            "parallel",
            holed,
            parallel_search(holed, s_par, th, start=(0, 0)),
            s_par,
            f"Variable-angle parallel search (eq. 5-6)\nS = W = {s_par:g} m, "
            f"θ = {deg(th):g}° (line bearing)",
        ),
        (
            "parallel_line",
            rect,
            parallel_line_search(center, length, width, rt, s_rect),
            s_rect,
            f"Parallel line search (Fig. 2): {length:g} m × {width:g} m at {deg(rt):g}°\n"
            f"tracks along the long side, S = W = {s_rect:g} m",
        ),
        (
            "horizontal_line",
            rect,
            horizontal_line_search(center, length, width, rt, s_rect),
            s_rect,
            f"Horizontal line search (Fig. 3): {length:g} m × {width:g} m at {deg(rt):g}°\n"
            f"tracks along the short side, S = W = {s_rect:g} m",
        ),
        (
            "sector",
            circle,
            sector,
            w_c,
            f"Sector search (Fig. 5): R = {r_c:g} m, "
            f"{len(sector.waypoints) // 2} passes\nperimeter gap {sector.spacing_m:.0f} m, "
            f"W = {w_c:g} m",
        ),
        (
            "expanding_square",
            circle,
            square,
            200.0,
            "Expanding square (Fig. 6): R = 1000 m, S = W = 200 m\nsecond square rotated 45°",
        ),
        (
            "spiral",
            circle,
            spiral_search((0, 0), r_c),
            w_c,
            f"Spiral search (Fig. 7): R = {r_c:g} m, slopes 20°/15°/10°/5°\n"
            f"one turn each, W = {w_c:g} m",
        ),
    ]
    from poc_env.viz.plots import save_figure_atomic

    paths = []
    for kind, region, track, w, title in cases:
        fig = Figure(figsize=(5.5, 5.0))
        ax = fig.add_subplot(1, 1, 1)
        _draw(ax, region, track, w, title)
        fig.tight_layout()
        paths.append(save_figure_atomic(fig, out / f"pattern_{kind}.png", dpi=dpi))
    return paths
