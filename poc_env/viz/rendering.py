"""Frames of a running search (``rgb_array`` / ``human``) and animated GIFs of whole episodes.

:class:`Renderer` draws one env of a batched :class:`poc_env.sim.core.State`: the belief
(POC per cell, coarsened from the fine grid) as a heat map whose colour scale is fixed when the
history starts, so that the map visibly drains as it is searched; the no-fly zones (hatched
red), the threat peaks (the circle where ``exp(-lambda r^2)`` equals the threshold ``Th_s``),
the airfields (triangles), every UAV's track so far with its current position (a marker
pointing along the heading, an ``X`` once crashed, a square once landed), the strip its sensor
swept in the last step (the segment buffered by half the sweep width), the active
communication links (dashed grey lines), the hidden target (a green star, only once detected)
and a title with the step, POSC and detection state.

matplotlib and Pillow are imported inside the functions that need them: importing this module
loads neither. ``rgb_array`` frames come from a ``matplotlib.figure.Figure`` on an Agg canvas
(no pyplot); ``human`` mode opens a pyplot window on the first frame.

Typical use (the environment does the same)::

    from poc_env.sim import core as sim

    r = Renderer(params, "rgb_array")
    state = sim.initial(params, rngs)
    r.record(state)                  # after reset ...
    frames = [r.frame(state)]
    while not sim.episode_over(params, state).all():
        sim.step(params, state, actions, rngs)
        r.record(state)              # ... and after every step
        frames.append(r.frame(state))
    write_gif(frames, "episode.gif")
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.errors import ConfigError
from poc_env.io import atomic_path

__all__ = ["RENDER_MODES", "Renderer", "random_policy", "render_episode", "write_gif"]

#: The render modes :class:`Renderer` accepts.
RENDER_MODES = ("rgb_array", "human")

_KM = 1e3
#: Axes and colour-bar boxes in figure fractions (fixed, so that frames do not jitter).
_AX_BOX = (0.08, 0.08, 0.76, 0.80)
_CB_BOX = (0.86, 0.08, 0.025, 0.80)
_CMAP = "bone_r"
_LINK_COLOR = "0.35"
_THREAT_COLOR = "darkorange"
_TARGET_COLOR = "lime"
#: Frames sampled for the shared palette of a GIF.
_PALETTE_FRAMES = 8


def _stadium(a: np.ndarray, b: np.ndarray, r: float, n: int = 12) -> np.ndarray:
    """Vertices (2n, 2) of segment a-b buffered by ``r`` (a rectangle with round caps)."""
    d = b - a
    theta = float(np.arctan2(d[1], d[0]))
    t = np.linspace(-np.pi / 2, np.pi / 2, n)
    cap_b = b + r * np.column_stack([np.cos(theta + t), np.sin(theta + t)])
    cap_a = a + r * np.column_stack([np.cos(theta + np.pi + t), np.sin(theta + np.pi + t)])
    return np.vstack([cap_b, cap_a])


class Renderer:
    """Draws frames of one env of a simulator state; keeps that env's track history.

    Parameters
    ----------
    params:
        The :class:`poc_env.sim.core.Params` of the scenario.
    render_mode:
        ``"rgb_array"`` (off-screen Agg canvas) or ``"human"`` (a pyplot window, opened lazily
        on the first frame).
    figsize, dpi:
        Figure size in inches and resolution; the default gives 640 x 480 frames.

    Call :meth:`record` after every reset and step (it is idempotent per step, and a state
    whose step count went backwards starts a new history), :meth:`frame` whenever a picture is
    wanted, :meth:`reset_history` to forget the tracks and fix a new colour scale.
    """

    def __init__(
        self,
        params: Any,
        render_mode: str = "rgb_array",
        *,
        figsize: tuple[float, float] = (6.4, 4.8),
        dpi: int = 100,
    ) -> None:
        if render_mode not in RENDER_MODES:
            raise ConfigError("render_mode", render_mode, '"rgb_array" or "human"')
        self.params = params
        self.render_mode = render_mode
        self.figsize = (float(figsize[0]), float(figsize[1]))
        self.dpi = int(dpi)
        self._fig: Any = None
        self._canvas: Any = None
        self._ax: Any = None
        self._image: Any = None
        self._overlay: list[Any] = []  # static artists drawn over the heat map
        self._dynamic: list[Any] = []
        # rgb_array: what never changes is rendered once, then blitted back on every frame
        self._blit = render_mode == "rgb_array"
        self._background: Any = None
        self._background_vmax: float | None = None
        self.reset_history()

    # ------------------------------------------------------------------ history

    def reset_history(self) -> None:
        """Forget the tracks; the next recorded or drawn state fixes the colour scale."""
        self._track: list[np.ndarray] = []  # (N, 2) positions, one per recorded step
        self._steps: list[int] = []
        self._env: int | None = None
        self._vmax: float | None = None

    @property
    def n_recorded(self) -> int:
        """Number of distinct steps in the track history."""
        return len(self._track)

    def _coarse(self, state: Any, e: int) -> np.ndarray:
        p = self.params
        return p.grid.coarsen(state.belief[e], p.s)

    def _sync(self, state: Any, e: int) -> None:
        """Start a new history for another env or a new episode; fix the colour scale."""
        if (self._env is not None and self._env != e) or (
            self._steps and int(state.step[e]) < self._steps[-1]
        ):
            self.reset_history()
        if self._vmax is None:
            top = float(self._coarse(state, e).max())
            self._vmax = top if top > 0 else 1.0
        self._env = e

    def record(self, state: Any, env_index: int = 0) -> None:
        """Append env ``env_index``'s current horizontal positions to the track history."""
        e = int(env_index)
        step = int(state.step[e])
        self._sync(state, e)
        xy = np.array(state.pos[e, :, :2], dtype=float)
        if self._steps and self._steps[-1] == step:
            self._track[-1] = xy
        else:
            self._track.append(xy)
            self._steps.append(step)

    def _tracks(self, state: Any, e: int) -> np.ndarray:
        """(T, N, 2) history in metres, with the current position appended if not recorded."""
        cur = np.asarray(state.pos[e, :, :2], dtype=float)
        if not self._steps:
            return cur[None]
        pts = list(self._track)
        if self._steps[-1] != int(state.step[e]):
            pts.append(cur)
        return np.stack(pts)

    # ------------------------------------------------------------------ figure

    def _ensure_figure(self) -> None:
        if self._fig is not None:
            return
        if self.render_mode == "human":
            import matplotlib.pyplot as plt

            plt.ion()
            fig = plt.figure(figsize=self.figsize, dpi=self.dpi)
            canvas = fig.canvas
        else:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            fig = Figure(figsize=self.figsize, dpi=self.dpi)
            canvas = FigureCanvasAgg(fig)
        self._fig, self._canvas = fig, canvas
        self._draw_static()

    def _draw_static(self) -> None:
        """Axes, heat map, colour bar, search area, no-fly zones, threats and airfields."""
        from matplotlib.patches import Circle, PathPatch, Rectangle
        from matplotlib.path import Path as MplPath
        from shapely.geometry.polygon import orient

        p = self.params
        fig = self._fig
        ax = fig.add_axes(_AX_BOX)
        cax = fig.add_axes(_CB_BOX)
        self._ax = ax
        x0, y0, x1, y1 = (v / _KM for v in p.grid.bounds)
        self._image = ax.imshow(
            np.zeros(p.grid.shape),
            origin="lower",
            extent=(x0, x1, y0, y1),
            cmap=_CMAP,
            vmin=0.0,
            vmax=1.0,
            interpolation="nearest",
            zorder=0,
        )
        fig.colorbar(self._image, cax=cax, label="POC per cell")
        overlay = [
            ax.add_patch(
                Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec="0.2", lw=0.8, zorder=1)
            )
        ]
        for poly in p.zones.polygons:
            poly = orient(poly, 1.0)  # exterior CCW, holes CW: holes stay open when filled
            verts, codes = [], []
            for ring in [poly.exterior, *poly.interiors]:
                xy = np.asarray(ring.coords, dtype=float)[:, :2] / _KM
                verts.append(xy)
                codes += [MplPath.MOVETO] + [MplPath.LINETO] * (len(xy) - 2) + [MplPath.CLOSEPOLY]
            patch = PathPatch(
                MplPath(np.vstack(verts), codes),
                fc=(1.0, 0.0, 0.0, 0.15),
                ec="red",
                hatch="///",
                lw=1.0,
                zorder=2,
            )
            overlay.append(ax.add_patch(patch))
        th = float(p.scenario.map.threat_threshold)
        for c, lam in zip(np.asarray(p.threat_centers), np.asarray(p.threat_lambdas)):
            cx, cy = c / _KM
            if 0.0 < th < 1.0 and lam > 0:
                r = np.sqrt(-np.log(th) / lam) / _KM  # exp(-lambda r^2) = Th_s
                circle = Circle(
                    (cx, cy), r, fc=(1.0, 0.55, 0.0, 0.12), ec=_THREAT_COLOR, ls="--", zorder=2
                )
                overlay.append(ax.add_patch(circle))
            overlay += ax.plot(
                [cx], [cy], marker="o", ms=5, mfc="none", mec=_THREAT_COLOR, mew=1.5, zorder=3
            )
        fields = np.unique(np.vstack([p.takeoff, p.landing]), axis=0) / _KM
        overlay += ax.plot(
            fields[:, 0], fields[:, 1], ls="none", marker="^", ms=9, mfc="gold", mec="k", zorder=4
        )
        self._overlay = overlay
        if self._blit:  # drawn on every frame, over the heat map, not into the background
            for artist in [self._image, *overlay, ax.title]:
                artist.set_animated(True)
        self._legend(ax)  # in the free column left of the (square-ish) map
        bx0, by0, bx1, by1 = (v / _KM for v in p.bounds)
        ax.set_xlim(bx0, bx1)
        ax.set_ylim(by0, by1)
        ax.set_aspect("equal", adjustable="box")
        ax.set_anchor("E")
        ax.set_xlabel("x / km", fontsize=8)
        ax.set_ylabel("y / km", fontsize=8)
        ax.tick_params(labelsize=7)
        cax.tick_params(labelsize=7)
        cax.yaxis.label.set_size(8)

    def _legend(self, ax: Any) -> None:
        """Key of the symbols (UAVs are numbered on the map instead)."""
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch

        p = self.params
        handles = [
            Line2D([], [], ls="none", marker="^", ms=7, mfc="gold", mec="k", label="airfield"),
            Line2D([], [], ls="none", marker=">", ms=7, mfc="0.6", mec="k", label="UAV"),
            Line2D([], [], ls="none", marker="s", ms=6, mfc="0.6", mec="k", label="landed"),
            Line2D([], [], ls="none", marker="X", ms=7, mfc="0.6", mec="k", label="crashed"),
            Patch(fc="0.6", alpha=0.4, label="swept strip"),
            Line2D([], [], color=_LINK_COLOR, ls="--", lw=0.8, label="comm link"),
            Line2D([], [], ls="none", marker="*", ms=9, mfc=_TARGET_COLOR, mec="k", label="target"),
        ]
        if len(p.zones):
            handles.append(Patch(fc=(1.0, 0.0, 0.0, 0.15), ec="red", hatch="///", label="no-fly"))
        if len(p.threat_lambdas):
            th = p.scenario.map.threat_threshold
            handles.append(
                Patch(
                    fc=(1.0, 0.55, 0.0, 0.12), ec=_THREAT_COLOR, ls="--", label=f"threat > {th:g}"
                )
            )
        ax.figure.legend(
            handles=handles,
            loc="upper left",
            bbox_to_anchor=(0.005, _AX_BOX[1] + _AX_BOX[3]),
            fontsize=6,
            frameon=False,
            handlelength=1.6,
            borderaxespad=0.0,
        )

    def _agent_colors(self) -> list[Any]:
        from matplotlib import colormaps

        cmap = colormaps["tab10"]
        return [cmap(k % 10) for k in range(self.params.n_agents)]

    def _draw_dynamic(self, state: Any, e: int) -> None:
        from matplotlib.collections import LineCollection
        from matplotlib.markers import MarkerStyle
        from matplotlib.transforms import Affine2D

        p = self.params
        ax = self._ax
        for artist in self._dynamic:
            artist.remove()
        dyn: list[Any] = []
        self._image.set_data(self._coarse(state, e))
        self._image.set_clim(0.0, self._vmax)

        tracks = self._tracks(state, e) / _KM  # (T, N, 2)
        colors = self._agent_colors()
        half = p.scenario.sensor.sweep_width_m / 2.0 / _KM
        flying = np.asarray(state.flying[e], dtype=bool)
        landed = np.asarray(state.landed[e], dtype=bool)
        crashed = np.asarray(state.crashed[e], dtype=bool)
        for i in range(p.n_agents):
            col = colors[i]
            if len(tracks) >= 2:
                a, b = tracks[-2, i], tracks[-1, i]
                if np.hypot(*(b - a)) > 0:
                    poly = _stadium(a, b, half)
                    dyn += ax.fill(poly[:, 0], poly[:, 1], color=col, alpha=0.3, lw=0, zorder=5)
                (line,) = ax.plot(tracks[:, i, 0], tracks[:, i, 1], color=col, lw=1.2, zorder=6)
                dyn.append(line)
            x, y = tracks[-1, i]
            if crashed[i]:
                style: dict[str, Any] = {"marker": "X", "ms": 10, "mec": "k", "mew": 0.8}
            elif landed[i]:
                style = {"marker": "s", "ms": 7, "mec": "k", "mew": 0.8}
            else:
                heading = float(state.heading[e, i])
                marker = MarkerStyle(">", transform=Affine2D().rotate(heading))
                style = {"marker": marker, "ms": 9, "mec": "k", "mew": 0.6}
            (mark,) = ax.plot([x], [y], ls="none", color=col, zorder=8, **style)
            dyn.append(mark)
            dyn.append(
                ax.annotate(
                    str(i),
                    (x, y),
                    textcoords="offset points",
                    xytext=(5, 4),
                    fontsize=7,
                    color=col,
                    weight="bold",
                    zorder=9,
                )
            )

        links = np.asarray(state.links[e], dtype=bool)
        cur = tracks[-1]
        segs = [
            (cur[i], cur[j])
            for i in range(p.n_agents)
            for j in range(i + 1, p.n_agents)
            if (links[i, j] or links[j, i]) and flying[i] and flying[j]
        ]
        if segs:
            lc = LineCollection(segs, colors=_LINK_COLOR, linestyles="--", linewidths=0.8, zorder=7)
            ax.add_collection(lc, autolim=False)
            dyn.append(lc)

        detected = bool(state.detected[e])
        if detected:
            tx, ty = np.asarray(state.target[e], dtype=float) / _KM
            (star,) = ax.plot(
                [tx], [ty], ls="none", marker="*", ms=13, mfc=_TARGET_COLOR, mec="k", zorder=10
            )
            dyn.append(star)

        step = int(state.step[e])
        posc = float(state.posc[e])
        mass = float(state.initial_mass[e])
        share = posc / mass if mass > 0 else 0.0
        if detected:
            found = f"target detected at step {int(state.detect_step[e])}"
        else:
            found = "target not detected"
        minutes = step * p.dt / 60.0
        ax.set_title(
            f"{p.scenario.name}: step {step}/{p.horizon} ({minutes:.0f} min)   "
            f"POSC {posc:.4f} ({100 * share:.1f}%)\n"
            f"flying {int(flying.sum())}  landed {int(landed.sum())}  "
            f"crashed {int(crashed.sum())}   {found}",
            fontsize=9,
        )
        if self._blit:
            for artist in dyn:
                artist.set_animated(True)
        self._dynamic = dyn

    def _render(self) -> None:
        """Draw the figure: in full (human mode), or restore the cached background and draw
        the heat map, the overlays, the moving artists and the title on it (rgb_array mode)."""
        canvas = self._canvas
        if not self._blit:
            canvas.draw()
            return
        if self._background is None or self._background_vmax != self._vmax:
            canvas.draw()  # leaves the animated artists out
            self._background = canvas.copy_from_bbox(self._fig.bbox)
            self._background_vmax = self._vmax  # the colour bar's ticks depend on it
        else:
            canvas.restore_region(self._background)
        renderer = canvas.get_renderer()
        artists = sorted([self._image, *self._overlay, *self._dynamic], key=lambda a: a.zorder)
        for artist in [*artists, self._ax.title]:
            artist.draw(renderer)

    def frame(self, state: Any, env_index: int = 0) -> np.ndarray:
        """Draw env ``env_index`` of ``state``; return the picture as uint8 ``(H, W, 3)``.

        The track drawn is the recorded history plus the current position if this step was not
        recorded. In ``rgb_array`` mode the frame is ``figsize * dpi`` pixels (640 x 480 by
        default); in ``human`` mode the window is refreshed as well.
        """
        e = int(env_index)
        self._sync(state, e)
        self._ensure_figure()
        self._draw_dynamic(state, e)
        self._render()
        if self.render_mode == "human":
            import matplotlib.pyplot as plt

            self._canvas.flush_events()
            plt.pause(1e-3)
        rgba = np.asarray(self._canvas.buffer_rgba())
        return np.ascontiguousarray(rgba[..., :3], dtype=np.uint8)

    def data_to_pixel(self, xy_m: Any) -> np.ndarray:
        """Pixel ``(column, row)`` in the last frame of points ``xy_m (..., 2)`` in metres."""
        if self._fig is None:
            raise RuntimeError("data_to_pixel needs a frame to have been drawn")
        xy = np.asarray(xy_m, dtype=float) / _KM
        flat = self._ax.transData.transform(xy.reshape(-1, 2))
        height = self._canvas.get_width_height()[1]
        out = np.column_stack([flat[:, 0], height - flat[:, 1]])
        return out.reshape(xy.shape)

    def close(self) -> None:
        """Release the figure (closes the window in ``human`` mode)."""
        if self._fig is None:
            return
        if self.render_mode == "human":
            import matplotlib.pyplot as plt

            plt.close(self._fig)
        else:
            self._fig.clear()
        self._fig = self._canvas = self._ax = self._image = None
        self._overlay, self._dynamic = [], []
        self._background = self._background_vmax = None

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# ---------------------------------------------------------------------- GIF


