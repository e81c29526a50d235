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

Implementation: each law is one compiled scalar function of a point and a segment (numba).
The array functions here (:func:`segment_exponent`, :func:`segment_pod`, :func:`sweep_windows`)
map it over numpy arrays; :func:`sweep_segments`, the fused kernel the simulator uses, calls it
point by point over each segment's reach and updates the belief in place.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np
from llvmlite import ir as llvm_ir
from numba import njit, types, vectorize
from numba.core import cgutils
from numba.extending import intrinsic
from scipy.special import erf

from poc_env.errors import ConfigError, check_positive
from poc_env.theory.probability_map import Grid

LAWS = ("inverse_cube", "exponential", "definite_range")
_LAW_CODE = {law: k for k, law in enumerate(LAWS)}
_INVERSE_CUBE, _EXPONENTIAL, _DEFINITE_RANGE = range(3)
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


# Scalar kernels. Each detection law is written once, here, as a compiled scalar function of one
# point and one segment. The numpy API below (segment_exponent, segment_pod, clip_length,
# distance_to_segment, sweep_windows) maps them over arrays with numba ufuncs; the fused sweep
# kernel (sweep_segments) calls the same functions point by point. error_model="numpy" makes
# x / 0 an inf instead of an exception; inline="always" lets the compiler vectorise the sweep's
# inner loop (it must see the whole computation, with no call in it).
_jit = njit(cache=True, error_model="numpy")
_jit_inline = njit(cache=True, error_model="numpy", inline="always")

_LN2_HI = 6.93147180369123816490e-01  # ln 2 split for an exact n * ln2_hi (fdlibm)
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00


@intrinsic
def _pow2_neg(typingctx, m):
    """``2.0 ** -m`` for an int64 ``0 <= m <= 1022``, built from its exponent bits (exact)."""
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):
        i64 = llvm_ir.IntType(64)
        bits = builder.shl(
            builder.sub(llvm_ir.Constant(i64, 1023), args[0]), llvm_ir.Constant(i64, 52)
        )
        return builder.bitcast(bits, llvm_ir.DoubleType())

    return sig, codegen


@intrinsic
def _prefetch(typingctx, arr, j, k):
    """Ask the CPU to fetch ``arr[j, k]`` into the cache (``llvm.prefetch``; results unchanged)."""
    sig = types.void(arr, j, k)

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, value=args[0])
        ptr = cgutils.get_item_pointer(
            context, builder, aryty, ary, [args[1], args[2]], wraparound=False
        )
        i8p = llvm_ir.IntType(8).as_pointer()
        i32 = llvm_ir.IntType(32)
        fnty = llvm_ir.FunctionType(llvm_ir.VoidType(), [i8p, i32, i32, i32])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.prefetch.p0")
        flags = [llvm_ir.Constant(i32, v) for v in (1, 3, 1)]  # write, keep, data
        builder.call(fn, [builder.bitcast(ptr, i8p), *flags])
        return context.get_dummy_value()

    return sig, codegen


@_jit_inline
def _one_minus_exp_neg(f):
    """``1 - exp(-f)`` for ``f >= 0`` (``inf -> 1``), i.e. ``-expm1(-f)``, to within 2 ulp.

    Written out (Cody-Waite reduction ``f = n ln 2 + r``, ``|r| <= ln 2 / 2``, and the Taylor
    polynomial of ``expm1`` to degree 13, whose truncation error is below 1e-17 there) instead of
    calling ``math.expm1``: a library call per point costs 6-15 ns and keeps the compiler from
    vectorising the sweep; this form is branch-free. ``f >= 50`` gives 1 exactly, as it must.
    """
    ff = min(f, 50.0)
    n = np.floor(ff * _INV_LN2 + 0.5)
    y = n * _LN2_LO - (ff - n * _LN2_HI)  # -r
    q = 1.0 / 6227020800.0
    q = q * y + 1.0 / 479001600.0
    q = q * y + 1.0 / 39916800.0
    q = q * y + 1.0 / 3628800.0
    q = q * y + 1.0 / 362880.0
    q = q * y + 1.0 / 40320.0
    q = q * y + 1.0 / 5040.0
    q = q * y + 1.0 / 720.0
    q = q * y + 1.0 / 120.0
    q = q * y + 1.0 / 24.0
    q = q * y + 1.0 / 6.0
    q = q * y + 0.5
    em = y + y * y * q  # expm1(-r)
    m = int(n)  # 0 <= m <= 73
    return 0.0 - em if m == 0 else 1.0 - _pow2_neg(m) * (1.0 + em)


