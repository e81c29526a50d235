"""Compiled observations: the raster channels, the state vectors and the compass sums.

The kernels behind :func:`poc_env.sim.observations.rasters`, :func:`~poc_env.sim.observations.
vectors` and :class:`~poc_env.sim.observations.CompassFeatures`; tested against plain numpy
in ``tests/sim/test_kernels.py``.

A kernel module: imports nothing of the project (the cache rule, :mod:`poc_env._kernels`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy")

# ------------------------------------------------------------------------------------ observations


@_jit
def _cells(pos, flying, e, x0, y0, x1, y1, cell, ny, nx, present, rows, cols):
    """Fill ``present``, ``rows``, ``cols (N,)`` for env ``e``: a UAV is present when flying
    inside the grid ``[x0, x1] x [y0, y1]`` (``Grid.contains``); its cell is ``Grid.cell_of``'s,
    ``floor((x - x0) / cell)`` clipped to the grid."""
    for k in range(present.shape[0]):
        x, y = pos[e, k, 0], pos[e, k, 1]
        present[k] = flying[e, k] and x >= x0 and x <= x1 and y >= y0 and y <= y1
        if present[k]:
            rows[k] = min(max(math.floor((y - y0) / cell), 0), ny - 1)
            cols[k] = min(max(math.floor((x - x0) / cell), 0), nx - 1)


@_jit
def _coarse_poc(belief, e, s, coarse, own_sum, scale, poc_sum, poc):
    """Fill ``poc (ny, nx)`` float32 with env ``e``'s coarse POC / ``scale`` clipped to [0, 1]:
    cells summed as ``Grid.coarsen`` does with numpy (``own_sum``), or taken from ``coarse``;
    ``poc_sum (ny, nx)`` is scratch."""
    ny, nx = poc.shape
    if own_sum and s == 4:  # the last branch cell by cell (scalar: 1.5 times its vector code)
        for j in range(ny):
            r0 = belief[e, 4 * j]
            r1 = belief[e, 4 * j + 1]
            r2 = belief[e, 4 * j + 2]
            r3 = belief[e, 4 * j + 3]
            acc = poc_sum[j]
            for i in range(nx):
                k = 4 * i  # -0.0 + x is x: each sub-row's sum starts at its first value
                c = 0.0
                c += ((r0[k] + r0[k + 1]) + r0[k + 2]) + r0[k + 3]
                c += ((r1[k] + r1[k + 1]) + r1[k + 2]) + r1[k + 3]
                c += ((r2[k] + r2[k + 1]) + r2[k + 2]) + r2[k + 3]
                c += ((r3[k] + r3[k + 1]) + r3[k + 2]) + r3[k + 3]
                acc[i] = c
    elif own_sum and s == 2:  # the same for two sub-rows (Paper62)
        for j in range(ny):
            r0 = belief[e, 2 * j]
            r1 = belief[e, 2 * j + 1]
            acc = poc_sum[j]
            for i in range(nx):
                k = 2 * i
                c = 0.0
                c += r0[k] + r0[k + 1]
                c += r1[k] + r1[k + 1]
                acc[i] = c
    elif own_sum:  # numpy's multi-axis sum: 0 + each sub-row's sum (started from -0.0)
        for j in range(ny):
            acc = poc_sum[j]
            acc[:] = 0.0
            for a in range(s):
                row = belief[e, j * s + a]
                for i in range(nx):
                    r = -0.0
                    for b in range(s):
                        r += row[i * s + b]
                    acc[i] += r
    else:
        poc_sum[:] = coarse[e]
    for j in range(ny):
        for i in range(nx):
            q = poc_sum[j, i] / scale
            if q < 0.0:  # np.clip(q, 0.0, 1.0) with scalar bounds; NaN stays NaN
                q = 0.0
            elif q > 1.0:
                q = 1.0
            poc[j, i] = q


@_jit
def coarse_poc(belief, s, coarse, own_sum, scale, out):
    """Fill ``out (E, ny, nx)`` float32 with each env's raster channel 0 (:func:`rasters`),
    once per env rather than once per UAV."""
    n_env, ny, nx = out.shape
    poc_sum = np.empty((ny, nx))
    for e in range(n_env):
        _coarse_poc(belief, e, s, coarse, own_sum, scale[e], poc_sum, out[e])


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
        _cells(pos, flying, e, x0, y0, x1, y1, cell, ny, nx, present, rows, cols)
        _coarse_poc(belief, e, s, coarse, own_sum, scale[e], poc_sum, poc)
        for k in range(n):  # row by row, one channel at a time: loops that vectorise
            for j in range(ny):
                o0, o1, o2, o3 = out[e, k, 0, j], out[e, k, 1, j], out[e, k, 2, j], out[e, k, 3, j]
                p, hz = poc[j], hazard[j]
                for i in range(nx):
                    o0[i] = p[i]
                for i in range(nx):
                    o1[i] = 0.0
                for i in range(nx):
                    o2[i] = 0.0
                for i in range(nx):
                    o3[i] = hz[i]
        for k in range(n):
            if present[k]:
                rj, ci = rows[k], cols[k]
                out[e, k, 1, rj, ci] = 1.0
                for m in range(n):
                    if m != k:
                        out[e, m, 2, rj, ci] = 1.0


@_jit
def _neighbours(pos, flying, e, i, range_m):
    """How many other flying UAVs of env ``e`` are within ``range_m`` of UAV ``i`` (0 unless it
    flies): the row of eq. 24's in-range graph, with the operations of the swarm kernels
    ``pairwise_distances`` (``sqrt(0 + dx^2 + dy^2)``) and ``in_range`` (``dist <= range_m``),
    which this module may not call (the cache rule, :mod:`poc_env._kernels`)."""
    count = 0
    if flying[e, i]:
        for j in range(flying.shape[1]):
            if flying[e, j] and i != j:
                d2 = 0.0
                for k in range(2):
                    c = pos[e, i, k] - pos[e, j, k]
                    d2 += c * c
                if math.sqrt(d2) <= range_m:
                    count += 1
    return count


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
    are counted by :func:`_neighbours` (:func:`comms.in_range`'s graph)."""
    n_env, n = flying.shape
    v = np.empty(out.shape[2])
    for e in range(n_env):
        t = step[e] / horizon
        for i in range(n):
            x, y = pos[e, i, 0], pos[e, i, 1]
            v[0] = (x - bx0) / w
            v[1] = (y - by0) / h
            v[2] = pos[e, i, 2] / max_alt
            # a fixed-speed UAV (v_min = v_max) is at its one speed: 0, not 0 / 0
            v[3] = (speed[e, i] - min_speed) / speed_span if speed_span > 0.0 else 0.0
            v[4] = sin_h[e, i]
            v[5] = cos_h[e, i]
            v[6] = pitch[e, i] / max_pitch
            v[7] = 1.0 - elapsed[e, i] / endurance
            v[8] = 1.0 - elapsed[e, i] / usable
            v[9] = (landing[i, 0] - x) / diag
            v[10] = (landing[i, 1] - y) / diag
            v[11] = _neighbours(pos, flying, e, i, range_m) / others
            v[12] = 1.0 if flying[e, i] else 0.0
            v[13] = t
            for k in range(v.size):
                q = v[k]
                if not np.isnan(q):  # np.clip with array bounds: ties go to the bound
                    q = q if q > low[k] else low[k]
                    q = q if q < high[k] else high[k]
                out[e, i, k] = q


