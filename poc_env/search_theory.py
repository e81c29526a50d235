"""Search theory of the paper (§3.1, eq. 7-16) and the step-wise detection law (DESIGN.md §3).

One implementation of each equation, used by the planner, the environment and the reports.

Detection laws (``law``):

``inverse_cube``
    Koopman's inverse-cube law. One infinite straight track has the lateral range curve
    ``p(x) = 1 - exp(-W^2 / (4 pi x^2))`` (:func:`lateral_range`), whose integral over ``x`` is
    the sweep width ``W``. A straight *segment* gives every point the detection exponent of
    :func:`segment_exponent`; exponents of consecutive segments add, so a track cut into steps
    detects exactly as the whole track would, and parallel tracks at spacing ``S`` give, on
    average over the area, eq. 10: ``POD = erf(sqrt(pi)/2 * W/S)``.
``exponential``
    Random search: the effort ``W * L`` a segment spends inside a cell is spread uniformly over
    the cell, ``POD = 1 - exp(-W L / A)``; as a function of coverage, ``1 - exp(-C)``.
``definite_range``
    Cookie cutter: every point within ``W/2`` of the segment (perpendicular foot on it) is
    detected with certainty; as a function of coverage, ``min(C, 1)``.

POC bookkeeping (eq. 12-14): the belief is kept on a fine grid of ``s x s`` sample points per
cell (the target is uniform inside its cell, and a 5 km cell is far coarser than the detection
profile of a 5 km sweep width). After a step, ``POC_new = (1 - p) POC_old`` at every sample point
(eq. 14) and the step's POS is ``sum POC_old * p`` (eq. 12); POSC is their running sum (eq. 13),
so ``POSC + sum(POC)`` stays equal to the initial total.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.special import erf

from poc_env.errors import ConfigError, check_positive
from poc_env.probability_map import Grid

LAWS = ("inverse_cube", "exponential", "definite_range")
_SQRT_PI_2 = np.sqrt(np.pi) / 2.0


def _check_law(law: str) -> str:
    if law not in LAWS:
        raise ConfigError("law", law, "one of " + ", ".join(LAWS))
    return law


# --------------------------------------------------------------------------- eq. 7-11


def coverage_factor(effective_area_m2, required_area_m2):
    """Coverage factor C = Z / A (eq. 7)."""
    return np.asarray(effective_area_m2, dtype=float) / np.asarray(required_area_m2, dtype=float)


def effective_sweep_area(speed_mps, time_s, sweep_width_m):
    """Effective search area Z = V T W (eq. 8)."""
    return np.asarray(speed_mps, float) * np.asarray(time_s, float) * np.asarray(sweep_width_m)


def parallel_coverage(sweep_width_m, spacing_m):
    """Coverage factor of parallel sweeps, C = W / S (eq. 9)."""
    return np.asarray(sweep_width_m, dtype=float) / np.asarray(spacing_m, dtype=float)


def pod_parallel(sweep_width_m, spacing_m):
    """POD of parallel sweeps at spacing S, ``erf(sqrt(pi)/2 * W/S)`` (eq. 10, eq. 15).

    ``erf`` is eq. 11 (``scipy.special.erf``). POD(W = S) = erf(sqrt(pi)/2) = 0.78991.
    """
    return erf(_SQRT_PI_2 * parallel_coverage(sweep_width_m, spacing_m))


def pod_from_coverage(coverage, law: str = "inverse_cube"):
    """POD as a function of the coverage factor C for each detection law.

    ``inverse_cube``: erf(sqrt(pi)/2 C) (eq. 10); ``exponential``: 1 - exp(-C) (random search);
    ``definite_range``: min(C, 1).
    """
    c = np.maximum(np.asarray(coverage, dtype=float), 0.0)
    law = _check_law(law)
    if law == "inverse_cube":
        return erf(_SQRT_PI_2 * c)
    if law == "exponential":
        return -np.expm1(-c)
    return np.minimum(c, 1.0)


def pod_derivative(coverage, law: str = "inverse_cube"):
    """d POD / d C of :func:`pod_from_coverage` (used by the optimal-allocation bound)."""
    c = np.maximum(np.asarray(coverage, dtype=float), 0.0)
    law = _check_law(law)
    if law == "inverse_cube":
        return np.exp(-np.pi * c * c / 4.0)
    if law == "exponential":
        return np.exp(-c)
    return (c < 1.0).astype(float)


def lateral_range(x_m, sweep_width_m):
    """Inverse-cube lateral range curve of one infinite track: 1 - exp(-W^2 / (4 pi x^2)).

    Its integral over x from -inf to inf equals W (that is what a sweep width is).
    """
    x2 = np.square(np.asarray(x_m, dtype=float))
    w2 = float(sweep_width_m) ** 2
    with np.errstate(divide="ignore"):
        return -np.expm1(-w2 / (4.0 * np.pi * x2))


def segment_exponent(x_m, y1_m, y2_m, sweep_width_m):
    """Inverse-cube detection exponent F of one straight segment for a point (DESIGN.md §3).

    The point is at lateral distance ``x`` from the segment's line; the segment's ends are at
    along-track coordinates ``y1 <= y2`` measured from the foot of the perpendicular:

        F = W^2 / (8 pi x^2) * (y2 / sqrt(x^2 + y2^2) - y1 / sqrt(x^2 + y1^2)),

    and the point's detection probability is ``1 - exp(-F)``. For ``y1 -> -inf, y2 -> inf`` it is
    the lateral range curve's exponent ``W^2 / (4 pi x^2)``. When both ends lie on one side of
    the foot, the difference is rewritten without cancellation,
    ``x^2 (y2^2 - y1^2) / (r1 r2 (y2 r1 + y1 r2))``, so the limit ``x -> 0`` is finite
    (``W^2 / (16 pi) * (1/y1^2 - 1/y2^2)``); a point on the segment itself gets ``F = inf``.
    """
    x2 = np.square(np.asarray(x_m, dtype=float))
    y1 = np.asarray(y1_m, dtype=float)
    y2 = np.asarray(y2_m, dtype=float)
    w2 = float(sweep_width_m) ** 2
    # Mirror segments lying wholly on the negative side so that the one-sided case has y1 >= 0.
    neg = y2 <= 0
    a = np.where(neg, -y2, y1)
    b = np.where(neg, -y1, y2)
    r1 = np.sqrt(x2 + a * a)
    r2 = np.sqrt(x2 + b * b)
    with np.errstate(divide="ignore", invalid="ignore"):
        one_sided = w2 / (8 * np.pi) * (b * b - a * a) / (r1 * r2 * (b * r1 + a * r2))
        straddle = w2 / (8 * np.pi * x2) * (b / r2 - a / r1)
    f = np.where(a >= 0, one_sided, straddle)
    # zero-length segments (a == b) and 0/0 corners give no detection; x = 0 straddling gives inf
    f = np.where(b - a > 0, f, 0.0)
    return np.where(np.isnan(f), np.inf, f)


def _segment_frame(points, a, b):
    """Lateral offset, along-track coordinate and length of ``points`` relative to a -> b."""
    p = np.asarray(points, dtype=float)
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    d = b - a
    length = np.hypot(d[..., 0], d[..., 1])
    safe = np.where(length > 0, length, 1.0)
    ux, uy = d[..., 0] / safe, d[..., 1] / safe
    rx, ry = p[..., 0] - a[..., 0], p[..., 1] - a[..., 1]
    along = rx * ux + ry * uy
    lateral = ux * ry - uy * rx
    return lateral, along, length


def distance_to_segment(points, a, b):
    """Euclidean distance from ``points`` to the segments ``a -> b`` (broadcast)."""
    lateral, along, length = _segment_frame(points, a, b)
    beyond = np.where(along < 0, -along, np.where(along > length, along - length, 0.0))
    return np.hypot(lateral, beyond)


def clip_length(a, b, lo, hi):
    """Length of segment a -> b inside the axis-aligned boxes [lo, hi] (Liang-Barsky, broadcast)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    d = b - a
    t0 = np.zeros(np.broadcast_shapes(a.shape[:-1], lo.shape[:-1]))
    t1 = np.ones_like(t0)
    with np.errstate(divide="ignore", invalid="ignore"):
        for k in range(2):
            dk = d[..., k]
            ta = (lo[..., k] - a[..., k]) / dk
            tb = (hi[..., k] - a[..., k]) / dk
            tmin = np.minimum(ta, tb)
            tmax = np.maximum(ta, tb)
            inside = (a[..., k] >= lo[..., k]) & (a[..., k] <= hi[..., k])
            tmin = np.where(dk == 0, np.where(inside, -np.inf, np.inf), tmin)
            tmax = np.where(dk == 0, np.where(inside, np.inf, -np.inf), tmax)
            t0 = np.maximum(t0, tmin)
            t1 = np.minimum(t1, tmax)
    return np.maximum(t1 - t0, 0.0) * np.hypot(d[..., 0], d[..., 1])


