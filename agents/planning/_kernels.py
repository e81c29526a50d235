"""Compiled passes of the planner: its rectangles for a whole population, and route timing.

:func:`plan_rectangles` is the map repair, lawnmower and transit of
:mod:`poc_env.agents.planning.objective` for a population in one pass (the prior masses then
come from :func:`poc_env._kernels.rectangles.rectangle_masses`, called by the objective);
:func:`route_timeline` and :func:`route_sample` time and sample a flight along a path and
:func:`fits_batch` times a waypoint's candidate edits, :func:`first_fitting` the polish's
candidates in turn, and :func:`leg_samples` samples legs onto
the grid (:mod:`poc_env.agents.planning.refine`);
:func:`best_box` is the greedy rectangle planner's box search
(:mod:`poc_env.agents.planning.greedy_rectangles`) and the coverage boxes'
(:mod:`poc_env.agents.planning.coverage_boxes`).

A kernel module under the cache rule of :mod:`poc_env._kernels`: it imports nothing of the
project, so the planner composes its kernels with the environment's in Python.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy")

# ------------------------------------------------------------------- the rectangles of a population


@_jit
def plan_rectangles(x, box, takeoff, landing, geo, terms, rects):
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
    (n - 1) d`` and the transit in columns 0-4 (column 5, the prior mass, is the caller's:
    :func:`poc_env.agents.planning.objective.plan_rectangles`); ``rects (6, P n)`` the
    rectangles as :func:`poc_env._kernels.rectangles.rectangle_masses` takes them (centre
    ``x``, ``y``, half length, half width, cos and sin of theta; rectangle ``p n + i``).
    """
    n_ind = x.shape[0]
    n_uav = x.shape[1] // 6
    bx0, by0, bx1, by1 = box[0], box[1], box[2], box[3]
    cx, cy, hl, hw, ct, st = rects[0], rects[1], rects[2], rects[3], rects[4], rects[5]
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


# ------------------------------------------------------------------------------------ route timing


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
def fits_batch(p, i, qs, ops, v_out, v_line, v_home, turn_cost, budget, reserve, heading0, ok):
    """:func:`route_timeline`'s fit of candidate edits of the path ``p`` (m, 2) at point ``i``
    into ``ok`` (C,): candidate ``c`` moves point ``i`` to ``qs[c]`` (``ops[c]`` 0), deletes it
    (1) or inserts ``qs[c]`` before it (2)."""
    m = p.shape[0]
    buf = np.empty((m + 1, 2))
    out = np.empty(m + 1)
    dep = np.empty(m + 1)
    for c in range(ops.shape[0]):
        op = ops[c]
        k = 0
        for j in range(m):
            if j == i:
                if op == 0:
                    buf[k, 0] = qs[c, 0]
                    buf[k, 1] = qs[c, 1]
                    k += 1
                    continue
                if op == 1:
                    continue
                buf[k, 0] = qs[c, 0]
                buf[k, 1] = qs[c, 1]
                k += 1
            buf[k, 0] = p[j, 0]
            buf[k, 1] = p[j, 1]
            k += 1
        ok[c] = route_timeline(
            buf[:k], v_out, v_line, v_home, turn_cost, budget, reserve, heading0, out[:k], dep[:k]
        )


