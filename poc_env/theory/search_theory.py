"""Search theory of the paper (§3.1, eq. 7-16) and the step-wise form of the detection laws.

One implementation of each equation, used by the planner, the environment and the reports.

Detection laws (``law``) are the entries of the table :data:`poc_env.theory.detection.LAWS`
(inverse cube, exponential, definite range): their POD as a function of coverage, bound terms,
reach and compiled branch. For the inverse-cube law, one infinite straight track has the
lateral range curve ``p(x) = 1 - exp(-W^2 / (4 pi x^2))`` (:func:`lateral_range`), whose
integral over ``x`` is the sweep width ``W``; a straight *segment* gives every point the
exponent of :func:`segment_exponent`, exponents of consecutive segments add, and parallel
tracks at spacing ``S`` give, on average over the area, eq. 10: ``POD = erf(sqrt(pi)/2 W/S)``.

POC bookkeeping (eq. 12-14): the belief is kept on a fine grid of ``s x s`` sample points per
cell (the target is uniform inside its cell, and a 5 km cell is far coarser than the detection
profile of a 5 km sweep width). After a step, ``POC_new = (1 - p) POC_old`` at every sample point
(eq. 14) and the step's POS is ``sum POC_old * p`` (eq. 12); POSC is their running sum (eq. 13),
so ``POSC + sum(POC)`` stays equal to the initial total.

Implementation: each law's step-wise form is one compiled scalar function of a point and a
segment (:mod:`poc_env._kernels.sensing`). The array functions here (:func:`segment_exponent`,
:func:`segment_pod`, :func:`sweep_windows`) map it over numpy arrays; :func:`sweep_segments`,
the fused kernel the simulator uses, calls it point by point over each segment's reach and
updates the belief in place. The numpy path (:func:`sweep_windows` + :func:`apply_windows`) is
the tests' reference for the fused kernel.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

import poc_env._kernels.sensing as _sensing
from poc_env.errors import ConfigError, check_positive
from poc_env.theory.detection import LAW_NAMES, detection_law
from poc_env.theory.probability_map import Grid

#: The detection laws' names (the table: :data:`poc_env.theory.detection.LAWS`).
LAWS = LAW_NAMES


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

    ``erf`` is eq. 11 (``scipy.special.erf``). POD(W = S) = erf(sqrt(pi)/2) = 0.78991. The
    inverse-cube entry of the law table; :func:`pod_from_coverage` gives every law's.

    Examples
    --------
    >>> from poc_env.theory.search_theory import pod_parallel
    >>> round(float(pod_parallel(sweep_width_m=5e3, spacing_m=5e3)), 5)
    0.78991
    >>> [round(float(p), 4) for p in pod_parallel(5e3, [2.5e3, 10e3])]  # S = W/2, S = 2W
    [0.9878, 0.4691]
    """
    return detection_law("inverse_cube").pod(parallel_coverage(sweep_width_m, spacing_m))


def pod_from_coverage(coverage, law: str = "inverse_cube"):
    """POD as a function of the coverage factor C (eq. 7-9) under ``law`` (its table entry).

    ``inverse_cube``: erf(sqrt(pi)/2 C) (eq. 10); ``exponential``: 1 - exp(-C) (random search);
    ``definite_range``: min(C, 1). Negative coverage counts as 0.

    Examples
    --------
    >>> from poc_env.theory.search_theory import pod_from_coverage
    >>> pod_from_coverage([0.5, 1.0, 2.0], law="definite_range").tolist()
    [0.5, 1.0, 1.0]
    >>> pod_from_coverage([0.5, 1.0, 2.0], law="exponential").round(4).tolist()
    [0.3935, 0.6321, 0.8647]
    """
    entry = detection_law(law)
    return entry.pod(np.maximum(np.asarray(coverage, dtype=float), 0.0))


def pod_derivative(coverage, law: str = "inverse_cube"):
    """d POD / d C of :func:`pod_from_coverage` (used by the optimal-allocation bound)."""
    entry = detection_law(law)
    return entry.pod_slope(np.maximum(np.asarray(coverage, dtype=float), 0.0))


def lateral_range(x_m, sweep_width_m):
    """Inverse-cube lateral range curve of one infinite track: 1 - exp(-W^2 / (4 pi x^2)).

    Its integral over x from -inf to inf equals W (that is what a sweep width is).
    """
    x2 = np.square(np.asarray(x_m, dtype=float))
    w2 = float(sweep_width_m) ** 2
    with np.errstate(divide="ignore"):
        return -np.expm1(-w2 / (4.0 * np.pi * x2))


def _xy(v):
    v = np.asarray(v, dtype=float)
    return v[..., 0], v[..., 1]