@_jit_inline
def _ic_exponent(x, y1, y2, w2):
    """Inverse-cube exponent F of one segment for one point, ``w2 = W^2`` (see segment_exponent).

    Both cases are written as ``W^2 / (8 pi) * num / den`` (one division, branch-free), with
    ``r1 = sqrt(x^2 + a^2)``, ``r2 = sqrt(x^2 + b^2)``: one-sided (``0 <= a < b`` after
    mirroring) ``num = (b - a)(b + a)``, ``den = r1 r2 (b r1 + a r2)``; straddling
    (``a < 0 < b``) ``num = b r1 - a r2`` (no cancellation), ``den = x^2 r1 r2``. ``den = 0`` is
    a point on the segment (``F = inf``); a zero-length segment gives 0.
    """
    x2 = x * x
    # Mirror segments lying wholly on the negative side so that the one-sided case has a >= 0.
    neg = y2 <= 0.0
    a = -y2 if neg else y1
    b = -y1 if neg else y2
    r1 = math.sqrt(x2 + a * a)
    r2 = math.sqrt(x2 + b * b)
    one_sided = a >= 0.0
    num = (b - a) * (b + a) if one_sided else b * r1 - a * r2
    den = r1 * r2 * (b * r1 + a * r2) if one_sided else x2 * r1 * r2
    f = w2 / (8.0 * math.pi) * num / (den if den > 0.0 else 1.0)
    f = f if den > 0.0 else math.inf
    return f if b - a > 0.0 else 0.0


@_jit_inline
def _seg_axis(ax, ay, bx, by):
    """Unit direction and length of the segment a -> b (direction (0, 0) if it has no length)."""
    dx = bx - ax
    dy = by - ay
    length = math.hypot(dx, dy)
    safe = length if length > 0.0 else 1.0
    return dx / safe, dy / safe, length


@_jit_inline
def _frame(px, py, ax, ay, ux, uy, length):
    """Lateral offset, along-track coordinate and distance beyond the ends of p, for a -> b."""
    rx = px - ax
    ry = py - ay
    along = rx * ux + ry * uy
    lateral = ux * ry - uy * rx
    beyond = max(max(-along, along - length), 0.0)
    return lateral, along, beyond


@_jit_inline
def _ic_pod(px, py, ax, ay, ux, uy, length, w2, cutoff):
    """Inverse-cube POD ``1 - exp(-F)`` of point p; 0 beyond ``cutoff`` from the segment."""
    lateral, along, beyond = _frame(px, py, ax, ay, ux, uy, length)
    p = _one_minus_exp_neg(_ic_exponent(lateral, -along, length - along, w2))
    return p if lateral * lateral + beyond * beyond <= cutoff * cutoff else 0.0


@_jit_inline
def _dr_pod(px, py, ax, ay, ux, uy, length, w):
    """Definite-range POD: 1 within ``W/2`` of the segment, the foot on it; else 0."""
    lateral, along, _ = _frame(px, py, ax, ay, ux, uy, length)
    hit = abs(lateral) <= 0.5 * w and 0.0 <= along <= length and length > 0.0
    return 1.0 if hit else 0.0


@_jit
def _clip_len(ax, ay, bx, by, lox, loy, hix, hiy):
    """Length of segment a -> b inside the box [lo, hi] (Liang-Barsky)."""
    t0 = 0.0
    t1 = 1.0
    for k in range(2):
        if k == 0:
            p, d, lo, hi = ax, bx - ax, lox, hix
        else:
            p, d, lo, hi = ay, by - ay, loy, hiy
        if d == 0.0:
            if not (lo <= p <= hi):
                return 0.0
        else:
            ta = (lo - p) / d
            tb = (hi - p) / d
            t0 = max(t0, min(ta, tb))
            t1 = min(t1, max(ta, tb))
    return max(t1 - t0, 0.0) * math.hypot(bx - ax, by - ay)