@_jit
def first_fitting(path, i0, i1, pts, off, order, t0, t1, v_out, v_line, v_home, turn_cost,
                  budget, reserve, heading0):  # fmt: skip
    """The first position ``t0 <= t < t1`` in ``order`` whose candidate keeps the path ``path``
    (m, 2) flyable, or ``t1`` if none (i24-budget: the polish's ``route_fits`` of its candidates
    in turn, in one call): candidate ``c = order[t]`` replaces ``path[i0 : i1 + 1]`` by the
    points ``pts[off[c] : off[c + 1]]``, and fits if :func:`route_timeline` of the path so made
    says so (the same points, so the same answer as ``route_fits`` of
    ``np.concatenate([path[:i0], points, path[i1 + 1:]])``; a path of fewer than 2 points
    fits)."""
    m = path.shape[0]
    most = 0
    for t in range(t0, t1):
        c = order[t]
        most = max(most, off[c + 1] - off[c])
    n_max = i0 + most + (m - i1 - 1)
    buf = np.empty((n_max, 2))
    out = np.empty(n_max)
    dep = np.empty(n_max)
    for j in range(i0):
        buf[j, 0] = path[j, 0]
        buf[j, 1] = path[j, 1]
    for t in range(t0, t1):
        c = order[t]
        k = i0
        for q in range(off[c], off[c + 1]):
            buf[k, 0] = pts[q, 0]
            buf[k, 1] = pts[q, 1]
            k += 1
        for j in range(i1 + 1, m):
            buf[k, 0] = path[j, 0]
            buf[k, 1] = path[j, 1]
            k += 1
        if k < 2 or route_timeline(
            buf[:k], v_out, v_line, v_home, turn_cost, budget, reserve, heading0, out[:k],
            dep[:k],
        ):  # fmt: skip
            return t
    return t1


@_jit
def cut_fit(head, wps, landing, v_out, v_line, v_home, turn_cost, budget, reserve, heading0,
            part, steps):  # fmt: skip
    """The fits of ``poc_env.agents.planning.coverage_boxes.cut_lines`` for a route
    ``head`` (take-off and any waypoints before the lawnmower), ``wps`` (the lawnmower, a line
    = two waypoints), ``landing``, each a :func:`route_timeline` of the same points: the most
    whole lines' waypoints ``kept`` (even) for which the route fits (scanning down from all
    of them; 0 if none), then, with ``part`` and a next line, the bisection (``steps``
    halvings) of the share ``lo`` of that line's length that still fits (-1: not even its
    start fits, or no part tried). Returns ``(kept, lo)``; the part's point ``a + t (b - a)``
    is computed as numpy computes it (no fused operations)."""
    nh = head.shape[0]
    nw = wps.shape[0]
    buf = np.empty((nh + nw + 2, 2))
    out = np.empty(nh + nw + 2)
    dep = np.empty(nh + nw + 2)
    buf[:nh] = head
    buf[nh : nh + nw] = wps
    kept = nw - nw % 2
    while kept > 0:
        m = nh + kept + 1
        buf[nh + kept, 0] = landing[0]
        buf[nh + kept, 1] = landing[1]
        if route_timeline(buf[:m], v_out, v_line, v_home, turn_cost, budget, reserve, heading0,
                          out[:m], dep[:m]):  # fmt: skip
            break
        kept -= 2
    lo = -1.0
    if part and kept + 1 < nw:
        ax, ay = wps[kept, 0], wps[kept, 1]
        dx, dy = wps[kept + 1, 0] - ax, wps[kept + 1, 1] - ay
        m = nh + kept + 3
        buf[nh + kept, 0] = ax
        buf[nh + kept, 1] = ay
        buf[nh + kept + 2, 0] = landing[0]
        buf[nh + kept + 2, 1] = landing[1]
        buf[nh + kept + 1, 0] = ax + 0.0 * dx
        buf[nh + kept + 1, 1] = ay + 0.0 * dy
        if route_timeline(buf[:m], v_out, v_line, v_home, turn_cost, budget, reserve, heading0,
                          out[:m], dep[:m]):  # fmt: skip
            lo = 0.0
            hi = 1.0
            for _ in range(steps):
                mid = 0.5 * (lo + hi)
                buf[nh + kept + 1, 0] = ax + mid * dx
                buf[nh + kept + 1, 1] = ay + mid * dy
                if route_timeline(buf[:m], v_out, v_line, v_home, turn_cost, budget, reserve,
                                  heading0, out[:m], dep[:m]):  # fmt: skip
                    lo = mid
                else:
                    hi = mid
    return kept, lo


