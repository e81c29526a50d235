"""Regrade: a run of lawnmower lines re-spaced jointly in the environment's own sensor model.

The polish (:mod:`~poc_env.agents.planning.polish`) moves one waypoint, one leg or a window of
a few lines by one factor or one offset at a time, so a box stays swept at (about) the one
line spacing it was laid at while the relaxation grades the coverage inside it: the
**grading** link of the loss chain (docs/PLANNER.md, "Where the loss goes, link by link":
0.052-0.062 of the rule-aware bound on ``paper_6_2``). :func:`regrade_routes` re-solves the
offsets of all the lines of a run together (i24-regrade):

1. **Runs** (:func:`find_runs`): in each route, maximal runs of at least ``min_lines``
   consecutive *lines* -- legs ``i -> i + 1``, ``i + 2 -> i + 3``, ... of inner waypoints --
   each antiparallel to the one before (within :data:`ANGLE_TOL_DEG`), of roughly equal length
   (ratio within :data:`LENGTH_RATIO`), longer than half a sweep width, their midpoints'
   offsets across the run strictly monotone (steps of at least :data:`MIN_GAP` sweep widths):
   a lawnmower, the legs between them its connectors.
2. **Water-filling** (:func:`~poc_env.agents.planning.coverage_boxes.graded_offsets`, the
   boxes' own graded lines, here on the sample lattice): the run's legs are taken out of the
   swarm's exposure ``E`` (the polish's :class:`~poc_env.agents.planning.polish.Exposure`); the
   mass not yet found, ``p exp(-E)``, of the sample points between the run's ends along the
   lines is summed per sample row across them (rows ``h = cell / samples`` wide); the run's
   lines are water-filled over those rows by marginal gain of eq. 10's POD (concave, so the
   steps of most gain give the best split) and placed at the mid-quantiles of the cumulative
   line density: denser where the mass left is. Each line is translated across to its new
   offset (its length and ends along the run kept; the connectors follow). With ``counts``
   the run is also laid with one line fewer (the last dropped) or one more (a copy of the
   last line but one appended, every line shortened by ``m / (m + 1)`` about its midpoint so
   the track length is about kept).
3. **Coordinate search**: a few sweeps (``sweeps``) over the lines of each candidate (and of
   the run as it is), each line translated across by ``+-r`` sweep widths (``radii``) with
   its connectors, the best gain in the environment's model kept where the route still fits.
4. The candidate of most POS is kept if it gains more than the polish's
   :data:`~poc_env.agents.planning.polish.TOL` in the environment's sensor model and the
   route stays as the polish keeps it: eq. 17-18 time with turns
   (:func:`~poc_env.agents.planning.refine.route_fits`), inside the map, no more eq. 21 / 24
   violations at the planned positions (:class:`~poc_env.agents.planning.refine.AirspaceCount`).

Deterministic: no clock, no random draw. No-fly zones (i24-smallfix): with a ``router`` a
regraded run is kept only if :func:`~poc_env.agents.planning.polish.zone_guard` (the polish's
check, eq. 20) passes it -- no leg into a zone, no more legs across the router's clearance ring
than the run it replaces; without one (before), the regrade entered zones on ``paper_6_2`` with
two zones (2 routes, 5 legs across the ring), so the allocation planner skipped it on maps with
zones; it now regrades there with the router, as it polishes (``options.polish_zones``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from poc_env.agents.planning.coverage_boxes import graded_offsets
from poc_env.agents.planning.polish import TOL, start, zone_guard
from poc_env.agents.planning.refine import Airspace, _dedupe, route_fits, track
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import Grid

#: consecutive lines of a run are antiparallel within this angle (degrees).
ANGLE_TOL_DEG = 15.0
#: ... their lengths within this ratio of each other ...
LENGTH_RATIO = 0.5
#: ... and their offsets across the run at least this many sweep widths apart.
MIN_GAP = 0.1
#: a laid run's lines are scaled along the run by at least this share of the factor that
#: keeps its track length (the largest that fits the time, found in :data:`BISECT` halvings).
SCALE_LOW = 0.6
BISECT = 8
#: a clipped line runs between the alpha and 1 - alpha quantiles of its strip's mass,
#: alpha at most this.
ALPHA_HIGH = 0.45
#: the most lines a run may gain or lose in one regrade.
MAX_COUNT = 3
#: the coordinate search's translations of a line, in sweep widths.
SEARCH_RADII = (0.125, 0.25, 0.5, 1.0)


def _unit(d: np.ndarray) -> np.ndarray:
    return d / np.hypot(d[..., 0], d[..., 1])[..., None]


def find_runs(path, w: float, min_lines: int = 3) -> list[tuple[int, int]]:
    """The runs of lawnmower lines of ``path`` (take-off, inner waypoints, landing; module
    docstring): ``(a, m)`` per run, its ``m >= min_lines`` lines the legs ``a + 2 j -> a + 2 j
    + 1`` (``j < m``), all of inner waypoints; in order along the path, not overlapping."""
    p = np.asarray(path, dtype=float).reshape(-1, 2)
    last = len(p) - 2  # the last inner waypoint
    cos_tol = np.cos(np.radians(ANGLE_TOL_DEG))
    out: list[tuple[int, int]] = []
    i = 1
    while i + 1 <= last:
        d0 = p[i + 1] - p[i]
        ln0 = float(np.hypot(*d0))
        if ln0 <= 0.5 * w:
            i += 1
            continue
        u0 = d0 / ln0
        nrm = np.array([-u0[1], u0[0]])
        m = 1
        sign = 0.0
        prev_u, prev_ln = u0, ln0
        prev_off = float(0.5 * (p[i] + p[i + 1]) @ nrm)
        while i + 2 * m + 1 <= last:
            a, b = p[i + 2 * m], p[i + 2 * m + 1]
            d = b - a
            ln = float(np.hypot(*d))
            if ln <= 0.5 * w or not (LENGTH_RATIO <= ln / prev_ln <= 1.0 / LENGTH_RATIO):
                break
            u = d / ln
            if float(u @ -prev_u) < cos_tol:
                break
            off = float(0.5 * (a + b) @ nrm)
            gap = off - prev_off
            if abs(gap) < MIN_GAP * w or (sign and np.sign(gap) != sign):
                break
            sign = float(np.sign(gap))
            prev_u, prev_ln, prev_off = u, ln, off
            m += 1
        if m >= min_lines:
            out.append((i, m))
            i += 2 * m - 1
        else:
            i += 1
    return out


def regrade_routes(
    routes: Sequence[Sequence[Sequence[float]]],
    takeoff,
    landing,
    prior: np.ndarray,
    grid: Grid,
    sensor,
    speeds,
    budget: float,
    turn_rate: float,
    reserve: float,
    passes: int = 1,
    headings=None,
    airspace: Airspace | None = None,
    radii: Sequence[float] = SEARCH_RADII,
    counts: Sequence[int] = (0, -1, 1, 2),
    sweeps: int = 2,
    min_lines: int = 2,
    step: float = 0.25,
    least: float = 0.5,
    quantiles: bool = False,
    router: Any = None,
) -> tuple[list[list[list[float]]], float, dict]:
    """Regraded waypoints per UAV, their planned POS and counts (module docstring); the
    arguments as :func:`~poc_env.agents.planning.polish.polish_routes`' (``passes`` over every
    run of every route; stops after a pass that keeps nothing). ``radii``: the coordinate
    search's translations (sweep widths); ``counts``: the changes of a run's number of lines
    tried (0: as many; -1 one fewer; 1 one more); ``sweeps``: the coordinate search's sweeps
    over a candidate's lines; ``step``, ``least``: the water-filling's step (lines) and least
    spacing (sweep widths), as ``graded_offsets``'; ``router``: the plan's
    :class:`~poc_env.sim.routing.ZoneRouter`: with zones every kept run passes
    :func:`~poc_env.agents.planning.polish.zone_guard` (module docstring). Returns
    ``(routes, pos, {"passes", "moves", "runs", "lines_added", "lines_dropped"})``."""
    if not isinstance(passes, int) or isinstance(passes, bool) or passes < 0:
        raise ConfigError("passes", passes, "an integer >= 0")
    rad = tuple(radii)
    if any(not np.isfinite(r) or r <= 0 for r in rad):
        raise ConfigError("radii", radii, "positive numbers (sweep widths)")
    cnt = tuple(dict.fromkeys(counts))
    if not cnt or not set(cnt) <= set(range(-MAX_COUNT, MAX_COUNT + 1)):
        raise ConfigError("counts", counts, f"integers in [-{MAX_COUNT}, {MAX_COUNT}]")
    if not isinstance(min_lines, int) or min_lines < 2:
        raise ConfigError("min_lines", min_lines, "an integer >= 2")
    st = start(routes, takeoff, landing, prior, grid, sensor, speeds, budget, turn_rate,
               headings, airspace)  # fmt: skip
    ex, lo, hi, flying, paths, h0 = st.ex, st.lo, st.hi, st.flying, st.paths, st.h0
    count: Any = st.count  # used only where ``airspace`` is given, as ``times``
    times: Any = st.times
    n, w = len(paths), st.w
    x0, y0 = grid.bounds[:2]
    ny_s, nx_s = ex.mass.shape
    px = np.broadcast_to(x0 + (np.arange(nx_s) + 0.5) * ex.h, (ny_s, nx_s)).ravel()
    py = np.broadcast_to((y0 + (np.arange(ny_s) + 0.5) * ex.h)[:, None], (ny_s, nx_s)).ravel()
    signed = np.concatenate([np.asarray(rad, dtype=float), -np.asarray(rad, dtype=float)]) * w
    zone_bad = zone_guard(router)

    def fits(k: int, full: np.ndarray) -> bool:
        return route_fits(full, speeds, turn_rate, budget, reserve, h0[k])

    def set_expo(e: np.ndarray) -> None:
        ex.expo[:] = e
        ex.live = ex.mass * np.exp(-ex.expo)

    def search(k: int, head: np.ndarray, win: np.ndarray, tail: np.ndarray, nrm) -> np.ndarray:
        """Coordinate search over the lines of ``win`` (waypoints: the fixed point before,
        the lines' ends in pairs, the fixed point after), whose legs are in ``ex``: each line
        translated across by the signed radii, the best fitting gain kept; the window after."""
        win = win.copy()
        m = (len(win) - 2) // 2
        for _ in range(sweeps):
            moved = False
            for j in range(m):
                a = 1 + 2 * j  # the line's first point in the window
                old = win[a - 1 : a + 3]  # connector in, line, connector out
                cands = np.repeat(old[None], len(signed), axis=0)
                cands[:, 1:3] = np.clip(
                    old[None, 1:3] + signed[:, None, None] * nrm[None, None], lo, hi
                )
                first = np.arange(len(signed) + 1, dtype=np.int64) * 3
                gain = ex.gains(old[:-1], old[1:], cands[:, :-1].reshape(-1, 2),
                                cands[:, 1:].reshape(-1, 2), first)  # fmt: skip
                for cj in np.argsort(-gain, kind="stable"):
                    if not gain[cj] > TOL:
                        break
                    new = win.copy()
                    new[a : a + 2] = cands[cj, 1:3]
                    if not fits(k, np.concatenate([head, new, tail])):
                        continue
                    ex.add(old[:-1], old[1:], -1.0)
                    ex.add(cands[cj, :-1], cands[cj, 1:], 1.0)
                    win = new
                    moved = True
                    break
            if not moved:
                break
        return win

    def laid(P, Q, o, nrm, s_lo, rows_mass, mm: int):
        """The run laid with ``mm`` lines at water-filled offsets (or None): the lines'
        ends (mm, 2) each, translated across from their present offsets ``o``."""
        m = len(P)
        if mm < 1:
            return None
        if mm < m:  # the last lines dropped
            P, Q, o = P[:mm], Q[:mm], o[:mm]
        elif mm > m:  # lines appended: copies of the last two, each of its own direction
            if m < 2:
                return None
            extra = [m - 2 + (i % 2) for i in range(mm - m)]
            P, Q, o = np.vstack([P, P[extra]]), np.vstack([Q, Q[extra]]), np.append(o, o[extra])
        new = graded_offsets(
            rows_mass[:, None], np.zeros((len(rows_mass), 1)), np.zeros((len(rows_mass), 1)),
            mm, ex.h, w, ex.law, step, least,
        )  # fmt: skip
        if len(new) != mm:
            return None
        d = (s_lo + new - o)[:, None] * nrm[None]
        return np.clip(P + d, lo, hi), np.clip(Q + d, lo, hi)

    def most_fitting(k, head, tail, win, safe: float, want: float):
        """``win(x)`` (a window) at ``want`` if the route fits with it, else at the ``x``
        nearest ``want`` between ``safe`` and ``want`` at which it fits (:data:`BISECT`
        halvings), None if it does not fit at ``safe``."""
        if fits(k, np.concatenate([head, win(want), tail])):
            return win(want)
        if not fits(k, np.concatenate([head, win(safe), tail])):
            return None
        for _ in range(BISECT):
            mid = 0.5 * (safe + want)
            if fits(k, np.concatenate([head, win(mid), tail])):
                safe = mid
            else:
                want = mid
        return win(safe)

    def fitted(k, head, win0, tail, P, Q, u, centre, f_lo, f_hi):
        """The window with lines ``P -> Q`` scaled along ``u`` about ``centre`` by the largest
        factor in ``[f_lo, f_hi]`` (bisection) at which the route fits, or None."""

        def win(f: float) -> np.ndarray:
            mid = np.empty((2 * len(P), 2))
            for j, E in enumerate((P, Q)):
                along = (E @ u - centre) * (f - 1.0)
                mid[j::2] = np.clip(E + along[:, None] * u[None], lo, hi)
            return np.vstack([win0[0], mid, win0[-1]])

        return most_fitting(k, head, tail, win, f_lo, f_hi)

    def clipped(k, head, win0, tail, P, Q, u, nrm, along):
        """The window with each line ``P_j -> Q_j`` (at its offset) running between the
        ``alpha`` and ``1 - alpha`` quantiles of the mass left along its own strip (half-way
        to its neighbours, at least half a sweep width each side), ``alpha`` the least (in
        :data:`BISECT` halvings of [0, :data:`ALPHA_HIGH`]) at which the route fits; or None."""
        t_lo, nt, s_w, b_w, m_w = along
        off = 0.5 * (P + Q) @ nrm
        order = np.argsort(off)
        so = off[order]
        half = np.full(len(off), 0.5 * w)
        if len(off) > 1:
            gaps = np.diff(so)
            h_s = np.maximum(
                0.5 * w,
                0.5 * np.concatenate([[gaps[0]], np.maximum(gaps[:-1], gaps[1:]), [gaps[-1]]]),
            )
            half[order] = h_s
        cdfs = []
        for j in range(len(off)):
            strip = np.abs(s_w - off[j]) <= half[j]
            mj = np.bincount(b_w[strip], weights=m_w[strip], minlength=nt)
            tot = float(mj.sum())
            if tot <= 0.0:
                return None
            cdfs.append(np.concatenate([[0.0], np.cumsum(mj) / tot]))
        edges = t_lo + np.arange(nt + 1) * ex.h
        fwd = ((Q - P) @ u) >= 0.0

        def win(alpha: float) -> np.ndarray:
            mid = np.empty((2 * len(P), 2))
            for j, cdf in enumerate(cdfs):
                ta = float(np.interp(alpha, cdf, edges))
                tb = float(np.interp(1.0 - alpha, cdf, edges))
                if tb - ta < 0.5 * w:
                    c_ = 0.5 * (ta + tb)
                    ta, tb = c_ - 0.25 * w, c_ + 0.25 * w
                if not fwd[j]:
                    ta, tb = tb, ta
                mid[2 * j] = off[j] * nrm + ta * u
                mid[2 * j + 1] = off[j] * nrm + tb * u
            return np.vstack([win0[0], np.clip(mid, lo, hi), win0[-1]])

        return most_fitting(k, head, tail, win, ALPHA_HIGH, 0.0)

    def regrade_run(k: int, a: int, m: int) -> tuple[int, int]:
        """Regrade the run of ``m`` lines from waypoint ``a`` of UAV ``k``'s route: (kept 0/1,
        the change of its number of lines)."""
        path = paths[k]
        i0, i1 = a - 1, a + 2 * m
        head, tail = path[:i0], path[i1 + 1 :]
        win0 = path[i0 : i1 + 1]
        P, Q = path[a : a + 2 * m : 2], path[a + 1 : a + 2 * m : 2]
        u = _unit(Q - P)
        u[1::2] *= -1.0
        u = _unit(u.sum(axis=0))
        nrm = np.array([-u[1], u[0]])
        o = 0.5 * (P + Q) @ nrm
        if o[-1] < o[0]:
            nrm, o = -nrm, -o
        before = ex.pos()
        full_e = ex.expo.copy()
        ex.add(win0[:-1], win0[1:], -1.0)
        other = ex.expo.copy()
        # the mass left (other legs' exposure) per sample row across the run, between its ends
        t = np.concatenate([P @ u, Q @ u])
        gaps = np.diff(o)
        margin = float(max(gaps.max(), w))
        s_lo, s_hi = float(o[0] - margin), float(o[-1] + margin)
        tp = px * u[0] + py * u[1]
        sp = px * nrm[0] + py * nrm[1]
        sel = (tp >= t.min()) & (tp <= t.max()) & (sp >= s_lo) & (sp < s_hi)
        nb = max(1, int(np.ceil((s_hi - s_lo) / ex.h)))
        rows_mass = np.bincount(
            np.minimum(((sp[sel] - s_lo) / ex.h).astype(np.int64), nb - 1),
            weights=ex.live.ravel()[sel], minlength=nb,
        )  # fmt: skip
        best: tuple[float, np.ndarray, int] | None = None
        starts: list[tuple[np.ndarray, int]] = [(win0, 0)]
        # the mass left along the run, on rows h apart, over its length and a quarter more
        # at each end (for the lines clipped to their own strip's mass)
        along = None
        if quantiles:
            ext = 0.25 * float(t.max() - t.min())
            t_lo = float(t.min()) - ext
            nt = max(1, int(np.ceil((float(t.max()) + ext - t_lo) / ex.h)))
            wide = (tp >= t_lo) & (tp < t_lo + nt * ex.h) & (sp >= s_lo) & (sp < s_hi)
            along = (t_lo, nt, sp[wide], np.minimum(((tp[wide] - t_lo) / ex.h).astype(np.int64),
                     nt - 1), ex.live.ravel()[wide])  # fmt: skip
        # the along-centre of the mass left over the run: lines are lengthened or shortened
        # about it (along the run only) to the longest that fits the time
        wl = ex.live.ravel()[sel]
        centre = float(np.sum(wl * tp[sel]) / np.sum(wl)) if np.sum(wl) > 0 else float(t.mean())
        for dc in cnt:
            got = laid(P, Q, o, nrm, s_lo, rows_mass, m + dc)
            if got is None:
                continue
            nP, nQ = got
            top = (m + dc) and m / (m + dc)  # about the same track length
            win = fitted(k, head, win0, tail, nP, nQ, u, centre, SCALE_LOW * top, top)
            if win is not None:
                starts.append((win, dc))
            if quantiles:
                win = clipped(k, head, win0, tail, nP, nQ, u, nrm, along)
                if win is not None:
                    starts.append((win, dc))
        for win, dc in starts:
            if not fits(k, np.concatenate([head, win, tail])):
                continue
            set_expo(other)
            ex.add(win[:-1], win[1:], 1.0)
            win = search(k, head, win, tail, nrm)
            if zone_bad is not None and zone_bad(win0, win):  # eq. 20 (the polish's check)
                continue
            gain = ex.pos() - before
            if best is None or gain > best[0]:
                best = (gain, win, dc)
        if best is not None and best[0] > TOL:
            gain, win, dc = best
            cand = np.concatenate([head, win, tail])
            ok = True
            if airspace is not None:
                v_new, state = count.move(k, *track(cand, speeds, turn_rate, times, h0[k]))
                ok = v_new <= count.value
                if ok:
                    count.keep(state)
            if ok:
                set_expo(other)
                ex.add(win[:-1], win[1:], 1.0)
                paths[k] = cand
                return 1, dc
        set_expo(full_e)
        return 0, 0

    stats = {"passes": 0, "moves": 0, "runs": 0, "lines_added": 0, "lines_dropped": 0}
    for _ in range(passes):
        stats["passes"] += 1
        kept = 0
        for k in range(n):
            if not flying[k]:
                continue
            runs = find_runs(paths[k], w, min_lines)
            stats["runs"] += len(runs)
            for a, m in reversed(runs):  # from the end: earlier runs keep their indices
                got, dc = regrade_run(k, a, m)
                kept += got
                stats["lines_added"] += max(dc, 0)
                stats["lines_dropped"] += max(-dc, 0)
        stats["moves"] += kept
        if not kept:
            break
    out = [
        [[float(x), float(y)] for x, y in _dedupe(p)[1:-1]] if flying[k] else []
        for k, p in enumerate(paths)
    ]
    return out, ex.pos(), stats