@_jit
def vectors_of(pos, speed, sin_h, cos_h, pitch, elapsed, flying, step, landing, c, low, high, out):
    """:func:`vectors` with its 14 scalars ``bx0 ... others`` in that order in one float64
    array ``c``: the single environment's call at each step (numba unboxes one array faster
    than 14 floats)."""
    vectors(
        pos, speed, sin_h, cos_h, pitch, elapsed, flying, step, landing, c[0], c[1], c[2], c[3],
        c[4], c[5], c[6], c[7], c[8], c[9], c[10], c[11], c[12], c[13], low, high, out,
    )  # fmt: skip


@_jit
def rasters_vectors(
    belief, s, coarse, own_sum, scale, hazard, pos, flying, x0, y0, x1, y1, cell,
    speed, sin_cos, pitch, elapsed, step, landing, c_low_high, raster, vector,
):  # fmt: skip
    """:func:`rasters` into ``raster``, then :func:`vectors_of` into ``vector``: the single
    environment's observations in one call (:class:`poc_env.sim.single.SingleStep`), with the
    headings' sines and cosines as the rows of ``sin_cos (2, E, N)`` and ``vectors_of``'s
    ``c``, ``low`` and ``high`` as those of ``c_low_high (3, VECTOR_SIZE)`` (fewer arrays:
    numba's dispatch costs about 60 ns per array argument)."""
    rasters(belief, s, coarse, own_sum, scale, hazard, pos, flying, x0, y0, x1, y1, cell, raster)
    vectors_of(
        pos, speed, sin_cos[0], sin_cos[1], pitch, elapsed, flying, step, landing,
        c_low_high[0], c_low_high[1], c_low_high[2], vector,
    )  # fmt: skip