@_jit
def leg_samples(sx, sy, dx, dy, length, ox, oy, c, nx, ny, w, area):
    """The coverage samples of legs from ``(sx, sy)`` by ``(dx, dy)`` of ``length`` (numpy's
    ``hypot``, computed by the caller: transcendentals stay in numpy), ``m = max(1, ceil(4 L /
    c))`` points a leg at ``t = (j + 1/2) / m``: per point inside the ``nx x ny`` grid of cell
    ``c`` from ``(ox, oy)``, its leg, flat cell and coverage ``w L / m / area`` (eq. 10 per
    cell). The operations and their order are ``refine``'s numpy formulation's, so the samples
    are the same bit for bit (``tests/planning/test_refine.py``)."""
    n_legs = len(sx)
    m = np.empty(n_legs, np.int64)
    total = 0
    for i in range(n_legs):
        k = np.ceil(4.0 * length[i] / c)
        m[i] = np.int64(k) if k > 1.0 else 1
        total += m[i]
    leg = np.empty(total, np.int64)
    cell = np.empty(total, np.int64)
    weight = np.empty(total)
    n = 0
    for i in range(n_legs):
        wi = w * length[i] / m[i] / area
        for j in range(m[i]):
            t = (j + 0.5) / m[i]
            col = np.int64(np.floor((sx[i] + t * dx[i] - ox) / c))
            row = np.int64(np.floor((sy[i] + t * dy[i] - oy) / c))
            if 0 <= col < nx and 0 <= row < ny:
                leg[n] = i
                cell[n] = row * nx + col
                weight[n] = wi
                n += 1
    return leg[:n], cell[:n], weight[:n]


@_jit
def airspace_move(pos, act, close, near, flying, k, pos_k, act_k, old_c, old_n, sep, rng, min_nb,
                  close_out, near_out, flying_out):  # fmt: skip
    """``poc_env.agents.planning.refine.AirspaceCount.move`` in one pass: the counts with UAV
    ``k`` at ``pos_k (S, 2)``, flying ``act_k (S,)``, from the swarm's ``pos (S, n, 2)``,
    ``act``, counts ``close``, ``near`` (S, n), ``flying`` (S,) and UAV ``k``'s current pairs
    ``old_c``, ``old_n`` (S, n) into ``close_out``, ``near_out`` and ``flying_out``; returns the
    violation count. The distances are numpy's (``sqrt(dx dx + dy dy)``, same operations), so
    the pairs and counts are the same."""
    n_s = act.shape[0]
    n = act.shape[1]
    value = 0
    for s in range(n_s):
        ak = act_k[s]
        fl = flying[s] + (1 if ak else 0) - (1 if act[s, k] else 0)
        flying_out[s] = fl
        need = min(min_nb, fl - 1)
        ck = 0
        nk = 0
        for j in range(n):
            if j == k:
                continue
            nc = 0
            nn = 0
            if ak and act[s, j]:
                cx = pos[s, j, 0] - pos_k[s, 0]
                cy = pos[s, j, 1] - pos_k[s, 1]
                d = math.sqrt(cx * cx + cy * cy)
                if d < sep:
                    nc = 1
                if d <= rng:
                    nn = 1
            c = close[s, j] + nc - (1 if old_c[s, j] else 0)
            m = near[s, j] + nn - (1 if old_n[s, j] else 0)
            close_out[s, j] = c
            near_out[s, j] = m
            ck += nc
            nk += nn
            if act[s, j]:
                if c > 0:
                    value += 1
                if m < need:
                    value += 1
        close_out[s, k] = ck
        near_out[s, k] = nk
        if ak:
            if ck > 0:
                value += 1
            if nk < need:
                value += 1
    return value


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


# ------------------------------------------------------------------------- the greedy box search

#: the box search bounds the boxes of a row band in runs of this many positions (i24-speed).
_CHUNK = 8