def segment_pod(points, a, b, sweep_width_m, law="inverse_cube", cutoff_m=np.inf, cell_m=None):
    """Detection probability of each point for one step flown straight from ``a`` to ``b``.

    ``points`` (..., 2) broadcast against ``a`` and ``b``. Points farther than ``cutoff_m`` from
    the segment get 0 (the documented tail cut-off of the inverse-cube law, see
    :func:`cutoff_error`). For the ``exponential`` law ``cell_m`` is needed: the effort ``W L``
    the segment spends in a point's grid cell (cells aligned on multiples of ``cell_m`` from the
    origin) is spread over that cell.
    """
    law = _check_law(law)
    p = np.asarray(points, dtype=float)
    if law == "exponential":
        if cell_m is None:
            raise ConfigError("cell_m", cell_m, "the cell size when law is exponential")
        lo = np.floor(p / cell_m) * cell_m
        effort = sweep_width_m * clip_length(a, b, lo, lo + cell_m)
        return -np.expm1(-effort / (cell_m * cell_m))
    lateral, along, length = _segment_frame(p, a, b)
    if law == "definite_range":
        hit = (np.abs(lateral) <= 0.5 * sweep_width_m) & (along >= 0) & (along <= length)
        return hit & (length > 0)
    f = segment_exponent(lateral, -along, length - along, sweep_width_m)
    pod = -np.expm1(-f)
    if np.isfinite(cutoff_m):
        pod = np.where(distance_to_segment(p, a, b) <= cutoff_m, pod, 0.0)
    return pod