@_jit
def _exp_pod(px, py, ax, ay, bx, by, w, cell):
    """Exponential (random search) POD ``1 - exp(-W L / c^2)``, L the length in p's cell."""
    lox = math.floor(px / cell) * cell
    loy = math.floor(py / cell) * cell
    effort = w * _clip_len(ax, ay, bx, by, lox, loy, lox + cell, loy + cell)
    return _one_minus_exp_neg(effort / (cell * cell))


@_jit
def _point_pod(law, px, py, ax, ay, bx, by, w, cutoff, cell):
    """Detection probability of point p for the step a -> b under ``law`` (a _LAW_CODE)."""
    if law == _EXPONENTIAL:
        return _exp_pod(px, py, ax, ay, bx, by, w, cell)
    ux, uy, length = _seg_axis(ax, ay, bx, by)
    if law == _DEFINITE_RANGE:
        return _dr_pod(px, py, ax, ay, ux, uy, length, w)
    return _ic_pod(px, py, ax, ay, ux, uy, length, w * w, cutoff)


@_jit
def _window_start(mid, origin, h, k, n):
    """First fine index of the ``k`` wide window centred on ``mid``, clipped to ``[0, n - k]``."""
    return min(max(round((mid - origin) / h - k / 2), 0), n - k)


def _ufunc(*signatures: str):
    """Map a compiled scalar over numpy arrays: a numba ufunc, built (or loaded from the
    on-disk cache) at its first call rather than at import."""

    def wrap(fn):
        built = []

        @functools.wraps(fn)
        def call(*args):
            if not built:
                built.append(vectorize(list(signatures), cache=True)(fn))
            return built[0](*args)

        return call

    return wrap


_F8 = "float64"


@_ufunc(f"{_F8}({_F8}, {_F8}, {_F8}, {_F8})")
def _segment_exponent_ufunc(x, y1, y2, w):
    return _ic_exponent(x, y1, y2, w * w)


@_ufunc(f"{_F8}(int64, {', '.join([_F8] * 9)})")
def _segment_pod_ufunc(law, px, py, ax, ay, bx, by, w, cutoff, cell):
    return _point_pod(law, px, py, ax, ay, bx, by, w, cutoff, cell)


@_ufunc(f"{_F8}({', '.join([_F8] * 8)})")
def _clip_length_ufunc(ax, ay, bx, by, lox, loy, hix, hiy):
    return _clip_len(ax, ay, bx, by, lox, loy, hix, hiy)


@_ufunc(f"{_F8}({', '.join([_F8] * 6)})")
def _distance_ufunc(px, py, ax, ay, bx, by):
    ux, uy, length = _seg_axis(ax, ay, bx, by)
    lateral, _, beyond = _frame(px, py, ax, ay, ux, uy, length)
    return math.hypot(lateral, beyond)


@_ufunc(f"int64({_F8}, {_F8}, {_F8}, int64, int64)")
def _window_start_ufunc(mid, origin, h, k, n):
    return _window_start(mid, origin, h, k, n)


