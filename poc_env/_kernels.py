"""Every compiled (numba) function of the project, in one private module.

Numba's on-disk cache (``cache=True``) keys a compiled function on the source file it was
defined in; a kernel that calls a compiled function of another file would keep running a stale
copy of it after that file is edited. With every compiled function here, any edit of this file
invalidates every cached kernel, and no kernel depends on another file's code. The public
functions live in their modules (:mod:`poc_env.theory.search_theory`,
:mod:`poc_env.sim.constraints`, :mod:`poc_env.sim.comms`, :mod:`poc_env.sim.core`,
:mod:`poc_env.sim.observations`, :mod:`poc_env.theory.regions`) and call these kernels; the
tests compare each kernel with a plain-numpy reference.

Base layer: imports only numpy, numba (and llvmlite, numba's code generator, for two
intrinsics) and the standard library. ``error_model="numpy"`` makes ``x / 0`` an inf instead of
an exception; ``inline="always"`` lets the compiler vectorise the sweep's inner loop.

Sections: detection laws and the fused sensing sweep (eq. 12-14 of the paper), eq. 20-21
constraint checks, eq. 24 communication graphs, the simulator step, observations, the area
fractions of rotated rectangles over grid cells, and their weighted masses by boundary integrals.
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


# ------------------------------------------------------------------------- constraints (eq. 20-21)


@_jit
def _outside(x, y, x0, y0, x1, y1):
    """Point (x, y) lies outside the rectangle [x0, x1] x [y0, y1] (eq. 20, ``Omega_b``)."""
    return x < x0 or x > x1 or y < y0 or y > y1


@_jit
def outside_boundary(p, x0, y0, x1, y1, out):
    """:func:`_outside` of every point ``p (P, 2)`` into ``out (P,)``."""
    for k in range(p.shape[0]):
        out[k] = _outside(p[k, 0], p[k, 1], x0, y0, x1, y1)


@_jit
def pairwise_distances(p, out):
    """Distances ``out (B, n, n)`` of the points ``p (B, n, d)``: sqrt(0 + dx0^2 + dx1^2 ...)."""
    n_b, n, d = p.shape
    for b in range(n_b):
        for i in range(n):
            for j in range(n):
                d2 = 0.0
                for k in range(d):
                    c = p[b, i, k] - p[b, j, k]
                    d2 += c * c
                out[b, i, j] = math.sqrt(d2)


@_jit
def separation(dist, d_s, act, use_act, pairs, per_agent):
    """Eq. 21 on distances ``dist (B, n, n)``: ``pairs`` closer than ``d_s`` between distinct
    (and, with ``use_act``, active) UAVs; ``per_agent (B, n)`` has at least one such pair."""
    n_b, n = dist.shape[0], dist.shape[1]
    for b in range(n_b):
        for i in range(n):
            hit = False
            for j in range(n):
                v = i != j and dist[b, i, j] < d_s
                if use_act:
                    v = v and act[b, i] and act[b, j]
                pairs[b, i, j] = v
                hit = hit or v
            per_agent[b, i] = hit


# -------------------------------------------------------------------------- communication (eq. 24)


@_jit
def in_range(dist, range_m, act, out):
    """Eq. 24 adjacency ``out (B, n, n)``: distinct active UAVs with ``dist <= range_m``."""
    n_b, n = out.shape[0], out.shape[1]
    for b in range(n_b):
        for i in range(n):
            ai = act[b, i]
            for j in range(n):
                out[b, i, j] = ai and act[b, j] and i != j and dist[b, i, j] <= range_m


@_jit
def two_neighbour(adj, min_neighbours, act, use_act, out):
    """The §3.2.4 rule per UAV into ``out (B, n)``, see :func:`two_neighbour_ok`."""
    n_b, n = adj.shape[0], adj.shape[1]
    for b in range(n_b):
        need = min_neighbours
        if use_act:
            n_act = 0
            for i in range(n):
                if act[b, i]:
                    n_act += 1
            need = min(min_neighbours, n_act - 1)
        for i in range(n):
            count = 0
            for j in range(n):
                if adj[b, i, j]:
                    count += 1
            out[b, i] = (use_act and not act[b, i]) or count >= need


@_jit
def auto_topology(av, dist, use_dist, act, k_nearest, links, n_comp):
    """:func:`auto_topology` of each env into ``links (E, n, n)`` and ``n_comp (E,)``.

    A pair is available when ``av`` says so, both UAVs are active and they are distinct; it
    weighs ``dist`` (or 1 without ``use_dist``), an unavailable pair ``inf``. Prim's algorithm
    as in the docstring of :func:`auto_topology`: each round takes the unvisited UAV of
    smallest key (the first on ties), or starts a new component at the first unvisited UAV
    when no key is finite; then every UAV's ``k_nearest`` lightest available links (the first
    on ties).
    """
    n_env, n = av.shape[0], av.shape[1]
    w = np.empty((n, n))
    key = np.empty(n)
    parent = np.zeros(n, dtype=np.intp)
    visited = np.empty(n, dtype=np.bool_)
    chosen = np.empty(n, dtype=np.bool_)
    for e in range(n_env):
        for i in range(n):
            for j in range(n):
                links[e, i, j] = False
                if av[e, i, j] and act[e, i] and act[e, j] and i != j:
                    w[i, j] = dist[e, i, j] if use_dist else 1.0
                else:
                    w[i, j] = np.inf
            visited[i] = not act[e, i]
            key[i] = np.inf
            parent[i] = 0
        comps = 0
        for _ in range(n):
            j = -1
            best = np.inf
            remaining = False
            for i in range(n):
                if not visited[i]:
                    remaining = True
                    if key[i] < best:
                        best = key[i]
                        j = i
            if not remaining:
                break
            if j >= 0:  # grow the current tree along its lightest edge
                links[e, parent[j], j] = True
            else:  # no finite key: a new component at the first unvisited UAV
                comps += 1
                for i in range(n):
                    if not visited[i]:
                        j = i
                        break
            visited[j] = True
            for i in range(n):
                if not visited[i] and w[j, i] < key[i]:
                    key[i] = w[j, i]
                    parent[i] = j
        n_comp[e] = comps
        for i in range(n):
            for j in range(n):
                chosen[j] = False
            for _ in range(k_nearest):
                m = -1
                best = np.inf
                for j in range(n):
                    if not chosen[j] and w[i, j] < best:
                        best = w[i, j]
                        m = j
                if m < 0:
                    break
                chosen[m] = True
                links[e, i, m] = True
        for i in range(n):
            for j in range(i + 1, n):
                v = links[e, i, j] or links[e, j, i]
                links[e, i, j] = v
                links[e, j, i] = v


# ------------------------------------------------------------------------------ the simulator step

# Rows of the bool ``flags`` array that :func:`step` fills (one array: fewer arguments).
OVERTIME, OOB, COLLISION, COMMS_OK, LANDED, CRASHED = range(6)
N_FLAGS = 6


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
def auto_links(dist, range_m, flying, k_nearest, links, n_comp):
    """:func:`comms.auto_topology` on :func:`comms.in_range` of ``dist`` among the flying."""
    adj = np.empty(links.shape, dtype=np.bool_)
    in_range(dist, range_m, flying, adj)
    auto_topology(adj, dist, True, flying, k_nearest, links, n_comp)


@_jit
def step(
    found,
    agent_pos,
    posc,
    team,
    pos,
    speed,
    moving,
    nofly,
    threat,
    exponent,
    threshold,
    step_count,
    detected,
    detect_step,
    elapsed,
    left_home,
    landed,
    crashed,
    flying,
    violations,
    landing,
    dt,
    usable,
    time_share,
    endurance,
    x0,
    y0,
    x1,
    y1,
    d_s,
    range_m,
    min_neighbours,
    landing_radius,
    landing_max_alt,
    landing_max_speed,
    terminate,
    detected_now,
    time_term,
    flags,
    dist,
):
    """Steps 3-5 of :func:`step` after sensing, in place on the state arrays.

    What each UAV found (``agent_pos``), the team's POS (``team``, eq. 12 summed over the UAVs
    in agent order) and POSC (eq. 13);
    detection of the hidden target; the time model (eq. 17-18); the boundary (eq. 20),
    separation (eq. 21) and two-neighbour (eq. 24) checks through the same kernels
    :mod:`~poc_env.sim.constraints` and :mod:`~poc_env.sim.comms` call; violation counts;
    landing and crashes; the step counter. ``dist`` receives the pairwise distances of the new
    positions (for the topology update).
    """
    n_env, n = moving.shape
    pairwise_distances(pos[:, :, :2], dist)
    pairs = np.empty((n_env, n, n), dtype=np.bool_)
    separation(dist, d_s, moving, True, pairs, flags[COLLISION])
    in_range(dist, range_m, moving, pairs)
    two_neighbour(pairs, min_neighbours, moving, True, flags[COMMS_OK])
    for e in range(n_env):
        total = 0.0
        for i in range(n):
            total += found[e, i]
        team[e] = total
        posc[e] += total
        now = not detected[e] and exponent[e] >= threshold[e]
        detected_now[e] = now
        if now:
            detected[e] = True
            detect_step[e] = step_count[e] + 1
        step_count[e] += 1
        for i in range(n):
            agent_pos[e, i] += found[e, i]
            mv = moving[e, i]
            elapsed[e, i] = elapsed[e, i] + (dt if mv else 0.0)
            flags[OVERTIME, e, i] = mv and elapsed[e, i] > usable
            time_term[e, i] = time_share if mv else 0.0
            x, y, z = pos[e, i, 0], pos[e, i, 1], pos[e, i, 2]
            oob = mv and _outside(x, y, x0, y0, x1, y1)
            flags[OOB, e, i] = oob
            collision = mv and flags[COLLISION, e, i]
            flags[COLLISION, e, i] = collision
            comms_ok = flags[COMMS_OK, e, i] or not mv
            flags[COMMS_OK, e, i] = comms_ok
            unsafe = oob or nofly[e, i] or collision or threat[e, i]
            if mv and (unsafe or not comms_ok):
                violations[e, i] += 1
            home = math.hypot(x - landing[i, 0], y - landing[i, 1])
            if mv and home > landing_radius:
                left_home[e, i] = True
            land = (
                mv
                and left_home[e, i]
                and home <= landing_radius
                and z <= landing_max_alt
                and speed[e, i] <= landing_max_speed
            )
            crash = mv and not land and (z <= 0.0 or elapsed[e, i] >= endurance)
            if terminate:
                crash = crash or (mv and not land and unsafe)
            flags[LANDED, e, i] = land
            flags[CRASHED, e, i] = crash
            if land:
                landed[e, i] = True
            if crash:
                crashed[e, i] = True
            if land or crash:
                flying[e, i] = False


# ------------------------------------------------------------------------------------ observations


@_jit
def rasters(belief, s, coarse, own_sum, scale, hazard, pos, flying, x0, y0, x1, y1, cell, out):
    """Fill ``out (E, N, C, ny, nx)``: channel 0 the coarse POC / ``scale`` clipped to [0, 1]
    (cells summed as ``Grid.coarsen`` does with numpy, or taken from ``coarse``), 1 the own
    cell, 2 the cells of the other present UAVs, 3 ``hazard``. A UAV is present when flying
    inside the grid ``[x0, x1] x [y0, y1]`` (``Grid.contains``); its cell is
    ``Grid.cell_of``'s, ``floor((x - x0) / cell)`` clipped to the grid."""
    n_env, n, _, ny, nx = out.shape
    poc = np.empty((ny, nx), dtype=np.float32)
    poc_sum = np.empty((ny, nx))
    rows = np.empty(n, dtype=np.intp)
    cols = np.empty(n, dtype=np.intp)
    present = np.empty(n, dtype=np.bool_)
    for e in range(n_env):
        for k in range(n):
            x, y = pos[e, k, 0], pos[e, k, 1]
            present[k] = flying[e, k] and x >= x0 and x <= x1 and y >= y0 and y <= y1
            if present[k]:
                rows[k] = min(max(math.floor((y - y0) / cell), 0), ny - 1)
                cols[k] = min(max(math.floor((x - x0) / cell), 0), nx - 1)
        if own_sum:  # numpy's multi-axis sum: 0 + each sub-row's sum (started from -0.0)
            for j in range(ny):
                acc = poc_sum[j]
                acc[:] = 0.0
                for a in range(s):
                    row = belief[e, j * s + a]
                    if s == 2:
                        for i in range(nx):
                            acc[i] += row[2 * i] + row[2 * i + 1]
                    else:
                        for i in range(nx):
                            r = -0.0
                            for b in range(s):
                                r += row[i * s + b]
                            acc[i] += r
        else:
            poc_sum[:] = coarse[e]
        for j in range(ny):
            for i in range(nx):
                q = poc_sum[j, i] / scale[e]
                if q < 0.0:  # np.clip(q, 0.0, 1.0) with scalar bounds; NaN stays NaN
                    q = 0.0
                elif q > 1.0:
                    q = 1.0
                poc[j, i] = q
        for k in range(n):
            out[e, k, 0] = poc
            out[e, k, 1] = 0.0
            out[e, k, 2] = 0.0
            out[e, k, 3] = hazard
        for k in range(n):
            if present[k]:
                rj, ci = rows[k], cols[k]
                out[e, k, 1, rj, ci] = 1.0
                for m in range(n):
                    if m != k:
                        out[e, m, 2, rj, ci] = 1.0


