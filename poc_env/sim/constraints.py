"""Safety constraints of §3.2.3 (eq. 20-23) and a safety shield, batched over envs and agents.

Pure functions of explicit state. Positions are metres, shaped ``(n_envs, n_agents, 2)`` (any
leading shape ``(..., 2)`` where a function says so); headings and turns are radians.

- eq. 20: the next position must lie inside the search rectangle (outside ``Omega_b``) and
  outside every no-fly zone (``Omega_p``): :func:`outside_boundary`, :class:`NoFlyZones`.
- eq. 21: UAVs keep at least ``d_s`` apart: :func:`separation_violations`.
- eq. 22-23: terrain threat peaks and the threshold ``Th_s``: :func:`terrain_threat`,
  :func:`threat_violation`.
- :func:`shield_heading` turns a proposed heading change into the closest admissible one that
  keeps the next position safe (used when ``constraints.violation == "shield"``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from shapely.geometry import Polygon

import poc_env._kernels.swarm as _swarm
from poc_env.errors import ConfigError
from poc_env.geometry import as_polygon

__all__ = [
    "NoFlyZones",
    "ShieldResult",
    "outside_boundary",
    "pairwise_distances",
    "separation_violations",
    "shield_heading",
    "terrain_threat",
    "threat_arrays",
    "threat_violation",
]


def _cross(ax, ay, bx, by):
    """z component of the cross product (ax, ay) x (bx, by)."""
    return ax * by - ay * bx


class NoFlyZones:
    """The no-fly area ``Omega_p`` of eq. 20: a union of polygons (metres).

    Built once; every vertex ring (exterior and any interior ring of a shapely polygon) is
    stored as numpy edge arrays, so that the queries below are vectorised over any number of
    points with no shapely call per point. Membership uses the even-odd rule per polygon (a
    hole is outside its polygon) and a point is inside the area when it is inside any polygon.
    Points exactly on an edge may be classified either way by :meth:`inside`; :meth:`distance`
    is 0 there and :meth:`segment_crosses` counts touching an edge as entering.

    Parameters
    ----------
    polygons:
        Vertex arrays ``(k, 2)`` or shapely polygons, e.g. ``MapConfig.no_fly_zones_m``. Each
        is validated with :func:`poc_env.geometry.as_polygon` (raises ``GeometryError``).
    """

    def __init__(self, polygons: Sequence[Any] = ()) -> None:
        starts, ends, owner = [], [], []
        self.polygons: tuple[Polygon, ...] = tuple(
            as_polygon(p, f"no_fly_zones[{i}]") for i, p in enumerate(polygons)
        )
        for k, poly in enumerate(self.polygons):
            for ring in (poly.exterior, *poly.interiors):
                pts = np.asarray(ring.coords, dtype=float)[:, :2]
                if np.allclose(pts[0], pts[-1]):
                    pts = pts[:-1]
                starts.append(pts)
                ends.append(np.roll(pts, -1, axis=0))
                owner.append(np.full(len(pts), k))
        if starts:
            a, b = np.concatenate(starts), np.concatenate(ends)
            self._owner = np.concatenate(owner)
        else:
            a = b = np.zeros((0, 2))
            self._owner = np.zeros(0, dtype=int)
        self._ax, self._ay = a[:, 0], a[:, 1]
        self._bx, self._by = b[:, 0], b[:, 1]
        # edges are grouped by polygon, in order: start index of each polygon's edges
        self._first = np.searchsorted(self._owner, np.arange(len(self.polygons)))
        # bounding box of the whole no-fly area: points and steps outside it skip the edge tests
        if len(a):
            self._box = (
                min(a[:, 0].min(), b[:, 0].min()),
                min(a[:, 1].min(), b[:, 1].min()),
                max(a[:, 0].max(), b[:, 0].max()),
                max(a[:, 1].max(), b[:, 1].max()),
            )

    @classmethod
    def from_config(cls, map_cfg: Any) -> NoFlyZones:
        """The zones of a :class:`poc_env.config.MapConfig` (``no_fly_zones_m``)."""
        return cls(map_cfg.no_fly_zones_m)

    @property
    def n_zones(self) -> int:
        return len(self.polygons)

    @property
    def n_edges(self) -> int:
        return len(self._ax)

    def __len__(self) -> int:
        return self.n_zones

    def _near(self, lo_x, lo_y, hi_x, hi_y) -> np.ndarray:
        x0, y0, x1, y1 = self._box
        return (lo_x <= x1) & (hi_x >= x0) & (lo_y <= y1) & (hi_y >= y0)

    def _inside_flat(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Even-odd test of points ``x, y (P,)`` against every zone: bool ``(P,)``."""
        x, y = x[:, None], y[:, None]
        ax, ay, bx, by = self._ax, self._ay, self._bx, self._by
        # the ray from the point towards +x crosses edge a-b: the edge straddles y and its
        # crossing abscissa lies right of x (sign of the cross product, no division)
        straddle = (ay > y) != (by > y)
        side = ((bx - ax) * (y - ay) - (x - ax) * (by - ay)) * (by - ay) > 0
        per_zone = np.add.reduceat((straddle & side).astype(np.int32), self._first, axis=1)
        return np.any(per_zone % 2 == 1, axis=1)

    def inside(self, xy: np.ndarray) -> np.ndarray:
        """Bool ``(...)``: which points ``xy (..., 2)`` lie in some zone (even-odd rule)."""
        p = np.asarray(xy, dtype=float)
        out = np.zeros(p.shape[:-1], dtype=bool).reshape(-1)
        if self.n_zones == 0:
            return out.reshape(p.shape[:-1])
        x, y = p[..., 0].reshape(-1), p[..., 1].reshape(-1)
        near = self._near(x, y, x, y)
        out[near] = self._inside_flat(x[near], y[near])
        return out.reshape(p.shape[:-1])

    def _edges_hit(self, ax, ay, bx, by) -> np.ndarray:
        """Bool ``(P,)``: segment a->b (each coordinate ``(P,)``) meets or touches some edge."""
        ax, ay, bx, by = ax[:, None], ay[:, None], bx[:, None], by[:, None]
        px, py, qx, qy = self._ax, self._ay, self._bx, self._by
        dx, dy = bx - ax, by - ay
        ex, ey = qx - px, qy - py
        d1 = _cross(dx, dy, px - ax, py - ay)
        d2 = _cross(dx, dy, qx - ax, qy - ay)
        d3 = _cross(ex, ey, ax - px, ay - py)
        d4 = _cross(ex, ey, bx - px, by - py)
        # bounding boxes overlap: needed for collinear segments, harmless otherwise
        box = (
            (np.minimum(ax, bx) <= np.maximum(px, qx))
            & (np.minimum(px, qx) <= np.maximum(ax, bx))
            & (np.minimum(ay, by) <= np.maximum(py, qy))
            & (np.minimum(py, qy) <= np.maximum(ay, by))
        )
        return np.any((d1 * d2 <= 0) & (d3 * d4 <= 0) & box, axis=1)

    def segment_crosses(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Bool ``(...)``: whether the straight step ``a -> b`` (each ``(..., 2)``) enters a zone.

        True when the end ``b`` lies inside a zone or the segment meets any zone edge, so a
        step that jumps over a thin zone with both ends outside is caught (eq. 20 applied to
        the whole step, not only to the next position). A step starting inside a zone is
        caught too: it either ends inside or crosses an edge on the way out.
        """
        a, b = np.broadcast_arrays(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
        shape = a.shape[:-1]
        out = np.zeros(shape, dtype=bool).reshape(-1)
        if self.n_zones == 0:
            return out.reshape(shape)
        ax, ay = a[..., 0].reshape(-1), a[..., 1].reshape(-1)
        bx, by = b[..., 0].reshape(-1), b[..., 1].reshape(-1)
        near = self._near(
            np.minimum(ax, bx), np.minimum(ay, by), np.maximum(ax, bx), np.maximum(ay, by)
        )
        ax, ay, bx, by = ax[near], ay[near], bx[near], by[near]
        out[near] = self._edges_hit(ax, ay, bx, by) | self._inside_flat(bx, by)
        return out.reshape(shape)

    def distance(self, xy: np.ndarray) -> np.ndarray:
        """Distance ``(...)`` in metres from ``xy (..., 2)`` to the nearest zone; 0 inside.

        ``inf`` when there are no zones.
        """
        p = np.asarray(xy, dtype=float)
        shape = p.shape[:-1]
        if self.n_zones == 0:
            return np.full(shape, np.inf)
        x = p[..., 0].reshape(-1, 1)
        y = p[..., 1].reshape(-1, 1)
        ex, ey = self._bx - self._ax, self._by - self._ay
        len2 = ex * ex + ey * ey
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((x - self._ax) * ex + (y - self._ay) * ey) / len2
        t = np.clip(np.nan_to_num(t), 0.0, 1.0)
        d = np.hypot(x - (self._ax + t * ex), y - (self._ay + t * ey)).min(axis=1)
        d = np.where(self._inside_flat(x[:, 0], y[:, 0]), 0.0, d)
        return d.reshape(shape)


def outside_boundary(xy: np.ndarray, bounds: Sequence[float]) -> np.ndarray:
    """Bool ``(...)``: ``xy (..., 2)`` lies in ``Omega_b``, outside the search rectangle (eq. 20).

    ``bounds`` is ``(xmin, ymin, xmax, ymax)`` in metres, e.g. ``Grid.bounds``; the boundary
    line itself counts as inside.
    """
    p = np.asarray(xy, dtype=float)
    x0, y0, x1, y1 = (float(v) for v in bounds)
    out = np.empty(p.shape[:-1], dtype=bool)
    flat = np.ascontiguousarray(p[..., :2]).reshape(-1, 2)
    _swarm.outside_boundary(flat, x0, y0, x1, y1, out.reshape(-1))
    return out


def pairwise_distances(xy: np.ndarray) -> np.ndarray:
    """Pairwise Euclidean distances ``(..., n, n)`` of points ``(..., n, d)``."""
    p = np.asarray(xy, dtype=float)
    n, d = p.shape[-2], p.shape[-1]
    out = np.empty((*p.shape[:-1], n))
    _swarm.pairwise_distances(np.ascontiguousarray(p).reshape(-1, n, d), out.reshape(-1, n, n))
    return out


def separation_violations(
    xy: np.ndarray,
    d_s: float,
    active: np.ndarray | None = None,
    dist: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Collision-avoidance check of eq. 21 for positions ``xy (n_envs, n_agents, 2)``.

    Returns ``(per_agent, pairs)``: ``pairs (n_envs, n, n)`` is True where two distinct active
    UAVs are closer than ``d_s`` metres (symmetric, False on the diagonal); ``per_agent
    (n_envs, n)`` is True for a UAV with at least one such partner. ``active (n_envs, n)``
    excludes landed or crashed UAVs (they neither violate nor cause violations). ``dist``
    optionally passes the already computed ``pairwise_distances(xy)``. Apply it to ``x(k)``
    and to ``x(k+1)`` for the two lines of eq. 21.
    """
    p = np.asarray(xy, dtype=float)
    n = p.shape[-2]
    d = pairwise_distances(p) if dist is None else np.asarray(dist, dtype=float)
    pairs = d < float(d_s)
    pairs &= ~np.eye(n, dtype=bool)
    if active is not None:
        act = np.asarray(active, dtype=bool)
        pairs &= act[..., :, None] & act[..., None, :]
    return np.asarray(pairs.any(axis=-1)), pairs


def threat_arrays(peaks: Sequence[Any]) -> tuple[np.ndarray, np.ndarray]:
    """``(centers (P, 2), lambdas (P,))`` from ``MapConfig.threat_peaks`` (``ThreatPeak``)."""
    centers = np.array([p.center_m for p in peaks], dtype=float).reshape(-1, 2)
    lambdas = np.array([p.lambda_per_m2 for p in peaks], dtype=float).reshape(-1)
    return centers, lambdas


def terrain_threat(xy: np.ndarray, centers: np.ndarray, lambdas: np.ndarray) -> np.ndarray:
    """Threat of each terrain peak at ``xy (..., 2)``, shape ``(..., n_peaks)`` (eq. 22).

    ``f_i = exp(-lambda_i * ((x - x_pi)^2 + (y - y_pi)^2))`` with ``lambda`` in 1/m^2.

    The paper prints the exponent as ``-lambda[(x - x_pi) + (y - y_pi)]``, without squares.
    That is not a peak: it grows without bound on one side of the line ``x + y = const`` and
    is not symmetric about the centre. The squared form, a Gaussian bump equal to 1 at the
    centre and decaying with distance, is what the text ("threat distance of the peak") and
    Fig. 11 describe, so it is used here.
    """
    p = np.asarray(xy, dtype=float)
    c = np.asarray(centers, dtype=float).reshape(-1, 2)
    lam = np.asarray(lambdas, dtype=float).reshape(-1)
    if len(c) != len(lam):
        raise ConfigError("threat_peaks", (len(c), len(lam)), "as many lambdas as centres")
    d2 = (p[..., None, 0] - c[:, 0]) ** 2 + (p[..., None, 1] - c[:, 1]) ** 2
    return np.exp(-lam * d2)


def threat_violation(
    xy: np.ndarray, centers: np.ndarray, lambdas: np.ndarray, th_s: float
) -> np.ndarray:
    """Bool ``(...)``: some peak's threat exceeds ``Th_s`` at ``xy`` (violates eq. 23)."""
    return np.any(terrain_threat(xy, centers, lambdas) > float(th_s), axis=-1)


@dataclass(frozen=True)
class ShieldResult:
    """Output of :func:`shield_heading`; arrays are ``(n_envs, n_agents)``."""

    #: heading change to apply, radians, within ``[-max_turn, max_turn]``.
    turn: np.ndarray
    #: the proposal was replaced by another candidate.
    shielded: np.ndarray
    #: no candidate turn satisfies every constraint (the least-violating one is returned).
    no_safe_option: np.ndarray


def shield_heading(
    xy: np.ndarray,
    heading: np.ndarray,
    speed: np.ndarray,
    dt: float,
    proposed_turn: np.ndarray,
    max_turn: float,
    *,
    zones: NoFlyZones | None = None,
    bounds: Sequence[float] | None = None,
    d_s: float | None = None,
    active: np.ndarray | None = None,
    threat: tuple[np.ndarray, np.ndarray, float] | None = None,
    n_candidates: int = 15,
) -> ShieldResult:
    """Safety shield: the admissible heading change closest to the proposal that keeps eq. 20-23.

    Each agent moves ``speed * dt`` metres along ``heading + turn`` (the horizontal part of
    eq. 19; pass ``v cos(beta)`` as ``speed`` when climbing). The candidates are the proposal
    (clipped to ``[-max_turn, max_turn]``) and ``n_candidates`` evenly spaced turns in that
    interval. A candidate is safe when the step stays inside ``bounds`` (eq. 20, ``Omega_b``),
    the step a -> b does not enter a no-fly zone (eq. 20, ``Omega_p``, whole segment), the next
    position is at least ``d_s`` from every other active agent's next position (eq. 21, second
    line) and, if ``threat = (centers, lambdas, th_s)`` is given, below the threat threshold
    (eq. 23). Any constraint whose argument is None is not checked. Separation is checked
    between next positions only, not along the two steps (keep ``v dt`` below ``d_s``).

    Agents are resolved one after another in index order (a Gauss-Seidel pass, vectorised over
    envs and candidates). Agent ``i`` must keep ``d_s`` from the already-shielded next
    positions of agents ``< i`` (a hard constraint, like eq. 20 and 23), so when every agent
    has a safe option all pairwise separations hold at the end. Towards agents ``> i``, whose
    next positions are only planned (their proposals), a shortfall below ``d_s`` is a soft cost:
    agent ``i`` yields as far as it can, which lets two UAVs on a collision course both turn.
    The chosen candidate minimises, in this order, the number of hard violations, the soft
    shortfall and the distance to the proposal (the proposal itself wins when it is safe).
    ``no_safe_option`` is set when the choice still violates a hard constraint (it is then the
    least-violating candidate). Inactive agents keep their proposal and are ignored by the
    others.

    Parameters
    ----------
    xy, heading, speed, proposed_turn:
        ``(n_envs, n_agents, 2)`` metres and ``(n_envs, n_agents)`` radians, m/s, radians.
    dt:
        Time step in seconds.
    max_turn:
        ``Delta alpha_max`` of eq. 19, radians.
    """
    p = np.asarray(xy, dtype=float)
    n_envs, n = p.shape[0], p.shape[1]
    hdg = np.broadcast_to(np.asarray(heading, dtype=float), (n_envs, n))
    step = np.broadcast_to(np.asarray(speed, dtype=float) * float(dt), (n_envs, n))
    m = float(max_turn)
    prop = np.clip(np.broadcast_to(np.asarray(proposed_turn, dtype=float), (n_envs, n)), -m, m)
    act = (
        np.ones((n_envs, n), dtype=bool)
        if active is None
        else np.broadcast_to(np.asarray(active, dtype=bool), (n_envs, n))
    )
    grid = np.linspace(-m, m, int(n_candidates)) if n_candidates > 1 else np.zeros(1)
    # candidates (n_envs, n, C): the proposal first, so that ties keep it
    cand = np.concatenate([prop[..., None], np.broadcast_to(grid, (n_envs, n, len(grid)))], -1)
    ang = hdg[..., None] + cand
    nxt = np.empty((*ang.shape, 2))
    nxt[..., 0] = p[:, :, None, 0] + step[..., None] * np.cos(ang)
    nxt[..., 1] = p[:, :, None, 1] + step[..., None] * np.sin(ang)

    # constraints that do not depend on the other agents: (n_envs, n, C) violation counts
    bad = np.zeros(cand.shape, dtype=np.int32)
    if bounds is not None:
        bad += outside_boundary(nxt, bounds)
    if zones is not None and zones.n_zones:
        bad += zones.segment_crosses(np.broadcast_to(p[:, :, None, :], nxt.shape), nxt)
    if threat is not None:
        centers, lambdas, th_s = threat
        bad += threat_violation(nxt, centers, lambdas, th_s)

    # lexicographic cost: hard violations, then any shortfall against unresolved agents (the
    # larger the gap the better), then distance to the proposal (<= 2 max_turn < tier)
    tier = 4.0 * m + 1.0
    closeness = np.abs(cand - prop[..., None])
    choice = np.zeros((n_envs, n), dtype=np.intp)
    n_bad = np.zeros((n_envs, n), dtype=np.int32)
    envs = np.arange(n_envs)
    if d_s is None or float(d_s) <= 0 or n < 2:  # no coupling between agents: all at once
        choice = np.where(act, np.argmin(bad * (1e9 * tier) + closeness, axis=-1), 0)
        n_bad = np.where(act, np.take_along_axis(bad, choice[..., None], -1)[..., 0], 0)
    else:
        ds = float(d_s)
        cx = np.ascontiguousarray(nxt[..., 0])  # (n_envs, n, C)
        cy = np.ascontiguousarray(nxt[..., 1])
        # squared distance d2[j, e, i, c] from agent i's candidate c to agent j's next
        # position, first as planned (proposal); row j is refreshed once agent j is resolved.
        # Agent j leads so that reductions over j run over contiguous slices.
        px, py = cx[:, :, 0].T, cy[:, :, 0].T  # (n, n_envs)
        d2 = (cx[None] - px[:, :, None, None]) ** 2 + (cy[None] - py[:, :, None, None]) ** 2
        d2[np.arange(n), :, np.arange(n), :] = np.inf
        d2[~act.T] = np.inf
        for i in range(n):
            hard = bad[:, i, :]
            soft: np.ndarray | float = 0.0
            if i > 0:  # resolved agents: final positions, a hard constraint
                hard = hard + (d2[:i, :, i, :].min(axis=0) < ds * ds)
            if i + 1 < n:  # unresolved agents: planned positions, a soft cost
                gap = np.sqrt(d2[i + 1 :, :, i, :].min(axis=0))
                short = np.clip((ds - gap) / ds, 0.0, 1.0)
                soft = np.where(short > 0, 1.0 + 1e6 * short, 0.0)
            cost = hard * (1e9 * tier) + soft * tier + closeness[:, i, :]
            k = np.where(act[:, i], np.argmin(cost, axis=-1), 0)
            choice[:, i] = k
            n_bad[:, i] = np.where(act[:, i], hard[envs, k], 0)
            if i + 1 < n:
                fx, fy = cx[envs, i, k], cy[envs, i, k]
                row = (cx[:, i + 1 :] - fx[:, None, None]) ** 2
                row += (cy[:, i + 1 :] - fy[:, None, None]) ** 2
                d2[i, :, i + 1 :, :] = np.where(act[:, i, None, None], row, np.inf)
    turn = np.take_along_axis(cand, choice[..., None], axis=-1)[..., 0]
    return ShieldResult(
        turn=turn,
        shielded=act & (choice != 0) & (turn != prop),
        no_safe_option=act & (n_bad > 0),
    )