def segment_exponent(x_m, y1_m, y2_m, sweep_width_m):
    """Inverse-cube detection exponent F of one straight segment for a point.

    The point is at lateral distance ``x`` from the segment's line; the segment's ends are at
    along-track coordinates ``y1 <= y2`` measured from the foot of the perpendicular:

        F = W^2 / (8 pi x^2) * (y2 / sqrt(x^2 + y2^2) - y1 / sqrt(x^2 + y1^2)),

    and the point's detection probability is ``1 - exp(-F)``. For ``y1 -> -inf, y2 -> inf`` it is
    the lateral range curve's exponent ``W^2 / (4 pi x^2)``. When both ends lie on one side of
    the foot, the difference is rewritten without cancellation,
    ``x^2 (y2^2 - y1^2) / (r1 r2 (y2 r1 + y1 r2))``, so the limit ``x -> 0`` is finite
    (``W^2 / (16 pi) * (1/y1^2 - 1/y2^2)``); a point on the segment itself gets ``F = inf``.
    The formula is the compiled scalar the sweep kernel uses (:mod:`poc_env._kernels.sensing`).
    """
    return _sensing.segment_exponent(x_m, y1_m, y2_m, float(sweep_width_m))


def distance_to_segment(points, a, b):
    """Euclidean distance from ``points`` to the segments ``a -> b`` (broadcast)."""
    return _sensing.distance_to_segment(*_xy(points), *_xy(a), *_xy(b))


def clip_length(a, b, lo, hi):
    """Length of segment a -> b inside the axis-aligned boxes [lo, hi] (Liang-Barsky, broadcast)."""
    return _sensing.clip_length(*_xy(a), *_xy(b), *_xy(lo), *_xy(hi))


def segment_pod(
    points, a, b, sweep_width_m, law="inverse_cube", cutoff_m=np.inf, cell_m=None, origin=(0, 0)
):
    """Detection probability of each point for one step flown straight from ``a`` to ``b``.

    ``points`` (..., 2) broadcast against ``a`` and ``b``. Points farther than ``cutoff_m`` from
    the segment get 0 (the documented tail cut-off of the inverse-cube law, see
    :func:`cutoff_error`). For the ``exponential`` law ``cell_m`` is needed: the effort ``W L``
    the segment spends in a point's grid cell (cells aligned on multiples of ``cell_m`` from the
    grid's ``origin``) is spread over that cell. ``definite_range`` returns a boolean array.
    """
    o = np.asarray(origin, dtype=float)
    points, a, b = (np.asarray(v, dtype=float) - o for v in (points, a, b))
    entry = detection_law(law)
    if entry.needs_cell and cell_m is None:
        raise ConfigError("cell_m", cell_m, f"the cell size when law is {entry.name}")
    cell = float(cell_m) if cell_m is not None else 1.0
    pod = _sensing.segment_pod(
        entry.code, *_xy(points), *_xy(a), *_xy(b), float(sweep_width_m), float(cutoff_m), cell
    )
    return pod > 0.0 if entry.indicator else pod


# --------------------------------------------------------------------------- eq. 12-14


def pos(poc, pod):
    """Probability of success POS = POC x POD (eq. 12), elementwise."""
    return np.asarray(poc, dtype=float) * np.asarray(pod, dtype=float)


def posc(pos_values, axis=None):
    """Cumulative probability of success POSC = POS_1 + ... + POS_n (eq. 13)."""
    return np.sum(np.asarray(pos_values, dtype=float), axis=axis)


def update_poc(poc, pod):
    """POC after a search: POC_new = (1 - POD) x POC_old (eq. 14); unsearched cells keep theirs.

    Examples
    --------
    >>> from poc_env.theory.search_theory import update_poc
    >>> update_poc([0.5, 0.3, 0.2], [0.8, 0.0, 0.5]).round(12).tolist()
    [0.1, 0.3, 0.1]
    """
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