@_jit
def _bins(cx, cy, px, py, poc, others, edges, radius, n_sectors, mass, count):
    """One UAV's row of :func:`compass_bins`: add ``poc[j]`` into ``mass`` per (sector, ring)
    and ``others[j]`` into ``count`` per sector over the cells within ``radius``, the cells
    visited in index order (those where both are zero add nothing and are skipped), each
    decided by :func:`_classify`."""
    n_rings = edges.shape[0] + 1
    for j in range(cx.shape[0]):
        q = poc[j]
        w = others[j]
        if q == 0.0 and w == 0.0:  # adding +-0.0 to sums started at +0.0 changes nothing
            continue
        sector, ring, inside = _classify(cx[j] - px, cy[j] - py, edges, radius, n_sectors)
        mass[sector * n_rings + ring] += q
        if inside:
            count[sector] += w


@njit(cache=True, error_model="numpy", inline="always")
def _classify(dx, dy, edges, radius, n_sectors):
    """Sector, ring and within-``radius`` flag of one offset (a cell centre minus a UAV's
    position; sector 0 starting due east, counter-clockwise; the ring: how many ``edges`` are
    <= the distance): the defining formulas (``arctan2``, ``hypot``) next to a boundary, and
    away from every boundary (a relative margin of 1e-9) the octant from the signs and
    ``|dy|`` vs ``|dx|`` and the ring from squared distances, which agree with them there."""
    n_rings = edges.shape[0] + 1
    tol = 1e-9
    ax = abs(dx)
    ay = abs(dy)
    big = max(ax, ay)
    if n_sectors == 8 and ay > tol * big and ax > tol * big and abs(ax - ay) > tol * big:
        if dy > 0 and dx > 0:
            sector = 0 if ay < ax else 1
        elif dy > 0:
            sector = 2 if ay > ax else 3
        elif dx < 0:
            sector = 4 if ay < ax else 5
        else:
            sector = 6 if ay > ax else 7
    else:
        ang = np.arctan2(dy, dx)
        sector = int(np.floor((ang + np.pi) / (2.0 * np.pi) * n_sectors)) % n_sectors
        sector = (sector + n_sectors // 2) % n_sectors
    d2 = dx * dx + dy * dy
    radius2 = radius * radius
    exact = abs(d2 - radius2) <= tol * radius2
    for r in range(n_rings - 1):
        e2 = edges[r] * edges[r]
        if abs(d2 - e2) <= tol * e2:
            exact = True
    ring = 0
    if exact:
        dist = np.hypot(dx, dy)
        while ring < n_rings - 1 and edges[ring] <= dist:
            ring += 1
        inside = dist <= radius
    else:
        while ring < n_rings - 1 and edges[ring] * edges[ring] <= d2:
            ring += 1
        inside = d2 <= radius2
    return sector, ring, inside


@njit(cache=True, error_model="numpy", inline="always")
def _clear_bin(dx, dy, lo0, lo1, lo2, hi0, hi1, hi2):
    """The bin ``sector * 4 + ring`` of an offset clearly inside an octant and a ring (8 sectors,
    3 ring edges: squared edges times ``1 -+ 1e-9`` in ``lo*``, ``hi*``), else -1: the octant
    from the signs of the offset and ``|dy| < |dx|``, the ring from how many squared edges the
    squared distance reaches, where :func:`_classify`'s fast branch decides the same (a squared
    distance within 1e-9 of a squared edge, where the squares and ``hypot`` might disagree, or
    an offset within 1e-9 of a sector boundary gives -1). No branches, so that a loop over cells
    calling it vectorises."""
    tol = 1e-9
    ax = abs(dx)
    ay = abs(dy)
    tb = tol * max(ax, ay)
    d2 = dx * dx + dy * dy
    ring = np.intp(d2 >= lo0) + np.intp(d2 >= lo1) + np.intp(d2 >= lo2)
    ring_hi = np.intp(d2 > hi0) + np.intp(d2 > hi1) + np.intp(d2 > hi2)
    clear = (ay > tb) & (ax > tb) & (abs(ax - ay) > tb) & (ring == ring_hi)
    # octants 0-7 counter-clockwise from east: quadrant 0 (+, +), 1 (-, +), 2 (-, -), 3 (+, -),
    # its lower octant where |dy| < |dx| in quadrants 0 and 2, else the upper one
    sx = np.intp(dx > 0)
    sy = np.intp(dy > 0)
    quad = sy * (1 - sx) + (1 - sy) * (2 + sx)
    upper = np.intp(ay < ax) ^ np.intp(sx == sy)
    return (2 * quad + upper) * 4 + ring if clear else -1


@_jit
def _cell_bins(cx, cy, pxs, pys, g, cnt, edges, radius, n_sectors, bins):
    """Each cell's (sector, ring) bin of :func:`_bins` (``sector * n_rings + ring``) for the
    ``cnt`` (1 to 3) UAVs ``g, g + 1 ...`` at ``(pxs, pys)`` into ``bins[u] (cells,)``: one pass
    over the cells for the three (a shorter group repeats its last UAV), each cell's bin by
    :func:`_clear_bin`; then the cells it leaves (next to a sector or ring boundary; all of
    them for sectors other than octants or other than three ring edges) decided by
    :func:`_classify`. The "others" radius decides no bin."""
    n_cells = cx.shape[0]
    n_rings = edges.shape[0] + 1
    tol = 1e-9
    every = n_sectors != 8 or n_rings != 4  # no fast bins: every cell by _classify
    worst = -1
    if not every:
        lo0 = edges[0] * edges[0] * (1.0 - tol)
        lo1 = edges[1] * edges[1] * (1.0 - tol)
        lo2 = edges[2] * edges[2] * (1.0 - tol)
        hi0 = edges[0] * edges[0] * (1.0 + tol)
        hi1 = edges[1] * edges[1] * (1.0 + tol)
        hi2 = edges[2] * edges[2] * (1.0 + tol)
        k1 = g + min(1, cnt - 1)
        k2 = g + min(2, cnt - 1)
        px0, py0, px1, py1, px2, py2 = pxs[g], pys[g], pxs[k1], pys[k1], pxs[k2], pys[k2]
        b0 = bins[0]
        b1 = bins[1]
        b2 = bins[2]
        worst = 0
        for j in range(n_cells):
            x = cx[j]
            y = cy[j]
            v0 = _clear_bin(x - px0, y - py0, lo0, lo1, lo2, hi0, hi1, hi2)
            v1 = _clear_bin(x - px1, y - py1, lo0, lo1, lo2, hi0, hi1, hi2)
            v2 = _clear_bin(x - px2, y - py2, lo0, lo1, lo2, hi0, hi1, hi2)
            b0[j] = v0
            b1[j] = v1
            b2[j] = v2
            worst = min(worst, min(v0, min(v1, v2)))
    if worst < 0:
        for u in range(cnt):
            px, py = pxs[g + u], pys[g + u]
            for j in range(n_cells):
                if every or bins[u, j] < 0:
                    sector, ring, _in = _classify(cx[j] - px, cy[j] - py, edges, radius, n_sectors)
                    bins[u, j] = sector * n_rings + ring


@_jit
def _bin_sums(q, b0, b1, b2, m0, m1, m2, spare):
    """Three UAVs' sums of one shared POC row per bin, each bin summed in cell order (what
    :func:`_bins` adds): UAV ``u`` adds ``q[j]`` (float32) into ``m_u[b_u[j]]`` for ``j`` in
    order, the three chains of additions interleaved so that they overlap. Branch-free: while a
    UAV's cells stay in one bin its running sum stays in a register (the bin's slot is still
    written each time) and its load reads the never-written slot ``m_u[spare]`` instead of the
    slot just stored, so no addition waits on a store; a new bin's sum is read from its slot.
    A group of fewer than three UAVs passes a spare row for the others (bins all 0, a mass row
    nobody reads)."""
    d = np.uint64(spare)
    p0 = d
    p1 = d
    p2 = d
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    for j in range(b0.shape[0]):
        qj = np.float64(q[j])
        b = np.uint64(b0[j])
        same = b == p0
        v = m0[d if same else b]
        a0 = (a0 if same else v) + qj
        m0[b] = a0
        p0 = b
        b = np.uint64(b1[j])
        same = b == p1
        v = m1[d if same else b]
        a1 = (a1 if same else v) + qj
        m1[b] = a1
        p1 = b
        b = np.uint64(b2[j])
        same = b == p2
        v = m2[d if same else b]
        a2 = (a2 if same else v) + qj
        m2[b] = a2
        p2 = b


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
    mass = np.zeros((b, n_sectors * (edges.shape[0] + 1)))
    count = np.zeros((b, n_sectors))
    for i in range(b):
        _bins(cx, cy, px[i], py[i], poc[i], others[i], edges, radius, n_sectors, mass[i], count[i])
    return mass, count


@_jit
def np_sum(a):
    """numpy's ``a.sum()`` of a contiguous float64 vector, bit for bit: its pairwise sum
    (numpy's ``pairwise_sum``: below 8 values one running sum from -0.0; up to 128 eight
    running sums, combined as ``((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))``, then the
    tail in order; above 128 the two halves, split at a multiple of 8, summed apart)."""
    n = a.shape[0]
    if n < 8:
        res = -0.0
        for i in range(n):
            res += a[i]
        return res
    if n <= 128:
        r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
        r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
        i = 8
        while i < n - n % 8:
            r0 += a[i]
            r1 += a[i + 1]
            r2 += a[i + 2]
            r3 += a[i + 3]
            r4 += a[i + 4]
            r5 += a[i + 5]
            r6 += a[i + 6]
            r7 += a[i + 7]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += a[i]
            i += 1
        return res
    n2 = n // 2
    n2 -= n2 % 8
    return np_sum(a[:n2]) + np_sum(a[n2:])


@_jit
def compass(poc, vector, pos, flying, grid_box, area, cx, cy, edges, layout, out):
    """The compass observation of every UAV of every env into ``out (E, N, F)`` float32 (the
    blocks of :class:`poc_env.sim.observations.CompassFeatures`), computed straight from each
    env's raster channel 0 ``poc (E, P, ny, nx)`` (P = 1: shared by its UAVs; P = N: each UAV's
    own), its float64 total and mean (numpy's, :func:`np_sum`), the state vectors
    ``vector (E, N, V)`` and the positions: the sums :func:`compass_bins` makes from rasters,
    without building them.

    ``grid_box = (x0, y0, x1, y1, cell)`` places the UAVs in cells as :func:`rasters` does; the
    "others" channel is 1 on each cell holding another present UAV, so such a cell counts once.
    A UAV's own position is decoded from its float32 vector as ``decode_vector`` does, ``area =
    (bx0, by0, w, h)``. ``layout = (v0, c0, o0, m0, i0, n_ids, n_sectors, agent_index)``: the
    block offsets, the index block's size, the sectors, whether to set the index; ``area``'s
    tail holds the others radius and the count normaliser. Cell ``j * nx + i`` has its centre
    at ``(cx, cy)[j * nx + i]``: each UAV's cells are put in their bins (:func:`_cell_bins`) and
    the sums made three UAVs at a time (:func:`_bin_sums`); ``edges``: the ring edges."""
    v0, c0, o0, m0, i0, n_ids, n_sectors, agent_index = layout
    x0, y0, x1, y1, cell = grid_box
    bx0, by0, bw, bh, radius, others = area
    n_env, n = flying.shape
    n_shared, ny, nx = poc.shape[1], poc.shape[2], poc.shape[3]
    n_cells = ny * nx
    n_rings = edges.shape[0] + 1
    n_bins = n_sectors * n_rings
    n_vec = vector.shape[2]
    mass = np.empty((n + 1, n_bins + 1))  # row n, column n_bins: spares for _bin_sums
    count = np.empty(n_sectors)
    others_cells = np.zeros(ny * nx)  # the "others" channel of one UAV, cleared after use
    bins = np.empty((4, ny * nx), dtype=np.intp)  # a group's three UAVs, then the spare's
    bins[3] = 0
    rows = np.empty(n, dtype=np.intp)
    cols = np.empty(n, dtype=np.intp)
    present = np.empty(n, dtype=np.bool_)
    pxs = np.empty(n)
    pys = np.empty(n)
    wide = np.empty(ny * nx)  # a channel 0 in float64, for numpy's sums
    totals = np.empty(n_shared)
    means = np.empty(n_shared)
    for e in range(n_env):
        _cells(pos, flying, e, x0, y0, x1, y1, cell, ny, nx, present, rows, cols)
        for p in range(n_shared):
            flat = poc[e, p].reshape(ny * nx)
            for c in range(ny * nx):
                wide[c] = flat[c]
            totals[p] = np_sum(wide)
            means[p] = totals[p] / (ny * nx)
        mass[:] = 0.0
        rows_e = poc[e].reshape(n_shared, n_cells)
        for k in range(n):
            pxs[k] = bx0 + np.float64(vector[e, k, 0]) * bw
            pys[k] = by0 + np.float64(vector[e, k, 1]) * bh
        step = 3 if n_shared == 1 else 1  # UAVs summed together: those sharing a row
        for g in range(0, n, step):  # a group short of three is padded by the spare (row n)
            _cell_bins(cx, cy, pxs, pys, g, min(step, n - g), edges, radius, n_sectors, bins)
            k1 = g + 1 if step == 3 and g + 1 < n else n
            k2 = g + 2 if step == 3 and g + 2 < n else n
            _bin_sums(
                rows_e[g if n_shared > 1 else 0], bins[0], bins[1 if k1 < n else 3],
                bins[2 if k2 < n else 3], mass[g], mass[k1], mass[k2], n_bins,
            )  # fmt: skip
        for k in range(n):
            p = k if n_shared > 1 else 0
            o = out[e, k]
            o[:] = 0.0
            for t in range(n_vec):
                o[v0 + t] = vector[e, k, t]
            px = pxs[k]
            py = pys[k]
            count[:] = 0.0
            for m in range(n):  # each cell holding another UAV counts once (a 1.0)
                c = rows[m] * nx + cols[m]
                if m != k and present[m] and others_cells[c] == 0.0:
                    others_cells[c] = 1.0
                    dx, dy = cx[c] - px, cy[c] - py
                    sector, _ring, inside = _classify(dx, dy, edges, radius, n_sectors)
                    if inside:
                        count[sector] += 1.0
            for m in range(n):
                if present[m]:
                    others_cells[rows[m] * nx + cols[m]] = 0.0
            tot = totals[p]
            if tot > 0:  # else the zeros written above
                for b in range(n_bins):
                    o[c0 + b] = mass[k, b] / tot
            for b in range(n_sectors):
                o[o0 + b] = min(count[b] / others, 1.0)
            o[m0] = means[p]
            if agent_index:
                o[i0 + k % n_ids] = 1.0


@_jit
def _clip(q, lo, hi):
    """``q`` clipped to [lo, hi] (NaN stays NaN, as ``np.clip``)."""
    if q < lo:
        return lo
    if q > hi:
        return hi
    return q


@_jit
def swarm_set(pos, speed, heading, pitch, flying, role, scales, layout, out):
    """The set observation's blocks after the compass ones (:data:`poc_env.spec.SET_BLOCKS`)
    into ``out (E, N, F)`` for every UAV of every env, from the positions and velocities alone
    (nothing per-UAV is copied: each env's arrays are read in place).

    ``role (N,)``: each UAV's role cue; ``scales = (diag, v_max, range_m)``: the operating
    area's diagonal, the top speed, the communication range; ``layout = (role0, centroid0,
    fleet0, nb0, k_max, n_fields)``: the block offsets, the neighbour rows and their width.
    Ground velocity: ``v (cos alpha cos beta, sin alpha cos beta)`` (eq. 19's horizontal part).
    The centroid is the mean position of the other flying UAVs; neighbours are the ``k_max``
    nearest other flying UAVs by horizontal distance, ties by index (fewer: zero rows)."""
    role0, cen0, fleet0, nb0, k_max, n_fields = layout
    diag, v_max, range_m = scales
    n_env, n = flying.shape
    best_d = np.empty(k_max)
    best_j = np.empty(k_max, dtype=np.intp)
    vx = np.empty(n)
    vy = np.empty(n)
    for e in range(n_env):
        n_fly = 0
        sx = 0.0
        sy = 0.0
        for j in range(n):
            c = speed[e, j] * math.cos(pitch[e, j])
            vx[j] = c * math.cos(heading[e, j])
            vy[j] = c * math.sin(heading[e, j])
            if flying[e, j]:
                n_fly += 1
                sx += pos[e, j, 0]
                sy += pos[e, j, 1]
        for i in range(n):
            o = out[e, i]
            x, y = pos[e, i, 0], pos[e, i, 1]
            o[role0] = role[i]
            others = n_fly - (1 if flying[e, i] else 0)
            if others > 0:
                ox = sx - (x if flying[e, i] else 0.0)
                oy = sy - (y if flying[e, i] else 0.0)
                o[cen0] = _clip((ox / others - x) / diag, -2.0, 2.0)
                o[cen0 + 1] = _clip((oy / others - y) / diag, -2.0, 2.0)
            else:
                o[cen0] = 0.0
                o[cen0 + 1] = 0.0
            o[fleet0] = 1.0 - 1.0 / n
            o[fleet0 + 1] = n_fly / n
            m = 0  # neighbours found so far, kept sorted by (distance^2, index)
            for j in range(n):
                if j == i or not flying[e, j]:
                    continue
                dx = pos[e, j, 0] - x
                dy = pos[e, j, 1] - y
                d2 = dx * dx + dy * dy
                if m == k_max and d2 >= best_d[m - 1]:
                    continue  # not nearer than the farthest kept (ties: the lower index stays)
                slot = m if m < k_max else k_max - 1
                while slot > 0 and best_d[slot - 1] > d2:
                    if slot < k_max:
                        best_d[slot] = best_d[slot - 1]
                        best_j[slot] = best_j[slot - 1]
                    slot -= 1
                best_d[slot] = d2
                best_j[slot] = j
                if m < k_max:
                    m += 1
            for r in range(k_max):
                b = nb0 + r * n_fields
                if r >= m:
                    for f in range(n_fields):
                        o[b + f] = 0.0
                    continue
                j = best_j[r]
                dist = math.sqrt(best_d[r])
                o[b] = _clip((pos[e, j, 0] - x) / diag, -2.0, 2.0)
                o[b + 1] = _clip((pos[e, j, 1] - y) / diag, -2.0, 2.0)
                o[b + 2] = _clip((vx[j] - vx[i]) / v_max, -2.0, 2.0)
                o[b + 3] = _clip((vy[j] - vy[i]) / v_max, -2.0, 2.0)
                o[b + 4] = _clip(dist / diag, 0.0, 2.0)
                o[b + 5] = 1.0 if dist <= range_m else 0.0
                o[b + 6] = 1.0
