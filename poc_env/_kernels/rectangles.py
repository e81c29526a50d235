"""Compiled rectangle areas: fractions and weighted masses of rotated rectangles over grid cells.

The exact area fractions of rotated rectangles in every cell, plain or exclusive of the
rectangles before (§3.1.6), with an optional centre-point rule (:func:`rectangle_fractions`),
and their weighted masses by boundary integrals (:func:`rectangle_masses`):
:mod:`poc_env.theory.regions` and the planner's objective call them; tested against shapely.

A kernel module: imports nothing of the project (the cache rule, :mod:`poc_env._kernels`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy")
_jit_inline = njit(cache=True, error_model="numpy", inline="always")

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

#: Above this many earlier rectangles meeting one rectangle, :func:`rectangle_masses` leaves
#: inclusion-exclusion (up to ``2^n`` terms: 42 UAVs from one airfield took minutes) for the
#: per-cell exclusive areas of :func:`rectangle_fractions` (the same numbers, to rounding).
MAX_TERMS_OVERLAP = 12


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
def rectangle_masses(
    cx, cy, half_l, half_w, cos_t, sin_t, x0, y0, h, weights, exclusive, mass, max_overlap=-1
):
    """Weighted mass of rotated rectangles over a grid, by boundary integrals (no per-cell areas).

    ``weights (ny, nx)``: the mass of each ``h x h`` cell of the grid at origin ``(x0, y0)``,
    spread evenly over the cell. ``mass (P, n)`` gets, for rectangle ``p * n + k`` of the flat
    inputs (centre ``(cx, cy)``, half side ``half_l`` along ``(cos_t, sin_t)``, ``half_w``
    across), ``sum_cells area(cell ∩ Q) / h^2 * weights`` -- the same number as
    :func:`rectangle_fractions`' weighted masses, to rounding. With ``exclusive``, UAV ``k``
    gets the mass of ``Q_k`` minus the union of ``Q_0 .. Q_{k-1}`` of its individual (§3.1.6).

    Per rectangle, in cell units about its centre: the rectangle clipped to the map, minus the
    earlier rectangles whose bounding circles meet it (by inclusion-exclusion over convex pieces,
    :func:`_minus_rects_mass`), and each convex piece's mass by Green's theorem on the row-wise
    cumulative weights (:func:`_polygon_mass`): O(grid lines its edges cross), not O(cells).
    An individual in which a rectangle meets more than ``max_overlap`` earlier ones
    (default, ``-1``: :data:`MAX_TERMS_OVERLAP`; 0: always) is computed by the per-cell
    exclusive areas instead (:func:`rectangle_fractions`; the same numbers, to rounding):
    polynomial where inclusion-exclusion is exponential.
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
    limit = MAX_TERMS_OVERLAP if max_overlap < 0 else max_overlap
    tiny = 1e-14  # pieces under this area (cells) are dropped, as in rectangle_fractions
    no_cells = np.zeros((0, 0, 0, 0))
    for p in range(n_ind):
        dense = False
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
            if n_e > limit:  # inclusion-exclusion would cost up to 2^n_e terms
                dense = True
                break
            if n_e == 0:
                mass[p, k] = _polygon_mass(px, py, n, gx, gy, weights, pre, ny, nx, tiny)
            else:
                mass[p, k] = _minus_rects_mass(
                    n, n_e, rx, ry, ce, se, ae, be, sx, sy, sn, sp, qx, qy,
                    (gx, gy, weights, pre, ny, nx, tiny),
                )  # fmt: skip
        if dense:  # the whole individual by the per-cell exclusive areas: polynomial
            row = np.zeros((1, n_uav))
            lo = p * n_uav
            hi = lo + n_uav
            rectangle_fractions(
                cx[lo:hi], cy[lo:hi], half_l[lo:hi], half_w[lo:hi], cos_t[lo:hi], sin_t[lo:hi],
                x0, y0, h, ny, nx, True, False, weights, no_cells, row,
            )  # fmt: skip
            mass[p, :] = row[0]