def write_gif(frames: Iterable[np.ndarray], path: str | os.PathLike[str], fps: float = 8) -> Path:
    """Write uint8 ``(H, W, 3)`` frames as a looping animated GIF, atomically.

    The file is written to a temporary file in the same folder, then renamed over ``path``.
    All frames share one 256-colour palette taken from up to eight frames: the first, the last
    and six evenly between (a colour seen only in other frames is drawn in the nearest palette
    colour). Pillow merges consecutive identical frames into one (longer) frame.
    """
    p = Path(path)
    if p.suffix.lower() != ".gif":
        raise ConfigError("out", str(path), "a path ending in .gif")
    try:
        ok = float(fps) > 0 and np.isfinite(float(fps))
    except (TypeError, ValueError):
        ok = False
    if not ok or isinstance(fps, bool):
        raise ConfigError("fps", fps, "a number > 0")
    arrays = [np.asarray(f) for f in frames]
    if not arrays:
        raise ConfigError("frames", 0, "at least one frame")
    shape = arrays[0].shape
    for k, f in enumerate(arrays):
        if f.ndim != 3 or f.shape[2] != 3 or f.shape != shape or f.dtype != np.uint8:
            raise ConfigError(
                f"frames[{k}]", f"{f.dtype} {f.shape}", f"uint8 (H, W, 3) like frames[0] {shape}"
            )
    from PIL import Image

    # one palette for all frames (smaller files, no colour flicker), from the first, the last
    # and six frames between; maximum coverage keeps the colours of small symbols (airfields,
    # the target), which median cut (Pillow's default) merges into the large areas around them
    picks = sorted({int(k) for k in np.linspace(0, len(arrays) - 1, _PALETTE_FRAMES).round()})
    sample = Image.fromarray(np.vstack([arrays[k] for k in picks]))
    palette = sample.quantize(256, method=Image.Quantize.MAXCOVERAGE, dither=Image.Dither.NONE)
    images = [
        Image.fromarray(np.ascontiguousarray(f)).quantize(palette=palette, dither=Image.Dither.NONE)
        for f in arrays
    ]
    with atomic_path(p, suffix=".gif") as tmp:
        images[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=max(1, round(1000.0 / float(fps))),
            loop=0,
        )
    return p