@_jit
def vectors(
    pos,
    speed,
    sin_h,
    cos_h,
    pitch,
    elapsed,
    flying,
    step,
    landing,
    bx0,
    by0,
    w,
    h,
    diag,
    max_alt,
    min_speed,
    speed_span,
    max_pitch,
    endurance,
    usable,
    horizon,
    range_m,
    others,
    low,
    high,
    out,
):
    """The vector table of the module docstring into ``out (E, N, VECTOR_SIZE)``, float64
    values clipped to [low, high] as numpy clips them, then rounded to float32. Neighbours
    are counted on :func:`comms.in_range`'s kernel."""
    n_env, n = flying.shape
    dist = np.empty((n_env, n, n))
    adj = np.empty((n_env, n, n), dtype=np.bool_)
    pairwise_distances(pos[:, :, :2], dist)
    in_range(dist, range_m, flying, adj)
    v = np.empty(out.shape[2])
    for e in range(n_env):
        t = step[e] / horizon
        for i in range(n):
            x, y = pos[e, i, 0], pos[e, i, 1]
            v[0] = (x - bx0) / w
            v[1] = (y - by0) / h
            v[2] = pos[e, i, 2] / max_alt
            v[3] = (speed[e, i] - min_speed) / speed_span
            v[4] = sin_h[e, i]
            v[5] = cos_h[e, i]
            v[6] = pitch[e, i] / max_pitch
            v[7] = 1.0 - elapsed[e, i] / endurance
            v[8] = 1.0 - elapsed[e, i] / usable
            v[9] = (landing[i, 0] - x) / diag
            v[10] = (landing[i, 1] - y) / diag
            count = 0
            for j in range(n):
                if adj[e, i, j]:
                    count += 1
            v[11] = count / others
            v[12] = 1.0 if flying[e, i] else 0.0
            v[13] = t
            for k in range(v.size):
                q = v[k]
                if not np.isnan(q):  # np.clip with array bounds: ties go to the bound
                    q = q if q > low[k] else low[k]
                    q = q if q < high[k] else high[k]
                out[e, i, k] = q