def _reach(grid: Grid, law: str, sweep_width_m: float, cutoff_m: float) -> float:
    """Farthest distance from a segment at which ``law`` can detect anything."""
    return detection_law(law).reach(sweep_width_m, cutoff_m, grid.cell_m)


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
    cut-off the window is the whole grid. This is the numpy path (with :func:`apply_windows`);
    :func:`sweep_segments` is the fused kernel that gives the same result without temporaries.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    s = samples_per_cell
    ny, nx = grid.ny * s, grid.nx * s
    h = grid.cell_m / s
    cutoff_m = _reach(grid, law, sweep_width_m, cutoff_m)
    if size is None:
        if np.isfinite(cutoff_m):
            step = float(np.max(np.hypot(*(b - a).T))) if len(a) else 0.0
            size = window_size(grid, s, step, cutoff_m)
        else:
            size = max(ny, nx)
    ky, kx = min(size, ny), min(size, nx)
    mid = 0.5 * (a + b)
    x0, y0 = grid.origin_m
    i0 = _sensing.window_start(mid[:, 0], x0, h, kx, nx)
    j0 = _sensing.window_start(mid[:, 1], y0, h, ky, ny)
    xs = x0 + (i0[:, None] + np.arange(kx) + 0.5) * h  # (B, kx)
    ys = y0 + (j0[:, None] + np.arange(ky) + 0.5) * h  # (B, ky)
    pts = np.stack(np.broadcast_arrays(xs[:, None, :], ys[:, :, None]), axis=-1)
    pod = segment_pod(
        pts,
        a[:, None, None, :],
        b[:, None, None, :],
        sweep_width_m,
        law,
        cutoff_m,
        grid.cell_m,
        grid.origin_m,
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


def sweep_segments(
    belief_fine: np.ndarray,
    grid: Grid,
    samples_per_cell: int,
    a,
    b,
    sweep_width_m: float,
    law: str = "inverse_cube",
    cutoff_m: float = np.inf,
) -> np.ndarray:
    """Sweep the steps ``a[e, i] -> b[e, i]`` over ``belief_fine[e]`` (eq. 14, in place).

    ``belief_fine`` (E, ny s, nx s), ``a`` and ``b`` (E, N, 2); returns each step's POS (eq. 12),
    shape (E, N). The fused kernel of :func:`sweep_windows` + :func:`apply_windows`: envs are
    independent, the steps of one env are applied in order (a point two UAVs sweep in one step
    is credited to the first, §3.1.6), and every point within the law's reach of a segment gets
    the detection probability of :func:`segment_pod` -- the same compiled scalar formula.
    """
    code = detection_law(law).code
    belief = belief_fine
    if belief.dtype != np.float64 or not belief.flags.c_contiguous or belief.ndim != 3:
        raise ValueError("belief_fine must be a C-contiguous float64 array (E, ny*s, nx*s)")
    s = samples_per_cell
    if belief.shape[1:] != (grid.ny * s, grid.nx * s):
        raise ValueError(
            f"belief_fine has shape {belief.shape}, grid needs {grid.ny * s, grid.nx * s}"
        )
    # grid-relative coordinates: exponential-law cells are aligned on the grid's origin
    origin = np.asarray(grid.origin_m, dtype=np.float64)
    a = np.ascontiguousarray(np.asarray(a, dtype=np.float64) - origin)
    b = np.ascontiguousarray(np.asarray(b, dtype=np.float64) - origin)
    found = np.empty(a.shape[:2])
    x0, y0 = 0.0, 0.0
    _sensing.sweep(
        belief,
        a,
        b,
        code,
        float(sweep_width_m),
        float(cutoff_m),
        float(_reach(grid, law, sweep_width_m, cutoff_m)),
        float(grid.cell_m),
        float(x0),
        float(y0),
        grid.cell_m / s,
        found,
    )
    return found


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
    a = np.concatenate(starts)[None]
    b = np.concatenate(ends)[None]
    belief = np.ascontiguousarray(belief_fine, dtype=np.float64)
    found = sweep_segments(belief[None], grid, samples_per_cell, a, b, sweep_width_m, law, cutoff_m)
    if belief is not belief_fine:
        belief_fine[...] = belief
    return float(found.sum())


def cutoff_error(
    cutoff_sweep_widths: float,
    coverage: float = 1.0,
    step_sweep_widths: float = 0.0,
    n: int = 4001,
) -> float:
    """Relative error of eq. 10 when the inverse-cube tail is cut at ``cutoff x W``.

    Parallel infinite tracks at spacing S = W / coverage, flown in steps of ``step x W``: a point
    keeps every step within ``c`` of it, i.e. of a track at lateral distance ``d <= c`` the part
    ``+- sqrt(c^2 - d^2)`` inside the disc of radius ``c`` plus, on average, half a step on each
    side (steps reaching into the disc count whole); tracks farther than ``c`` give nothing.
    Returns the relative shortfall of the mean POD at ``n`` evenly spaced points across one
    spacing against the uncut tracks at the same points -- for large ``n`` that is
    erf(sqrt(pi)/2 C) (eq. 10); ``n = s`` gives the shortfall at the environment's sample
    points when a cell is one spacing wide. With ``step = 0`` it is the disc alone.
    """
    check_positive("cutoff_sweep_widths", cutoff_sweep_widths)
    check_positive("step_sweep_widths", step_sweep_widths, allow_zero=True)
    w = 1.0
    s = w / coverage
    c = cutoff_sweep_widths * w
    x = (np.arange(n) + 0.5) / n * s
    k = np.arange(-int(c / s) - 2, int(c / s) + 3)
    d = x[:, None] - k[None, :] * s
    half = np.sqrt(np.maximum(c * c - d * d, 0.0)) + 0.5 * step_sweep_widths * w
    f = np.where(np.abs(d) <= c, segment_exponent(d, -half, half, w), 0.0)
    cut = np.mean(-np.expm1(-f.sum(axis=1)))
    # all tracks, uncut: sum_k 1 / (x - kS)^2 = (pi / S)^2 / sin^2(pi x / S)
    full = np.mean(-np.expm1(-w * w * np.pi / (4 * s * s * np.sin(np.pi * x / s) ** 2)))
    return float((full - cut) / full)


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