def _xy(v):
    v = np.asarray(v, dtype=float)
    return v[..., 0], v[..., 1]


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
    The formula is the compiled scalar ``_ic_exponent``, the one the sweep kernel uses.
    """
    return _segment_exponent_ufunc(x_m, y1_m, y2_m, float(sweep_width_m))


def distance_to_segment(points, a, b):
    """Euclidean distance from ``points`` to the segments ``a -> b`` (broadcast)."""
    return _distance_ufunc(*_xy(points), *_xy(a), *_xy(b))


def clip_length(a, b, lo, hi):
    """Length of segment a -> b inside the axis-aligned boxes [lo, hi] (Liang-Barsky, broadcast)."""
    return _clip_length_ufunc(*_xy(a), *_xy(b), *_xy(lo), *_xy(hi))


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
    code = _LAW_CODE[_check_law(law)]
    if code == _EXPONENTIAL and cell_m is None:
        raise ConfigError("cell_m", cell_m, "the cell size when law is exponential")
    cell = float(cell_m) if cell_m is not None else 1.0
    pod = _segment_pod_ufunc(
        code, *_xy(points), *_xy(a), *_xy(b), float(sweep_width_m), float(cutoff_m), cell
    )
    return pod > 0.0 if code == _DEFINITE_RANGE else pod


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


def _reach(grid: Grid, law: str, sweep_width_m: float, cutoff_m: float) -> float:
    """Farthest distance from a segment at which ``law`` can detect anything."""
    if law == "definite_range":
        return min(cutoff_m, 0.5 * sweep_width_m)
    if law == "exponential":
        return min(cutoff_m, grid.cell_m * np.sqrt(2.0))
    return cutoff_m


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
    i0 = _window_start_ufunc(mid[:, 0], x0, h, kx, nx)
    j0 = _window_start_ufunc(mid[:, 1], y0, h, ky, ny)
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


@_jit
def _index_range(lo, hi, origin, h, n):
    """Half-open range of fine indices ``j`` whose sample ``origin + (j + 0.5) h`` lies in
    ``[lo, hi]`` (grown by 1e-6 h against rounding), clipped to ``[0, n)``."""
    first = min(max(np.ceil((lo - origin) / h - 0.5 - 1e-6), 0.0), float(n))
    last = min(max(np.floor((hi - origin) / h + 0.5 + 1e-6), 0.0), float(n))
    return int(first), int(last)


@_jit
def _capsule_row(py, ax, ay, bx, by, ux, uy, length, c, iux, iuy):
    """Interval ``[lo, hi]`` of x on the line ``y = py`` within ``c`` of the segment a -> b.

    The union of the two end discs and the band ``0 <= along <= length, |lateral| <= c``
    (``lo > hi`` when the line misses them); the segment has a length, ``iux = 1 / ux`` and
    ``iuy = 1 / uy`` (unused where ``ux`` or ``uy`` is 0). A superset is enough: the caller
    still tests each point's distance.
    """
    lo = math.inf
    hi = -math.inf
    for cx, cy in ((ax, ay), (bx, by)):
        dy = py - cy
        if abs(dy) <= c:
            half = math.sqrt(c * c - dy * dy)
            lo = min(lo, cx - half)
            hi = max(hi, cx + half)
    # along = ux t + uy ry and lateral = ux ry - uy t, with t = x - ax
    ry = py - ay
    s0 = -uy * ry
    s1 = ux * ry
    tlo = -math.inf
    thi = math.inf
    hit = True
    if ux > 0.0:
        tlo, thi = s0 * iux, (length + s0) * iux
    elif ux < 0.0:
        tlo, thi = (length + s0) * iux, s0 * iux
    else:
        hit = -length <= s0 <= 0.0
    if uy > 0.0:
        tlo, thi = max(tlo, (s1 - c) * iuy), min(thi, (s1 + c) * iuy)
    elif uy < 0.0:
        tlo, thi = max(tlo, (s1 + c) * iuy), min(thi, (s1 - c) * iuy)
    else:
        hit = hit and abs(s1) <= c
    if hit and tlo <= thi:
        lo = min(lo, ax + tlo)
        hi = max(hi, ax + thi)
    return lo, hi


@njit(cache=True, fastmath={"reassoc", "nsz"})
def _sum_range(x, k0, k1):
    """``sum(x[k0:k1])``, vectorised (the order of the additions is left to the compiler)."""
    xs = x[k0:k1]  # indices from 0 up: no negative-index wraparound, so the loop vectorises
    total = 0.0
    for k in range(k1 - k0):
        total += xs[k]
    return total


@_jit_inline
def _ic_row(row, hits, k0, k1, x0, h, py, ax, ay, ux, uy, length, w2, cutoff):
    """Eq. 12 and 14 on ``row[k0:k1]`` for an inverse-cube step; ``hits[k]`` += what is found."""
    seg = row[k0:k1]  # indices from 0 up: no negative-index wraparound, so the loop vectorises
    out = hits[k0:k1]
    for k in range(k1 - k0):
        p = _ic_pod(x0 + (k0 + k + 0.5) * h, py, ax, ay, ux, uy, length, w2, cutoff)
        v = seg[k]
        hit = v * p
        out[k] += hit
        seg[k] = v - hit


@_jit_inline
def _dr_row(row, hits, k0, k1, x0, h, py, ax, ay, ux, uy, length, w):
    seg = row[k0:k1]  # indices from 0 up: no negative-index wraparound, so the loop vectorises
    out = hits[k0:k1]
    for k in range(k1 - k0):
        p = _dr_pod(x0 + (k0 + k + 0.5) * h, py, ax, ay, ux, uy, length, w)
        v = seg[k]
        hit = v * p
        out[k] += hit
        seg[k] = v - hit


@_jit_inline
def _exp_row(row, hits, k0, k1, x0, h, py, ax, ay, bx, by, w, cell):
    seg = row[k0:k1]  # indices from 0 up: no negative-index wraparound, so the loop vectorises
    out = hits[k0:k1]
    for k in range(k1 - k0):
        p = _exp_pod(x0 + (k0 + k + 0.5) * h, py, ax, ay, bx, by, w, cell)
        v = seg[k]
        hit = v * p
        out[k] += hit
        seg[k] = v - hit


_LANES = 8  # rows are swept in multiples of this many points (no scalar remainder loop)


@_jit
def _sweep_kernel(belief, a, b, law, w, cutoff, reach, cell, x0, y0, h, found):
    """Eq. 12 and 14 for every segment ``a[e, i] -> b[e, i]`` on ``belief[e]``, in place.

    Envs one after another, the agents of an env in agent order (the overlap rule). Each
    segment visits the rows of its reach's bounding box and, in each row, the points near the
    row's stretch within reach (for the inverse-cube law the exact stretch of the capsule,
    padded to a multiple of ``_LANES`` points); each point gets its POD ``p`` from the law's
    scalar function and ``POC <- POC - POC p``; ``found[e, i]`` sums what was taken.
    Points out of reach get ``p = 0`` from the same function, so visiting more changes nothing.
    """
    n_env, n_agent = a.shape[0], a.shape[1]
    ny, nx = belief.shape[1], belief.shape[2]
    hits = np.zeros(nx)
    w2 = w * w
    for e in range(n_env):
        for i in range(n_agent):
            ax, ay, bx, by = a[e, i, 0], a[e, i, 1], b[e, i, 0], b[e, i, 1]
            total = 0.0
            kmin, kmax = nx, 0
            if ax != bx or ay != by:  # a zero-length step detects nothing, under every law
                ux, uy, length = _seg_axis(ax, ay, bx, by)
                c0, c1 = _index_range(min(ax, bx) - reach, max(ax, bx) + reach, x0, h, nx)
                r0, r1 = _index_range(min(ay, by) - reach, max(ay, by) + reach, y0, h, ny)
                capsule = law == _INVERSE_CUBE and reach < math.inf
                iux = 1.0 / ux if ux != 0.0 else 0.0
                iuy = 1.0 / uy if uy != 0.0 else 0.0
                for j in range(r0, r1):
                    py = y0 + (j + 0.5) * h
                    k0, k1 = c0, c1
                    if capsule:
                        lo, hi = _capsule_row(py, ax, ay, bx, by, ux, uy, length, reach, iux, iuy)
                        k0, k1 = _index_range(lo, hi, x0, h, nx)
                        span = -(-(k1 - k0) // _LANES) * _LANES
                        if k1 <= k0:
                            continue
                        if span <= nx:
                            k1 = min(k0 + span, nx)
                            k0 = k1 - span
                    if k1 <= k0:
                        continue
                    if j + 2 < r1:
                        for kk in range(max(k0 - 8, 0), min(k1 + 8, nx), 8):
                            _prefetch(belief[e], j + 2, kk)
                    row = belief[e, j]
                    if law == _INVERSE_CUBE:
                        _ic_row(row, hits, k0, k1, x0, h, py, ax, ay, ux, uy, length, w2, cutoff)
                    elif law == _DEFINITE_RANGE:
                        _dr_row(row, hits, k0, k1, x0, h, py, ax, ay, ux, uy, length, w)
                    else:
                        _exp_row(row, hits, k0, k1, x0, h, py, ax, ay, bx, by, w, cell)
                    kmin = min(kmin, k0)
                    kmax = max(kmax, k1)
            if kmin < kmax:  # column sums of what the segment found -> its POS; reset to 0
                total = _sum_range(hits, kmin, kmax)
                hits[kmin:kmax] = 0.0
            found[e, i] = total


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
    code = _LAW_CODE[_check_law(law)]
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
    _sweep_kernel(
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