@_jit
def compass_bins(cx, cy, px, py, poc, others, edges, radius, n_sectors):
    """The compass observation's sums (:class:`poc_env.sim.observations.CompassFeatures`) in
    one pass over the cells: for each UAV ``i`` at ``(px[i], py[i])`` and each cell centre
    ``(cx[j], cy[j])``, the sector (``n_sectors`` equal angles, sector 0 starting due east,
    counter-clockwise) and the ring (how many ``edges`` are <= the distance) of the cell; returns
    ``mass (B, n_sectors * (len(edges) + 1))``, the POC ``poc[i, j]`` summed per (sector, ring),
    and ``count (B, n_sectors)``, ``others[i, j]`` summed per sector over the cells within
    ``radius``. Cells are visited in index order, as ``np.bincount`` does."""
    b = px.shape[0]
    n_cells = cx.shape[0]
    n_rings = edges.shape[0] + 1
    mass = np.zeros((b, n_sectors * n_rings))
    count = np.zeros((b, n_sectors))
    two_pi = 2.0 * np.pi
    half = n_sectors // 2
    edges2 = edges * edges
    radius2 = radius * radius
    octants = n_sectors == 8
    tol = 1e-9  # relative margin around a boundary inside which the exact formula decides
    for i in range(b):
        for j in range(n_cells):
            dx = cx[j] - px[i]
            dy = cy[j] - py[i]
            ax = abs(dx)
            ay = abs(dy)
            big = max(ax, ay)
            if octants and ay > tol * big and ax > tol * big and abs(ax - ay) > tol * big:
                # clearly inside an octant: signs and |dy| vs |dx| name it, no arctan2 needed
                if dy > 0 and dx > 0:
                    sector = 0 if ay < ax else 1
                elif dy > 0:
                    sector = 2 if ay > ax else 3
                elif dx < 0:
                    sector = 4 if ay < ax else 5
                else:
                    sector = 6 if ay > ax else 7
            else:  # on or next to a sector boundary: the defining formula, bit for bit
                ang = np.arctan2(dy, dx)
                sector = int(np.floor((ang + np.pi) / two_pi * n_sectors)) % n_sectors
                sector = (sector + half) % n_sectors  # arctan2 + pi starts at west
            d2 = dx * dx + dy * dy
            ring = 0
            exact = False
            for r in range(n_rings - 1):  # squared distances decide unless next to an edge
                if abs(d2 - edges2[r]) <= tol * edges2[r]:
                    exact = True
            near_radius = abs(d2 - radius2) <= tol * radius2
            if exact or near_radius:
                dist = np.hypot(dx, dy)
                while ring < n_rings - 1 and edges[ring] <= dist:
                    ring += 1
                inside = dist <= radius
            else:
                while ring < n_rings - 1 and edges2[ring] <= d2:
                    ring += 1
                inside = d2 <= radius2
            mass[i, sector * n_rings + ring] += poc[i, j]
            if inside:
                count[i, sector] += others[i, j]
    return mass, count


# --------------------------------------------------------------------------------- rectangle areas


@_jit_inline
def _clip(px, py, n, qx, qy, nx_, ny_, t):
    """Clip the convex polygon ``p[:n]`` by the half-plane ``nx_ x + ny_ y <= t`` into ``q``.

    Each vertex's side ``s = nx_ x + ny_ y - t`` is computed once and carried to the next edge,
    and the wrap to vertex 0 is a compare, not an integer modulo (same numbers, fewer cycles).
    """
    m = 0
    if n == 0:
        return 0
    ax, ay = px[0], py[0]
    sa = nx_ * ax + ny_ * ay - t
    for k in range(n):
        kk = k + 1
        if kk == n:
            kk = 0
        bx, by = px[kk], py[kk]
        sb = nx_ * bx + ny_ * by - t
        if sa <= 0.0:
            qx[m] = ax
            qy[m] = ay
            m += 1
        if (sa < 0.0 < sb) or (sb < 0.0 < sa):
            r = sa / (sa - sb)
            qx[m] = ax + r * (bx - ax)
            qy[m] = ay + r * (by - ay)
            m += 1
        ax, ay, sa = bx, by, sb
    return m


@_jit_inline
def _area(px, py, n):
    """Area of the convex polygon ``p[:n]`` (shoelace; the wrap to vertex 0 without a modulo)."""
    area = 0.0
    for m in range(n):
        mm = m + 1
        if mm == n:
            mm = 0
        area += px[m] * py[mm] - px[mm] * py[m]
    return abs(0.5 * area)


@_jit_inline
def _slab_cdf(t, big, small):
    """P(U + V <= t) for independent U ~ U(-big, big), V ~ U(-small, small), big >= small.

    The area fraction of a square cell on one side of a line: the cell's offsets projected on
    the line's normal are such a sum (``big``, ``small`` = half the side times the larger and
    the smaller of ``|cos|``, ``|sin|``). Piecewise quadratic, exact.
    """
    if t <= -big - small:
        return 0.0
    if t >= big + small:
        return 1.0
    if t < small - big:
        r = t + big + small
        return r * r / (8.0 * big * small)
    if t <= big - small:
        return 0.5 + 0.5 * t / big
    r = big + small - t
    return 1.0 - r * r / (8.0 * big * small)


@_jit_inline
def _cell_square(h, qx, qy):
    """The cell ``[-h/2, h/2]^2`` (cell-centred coordinates) into ``q``; returns 4."""
    half = 0.5 * h
    qx[0], qy[0] = -half, -half
    qx[1], qy[1] = half, -half
    qx[2], qy[2] = half, half
    qx[3], qy[3] = -half, half
    return 4


@_jit_inline
def _rect_side(side, c, s, eo, fo, a, b):
    """Half-plane ``n . p <= t`` of side ``side`` (0: u <= a, 1: u >= -a, 2: v <= b, 3: v >= -b)
    of the rectangle with axes ``e = (c, s)``, ``f = (-s, c)``, half sides ``a``, ``b`` and
    centre at ``u = eo``, ``v = fo``: returns ``(n_x, n_y, t)``."""
    if side == 0:
        return c, s, eo + a
    if side == 1:
        return -c, -s, a - eo
    if side == 2:
        return -s, c, fo + b
    return s, -c, b - fo


