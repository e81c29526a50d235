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
    if own_sum:  # numpy's multi-axis sum: 0 + each sub-row's sum (started from -0.0)
        for j in range(ny):
            acc = poc_sum[j]
            acc[:] = 0.0
            for a in range(s):
                row = belief[e, j * s + a]
                if s == 2:
                    for i in range(nx):
                        acc[i] += row[2 * i] + row[2 * i + 1]
                elif s == 4:  # the loop below with its sub-cells unrolled (it vectorises)
                    for i in range(nx):
                        k = 4 * i
                        acc[i] += (((-0.0 + row[k]) + row[k + 1]) + row[k + 2]) + row[k + 3]
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
            v[3] = (speed[e, i] - min_speed) / speed_span
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
    visited in index order (those where both are zero add nothing and are skipped)."""
    n_cells = cx.shape[0]
    n_rings = edges.shape[0] + 1
    two_pi = 2.0 * np.pi
    half = n_sectors // 2
    radius2 = radius * radius
    octants = n_sectors == 8
    tol = 1e-9  # relative margin around a boundary inside which the exact formula decides
    for j in range(n_cells):
        q = poc[j]
        w = others[j]
        if q == 0.0 and w == 0.0:  # adding +-0.0 to sums started at +0.0 changes nothing
            continue
        dx = cx[j] - px
        dy = cy[j] - py
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
            if abs(d2 - (edges[r] * edges[r])) <= tol * (edges[r] * edges[r]):
                exact = True
        near_radius = abs(d2 - radius2) <= tol * radius2
        if exact or near_radius:
            dist = np.hypot(dx, dy)
            while ring < n_rings - 1 and edges[ring] <= dist:
                ring += 1
            inside = dist <= radius
        else:
            while ring < n_rings - 1 and edges[ring] * edges[ring] <= d2:
                ring += 1
            inside = d2 <= radius2
        mass[sector * n_rings + ring] += q
        if inside:
            count[sector] += w


@njit(cache=True, error_model="numpy", inline="always")
def _classify(dx, dy, edges, radius, n_sectors):
    """Sector, ring and within-``radius`` flag of one offset: the decisions of :func:`_bins`'
    loop body, spelled out once more for :func:`_grid_bins`, which calls it once per run of
    cells and next to a boundary (a call per cell would cost more than the decision, hence the
    copy)."""
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


#: Octant of an offset clearly inside one (the branches of :func:`_classify`), indexed by
#: ``4 * (dy > 0) + 2 * (dx > 0) + (|dy| < |dx|)``.
_OCTANT = np.array([5, 4, 6, 7, 2, 3, 1, 0], dtype=np.intp)


@_jit
def _cell_bins(cx, cy, px, py, poc, edges, radius, n_sectors, mass, bins, d2s):
    """The POC sums of :func:`_bins` (``mass``; each bin summed in cell order) without its
    "others" counts, for short rows, in passes over the cells without branches (so that they
    vectorise). First each cell's bin: a cell clearly inside an octant and away from every
    ring edge and from ``radius`` (:func:`_classify`'s fast branch) takes its octant from
    :data:`_OCTANT` and its ring from how many squared edges (``edges`` ascending) its squared
    distance reaches; any other cell gets -1. Then the sums in cell order, the -1 cells decided
    by :func:`_classify`. Adding a zero to a sum started at +0.0 changes nothing, so zero cells
    are not skipped (but a zero cell is never classified). ``bins``, ``d2s (cells,)``:
    scratch."""
    n_rings = edges.shape[0] + 1
    _cell_bin_ids(cx, cy, px, py, edges, radius, n_sectors, bins, d2s)
    for j in range(cx.shape[0]):
        q = poc[j]
        b = bins[j]
        if b >= 0:
            mass[b] += q
        elif q != 0.0:
            sector, ring, _inside = _classify(cx[j] - px, cy[j] - py, edges, radius, n_sectors)
            mass[sector * n_rings + ring] += q


@_jit
def _cell_bin_ids(cx, cy, px, py, edges, radius, n_sectors, bins, d2s):
    """The first pass of :func:`_cell_bins`: each cell's bin (``sector * n_rings + ring``) into
    ``bins``, or a negative number for a cell :func:`_classify` must decide."""
    n_cells = cx.shape[0]
    n_rings = edges.shape[0] + 1
    tol = 1e-9
    radius2 = radius * radius
    if n_sectors != 8:  # no octants: every cell by the defining formula
        bins[:n_cells] = -1
        return
    for j in range(n_cells):
        dx = cx[j] - px
        dy = cy[j] - py
        ax = abs(dx)
        ay = abs(dy)
        tb = tol * max(ax, ay)
        d2 = dx * dx + dy * dy
        d2s[j] = d2
        clear = (ay > tb) & (ax > tb) & (abs(ax - ay) > tb)
        clear &= abs(d2 - radius2) > tol * radius2
        k = 4 * np.intp(dy > 0) + 2 * np.intp(dx > 0) + np.intp(ay < ax)
        bins[j] = _OCTANT[k] * n_rings if clear else -n_cells * n_rings
    for r in range(n_rings - 1):
        e2 = edges[r] * edges[r]
        band = tol * e2
        for j in range(n_cells):  # a cell next to an edge is pushed below zero for good
            d2 = d2s[j]
            bins[j] += np.intp(d2 >= e2) - np.intp(abs(d2 - e2) <= band) * n_cells * n_rings


@_jit
def _shared_cell_bins(cx, cy, px, py, poc, edges, radius, n_sectors, mass, bins, d2s):
    """:func:`_cell_bins` of several UAVs over one shared row ``poc``: ``px``, ``py (B,)``,
    ``mass (B, bins)``, ``bins (B, cells)``. The same sums in the same order per UAV (each
    UAV's bins summed in cell order), the UAVs' additions interleaved cell by cell so that
    their chains of additions overlap."""
    b_n = px.shape[0]
    n_rings = edges.shape[0] + 1
    for k in range(b_n):
        _cell_bin_ids(cx, cy, px[k], py[k], edges, radius, n_sectors, bins[k], d2s)
    for j in range(cx.shape[0]):
        q = poc[j]
        for k in range(b_n):
            b = bins[k, j]
            if b >= 0:
                mass[k, b] += q
            elif q != 0.0:
                sector, ring, _inside = _classify(
                    cx[j] - px[k], cy[j] - py[k], edges, radius, n_sectors
                )
                mass[k, sector * n_rings + ring] += q


@_jit
def _grid_bins(xs, ys, px, py, poc, edges, radius, n_sectors, mass, bps, pos):
    """The POC sums of :func:`_bins` (``mass``; each bin summed in cell order) over a grid of
    cell centres ``(xs[i], ys[j])`` (``xs`` increasing, cell ``j * nx + i``), row by row: a
    row's boundaries (``dx`` = 0 or +-dy, a ring edge's circle) cut it into runs of cells that
    share a sector and ring; the first cell of a run is decided by :func:`_classify`, the
    others take its bin and are added in order, and every cell within a margin of a boundary
    is decided on its own. The margin, 2e-4 of the row's largest offsets, is far wider than the
    exact formulas' 1e-9 bands (at most ~3e-5 of a ring's radius wide in ``dx``, on a row
    nearly tangent to it), whatever the cell size. Rows too
    close to the UAV's own (``dy`` ~ 0) are decided cell by cell. ``bps``, ``pos``: scratch."""
    nx = xs.shape[0]
    ny = ys.shape[0]
    n_rings = edges.shape[0] + 1
    span = abs(xs[0] - px) + abs(xs[nx - 1] - px)
    for j in range(ny):
        dy = ys[j] - py
        base = j * nx
        if not (n_sectors == 8 and abs(dy) > 1e-6 * (span + 1.0)):
            for i in range(nx):
                q = poc[base + i]
                if q == 0.0:  # adding +-0.0 to sums started at +0.0 changes nothing
                    continue
                sector, ring, _inside = _classify(xs[i] - px, dy, edges, radius, n_sectors)
                mass[sector * n_rings + ring] += q
            continue
        # the row's boundaries, sorted: -P reversed, 0, P, where P is |dy| merged into the
        # chords of the ring edges the row reaches (ascending with the edges; the radius
        # decides no POC sum)
        ady = abs(dy)
        npos = 0
        placed = False
        for r in range(n_rings - 1):
            h = edges[r] * edges[r] - dy * dy
            if h >= 0.0:
                chord = math.sqrt(h)
                if not placed and ady <= chord:
                    pos[npos] = ady
                    npos += 1
                    placed = True
                pos[npos] = chord
                npos += 1
        if not placed:
            pos[npos] = ady
            npos += 1
        bps[npos] = 0.0
        for a in range(npos):
            bps[npos - 1 - a] = -pos[a]
            bps[npos + 1 + a] = pos[a]
        nb = 2 * npos + 1
        m = 2e-4 * (span + ady + radius + edges[n_rings - 2])
        ptr = 0
        i = 0
        while i < nx:
            dx = xs[i] - px
            while ptr < nb and bps[ptr] < dx - m:
                ptr += 1
            if ptr < nb and bps[ptr] <= dx + m:  # next to a boundary: this cell alone
                sector, ring, _inside = _classify(dx, dy, edges, radius, n_sectors)
                mass[sector * n_rings + ring] += poc[base + i]
                i += 1
                continue
            # a run, farther than the margin from every boundary: there :func:`_classify`
            # takes its octant branch and squared distances (dx and |dx| - |dy| are far from
            # 0, no ring edge is near; near the radius alone hypot and the squares agree)
            ax = abs(dx)
            if dy > 0 and dx > 0:
                sector = 0 if ady < ax else 1
            elif dy > 0:
                sector = 2 if ady > ax else 3
            elif dx < 0:
                sector = 4 if ady < ax else 5
            else:
                sector = 6 if ady > ax else 7
            d2 = dx * dx + dy * dy
            ring = 0
            while ring < n_rings - 1 and edges[ring] * edges[ring] <= d2:
                ring += 1
            bin_ = sector * n_rings + ring
            limit = bps[ptr] - m if ptr < nb else np.inf
            acc = mass[bin_]  # up to the next boundary's margin: one bin, in order
            while i < nx and xs[i] - px < limit:
                acc += poc[base + i]
                i += 1
            mass[bin_] = acc


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
def compass(poc, vector, pos, flying, grid_box, area, xs, ys, edges, layout, out):
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
    tail holds the others radius and the count normaliser. The cell centres are the grid
    ``(xs[i], ys[j])``, walked row by row (:func:`_grid_bins`); ``edges``: the ring edges."""
    v0, c0, o0, m0, i0, n_ids, n_sectors, agent_index = layout
    x0, y0, x1, y1, cell = grid_box
    bx0, by0, bw, bh, radius, others = area
    n_env, n = flying.shape
    n_shared, ny, nx = poc.shape[1], poc.shape[2], poc.shape[3]
    n_rings = edges.shape[0] + 1
    n_vec = vector.shape[2]
    mass = np.empty(n_sectors * n_rings)
    count = np.empty(n_sectors)
    others_cells = np.zeros(ny * nx)  # the "others" channel of one UAV, cleared after use
    bps = np.empty(2 * n_rings + 3)
    chords = np.empty(n_rings)
    short = nx < 16  # short rows: a row's boundaries would cost more than its cells' decisions
    cx = np.empty(ny * nx)
    cy = np.empty(ny * nx)
    cell_bin = np.empty(ny * nx if short else 0, dtype=np.intp)
    cell_d2 = np.empty(ny * nx if short else 0)
    for j in range(ny):
        for i in range(nx):
            cx[j * nx + i] = xs[i]
            cy[j * nx + i] = ys[j]
    rows = np.empty(n, dtype=np.intp)
    cols = np.empty(n, dtype=np.intp)
    present = np.empty(n, dtype=np.bool_)
    together = short and n_shared == 1  # the UAVs' sums over their env's row, interleaved
    all_mass = np.empty((n if together else 0, n_sectors * n_rings))
    all_bins = np.empty((n if together else 0, ny * nx), dtype=np.intp)
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
        for k in range(n):
            pxs[k] = bx0 + np.float64(vector[e, k, 0]) * bw
            pys[k] = by0 + np.float64(vector[e, k, 1]) * bh
        if together:
            all_mass[:] = 0.0
            row = poc[e, 0].reshape(ny * nx)
            _shared_cell_bins(
                cx, cy, pxs, pys, row, edges, radius, n_sectors, all_mass, all_bins, cell_d2
            )
        for k in range(n):
            p = k if n_shared > 1 else 0
            o = out[e, k]
            o[:] = 0.0
            for t in range(n_vec):
                o[v0 + t] = vector[e, k, t]
            px = pxs[k]
            py = pys[k]
            count[:] = 0.0
            if together:
                mass[:] = all_mass[k]
            else:
                mass[:] = 0.0
                row = poc[e, p].reshape(ny * nx)
                if short:
                    _cell_bins(
                        cx, cy, px, py, row, edges, radius, n_sectors, mass, cell_bin, cell_d2
                    )
                else:
                    _grid_bins(xs, ys, px, py, row, edges, radius, n_sectors, mass, bps, chords)
            for m in range(n):  # each cell holding another UAV counts once (a 1.0)
                c = rows[m] * nx + cols[m]
                if m != k and present[m] and others_cells[c] == 0.0:
                    others_cells[c] = 1.0
                    sector, _ring, inside = _classify(
                        xs[cols[m]] - px, ys[rows[m]] - py, edges, radius, n_sectors
                    )
                    if inside:
                        count[sector] += 1.0
            for m in range(n):
                if present[m]:
                    others_cells[rows[m] * nx + cols[m]] = 0.0
            tot = totals[p]
            for b in range(mass.size):
                o[c0 + b] = mass[b] / tot if tot > 0 else 0.0
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