@_jit
def best_box(table, widths, heights, orig, h, w, speeds, turn, budget, takeoff, landing):
    """The box search of ``poc_env.agents.planning.greedy_rectangles._best_box`` in one pass.

    ``table (ny + 1, nx + 1)``: the summed-area table of the remaining mass; boxes of ``nw x nh``
    cells (``widths`` x ``heights``, in that nesting) at every lower-left cell ``(j, i)``,
    mass ``T[j + nh, i + nw] - T[j, i + nw] - T[j + nh, i] + T[j, i]``; a box is kept when its
    flight-time estimate (``speeds = (out, line, home)``: straight from ``takeoff`` to its
    nearest point at ``out``, from it to ``landing`` at ``home``, its lines ``w`` apart along
    the longer side at ``line`` and a ``turn`` per line end; ``orig`` the map's lower-left
    corner, ``h`` the cell size) is within ``budget`` and its mass beats the best so far (ties:
    the first in this order, lower-left cells row by row). Returns ``(mass, i, j, nw, nh)``;
    mass 0 and ``nw = 0`` when no box has mass and fits. Rows, and runs of :data:`_CHUNK`
    positions in a row, whose masses together (an upper bound: masses >= 0) cannot beat the
    best so far are skipped: the boxes skipped are ones the search would not keep, so the
    result is the full search's (tests/planning/test_speed.py)."""
    ny = table.shape[0] - 1
    nx = table.shape[1] - 1
    best = 0.0
    bi = bj = bw = bh = 0
    # a box's mass <= its row band's, up to the rounding of the table's sums (slack: far above
    # it, so the rows skipped are exactly those where no box would beat the best)
    slack = 1e-12 * np.abs(table).max()
    for a in range(widths.shape[0]):
        nw = widths[a]
        for b in range(heights.shape[0]):
            nh = heights[b]
            lx = nw * h
            ly = nh * h
            long_ = max(lx, ly)
            short = min(lx, ly)
            n_lines = max(1.0, math.ceil(short / w - 1e-9))
            search = (n_lines * long_ + (n_lines - 1.0) * short / n_lines) / speeds[1]
            search += (n_lines - 1.0) * turn
            if search > budget:  # no position can fit it
                continue
            cur = best
            # the columns whose distance along x alone fits (hypot >= its x part): no box
            # outside [i0, i1] fits, so only those are searched and bound
            i0 = nx - nw + 1
            i1 = -1
            for i in range(nx - nw + 1):
                xlo = orig[0] + h * i
                dxt = max(max(xlo - takeoff[0], takeoff[0] - xlo - lx), 0.0)
                dxl = max(max(xlo - landing[0], landing[0] - xlo - lx), 0.0)
                if dxt / speeds[0] + dxl / speeds[2] + search <= budget:
                    i0 = min(i0, i)
                    i1 = i
            if i1 < 0:
                continue
            for j in range(ny - nh + 1):
                ylo = orig[1] + h * j
                dyt = max(max(ylo - takeoff[1], takeoff[1] - ylo - ly), 0.0)
                dyl = max(max(ylo - landing[1], landing[1] - ylo - ly), 0.0)
                if dyt / speeds[0] + dyl / speeds[2] + search > budget:
                    continue  # the row alone is too far (hypot >= its y part): no box fits
                e = i1 + nw
                band = table[j + nh, e] - table[j, e] - table[j + nh, i0] + table[j, i0]
                if band + slack < cur:
                    continue  # the row's band (masses >= 0) cannot beat the best
                for c0 in range(i0, i1 + 1, _CHUNK):
                    c1 = min(c0 + _CHUNK - 1, i1)
                    e = c1 + nw
                    part = table[j + nh, e] - table[j, e] - table[j + nh, c0] + table[j, c0]
                    if part + slack < cur:
                        continue  # no box starting in c0..c1 (inside this band) beats it
                    for i in range(c0, c1 + 1):
                        mass = (table[j + nh, i + nw] - table[j, i + nw] - table[j + nh, i]
                                + table[j, i])  # fmt: skip
                        if not mass > cur:
                            continue
                        xlo = orig[0] + h * i
                        dxt = max(max(xlo - takeoff[0], takeoff[0] - xlo - lx), 0.0)
                        dxl = max(max(xlo - landing[0], landing[0] - xlo - lx), 0.0)
                        t = math.hypot(dxt, dyt) / speeds[0] + math.hypot(dxl, dyl) / speeds[2]
                        if t + search <= budget:
                            cur, bi, bj, bw, bh = mass, i, j, nw, nh
            best = cur
    return best, bi, bj, bw, bh