@_jit_inline
def _clip_rect(px, py, n, qx, qy, rx, ry, c, s, a, b, half):
    """``p[:n]`` clipped to the rectangle centred at ``(rx, ry)`` (axes ``(c, s)``, half sides
    ``a``, ``b``), both in the same coordinates; the result in ``q`` (``p`` is overwritten).

    ``p`` lies in the cell ``[-half, half]^2`` (cell-centred coordinates), whose projection on
    a side's normal lies within ``+-half (|c| + |s|)``: a side whose line misses the cell
    leaves ``p`` as it is (the clip would copy it) and is skipped, and a side with the cell
    wholly beyond it leaves nothing. Most cells are cut by one or two of the four sides.
    """
    ext = half * (abs(c) + abs(s))
    eo = c * rx + s * ry  # u of the rectangle's centre along e = (c, s)
    fo = -s * rx + c * ry  # v along f = (-s, c)
    for side in range(4):
        nx_, ny_, t = _rect_side(side, c, s, eo, fo, a, b)
        if t >= ext:
            continue
        if t <= -ext:
            return 0
        n = _clip(px, py, n, qx, qy, nx_, ny_, t)
        for m in range(n):
            px[m] = qx[m]
            py[m] = qy[m]
    return n


@_jit_inline
def _minus_rects(
    n0, earlier, n_earlier, rx, ry, cos_t, sin_t, half_l, half_w, sx, sy, sn, sp, sk, tx, ty, tiny
):
    """Area of the convex polygon ``sx[0, :n0]`` minus the union of the rectangles ``earlier``.

    ``rx, ry`` are the rectangles' centres in the polygon's coordinates. Depth first: a
    polygon minus one rectangle is the union of at most four disjoint convex pieces (beyond
    ``u >= a``; beyond ``u <= -a``; within ``|u| <= a`` with ``v >= b``; with ``v <= -b``), and
    the leaves left after the last rectangle are disjoint, so their areas add up. A polygon
    inside the rectangle ends its branch, one clear of it passes on whole, and only the pieces
    its extent reaches are cut; pieces under ``tiny`` are dropped. ``sx, sy, sn, sp, sk`` are
    the per-level stack (polygon, size, next piece, pieces to cut); ``tx, ty`` scratch.
    """
    total = 0.0
    level = 0
    sn[0] = n0
    sp[0] = -1
    while level >= 0:
        if level == n_earlier:
            total += _area(sx[level], sy[level], sn[level])
            level -= 1
            continue
        r = earlier[level]
        c, s, a, b = cos_t[r], sin_t[r], half_l[r], half_w[r]
        eo = c * rx[level] + s * ry[level]
        fo = -s * rx[level] + c * ry[level]
        src_x, src_y, m = sx[level], sy[level], sn[level]
        dst_x, dst_y = sx[level + 1], sy[level + 1]
        if sp[level] < 0:  # first visit: where is the polygon relative to the rectangle?
            u_lo = v_lo = math.inf
            u_hi = v_hi = -math.inf
            for q in range(m):
                u = c * src_x[q] + s * src_y[q] - eo
                v = c * src_y[q] - s * src_x[q] - fo
                u_lo, u_hi = min(u_lo, u), max(u_hi, u)
                v_lo, v_hi = min(v_lo, v), max(v_hi, v)
            if u_lo >= -a and u_hi <= a and v_lo >= -b and v_hi <= b:
                level -= 1  # wholly inside: nothing of it is left
                continue
            if u_lo >= a or u_hi <= -a or v_lo >= b or v_hi <= -b:
                for q in range(m):  # clear of the rectangle: passes on whole
                    dst_x[q] = src_x[q]
                    dst_y[q] = src_y[q]
                sp[level] = 4
                level += 1
                sn[level] = m
                sp[level] = -1
                continue
            sk[level] = (u_hi > a) | ((u_lo < -a) << 1) | ((v_hi > b) << 2) | ((v_lo < -b) << 3)
            sp[level] = 0
        piece = sp[level]
        while piece < 4 and not (sk[level] >> piece) & 1:
            piece += 1
        if piece >= 4:
            level -= 1
            continue
        sp[level] = piece + 1
        if piece == 0:  # u >= a
            m = _clip(src_x, src_y, m, dst_x, dst_y, -c, -s, -a - eo)
        elif piece == 1:  # u <= -a
            m = _clip(src_x, src_y, m, dst_x, dst_y, c, s, eo - a)
        else:  # |u| <= a and v >= b (2) or v <= -b (3)
            m = _clip(src_x, src_y, m, tx, ty, c, s, eo + a)
            m = _clip(tx, ty, m, dst_x, dst_y, -c, -s, a - eo)
            for q in range(m):
                tx[q] = dst_x[q]
                ty[q] = dst_y[q]
            if piece == 2:
                m = _clip(tx, ty, m, dst_x, dst_y, s, -c, -b - fo)
            else:
                m = _clip(tx, ty, m, dst_x, dst_y, -s, c, fo - b)
        if m >= 3 and _area(dst_x, dst_y, m) > tiny:
            level += 1
            sn[level] = m
            sp[level] = -1
    return total


@_jit_inline
def _span_point(xm, ym, xn, yn, y_lo, y_hi, lo, hi):
    """``lo, hi`` widened by corner m (if in the band ``[y_lo, y_hi]``) and by the points where
    the edge m -> n crosses the band's two lines (interpolated along the edge, as in
    :func:`_clip`: well conditioned at any angle)."""
    if y_lo <= ym <= y_hi:
        lo = min(lo, xm)
        hi = max(hi, xm)
    for yy in (y_lo, y_hi):
        if (ym < yy < yn) or (yn < yy < ym):
            x = xm + (yy - ym) / (yn - ym) * (xn - xm)
            lo = min(lo, x)
            hi = max(hi, x)
    return lo, hi


@_jit_inline
def _row_span(dy, half, c, s, a, b):
    """x-range, from the centre, of the rectangle (half sides ``a`` along ``(c, s)``, ``b``
    across) within the band ``|y - dy| <= half``; ``lo > hi`` when they do not meet. The same
    range as clipping the rectangle to the band (:func:`_clip`), without the polygon arrays:
    the corners inside the band and the edges' crossings of its two lines."""
    y_lo = dy - half
    y_hi = dy + half
    x0_, y0_ = -a * c + b * s, -a * s - b * c
    x1_, y1_ = a * c + b * s, a * s - b * c
    x2_, y2_ = a * c - b * s, a * s + b * c
    x3_, y3_ = -a * c - b * s, -a * s + b * c
    lo = math.inf
    hi = -math.inf
    lo, hi = _span_point(x0_, y0_, x1_, y1_, y_lo, y_hi, lo, hi)
    lo, hi = _span_point(x1_, y1_, x2_, y2_, y_lo, y_hi, lo, hi)
    lo, hi = _span_point(x2_, y2_, x3_, y3_, y_lo, y_hi, lo, hi)
    lo, hi = _span_point(x3_, y3_, x0_, y0_, y_lo, y_hi, lo, hi)
    return lo, hi