# --------------------------------------------------------------------------- eq. 12-14


def pos(poc, pod):
    """Probability of success POS = POC x POD (eq. 12), elementwise."""
    return np.asarray(poc, dtype=float) * np.asarray(pod, dtype=float)


def posc(pos_values, axis=None):
    """Cumulative probability of success POSC = POS_1 + ... + POS_n (eq. 13)."""
    return np.sum(np.asarray(pos_values, dtype=float), axis=axis)


def update_poc(poc, pod):
    """POC after a search: POC_new = (1 - POD) x POC_old (eq. 14); unsearched cells keep theirs."""
    return (1.0 - np.asarray(pod, dtype=float)) * np.asarray(poc, dtype=float)


@dataclass(frozen=True)
class SearchWindow:
    """Fine-grid window of a segment: rows ``j0 : j0 + p.shape[-2]``, cols ``i0 : ...``."""

    j0: np.ndarray
    i0: np.ndarray
    pod: np.ndarray


def window_size(grid: Grid, samples_per_cell: int, max_step_m: float, cutoff_m: float) -> int:
    """Side (in fine cells) of the square window that holds every point a step can detect."""
    h = grid.cell_m / samples_per_cell
    k = int(np.ceil((max_step_m + 2.0 * cutoff_m) / h)) + 2
    return max(1, k)