# ---------------------------------------------------------------------- episodes


def random_policy(state: Any, rng: np.random.Generator) -> np.ndarray:
    """Uniform actions in [-1, 1] for dv and d alpha, 0 for d beta (level flight): (E, N, 3)."""
    e, n = state.pos.shape[:2]
    actions = rng.uniform(-1.0, 1.0, size=(e, n, 3))
    actions[..., 2] = 0.0
    return actions


def render_episode(
    scenario: Any,
    policy_fn: Callable[[Any, np.random.Generator], np.ndarray],
    out_path: str | os.PathLike[str],
    *,
    seed: int = 0,
    max_steps: int | None = None,
    every: int = 1,
    fps: float = 8,
) -> Path:
    """Fly one episode of ``scenario`` under ``policy_fn`` and write it as a GIF.

    ``scenario`` is anything :func:`poc_env.config.load_scenario` accepts. The episode is the
    one-env :class:`~poc_env.sim.engine.Engine`'s, whose generator is
    ``np.random.default_rng(seed)``; ``policy_fn(state, rng)`` returns actions ``(1, N, 3)``
    and gets its own generator, ``np.random.default_rng([seed, 1])``. The episode runs until
    it is over (:func:`poc_env.sim.core.episode_over`: every UAV landed or crashed, the target
    detected with ``episode.detection_ends_episode``, or the horizon), no UAV flies, or after
    ``max_steps`` steps
    (default: the scenario's horizon). A frame is drawn at reset, every ``every`` steps, and
    at the last step.
    """
    from poc_env.config import load_scenario
    from poc_env.sim.engine import Engine

    if isinstance(every, bool) or int(every) != every or every < 1:
        raise ConfigError("every", every, "a whole number >= 1")
    if out_path is None or Path(out_path).suffix.lower() != ".gif":
        raise ConfigError("out", str(out_path), "a path ending in .gif")
    engine = Engine(load_scenario(scenario), seeds=[seed])
    params = engine.params
    limit = params.horizon if max_steps is None else int(max_steps)
    if limit < 0:
        raise ConfigError("max_steps", max_steps, "a whole number >= 0")
    policy_rng = np.random.default_rng([seed, 1])
    engine.reset()
    state = engine.current
    renderer = Renderer(params, "rgb_array")
    try:
        renderer.record(state)
        frames = [renderer.frame(state)]
        k = 0
        over = False
        while k < limit and not over:
            actions = np.asarray(policy_fn(state, policy_rng), dtype=float)
            over = bool(engine.step(actions).over[0]) or not state.flying.any()
            k += 1
            renderer.record(state)
            last = k >= limit or over
            if k % every == 0 or last:
                frames.append(renderer.frame(state))
    finally:
        renderer.close()
    return write_gif(frames, out_path, fps=fps)