@_jit_inline
def _inside_columns(dy, c, s, ai, bi, ox, h, i0, i1):
    """Columns ``[f0, f1)`` of ``[i0, i1)`` whose cells lie wholly inside the rectangle.

    On the row at ``dy`` from the rectangle's centre (``ox`` = centre minus grid origin, in x),
    a cell is wholly inside when its centre's frame coordinates satisfy ``|u| <= ai`` and
    ``|v| <= bi`` (``ai = a - hp``, ``bi = b - hp``): an interval of the cell centre's ``dx``,
    shrunk by ``1e-9 h`` so that every column returned passes the per-cell test
    ``|u| + hp <= a``, ``|v| + hp <= b`` of :func:`rectangle_fractions` in floating point
    (the columns at the interval's ends that are not returned go through that test). Empty
    (``f0 = f1``) when the row has no such cell.
    """
    if ai < 0.0 or bi < 0.0:
        return i1, i1
    lo = -math.inf
    hi = math.inf
    su = s * dy  # u = c dx + s dy, |u| <= ai
    if c != 0.0:
        p0 = (-ai - su) / c
        p1 = (ai - su) / c
        lo, hi = max(lo, min(p0, p1)), min(hi, max(p0, p1))
    elif abs(su) > ai:
        return i1, i1
    cv = c * dy  # v = -s dx + c dy, |v| <= bi
    if s != 0.0:
        p0 = (cv - bi) / s
        p1 = (cv + bi) / s
        lo, hi = max(lo, min(p0, p1)), min(hi, max(p0, p1))
    elif abs(cv) > bi:
        return i1, i1
    margin = 1e-9 * h
    lo += margin
    hi -= margin
    if not lo <= hi:
        return i1, i1
    # dx of column i is (i + 0.5) h - ox
    f0 = max(math.ceil((lo + ox) / h - 0.5), i0) if lo > -math.inf else i0
    f1 = min(math.floor((hi + ox) / h - 0.5) + 1, i1) if hi < math.inf else i1
    return (f0, f1) if f0 < f1 else (i1, i1)


@_jit
def rectangle_fractions(
    cx, cy, half_l, half_w, cos_t, sin_t, x0, y0, h, ny, nx, exclusive, centres, weights, out, mass
):
    """Prior mass in rotated rectangles: the fraction of every ``h x h`` cell of an ``ny x nx``
    grid (origin ``(x0, y0)``) inside every rectangle.

    Two rules for a cell's fraction. ``centres=False``: the exact area fraction (below).
    ``centres=True``: 1 when the cell's centre lies in the rectangle (``|u| <= a`` and
    ``|v| <= b`` in its frame, eq. 6), else 0 -- a quadrature on the cell centres, used on a
    fine lattice of sample points. Results: ``out (P, n, ny, nx)``, zeros on entry, gets the
    fractions unless it is empty; ``mass (P, n)``, zeros on entry, gets
    ``sum fraction * weights`` over the cells unless ``weights`` is empty.

    Rectangle ``p * n + k`` (flat inputs) is UAV ``k`` of individual ``p``: centre
    ``(cx, cy)``, half side ``half_l`` along ``(cos_t, sin_t)``, ``half_w`` across. Per row,
    only the columns of the rectangle clipped to the row's band are visited. A cell is 1 when its
    projections on both rectangle axes lie inside, 0 when one lies outside; a cell crossed only
    by the two sides of one axis gets the exact fraction of that slab (:func:`_slab_cdf`); a
    cell near a corner is clipped by the rectangle (Sutherland-Hodgman).

    With ``exclusive``, UAV ``k``'s fraction excludes what the UAVs before it cover (§3.1.6,
    exactly): a cell wholly inside an earlier rectangle gives 0; in a cell that earlier
    rectangles cover in part, the cell clipped to rectangle ``k`` minus those rectangles
    (:func:`_minus_rects`). Under the centre rule, a cell counts for the first rectangle
    holding its centre only, so the masses of an individual's rectangles add up to the mass
    of their union.
    """
    n_ind, n_uav = mass.shape
    write = out.size > 0
    weigh = weights.size > 0
    full = np.zeros((ny, nx), np.bool_)
    count = np.zeros((ny, nx), np.int64)
    parts = np.empty((ny, nx, max(n_uav, 1)), np.int64)
    part_frac = np.empty((ny, nx))  # the (plain) fraction of a cell's first partial rectangle
    size = 16 + 3 * n_uav
    px = np.empty(size)
    py = np.empty(size)
    qx = np.empty(size)
    qy = np.empty(size)
    sx = np.empty((n_uav + 1, size))
    sy = np.empty((n_uav + 1, size))
    sn = np.empty(n_uav + 1, np.int64)
    sp = np.empty(n_uav + 1, np.int64)
    sk = np.empty(n_uav + 1, np.int64)
    rx = np.empty(n_uav)
    ry = np.empty(n_uav)
    half = 0.5 * h
    inv_area = 1.0 / (h * h)
    tiny = 1e-14 * h * h
    for p in range(n_ind):
        if exclusive:
            full[:, :] = False
            count[:, :] = 0
        for k in range(n_uav):
            r = p * n_uav + k
            c = cos_t[r]
            s = sin_t[r]
            a = half_l[r]
            b = half_w[r]
            ac = abs(c)
            as_ = abs(s)
            ey = a * as_ + b * ac
            j0 = max(math.floor((cy[r] - ey - y0) / h), 0)
            j1 = min(math.ceil((cy[r] + ey - y0) / h), ny)
            hp = half * (ac + as_)  # half extent of a cell projected on either rectangle axis
            big = half * max(ac, as_)
            small = half * min(ac, as_)
            for j in range(j0, j1):
                dy = y0 + (j + 0.5) * h - cy[r]
                # the rectangle's x-range within this row's band -> columns (grown by 1e-9 h:
                # a column of zero area is harmless, the per-cell tests give it nothing)
                lo_x, hi_x = _row_span(dy, half, c, s, a, b)
                if not lo_x <= hi_x:
                    continue
                i0 = max(math.floor((cx[r] + lo_x - x0) / h - 1e-9), 0)
                i1 = min(math.ceil((cx[r] + hi_x - x0) / h + 1e-9), nx)
                f0, f1 = i1, i1
                if not centres:
                    f0, f1 = _inside_columns(dy, c, s, a - hp, b - hp, cx[r] - x0, h, i0, i1)
                for i in range(i0, i1):
                    if exclusive and full[j, i]:
                        continue
                    if f0 <= i < f1 and not (exclusive and count[j, i]):
                        # wholly inside, no earlier UAV in the cell: the fraction is 1
                        if write:
                            out[p, k, j, i] = 1.0
                        if weigh:
                            mass[p, k] += weights[j, i]
                        full[j, i] = exclusive
                        continue
                    dx = x0 + (i + 0.5) * h - cx[r]
                    u = dx * c + dy * s
                    v = dy * c - dx * s
                    au = abs(u)
                    av = abs(v)
                    if centres:
                        if au <= a and av <= b:
                            if write:
                                out[p, k, j, i] = 1.0
                            if weigh:
                                mass[p, k] += weights[j, i]
                            full[j, i] = exclusive
                        continue
                    if au >= a + hp or av >= b + hp:
                        continue
                    in_u = au + hp <= a
                    in_v = av + hp <= b
                    own_full = in_u and in_v
                    earlier = count[j, i] if exclusive else 0
                    if own_full:
                        m_own = 1.0
                    elif in_v:  # only the sides u = +-a cross the cell
                        m_own = _slab_cdf(a - u, big, small) - _slab_cdf(-a - u, big, small)
                    elif in_u:  # only the sides v = +-b
                        m_own = _slab_cdf(b - v, big, small) - _slab_cdf(-b - v, big, small)
                    else:  # near a corner: clip the cell by the rectangle
                        n = _cell_square(h, px, py)
                        n = _clip_rect(px, py, n, qx, qy, -dx, -dy, c, s, a, b, half)
                        m_own = _area(px, py, n) * inv_area
                    plain = m_own
                    if earlier == 1 and own_full:  # the cell minus one rectangle
                        m_own = 1.0 - part_frac[j, i]
                    elif earlier == 1:  # (cell ∩ Q_k) minus (cell ∩ Q_k ∩ Q_e)
                        e = parts[j, i, 0]
                        n = _cell_square(h, px, py)
                        n = _clip_rect(px, py, n, qx, qy, -dx, -dy, c, s, a, b, half)
                        ex = cx[e] - (cx[r] + dx)
                        ey_ = cy[e] - (cy[r] + dy)
                        n = _clip_rect(
                            px,
                            py,
                            n,
                            qx,
                            qy,
                            ex,
                            ey_,
                            cos_t[e],
                            sin_t[e],
                            half_l[e],
                            half_w[e],
                            half,
                        )
                        m_own = m_own - _area(px, py, n) * inv_area
                    elif earlier:
                        n = _cell_square(h, sx[0], sy[0])
                        if not own_full:
                            n = _clip_rect(sx[0], sy[0], n, qx, qy, -dx, -dy, c, s, a, b, half)
                        for q in range(earlier):
                            e = parts[j, i, q]
                            rx[q] = cx[e] - (cx[r] + dx)
                            ry[q] = cy[e] - (cy[r] + dy)
                        area = _minus_rects(
                            n,
                            parts[j, i],
                            earlier,
                            rx,
                            ry,
                            cos_t,
                            sin_t,
                            half_l,
                            half_w,
                            sx,
                            sy,
                            sn,
                            sp,
                            sk,
                            qx,
                            qy,
                            tiny,
                        )
                        m_own = min(area * inv_area, m_own)
                    if m_own <= 1e-14:  # rounding residue of an exact 0
                        continue
                    m_own = min(m_own, 1.0)
                    if write:
                        out[p, k, j, i] = m_own
                    if weigh:
                        mass[p, k] += m_own * weights[j, i]
                    if exclusive:
                        if own_full:
                            full[j, i] = True
                        else:
                            parts[j, i, earlier] = r
                            if earlier == 0:
                                part_frac[j, i] = plain
                            count[j, i] = earlier + 1