def sweep_windows(
    grid: Grid,
    samples_per_cell: int,
    a,
    b,
    sweep_width_m: float,
    law: str = "inverse_cube",
    cutoff_m: float = np.inf,
    size: int | None = None,
) -> SearchWindow:
    """POD of a batch of steps ``a[k] -> b[k]`` on fixed-size windows of the fine grid.

    Only the sample points a sensor can reach are touched: each step gets a ``size x size``
    window (fine cells) centred on the segment's midpoint and clipped to the grid. ``a`` and
    ``b`` have shape (B, 2); the result's ``pod`` has shape (B, size, size). With the default
    ``size`` the window holds every point within ``cutoff_m`` of the segment; with an infinite
    cut-off the window is the whole grid.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    s = samples_per_cell
    ny, nx = grid.ny * s, grid.nx * s
    h = grid.cell_m / s
    if law == "definite_range":
        cutoff_m = min(cutoff_m, 0.5 * sweep_width_m)
    elif law == "exponential":
        cutoff_m = min(cutoff_m, grid.cell_m * np.sqrt(2.0))
    if size is None:
        if np.isfinite(cutoff_m):
            step = float(np.max(np.hypot(*(b - a).T))) if len(a) else 0.0
            size = window_size(grid, s, step, cutoff_m)
        else:
            size = max(ny, nx)
    ky, kx = min(size, ny), min(size, nx)
    mid = 0.5 * (a + b)
    x0, y0 = grid.origin_m
    i0 = np.clip(np.round((mid[:, 0] - x0) / h - kx / 2).astype(int), 0, nx - kx)
    j0 = np.clip(np.round((mid[:, 1] - y0) / h - ky / 2).astype(int), 0, ny - ky)
    xs = x0 + (i0[:, None] + np.arange(kx) + 0.5) * h  # (B, kx)
    ys = y0 + (j0[:, None] + np.arange(ky) + 0.5) * h  # (B, ky)
    pts = np.stack(np.broadcast_arrays(xs[:, None, :], ys[:, :, None]), axis=-1)
    pod = segment_pod(
        pts, a[:, None, None, :], b[:, None, None, :], sweep_width_m, law, cutoff_m, grid.cell_m
    )
    return SearchWindow(j0=j0, i0=i0, pod=np.asarray(pod, dtype=float))


def apply_windows(belief_fine: np.ndarray, windows: SearchWindow) -> np.ndarray:
    """Apply eq. 14 for each window in turn on ``belief_fine`` (in place); return each POS (eq. 12).

    Windows are applied in order, so a second UAV sweeping the same point in the same step is
    credited only with what the first left (the overlap rule of §3.1.6).
    """
    out = np.empty(len(windows.j0))
    ky, kx = windows.pod.shape[-2:]
    for k in range(len(windows.j0)):
        view = belief_fine[windows.j0[k] : windows.j0[k] + ky, windows.i0[k] : windows.i0[k] + kx]
        found = view * windows.pod[k]
        out[k] = found.sum()
        view -= found
    return out


def sweep_track(
    belief_fine: np.ndarray,
    grid: Grid,
    samples_per_cell: int,
    waypoints,
    sweep_width_m: float,
    law: str = "inverse_cube",
    cutoff_m: float = np.inf,
    step_m: float | None = None,
) -> float:
    """Fly a polyline over the fine belief, updating it by eq. 14; return the track's POS.

    Each leg is cut into steps no longer than ``step_m`` (default: the whole leg). Because the
    inverse-cube exponents of consecutive steps add, the step length changes nothing but speed.
    """
    w = np.asarray(waypoints, dtype=float)
    if len(w) < 2:
        return 0.0
    starts, ends = [], []
    for p, q in itertools.pairwise(w):
        n = 1 if not step_m else max(1, int(np.ceil(np.hypot(*(q - p)) / step_m)))
        t = np.linspace(0.0, 1.0, n + 1)
        pts = p + t[:, None] * (q - p)
        starts.append(pts[:-1])
        ends.append(pts[1:])
    a = np.concatenate(starts)
    b = np.concatenate(ends)
    total = 0.0
    chunk = 256
    for k in range(0, len(a), chunk):
        win = sweep_windows(
            grid, samples_per_cell, a[k : k + chunk], b[k : k + chunk], sweep_width_m, law, cutoff_m
        )
        total += float(apply_windows(belief_fine, win).sum())
    return total


def cutoff_error(cutoff_sweep_widths: float, coverage: float = 1.0, n: int = 4001) -> float:
    """Relative error of eq. 10 when the inverse-cube tail is cut at ``cutoff x W``.

    Parallel infinite tracks at spacing S = W / coverage; the mean POD over one spacing with the
    lateral range exponents of all tracks within the cut-off, against erf(sqrt(pi)/2 C). The
    cut-off drops about ``W^2 / (2 pi S c)`` of detection exponent per point.
    """
    check_positive("cutoff_sweep_widths", cutoff_sweep_widths)
    w = 1.0
    s = w / coverage
    c = cutoff_sweep_widths * w
    x = (np.arange(n) + 0.5) / n * s
    k = np.arange(-int(c / s) - 2, int(c / s) + 3)
    d = x[:, None] - k[None, :] * s
    f = np.where(np.abs(d) <= c, w * w / (4 * np.pi * d * d), 0.0)
    cut = np.mean(-np.expm1(-f.sum(axis=1)))
    exact = float(pod_parallel(w, s))
    return float((exact - cut) / exact)


# --------------------------------------------------------------------------- eq. 15-16


def swarm_pos(memberships, pods, prior):
    """Per-UAV POC_i, POS_i and J of eq. 15-16 with the overlap rule of §3.1.6.

    ``memberships`` (..., n, ny, nx) is the area fraction of each cell inside UAV i's region,
    ``pods`` (..., n) each UAV's POD_i (eq. 15), ``prior`` (ny, nx) the POC map. UAVs are taken in
    order; the part of a cell already allocated to earlier UAVs counts 0 for later ones (the
    paper sets its POC to 0): UAV i is credited with ``min(m_i, 1 - allocated)`` of each cell.
    This is exact for 0/1 memberships (sample points) and for regions that do not overlap inside
    a cell; for regions overlapping inside a cell it assumes the least overlap the fractions
    allow (pass exclusive memberships, e.g. region minus earlier regions, to be exact).
    Returns ``(poc_i, pos_i, J)`` with shapes (..., n), (..., n) and (...). Loops only over UAVs,
    never over individuals or cells.
    """
    m = np.asarray(memberships, dtype=float)
    pods = np.asarray(pods, dtype=float)
    p = np.asarray(prior, dtype=float)
    allocated = np.zeros(m.shape[:-3] + m.shape[-2:])
    poc_i = np.empty(m.shape[:-2])
    for i in range(m.shape[-3]):
        take = np.clip(np.minimum(m[..., i, :, :], 1.0 - allocated), 0.0, None)
        poc_i[..., i] = np.sum(take * p, axis=(-2, -1))
        allocated = allocated + take
    pos_i = pos(poc_i, pods)
    return poc_i, pos_i, posc(pos_i, axis=-1)
