"""Compiled sensing: the detection laws' scalar POD, their array forms, the fused sweep.

Eq. 12-14 of the paper: the inverse-cube, exponential and definite-range laws' detection
probability of a point for one straight step (:func:`_point_pod`), mapped over arrays as numba
ufuncs for :mod:`poc_env.theory.search_theory` (``segment_exponent``, ``segment_pod``,
``clip_length``, ``distance_to_segment``, ``window_start``), the sweep of every UAV's step over
the fine belief (:func:`sweep`), and the hidden target's POD for the simulator step
(:func:`target_pod`). Also the eq. 19 kinematics (:func:`kinematics`, moved here from the
swarm kernels so that the single environment's step flies and senses in one call,
:func:`fly_sense`). Tested against plain-numpy references in ``tests/sim``.

A kernel module: imports nothing of the project (the cache rule, :mod:`poc_env._kernels`).
Imports numpy, numba, and llvmlite (numba's code generator, for two intrinsics).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from llvmlite import ir as llvm_ir
from numba import njit, types, vectorize
from numba.core import cgutils
from numba.extending import intrinsic

_jit = njit(cache=True, error_model="numpy")
_jit_inline = njit(cache=True, error_model="numpy", inline="always")

# ---------------------------------------------------------------------------------- detection laws

#: Integer codes of the detection laws' compiled branches (:func:`_point_pod`, :func:`sweep`).
INVERSE_CUBE, EXPONENTIAL, DEFINITE_RANGE = range(3)
#: The compiled branch of each law by name. The table of laws is
#: :data:`poc_env.theory.detection.LAWS`; this mapping sits in the base layer so that the
#: configuration (which may not import the theory layer) can validate ``sensor.law``, and the
#: table checks at import that it covers exactly these names.
LAW_CODES = {
    "inverse_cube": INVERSE_CUBE,
    "exponential": EXPONENTIAL,
    "definite_range": DEFINITE_RANGE,
}


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
def one_minus_exp_neg(f):
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
    p = one_minus_exp_neg(_ic_exponent(lateral, -along, length - along, w2))
    return p if lateral * lateral + beyond * beyond <= cutoff * cutoff else 0.0


@_jit_inline
def _dr_pod(px, py, ax, ay, ux, uy, length, w):
    """Definite-range POD: 1 within ``W/2`` of the segment, the foot on it; else 0."""
    lateral, along, _ = _frame(px, py, ax, ay, ux, uy, length)
    hit = abs(lateral) <= 0.5 * w and 0.0 <= along <= length and length > 0.0
    return 1.0 if hit else 0.0


@_jit
def _clip_len(ax, ay, bx, by, lox, loy, hix, hiy):
    """Length of segment a -> b inside the half-open box [lo, hi) (Liang-Barsky).

    Half-open: a segment running exactly along an edge belongs to one cell (the one above or to
    the right), so effort along a shared edge is counted once, not in both cells."""
    t0 = 0.0
    t1 = 1.0
    for k in range(2):
        if k == 0:
            p, d, lo, hi = ax, bx - ax, lox, hix
        else:
            p, d, lo, hi = ay, by - ay, loy, hiy
        if d == 0.0:
            if not (lo <= p < hi):
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
    return one_minus_exp_neg(effort / (cell * cell))


@_jit
def _point_pod(law, px, py, ax, ay, bx, by, w, cutoff, cell):
    """Detection probability of point p for the step a -> b under ``law`` (a LAW_CODES value)."""
    if law == EXPONENTIAL:
        return _exp_pod(px, py, ax, ay, bx, by, w, cell)
    ux, uy, length = _seg_axis(ax, ay, bx, by)
    if law == DEFINITE_RANGE:
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
def segment_exponent(x, y1, y2, w):
    return _ic_exponent(x, y1, y2, w * w)


@_ufunc(f"{_F8}(int64, {', '.join([_F8] * 9)})")
def segment_pod(law, px, py, ax, ay, bx, by, w, cutoff, cell):
    return _point_pod(law, px, py, ax, ay, bx, by, w, cutoff, cell)


@_ufunc(f"{_F8}({', '.join([_F8] * 8)})")
def clip_length(ax, ay, bx, by, lox, loy, hix, hiy):
    return _clip_len(ax, ay, bx, by, lox, loy, hix, hiy)


@_ufunc(f"{_F8}({', '.join([_F8] * 6)})")
def distance_to_segment(px, py, ax, ay, bx, by):
    ux, uy, length = _seg_axis(ax, ay, bx, by)
    lateral, _, beyond = _frame(px, py, ax, ay, ux, uy, length)
    return math.hypot(lateral, beyond)


@_ufunc(f"int64({_F8}, {_F8}, {_F8}, int64, int64)")
def window_start(mid, origin, h, k, n):
    return _window_start(mid, origin, h, k, n)


# ------------------------------------------------------------------------------- the sensing sweep


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
def sweep(belief, a, b, law, w, cutoff, reach, cell, x0, y0, h, found):
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
                capsule = law == INVERSE_CUBE and reach < math.inf
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
                    if law == INVERSE_CUBE:
                        _ic_row(row, hits, k0, k1, x0, h, py, ax, ay, ux, uy, length, w2, cutoff)
                    elif law == DEFINITE_RANGE:
                        _dr_row(row, hits, k0, k1, x0, h, py, ax, ay, ux, uy, length, w)
                    else:
                        _exp_row(row, hits, k0, k1, x0, h, py, ax, ay, bx, by, w, cell)
                    kmin = min(kmin, k0)
                    kmax = max(kmax, k1)
            if kmin < kmax:  # column sums of what the segment found -> its POS; reset to 0
                total = _sum_range(hits, kmin, kmax)
                hits[kmin:kmax] = 0.0
            found[e, i] = total


# ------------------------------------------------------------------------ eq. 19 kinematics

#: The scalar constants of :func:`kinematics`, in the order of its ``constants`` array
#: (:func:`motion_constants` builds it once per scenario).
MOTION_CONSTANTS = (
    "dt_s",
    "max_accel_mps2",
    "max_turn_rate_rad_s",
    "max_pitch_rate_rad_s",
    "max_pitch_rad",
    "min_speed_mps",
    "max_speed_mps",
    "max_altitude_m",
)


def motion_constants(**values: float) -> np.ndarray:
    """The float64 array of :func:`kinematics`' constants from their names
    (:data:`MOTION_CONSTANTS`, every one and no other)."""
    if set(values) != set(MOTION_CONSTANTS):
        raise TypeError(f"motion_constants needs exactly {MOTION_CONSTANTS}, got {sorted(values)}")
    out = np.array([float(values[name]) for name in MOTION_CONSTANTS], dtype=np.float64)
    out.flags.writeable = False
    return out


@_jit
def _clip(q, lo, hi):
    """``q`` clipped to [lo, hi] (NaN stays NaN, as ``np.clip``)."""
    if q < lo:
        return lo
    if q > hi:
        return hi
    return q


@_jit
def _increment(a, limit, dt):
    """One normalised action ``a`` (clipped to [-1, 1]) as its eq. 19 increment: ``a *
    limit * dt`` (``limit`` the per-second bound)."""
    return _clip(a, -1.0, 1.0) * limit * dt


@_jit
def scale_actions(actions, constants, out):
    """Normalised actions ``(E, N, 3)`` -> the increments ``out (3, E, N)`` (dv, d alpha,
    d beta) within their eq. 19 per-step limits."""
    dt = constants[0]
    n_env, n = actions.shape[0], actions.shape[1]
    for e in range(n_env):
        for i in range(n):
            out[0, e, i] = _increment(actions[e, i, 0], constants[1], dt)
            out[1, e, i] = _increment(actions[e, i, 1], constants[2], dt)
            out[2, e, i] = _increment(actions[e, i, 2], constants[3], dt)


@_jit
def kinematics(actions, turn, moving, pos, heading, pitch, speed, constants, out):
    """Eq. 19 for the ``moving`` UAVs from normalised ``actions (E, N, 3)``: the new position
    into ``out[0] (E, N, 3)`` and heading, pitch and speed into ``out[1:4]``'s first channel
    (``out = (pos, heading, pitch, speed)`` arrays, the inputs untouched). ``turn (E, N)``
    (or None) replaces the heading increment of the actions (the shield's). Headings are wrapped
    to [-pi, pi) and pitches of UAVs that do not move are 0, as before."""
    new, alpha_out, beta_out, speed_out = out
    dt = constants[0]
    max_pitch = constants[4]
    v_min, v_max, z_max = constants[5], constants[6], constants[7]
    two_pi = 2.0 * np.pi
    n_env, n = moving.shape
    for e in range(n_env):
        for i in range(n):
            mv = moving[e, i]
            if turn is None:  # noqa: SIM108 (numba drops the dead branch of an if statement)
                dalpha = _increment(actions[e, i, 1], constants[2], dt)
            else:
                dalpha = turn[e, i]
            alpha = heading[e, i] + dalpha if mv else heading[e, i]
            alpha = (alpha + np.pi) % two_pi - np.pi
            dbeta = _increment(actions[e, i, 2], constants[3], dt)
            beta = _clip(pitch[e, i] + dbeta, -max_pitch, max_pitch) if mv else 0.0
            step = speed[e, i] * dt if mv else 0.0
            cb = math.cos(beta)
            new[e, i, 0] = pos[e, i, 0] + step * math.cos(alpha) * cb
            new[e, i, 1] = pos[e, i, 1] + step * math.sin(alpha) * cb
            z = pos[e, i, 2] + step * math.sin(beta)
            new[e, i, 2] = z_max if z > z_max else z  # np.minimum: NaN stays NaN
            alpha_out[e, i] = alpha
            beta_out[e, i] = beta
            if mv:
                dv = _increment(actions[e, i, 0], constants[1], dt)
                speed_out[e, i] = _clip(speed[e, i] + dv, v_min, v_max)
            else:
                speed_out[e, i] = speed[e, i]


# ------------------------------------------------------------------------------ the hidden target


@_jit
def target_pod(target, a, b, moving, ox, oy, law, w, cutoff, cell, out):
    """Detection probability ``out (E, N)`` of each env's hidden target for each moving UAV's
    step a -> b (0 for the others): :func:`search_theory.segment_pod`'s compiled scalar, on
    grid-relative coordinates, capped at 1 (definite range: 1 or 0). True if any is not 0."""
    hit = False
    for e in range(out.shape[0]):
        px = target[e, 0] - ox
        py = target[e, 1] - oy
        for i in range(out.shape[1]):
            p = 0.0
            if moving[e, i]:
                ax, ay = a[e, i, 0] - ox, a[e, i, 1] - oy
                bx, by = b[e, i, 0] - ox, b[e, i, 1] - oy
                pod = _point_pod(law, px, py, ax, ay, bx, by, w, cutoff, cell)
                if law == DEFINITE_RANGE:
                    p = 1.0 if pod > 0.0 else 0.0
                else:
                    p = 1.0 if pod > 1.0 else pod  # np.minimum(pod, 1): NaN stays NaN
            out[e, i] = p
            hit = hit or p != 0.0
    return hit


@_jit
def _hit_code(p_t):
    """What :func:`sense_step` returns for the hidden target's PODs ``p_t``: 0 if every one
    is 0, 2 if one is 1 or NaN (``log1p(-p)`` then warns: the caller silences it), else 1."""
    code = 0
    for v in p_t.flat:
        if v != 0.0:
            code = max(code, 1 if v < 1.0 else 2)
    return code


@_jit
def sense_step(
    belief, old, new, moving, target, ox, oy, law, w, cutoff, reach, cell, h, found, p_t
):
    """The sensing of one simulator step in one call: :func:`sweep` of every UAV's step
    ``old[e, i, :2] -> new[e, i, :2]`` (positions ``(E, N, >= 2)``) on ``belief`` in the grid's
    frame (each coordinate minus the origin ``(ox, oy)``, as numpy subtracts it), into
    ``found``; then :func:`target_pod` of the same steps into ``p_t``; returns 0 if every POD
    is 0 (nothing to add to the target's exponent), else 1, or 2 if one is 1 or NaN
    (:func:`_hit_code`). The single environment's step (:class:`poc_env.sim.single.SingleStep`)
    calls this rather than the two kernels and the numpy subtractions between them."""
    n_env, n = found.shape
    a = np.empty((n_env, n, 2))
    b = np.empty((n_env, n, 2))
    for e in range(n_env):
        for i in range(n):
            a[e, i, 0] = old[e, i, 0] - ox
            a[e, i, 1] = old[e, i, 1] - oy
            b[e, i, 0] = new[e, i, 0] - ox
            b[e, i, 1] = new[e, i, 1] - oy
    sweep(belief, a, b, law, w, cutoff, reach, cell, 0.0, 0.0, h, found)
    if target_pod(target, old, new, moving, ox, oy, law, w, cutoff, cell, p_t):
        return _hit_code(p_t)
    return 0


@_jit
def fly_sense(
    actions, moving, old, heading, pitch, speed, motion, new, alpha, beta, new_speed,
    belief, target, ox, oy, law, w, cutoff, reach, cell, h, found, p_t,
):  # fmt: skip
    """The single environment's kinematics and sensing in one call: :func:`kinematics` of the
    increments ``actions`` (no ``turn``; ``motion`` its constants) from ``old`` into ``new,
    alpha, beta, new_speed``, then :func:`sense_step` of the steps ``old -> new``, whose code
    it returns (:class:`poc_env.sim.single.SingleStep`: one dispatch, not two)."""
    kinematics(
        actions, None, moving, old, heading, pitch, speed, motion, (new, alpha, beta, new_speed)
    )
    return sense_step(
        belief, old, new, moving, target, ox, oy, law, w, cutoff, reach, cell, h, found, p_t
    )


# ------------------------------------------------------------------ exposure (the planner's polish)

#: the exposure ``-log(1 - p)`` a step gives a point at most: ``one_minus_exp_neg`` returns 1
#: exactly from 50 on, so a point with ``p = 1`` gets this (``1 - exp(-50)`` rounds to 1 too).
EXPOSURE_CAP = 50.0


@_jit_inline
def _ic_exposure_row(row, k0, k1, h, py, ax, ay, ux, uy, length, w2, cutoff, sign):
    """``row[k] += sign x min(F, EXPOSURE_CAP)`` for ``k0 <= k < k1``, the inverse-cube
    exponent ``F`` of the step (:func:`_ic_exponent`) at the sample ``((k + 1/2) h, py)``, for
    the points within ``cutoff`` of the step (the others get ``+ 0.0``, which leaves them as
    they are: the rows never hold ``-0.0``). Branch-free, so the loop vectorises
    (i24-fastpolish): each point's operations are the scalar ones, in the same order, so the
    sums are the same to the last bit (tests/planning/test_speed.py)."""
    seg = row[k0:k1]  # indices from 0 up: no negative-index wraparound, so the loop vectorises
    c2 = cutoff * cutoff
    for kk in range(k1 - k0):
        px = 0.0 + ((k0 + kk) + 0.5) * h
        lateral, along, beyond = _frame(px, py, ax, ay, ux, uy, length)
        f = _ic_exponent(lateral, -along, length - along, w2)
        v = sign * min(f, EXPOSURE_CAP)
        seg[kk] += v if lateral * lateral + beyond * beyond <= c2 else 0.0


@_jit
def leg_exposure(law, ax, ay, bx, by, w, cutoff, reach, cell, h, sign, expo, box):
    """Add ``sign x -log(1 - p)`` (at most :data:`EXPOSURE_CAP`) of the step a -> b to every
    point of the fine grid ``expo (ny, nx)`` it can detect, ``p`` the law's POD
    (:func:`_point_pod`'s branches, the same scalars :func:`sweep` applies, and for the
    inverse-cube law its exponent F itself, cut off as :func:`_ic_pod` does; grid-relative
    coordinates, samples at ``(k + 1/2) h``). The points visited are :func:`sweep`'s (the
    capsule of the reach for the inverse-cube law, the reach's box otherwise); ``box (4,)``
    (first row, end row, first column, end column) grows to hold them. Exposures of steps add:
    a point's ``1 - exp(-sum)`` is :func:`sweep`'s ``1 - prod(1 - p)`` to rounding."""
    ny, nx = expo.shape
    if ax == bx and ay == by:  # a zero-length step detects nothing, under every law
        return
    ux, uy, length = _seg_axis(ax, ay, bx, by)
    c0, c1 = _index_range(min(ax, bx) - reach, max(ax, bx) + reach, 0.0, h, nx)
    r0, r1 = _index_range(min(ay, by) - reach, max(ay, by) + reach, 0.0, h, ny)
    capsule = law == INVERSE_CUBE and reach < math.inf
    iux = 1.0 / ux if ux != 0.0 else 0.0
    iuy = 1.0 / uy if uy != 0.0 else 0.0
    w2 = w * w
    for j in range(r0, r1):
        py = 0.0 + (j + 0.5) * h
        k0, k1 = c0, c1
        if capsule:
            lo, hi = _capsule_row(py, ax, ay, bx, by, ux, uy, length, reach, iux, iuy)
            k0, k1 = _index_range(lo, hi, 0.0, h, nx)
            span = -(-(k1 - k0) // _LANES) * _LANES  # padded as sweep pads: no scalar remainder
            if k0 < k1 and span <= nx:
                k1 = min(k0 + span, nx)
                k0 = k1 - span
        if k1 <= k0:
            continue
        box[0] = min(box[0], j)
        box[1] = max(box[1], j + 1)
        box[2] = min(box[2], k0)
        box[3] = max(box[3], k1)
        if law == INVERSE_CUBE:  # the exponent F itself (_ic_pod's p = 1 - exp(-F))
            _ic_exposure_row(expo[j], k0, k1, h, py, ax, ay, ux, uy, length, w2, cutoff, sign)
            continue
        for k in range(k0, k1):
            px = 0.0 + (k + 0.5) * h
            if law == DEFINITE_RANGE:
                p = _dr_pod(px, py, ax, ay, ux, uy, length, w)
            else:
                p = _exp_pod(px, py, ax, ay, bx, by, w, cell)
            if p > 0.0:
                f = -math.log1p(-p) if p < 1.0 else EXPOSURE_CAP
                expo[j, k] += sign * min(f, EXPOSURE_CAP)


@_jit
def legs_exposure(law, a, b, w, cutoff, reach, cell, h, sign, expo):
    """:func:`leg_exposure` of the steps ``a[l] -> b[l]`` (L, 2) in turn, each ``sign``."""
    box = np.array([expo.shape[0], 0, expo.shape[1], 0])
    for i in range(a.shape[0]):
        leg_exposure(
            law, a[i, 0], a[i, 1], b[i, 0], b[i, 1], w, cutoff, reach, cell, h, sign, expo, box
        )


@_jit
def _kept_steps(old_a, old_b, law, w, cutoff, reach, cell, h, base, work, box_o):
    """:func:`leg_exposure` of the steps ``old_a -> old_b`` taken out of ``base`` (sign -1, in
    turn, ``box_o`` grown to hold them, as :func:`legs_exposure` would), each step's exposure
    also kept as a tile (i24-budget): ``(tiles, tbox, toff)``, step ``o``'s values
    ``min(F, EXPOSURE_CAP)`` (sign +1) over its box ``tbox[o]`` (first row, end row, first
    column, end column) in row-major order at ``tiles[toff[o]:toff[o + 1]]``. ``work`` (zero)
    is the scratch a step is computed in, zero again on return. Exact: a step's value is
    computed once into zero (``0.0 + v == v``) and taken out as ``-1.0 x v``, the same number
    the sign gives; the box's points outside the step's rows get ``-0.0``, which leaves every
    value as it is."""
    ny, nx = work.shape
    n_old = old_a.shape[0]
    tbox = np.empty((n_old, 4), np.int64)
    toff = np.zeros(n_old + 1, np.int64)
    tiles = np.empty(0)
    for o in range(n_old):
        tb = tbox[o]
        tb[0], tb[1], tb[2], tb[3] = ny, 0, nx, 0
        leg_exposure(
            law, old_a[o, 0], old_a[o, 1], old_b[o, 0], old_b[o, 1], w, cutoff, reach, cell,
            h, 1.0, work, tb,
        )  # fmt: skip
        toff[o + 1] = toff[o] + max(tb[1] - tb[0], 0) * max(tb[3] - tb[2], 0)
        if toff[o + 1] > tiles.shape[0]:
            grown = np.empty(max(2 * tiles.shape[0], toff[o + 1], 4096))
            grown[: toff[o]] = tiles[: toff[o]]
            tiles = grown
        s = toff[o]
        for j in range(tb[0], tb[1]):
            for k in range(tb[2], tb[3]):
                v = work[j, k]
                tiles[s] = v
                s += 1
                base[j, k] += -1.0 * v
                work[j, k] = 0.0
        box_o[0] = min(box_o[0], tb[0])
        box_o[1] = max(box_o[1], tb[1])
        box_o[2] = min(box_o[2], tb[2])
        box_o[3] = max(box_o[3], tb[3])
    return tiles, tbox, toff


@_jit_inline
def _kept_step(ax, ay, bx, by, old_a, old_b):
    """The index of the step ``a -> b`` among the steps ``old_a -> old_b`` (the same four
    coordinates), or -1."""
    for o in range(old_a.shape[0]):
        if old_a[o, 0] == ax and old_b[o, 0] == bx and old_a[o, 1] == ay and old_b[o, 1] == by:
            return o
    return -1


@_jit
def exposure_gains(
    live, old_a, old_b, new_a, new_b, first, law, w, cutoff, reach, cell, h, base, work,
    out,
):  # fmt: skip
    """The change of ``sum mass (1 - exp(-E))`` (``E`` the points' exposure, ``live = mass
    exp(-E)`` the mass not yet found) when the steps ``old_a -> old_b`` are replaced by
    candidate ``c``'s steps ``new_a[l] -> new_b[l]``, ``first[c] <= l < first[c + 1]``, into
    ``out[c]`` (the points the steps reach only: every other point keeps its exposure).
    ``base`` and ``work`` (the fine grid's shape) are zero scratch arrays, zero again on
    return. Per point ``live (1 - exp(-d))``, ``d`` the change of its exposure (``expm1``: no
    cancellation). A candidate's step that is one of the old steps (a leg the move keeps) adds
    that step's kept values (:func:`_kept_steps`) instead of computing them again
    (i24-budget: the same numbers added in the same order, so the same gains bit for bit)."""
    ny, nx = live.shape
    box_o = np.array([ny, 0, nx, 0])
    tiles, tbox, toff = _kept_steps(old_a, old_b, law, w, cutoff, reach, cell, h, base, work, box_o)
    box = np.empty(4, np.int64)
    for c in range(first.shape[0] - 1):
        box[:] = box_o
        for j in range(box_o[0], box_o[1]):
            for k in range(box_o[2], box_o[3]):
                work[j, k] = base[j, k]
        for i in range(first[c], first[c + 1]):
            ax, ay, bx, by = new_a[i, 0], new_a[i, 1], new_b[i, 0], new_b[i, 1]
            o = _kept_step(ax, ay, bx, by, old_a, old_b)
            if o < 0:
                leg_exposure(law, ax, ay, bx, by, w, cutoff, reach, cell, h, 1.0, work, box)
                continue
            tb = tbox[o]  # inside box_o, so inside the box: nothing to grow
            s = toff[o]
            for j in range(tb[0], tb[1]):
                for k in range(tb[2], tb[3]):
                    work[j, k] += tiles[s]
                    s += 1
        g = 0.0
        for j in range(box[0], box[1]):
            for k in range(box[2], box[3]):
                d = work[j, k]
                if d != 0.0:
                    g += live[j, k] * -math.expm1(-d)
                    work[j, k] = 0.0
        out[c] = g
    for j in range(box_o[0], box_o[1]):
        for k in range(box_o[2], box_o[3]):
            base[j, k] = 0.0


@_jit
def cut_steps(a, b, ox, oy, cell):
    """The legs ``a[l] -> b[l]`` (L, 2) cut into steps no longer than ``cell``, relative to the
    origin ``(ox, oy)``, as the polish scores them (i24-cheapolish: one compiled pass for the
    numpy expressions of ``Exposure.steps``, the same operations per point in the same order,
    so the same steps bit for bit): leg ``l`` (``d = (b - o) - (a - o)``) in ``n_l = max(1,
    ceil(|d| / cell))`` steps ``a - o + (j / n_l) d -> a - o + ((j + 1) / n_l) d``. Returns
    (starts, ends, steps per leg)."""
    m = a.shape[0]
    n = np.empty(m, np.int64)
    total = 0
    for i in range(m):
        dx = (b[i, 0] - ox) - (a[i, 0] - ox)
        dy = (b[i, 1] - oy) - (a[i, 1] - oy)
        n[i] = int(max(1.0, math.ceil(math.hypot(dx, dy) / cell)))
        total += n[i]
    sa = np.empty((total, 2))
    sb = np.empty((total, 2))
    s = 0
    for i in range(m):
        ax = a[i, 0] - ox
        ay = a[i, 1] - oy
        dx = (b[i, 0] - ox) - ax
        dy = (b[i, 1] - oy) - ay
        nl = float(n[i])
        for j in range(n[i]):
            t0 = j / nl
            t1 = (j + 1) / nl
            sa[s, 0] = ax + t0 * dx
            sa[s, 1] = ay + t0 * dy
            sb[s, 0] = ax + t1 * dx
            sb[s, 1] = ay + t1 * dy
            s += 1
    return sa, sb, n