# ---------------------------------------------------- rectangle masses by boundary integrals


@_jit_inline
def _edge_mass(xa, ya, xb, yb, gx, gy, xref, iref, w, pre, ny, nx):
    """``∫ F dY`` along the segment a -> b, with ``F(X, Y) = ∫_{xref}^{X} w(X', Y) dX'``.

    Cell units, ``X = (x - x_c) / h``: column ``i`` spans ``[gx + i, gx + i + 1]``, row ``j``
    ``[gy + j, gy + j + 1]``; ``w`` the weight (mass) of every cell, ``pre[j, i] = sum
    w[j, :i]``, ``iref`` the column of ``xref``. The segment is cut where it crosses grid lines
    (a DDA walk); on each piece ``F`` is linear along the segment, so the midpoint rule is exact.
    ``F`` counts from ``xref`` (the polygon's leftmost point), not from the map's edge: the
    terms then have the size of the polygon's own mass, and a tiny polygon keeps its digits.
    """
    dx = xb - xa
    dy = yb - ya
    if dy == 0.0:
        return 0.0
    i = math.floor(xa - gx)
    j = math.floor(ya - gy)
    if dx > 0.0:
        di, tx, dtx = 1, (gx + i + 1 - xa) / dx, 1.0 / dx
    elif dx < 0.0:
        di, tx, dtx = -1, (gx + i - xa) / dx, -1.0 / dx
    else:
        di, tx, dtx = 0, math.inf, math.inf
    if dy > 0.0:
        dj, ty, dty = 1, (gy + j + 1 - ya) / dy, 1.0 / dy
    else:
        dj, ty, dty = -1, (gy + j - ya) / dy, -1.0 / dy
    head = gx + iref + 1 - xref  # width of the reference column right of xref
    t0 = 0.0
    total = 0.0
    while True:
        t1 = min(tx, ty, 1.0)
        if t1 > t0:
            xm = xa + 0.5 * (t0 + t1) * dx
            jj = min(max(j, 0), ny - 1)
            ii = min(max(i, iref), nx - 1)  # a rounding step left of xref: extrapolate
            if ii == iref:
                f = w[jj, ii] * (xm - xref)
            else:
                f = (
                    w[jj, iref] * head
                    + (pre[jj, ii] - pre[jj, iref + 1])
                    + w[jj, ii] * (xm - gx - ii)
                )
            total += f * (t1 - t0)
            t0 = t1
        if t1 >= 1.0:
            break
        if tx <= ty:
            i += di
            tx += dtx
        else:
            j += dj
            ty += dty
    return total * dy


@_jit_inline
def _polygon_mass(px, py, n, gx, gy, w, pre, ny, nx, tiny):
    """Mass of the convex polygon ``p[:n]`` (counter-clockwise, inside the map) over the
    cell weights ``w``: Green's theorem, ``∬ w dA = ∮ F dY`` (:func:`_edge_mass`); 0 for a
    polygon of area ``<= tiny`` (cells)."""
    if n < 3 or _area(px, py, n) <= tiny:
        return 0.0
    xref = px[0]
    for m in range(1, n):
        xref = min(xref, px[m])
    iref = min(max(math.floor(xref - gx), 0), nx - 1)
    total = 0.0
    for m in range(n):
        mm = m + 1
        if mm == n:
            mm = 0
        total += _edge_mass(px[m], py[m], px[mm], py[mm], gx, gy, xref, iref, w, pre, ny, nx)
    return total


@_jit_inline
def _clip_box(px, py, n, qx, qy, lox, loy, hix, hiy):
    """``p[:n]`` clipped to the box ``[lox, hix] x [loy, hiy]`` (in place; ``q`` scratch)."""
    xl = yl = math.inf
    xh = yh = -math.inf
    for m in range(n):
        xl, xh = min(xl, px[m]), max(xh, px[m])
        yl, yh = min(yl, py[m]), max(yh, py[m])
    if xl >= lox and xh <= hix and yl >= loy and yh <= hiy:
        return n
    for side in range(4):
        if side == 0:
            nx_, ny_, t = -1.0, 0.0, -lox
        elif side == 1:
            nx_, ny_, t = 1.0, 0.0, hix
        elif side == 2:
            nx_, ny_, t = 0.0, -1.0, -loy
        else:
            nx_, ny_, t = 0.0, 1.0, hiy
        n = _clip(px, py, n, qx, qy, nx_, ny_, t)
        for m in range(n):
            px[m] = qx[m]
            py[m] = qy[m]
    return n


@_jit_inline
def _clip_to_rect(px, py, n, qx, qy, rx, ry, c, s, a, b):
    """``p[:n]`` clipped to the rectangle centred at ``(rx, ry)`` (axes ``(c, s)``, half sides
    ``a``, ``b``), the result in ``q``; returns its size (``p`` is overwritten)."""
    eo = c * rx + s * ry
    fo = -s * rx + c * ry
    for side in range(4):
        nx_, ny_, t = _rect_side(side, c, s, eo, fo, a, b)
        n = _clip(px, py, n, qx, qy, nx_, ny_, t)
        if n < 3:
            return 0
        if side < 3:
            for m in range(n):
                px[m] = qx[m]
                py[m] = qy[m]
    return n


@_jit_inline
def _minus_rects_mass(
    n0, n_earlier, rx, ry, cos_e, sin_e, a_e, b_e, sx, sy, sn, sp, tx, ty, mass_args
):
    """Mass of the convex polygon ``sx[0, :n0]`` minus the union of ``n_earlier`` rectangles
    (centres ``rx, ry`` in the polygon's coordinates, axes ``cos_e, sin_e``, half sides
    ``a_e, b_e``), by inclusion-exclusion: ``m(P) - sum m(P ∩ R_e) + sum m(P ∩ R_e ∩ R_f)
    - ...``, depth first over the intersections (level ``d`` holds ``P ∩`` d rectangles,
    ``sp`` the next rectangle to try there), a branch ending where its polygon has no area
    (``<= tiny``). Every intersection is convex (:func:`_clip_to_rect`), its mass by
    :func:`_polygon_mass` (``mass_args = (gx, gy, w, pre, ny, nx, tiny)``); the rectangles of
    a converged population rarely overlap, so there are few terms. A result under 1e-13 of
    the polygon's own mass (a copy's rounding residue) is 0, as the dense kernel's."""
    gx, gy, w, pre, ny, nx, tiny = mass_args
    whole = _polygon_mass(sx[0], sy[0], n0, gx, gy, w, pre, ny, nx, tiny)
    total = whole
    sn[0] = n0
    sp[0] = 0
    level = 0
    while level >= 0:
        e = sp[level]
        if e >= n_earlier:
            level -= 1
            continue
        sp[level] = e + 1
        src_x, src_y, dst_x, dst_y = sx[level], sy[level], sx[level + 1], sy[level + 1]
        m = sn[level]
        for q in range(m):
            dst_x[q] = src_x[q]
            dst_y[q] = src_y[q]
        m = _clip_to_rect(dst_x, dst_y, m, tx, ty, rx[e], ry[e], cos_e[e], sin_e[e], a_e[e], b_e[e])
        if m < 3 or _area(tx, ty, m) <= tiny:
            continue
        for q in range(m):
            dst_x[q] = tx[q]
            dst_y[q] = ty[q]
        part = _polygon_mass(dst_x, dst_y, m, gx, gy, w, pre, ny, nx, tiny)
        total += -part if level % 2 == 0 else part
        level += 1
        sn[level] = m
        sp[level] = e + 1
    # what the terms leave of an exact 0 (a copy of an earlier rectangle) is rounding: the
    # cancellation's error is a few ulp of the whole polygon's mass
    return total if total > 1e-13 * whole else 0.0


@_jit
def rectangle_masses(cx, cy, half_l, half_w, cos_t, sin_t, x0, y0, h, weights, exclusive, mass):
    """Weighted mass of rotated rectangles over a grid, by boundary integrals (no per-cell areas).

    ``weights (ny, nx)``: the mass of each ``h x h`` cell of the grid at origin ``(x0, y0)``,
    spread evenly over the cell. ``mass (P, n)`` gets, for rectangle ``p * n + k`` of the flat
    inputs (centre ``(cx, cy)``, half side ``half_l`` along ``(cos_t, sin_t)``, ``half_w``
    across), ``sum_cells area(cell ∩ Q) / h^2 * weights`` -- the same number as
    :func:`rectangle_fractions`' weighted masses, to rounding. With ``exclusive``, UAV ``k``
    gets the mass of ``Q_k`` minus the union of ``Q_0 .. Q_{k-1}`` of its individual (§3.1.6).

    Per rectangle, in cell units about its centre: the rectangle clipped to the map, minus the
    earlier rectangles whose bounding circles meet it (cut into disjoint convex pieces,
    :func:`_minus_rects_mass`), and each convex piece's mass by Green's theorem on the row-wise
    cumulative weights (:func:`_polygon_mass`): O(grid lines its edges cross), not O(cells).
    """
    n_ind, n_uav = mass.shape
    ny, nx = weights.shape
    pre = np.zeros((ny, nx + 1))
    for j in range(ny):
        for i in range(nx):
            pre[j, i + 1] = pre[j, i] + weights[j, i]
    size = 8 + 4 * n_uav  # the map clip adds 4 corners at most, each rectangle 4 more
    sx = np.empty((n_uav + 1, size))
    sy = np.empty((n_uav + 1, size))
    sn = np.empty(n_uav + 1, np.int64)
    sp = np.empty(n_uav + 1, np.int64)
    qx = np.empty(size)
    qy = np.empty(size)
    rx = np.empty(max(n_uav, 1))
    ry = np.empty(max(n_uav, 1))
    ce = np.empty(max(n_uav, 1))
    se = np.empty(max(n_uav, 1))
    ae = np.empty(max(n_uav, 1))
    be = np.empty(max(n_uav, 1))
    inv_h = 1.0 / h
    tiny = 1e-14  # pieces under this area (cells) are dropped, as in rectangle_fractions
    for p in range(n_ind):
        for k in range(n_uav):
            r = p * n_uav + k
            c = cos_t[r]
            s = sin_t[r]
            a = half_l[r] * inv_h
            b = half_w[r] * inv_h
            gx = (x0 - cx[r]) * inv_h
            gy = (y0 - cy[r]) * inv_h
            px, py = sx[0], sy[0]
            px[0], py[0] = -a * c + b * s, -a * s - b * c
            px[1], py[1] = a * c + b * s, a * s - b * c
            px[2], py[2] = a * c - b * s, a * s + b * c
            px[3], py[3] = -a * c - b * s, -a * s + b * c
            n = _clip_box(px, py, 4, qx, qy, gx, gy, gx + nx, gy + ny)
            if n < 3:
                continue
            n_e = 0
            if exclusive:
                rk = math.hypot(a, b)
                hx = a * abs(c) + b * abs(s)
                hy = a * abs(s) + b * abs(c)
                for e in range(k):  # the earlier rectangles whose bounding box and circle meet
                    q = p * n_uav + e
                    ex = (cx[q] - cx[r]) * inv_h
                    ey = (cy[q] - cy[r]) * inv_h
                    a_q = half_l[q] * inv_h
                    b_q = half_w[q] * inv_h
                    cq, sq = abs(cos_t[q]), abs(sin_t[q])
                    if abs(ex) > hx + a_q * cq + b_q * sq or abs(ey) > hy + a_q * sq + b_q * cq:
                        continue
                    if math.hypot(ex, ey) <= rk + math.hypot(a_q, b_q):
                        rx[n_e], ry[n_e] = ex, ey
                        ce[n_e], se[n_e] = cos_t[q], sin_t[q]
                        ae[n_e], be[n_e] = a_q, b_q
                        n_e += 1
            if n_e == 0:
                mass[p, k] = _polygon_mass(px, py, n, gx, gy, weights, pre, ny, nx, tiny)
            else:
                mass[p, k] = _minus_rects_mass(
                    n, n_e, rx, ry, ce, se, ae, be, sx, sy, sn, sp, qx, qy,
                    (gx, gy, weights, pre, ny, nx, tiny),
                )  # fmt: skip


@_jit
def plan_rectangles(x, box, takeoff, landing, x0, y0, h, weights, geo, terms):
    """The planner's rectangles (``poc_env.agents.planning.objective``) for a population, in one
    pass.

    ``x (P, 6 n)``: per UAV ``(x_c, y_c, l, w, theta, d)``. Per rectangle, as the objective's
    numpy steps (same operations, in the same order): the map repair of ``split`` (a rectangle
    whose bounding box, half-extents ``h_x, h_y``, is wider or taller than ``box = (x0, y0, x1,
    y1)`` scaled about its centre until it fits, the centre then clipped so that the box lies
    in the map); the lawnmower of ``lawnmower`` (lines along the long side ``L``, ``n = max(1,
    ceil(E/d - 1/2))`` of them, the first waypoint the corner of the outer lines nearest the
    take-off, the last on the other outer line) and its transit from ``takeoff[i]`` and to
    ``landing[i]``. Results: ``geo (P, n, 5)`` the repaired ``x_c, y_c, l, w, theta``;
    ``terms (P, n, 6)`` the line count, ``L``, the search legs ``n L``, the track ``n L +
    (n - 1) d``, the transit, and the prior mass of the rectangle less the ones before it
    (:func:`rectangle_masses`, exclusive, over ``weights`` on the grid at ``(x0, y0)``).
    """
    n_ind = x.shape[0]
    n_uav = x.shape[1] // 6
    bx0, by0, bx1, by1 = box[0], box[1], box[2], box[3]
    size = n_ind * n_uav
    cx = np.empty(size)
    cy = np.empty(size)
    hl = np.empty(size)
    hw = np.empty(size)
    ct = np.empty(size)
    st = np.empty(size)
    for p in range(n_ind):
        for i in range(n_uav):
            xc, yc, ln, wd, th, d = x[p, 6 * i : 6 * i + 6]
            c = abs(math.cos(th))
            s = abs(math.sin(th))
            hx = 0.5 * (ln * c + wd * s)
            hy = 0.5 * (ln * s + wd * c)
            k = min(1.0, min(0.5 * (bx1 - bx0) / hx, 0.5 * (by1 - by0) / hy))
            ln, wd, hx, hy = ln * k, wd * k, hx * k, hy * k
            xc = min(max(xc, bx0 + hx), max(bx0 + hx, bx1 - hx))
            yc = min(max(yc, by0 + hy), max(by0 + hy, by1 - hy))
            geo[p, i, 0], geo[p, i, 1], geo[p, i, 2] = xc, yc, ln
            geo[p, i, 3], geo[p, i, 4] = wd, th
            # the lawnmower
            alpha = th if ln >= wd else th + 0.5 * np.pi
            short = min(ln, wd)
            long_ = max(ln, wd)
            n = max(1.0, math.ceil(short / d - 0.5))
            elx, ely = math.cos(alpha), math.sin(alpha)
            eex, eey = -ely, elx
            v_first = 0.0 if short < d else 0.5 * (short - d)
            v_last = v_first - (n - 1.0) * d
            best = math.inf
            v_s = u_s = 0.0
            k_s = 0
            for q in range(4):
                v = v_first if q < 2 else v_last
                u = -0.5 * long_ if q % 2 == 0 else 0.5 * long_
                dx = xc + v * eex + u * elx - takeoff[i, 0]
                dy = yc + v * eey + u * ely - takeoff[i, 1]
                dist = math.sqrt(dx * dx + dy * dy)
                if dist < best:
                    best, v_s, u_s, k_s = dist, v, u, q
            v_e = v_last if k_s < 2 else v_first
            u_e = -u_s if n % 2 == 1 else u_s
            fx = xc + v_s * eex + u_s * elx - takeoff[i, 0]
            fy = yc + v_s * eey + u_s * ely - takeoff[i, 1]
            lx = landing[i, 0] - (xc + v_e * eex + u_e * elx)
            ly = landing[i, 1] - (yc + v_e * eey + u_e * ely)
            search = n * long_
            terms[p, i, 0] = n
            terms[p, i, 1] = long_
            terms[p, i, 2] = search
            terms[p, i, 3] = search + (n - 1.0) * d
            terms[p, i, 4] = math.sqrt(fx * fx + fy * fy) + math.sqrt(lx * lx + ly * ly)
            r = p * n_uav + i
            cx[r], cy[r], hl[r], hw[r] = xc, yc, 0.5 * ln, 0.5 * wd
            ct[r], st[r] = math.cos(th), math.sin(th)
    mass = np.zeros((n_ind, n_uav))
    rectangle_masses(cx, cy, hl, hw, ct, st, x0, y0, h, weights, True, mass)
    terms[:, :, 5] = mass


# ---------------------------------------------------------- route timing
# (poc_env.agents.planning.refine)


@_jit
def route_timeline(p, v_out, v_line, v_home, turn_cost, budget, reserve, heading0, out, dep):
    """Arrival times of the path ``p`` (m, 2) in ``out`` (m,) and whether it fits (see
    :func:`poc_env.agents.planning.refine.arrival_times` and ``route_fits``); points within 1 mm of
    the point before get the same time as it and no turn. ``heading0`` NaN: no heading at
    take-off. ``dep`` (m,) gets the time each point is left (its arrival plus the turn
    there)."""
    m = p.shape[0]
    out[0] = 0.0
    dep[:] = np.inf
    t = 0.0
    last = 0  # the last point kept
    have = not math.isnan(heading0)  # a heading exists (at take-off, or from a flown leg)
    hx = math.cos(heading0) if have else 0.0
    hy = math.sin(heading0) if have else 0.0
    fits = True
    for j in range(1, m):
        dx = p[j, 0] - p[last, 0]
        dy = p[j, 1] - p[last, 1]
        length = math.hypot(dx, dy)
        if length <= 1e-3 and j < m - 1:
            out[j] = t
            continue
        v = v_line
        if last == 0:
            v = v_out
        if j == m - 1:
            v = v_home
        if length > 0:
            if have:
                cross = hx * dy - hy * dx
                dot = hx * dx + hy * dy
                t += turn_cost * abs(math.atan2(cross, dot))
            hx = dx
            hy = dy
            have = True
            dep[last] = t
            t += length / v
        out[j] = t
        last = j
        if j < m - 1:
            home = math.hypot(p[m - 1, 0] - p[j, 0], p[m - 1, 1] - p[j, 1])
            if t + home / v_home + reserve > budget + 1e-9:
                fits = False
    if t > budget + 1e-9:
        fits = False
    return fits


@_jit
def route_sample(p, arrive, dep, times, out, act):
    """Positions ``out (S, 2)`` at ``times (S,)`` (ascending) along the path ``p`` flown with
    arrival times ``arrive`` and departure times ``dep`` (:func:`route_timeline`): still at a point
    while turning there, along a leg at constant speed; ``act`` False once landed."""
    m = p.shape[0]
    j = 0  # the point last left
    for s in range(times.shape[0]):
        tau = times[s]
        if tau >= arrive[m - 1]:
            out[s, 0] = p[m - 1, 0]
            out[s, 1] = p[m - 1, 1]
            act[s] = False
            continue
        act[s] = True
        while j < m - 1 and tau >= arrive[j + 1]:
            j += 1
        if tau <= dep[j] or not dep[j] < arrive[j + 1]:
            out[s, 0] = p[j, 0]
            out[s, 1] = p[j, 1]
        else:
            f = (tau - dep[j]) / (arrive[j + 1] - dep[j])
            out[s, 0] = p[j, 0] + f * (p[j + 1, 0] - p[j, 0])
            out[s, 1] = p[j, 1] + f * (p[j + 1, 1] - p[j, 1])
