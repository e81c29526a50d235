"""Coverage boxes: each UAV its own rectangle, line spacing and share of the mass (issue 24).

A start for the allocation planner's refinement (:mod:`poc_env.agents.planning.allocation`) on
maps where one chained route cut into pieces spends much of each UAV's time in transit. It
assigns each UAV its own region of the map and its own coverage there, as the allocation asks
(thin coverage where the mass is thin or far, dense where it is dense and near):

1. **Marginal gain per spacing.** With the swarm's coverage ``C`` so far (eq. 10 per cell, the
   refinement's score), a lawnmower of lines ``s`` apart adds ``W / s`` to the cells it crosses
   (eq. 10: ``C = W / d``), so cell ``j`` gains ``p_j (POD(C_j + W / s) - POD(C_j))``. For each
   spacing of :data:`SPACINGS` (in sweep widths; and :data:`DENSE_SPACINGS` on maps of at
   most :data:`MAX_CELLS` cells a side) these gains go in a summed-area table.
2. **Best box per UAV.** For every UAV the compiled box search of the greedy rectangles
   (:func:`poc_env.agents.planning._kernels.best_box`: every position of a set of side lengths,
   kept when a lower bound of its flight time fits 0.85 T) finds the box of most gain at each
   spacing (boxes of whole blocks of ``f x f`` cells, ``f`` the least that leaves at most
   :data:`MAX_CELLS` blocks a side); its lawnmower
   (:func:`poc_env.agents.planning.greedy_rectangles._lines`, lines ``s`` apart along the
   longer side) is cut until it keeps eq. 18's return rule
   (:func:`poc_env.agents.planning.refine.route_fits`; the first line dropped is flown in
   part, as far as still fits, :func:`cut_lines`), and the spacing whose route gains most
   (whole flight path counted, transit too) is the UAV's candidate. UAVs sharing both fields
   have the same candidate (computed once).
3. **Assignment.** Of all UAVs not yet assigned, the one whose candidate gains most takes it
   (ties: the lower index); its coverage is added and steps 1-3 repeat until every UAV has a
   route or none gains anything. Candidates are recomputed lazily: added coverage only lowers
   the gains (POD is concave), so a field's last candidate value bounds its new one, and only
   the field on top is recomputed until the one on top is fresh. Greedy on a monotone
   submodular gain over a partition (one route per UAV) is within 1/2 of the best choice
   among these candidates.
4. **Exchange.** Each UAV in turn drops its route and takes the best candidate against all the
   others' coverage (steps 1-2), if it gains more; :data:`ROUNDS` passes or until none moves.
5. **Two lawnmowers per UAV.** :data:`CHAIN_ROUNDS` more exchange passes (until none moves)
   in which a UAV's candidates also include two chained lawnmowers: the first searched as
   in step 2 with a share (:data:`CHAIN`) of 0.85 T, the second from the first's last
   waypoint with the time left there, its gains against the first's coverage added (so it
   may lie over the first: a denser core inside a sparse box, or a second blob). The whole
   route is cut to eq. 18 as in step 2. One box per UAV spends its time on one region; on
   priors with several blobs, or a core denser than its surroundings, the allocation asks
   for more than one (issue 24, docs/PLANNER.md). Chains only enter after the single-box
   exchange, so they never lower the start's gain (each pass takes a move only if it gains).

Deterministic: no clock, no random draw. No-fly zones: the start is flown around them by the
allocation planner like its other starts.

Options tried for issue 24 and left off (docs/PLANNER.md, "Excursions, turned boxes, and the
bound with three airfields": none gained +0.02 of the rule-aware bound on both maps'
validation priors): :data:`ANGLES` (boxes turned by given angles, searched on the gain table
resampled onto a turned raster), :data:`AXIS` (one turned box per candidate, along the gain's
principal axis around its axis-aligned box) and :data:`EXCURSIONS` (routes out to a point,
across and home, :mod:`poc_env.agents.planning.excursions`). Off, the routes are as before.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from poc_env.agents.planning import _kernels
from poc_env.agents.planning.excursions import excursion
from poc_env.agents.planning.flight_rules import Speeds
from poc_env.agents.planning.flight_rules import path_coverage as _path_coverage
from poc_env.agents.planning.greedy_rectangles import SCALES, _lines, _side_lengths
from poc_env.agents.planning.refine import arrival_times, route_fits
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import pod_from_coverage

#: line spacings tried, in sweep widths (coverage W / s: 1 to 1/4 of a sweep width's).
SPACINGS = (1.0, 1.5, 2.0, 3.0, 4.0)
#: spacings below one sweep width (0.75 W: coverage 4/3, a dense core near the field in one
#: box), tried as well where boxes are searched cell by cell (at most :data:`MAX_CELLS` cells a
#: side): on validation priors +0.003 (paper_6_2) and +0.02 (large_400) of the rule-aware
#: bound; on 24 UAVs over 160 x 160 cells they took 1.4 times the planning time for a lower POS.
DENSE_SPACINGS: tuple[float, ...] = (0.75,)
#: boxes are searched on blocks of cells so that the map has at most this many blocks a side
#: (160 x 160 cells: 2 x 2 blocks; the box search's cost grows as the fourth power of the side).
MAX_CELLS = 80
#: recompute candidates lazily (step 3); False recomputes every field's each round (same routes).
LAZY = True
#: passes of the exchange step (4).
ROUNDS = 2
#: shares of the budget the first of two chained lawnmowers is searched with (the second
#: gets the time left); () leaves one lawnmower per UAV.
CHAIN: tuple[float, ...] = (0.35, 0.55)
#: chains tried in the greedy and exchange steps too (True) or only in final passes (False).
CHAIN_EARLY = False
#: final exchange passes with chains.
CHAIN_ROUNDS = 2
#: line spacings (sweep widths) tried for the second chained lawnmower; () all of ``spacings``.
CHAIN_SPACINGS: tuple[float, ...] = ()
#: also try excursions (:mod:`poc_env.agents.planning.excursions`: take-off -> P -> Q ->
#: landing, the legs the search) as a UAV's candidate; False: boxes only (main's plans).
EXCURSIONS = False
#: box orientations tried besides the map's axes (degrees, counter-clockwise): a box turned by
#: an angle is searched on the gain table resampled onto a turned raster (:func:`turned_raster`)
#: and its lines clipped to the map; () only axis-aligned boxes (main's plans).
ANGLES: tuple[float, ...] = ()
#: also try, per UAV candidate, boxes turned to the principal axis of the gain around its best
#: axis-aligned route (rounded to :data:`AXIS_STEP` degrees), searched in a window around that
#: route grown by :data:`AXIS_GROW` of its size on each side (False: main's plans).
AXIS = False
AXIS_STEP = 15.0
AXIS_GROW = 0.5
#: a route that does not fit flies its first dropped line in part (True) or drops it whole.
PART = True
#: halvings of the bisection for the part of a line that fits.
PART_STEPS = 12
#: share one coverage's gain tables among the lawnmowers searched against it (False: each
#: lawnmower recomputes its own; same routes bit for bit, slower; kept for the tests).
_SHARE_TABLES = True


def rotation(deg: float) -> np.ndarray:
    """The 2 x 2 matrix turning map vectors by ``deg`` degrees counter-clockwise."""
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def turned_raster(grid: Grid, f: int, deg: float) -> tuple[np.ndarray, np.ndarray]:
    """A raster of ``f x f``-cell blocks in the frame turned by ``deg`` (map point ``p`` is
    ``R(-deg) p`` there) covering the whole map: its lower-left corner (turned frame) and, per
    block, the flat map cells of its ``f x f`` sub-cell centres (-1 outside the map), an array
    (rows, cols, f * f). A block's gain is the sum of its sub-cells' cells' (nearest cell)."""
    c = grid.cell_m
    x0, y0, x1, y1 = grid.bounds
    back = rotation(-deg)
    corners = np.array([[x0, y0], [x1, y0], [x0, y1], [x1, y1]]) @ back.T
    lo = corners.min(axis=0)
    size = corners.max(axis=0) - lo
    h = f * c
    mx, my = (max(1, math.ceil(v / h - 1e-9)) for v in size)
    sub = (np.arange(f) + 0.5) * c
    bx = lo[0] + h * np.arange(mx)[:, None] + sub[None, :]  # (mx, f)
    by = lo[1] + h * np.arange(my)[:, None] + sub[None, :]  # (my, f)
    qx = np.broadcast_to(bx[None, :, None, :], (my, mx, f, f))
    qy = np.broadcast_to(by[:, None, :, None], (my, mx, f, f))
    pts = np.stack([qx, qy], axis=-1).reshape(-1, 2) @ rotation(deg).T
    col = np.floor((pts[:, 0] - x0) / c).astype(np.int64)
    row = np.floor((pts[:, 1] - y0) / c).astype(np.int64)
    ok = (col >= 0) & (col < grid.nx) & (row >= 0) & (row < grid.ny)
    idx = np.where(ok, row * grid.nx + col, -1)
    return lo, idx.reshape(my, mx, f * f)


def clip_lines(wps: np.ndarray, bounds) -> np.ndarray:
    """Lawnmower waypoints (a line = two) with each line clipped to the rectangle ``bounds``
    (x0, y0, x1, y1) (Liang-Barsky); lines left shorter than 1 m are dropped."""
    x0, y0, x1, y1 = bounds
    out = []
    for a, b in np.asarray(wps, dtype=float).reshape(-1, 2, 2):
        d = b - a
        t0, t1 = 0.0, 1.0
        for p, q in ((-d[0], a[0] - x0), (d[0], x1 - a[0]), (-d[1], a[1] - y0), (d[1], y1 - a[1])):
            if abs(p) < 1e-12:
                if q < 0:
                    t0, t1 = 1.0, 0.0
                continue
            r = q / p
            if p < 0:
                t0 = max(t0, r)
            else:
                t1 = min(t1, r)
        if (t1 - t0) * float(np.hypot(*d)) >= 1.0:
            out += [a + t0 * d, a + t1 * d]
    return np.array(out).reshape(-1, 2)


def cut_lines(wps, fits, min_part: float = 0.0) -> tuple[np.ndarray, int]:
    """A lawnmower ``wps`` (a line = two waypoints) cut until ``fits(waypoints)``: its last lines
    dropped, then the first dropped line flown in part, as far as still fits (bisection to
    :data:`PART_STEPS` halvings of its length), if that part is at least ``min_part`` long.
    Returns the waypoints and the number of whole lines' waypoints kept."""
    wps = np.asarray(wps, dtype=float).reshape(-1, 2)
    kept = len(wps) - len(wps) % 2
    while kept and not fits(wps[:kept]):
        kept -= 2
    out = wps[:kept]
    if PART and kept + 1 < len(wps):
        a, b = wps[kept], wps[kept + 1]

        def part(t: float) -> np.ndarray:
            return np.vstack([out, a, a + t * (b - a)])

        if fits(part(0.0)):
            lo, hi = 0.0, 1.0
            for _ in range(PART_STEPS):
                mid = 0.5 * (lo + hi)
                if fits(part(mid)):
                    lo = mid
                else:
                    hi = mid
            if lo * float(np.hypot(*(b - a))) >= max(min_part, 1e-9):
                out = part(lo)
    return out, kept


def box_routes(
    prior: np.ndarray,
    grid: Grid,
    w: float,
    law: str,
    speeds: Speeds,
    takeoff,
    landing,
    budget: float,
    turn_rate: float,
    reserve: float,
    headings=None,
    spacings: tuple[float, ...] | None = None,
    rounds: int | None = None,
    chain: tuple[float, ...] | None = None,
) -> list[list[list[float]]]:
    """Each UAV's waypoints (between ``takeoff[k]`` and ``landing[k]``): one lawnmower box per
    UAV (module docstring). ``budget`` the usable endurance 0.85 T and ``reserve`` the time kept
    in hand at every waypoint (:func:`~poc_env.agents.planning.refine.route_fits`), ``turn_rate``
    the maximum turn rate (rad/s), ``headings`` the take-off headings (rad) or None. A UAV that
    can search nothing gets an empty list."""
    default = spacings is None
    spacings = SPACINGS if spacings is None else tuple(spacings)
    rounds = ROUNDS if rounds is None else int(rounds)
    chain = CHAIN if chain is None else tuple(chain)
    early = chain if CHAIN_EARLY else ()
    takeoff = np.asarray(takeoff, dtype=float).reshape(-1, 2)
    landing = np.asarray(landing, dtype=float).reshape(-1, 2)
    prior = np.asarray(prior, dtype=float)
    n = len(takeoff)
    h0 = [None] * n if headings is None else [float(x) for x in headings]
    f = max(1, math.ceil(max(grid.nx, grid.ny) / MAX_CELLS))  # boxes on f x f blocks of cells
    if default and f == 1:
        spacings = tuple(DENSE_SPACINGS) + spacings
    mx, my = math.ceil(grid.nx / f), math.ceil(grid.ny / f)
    widths = _side_lengths(mx).astype(np.int64)
    heights = _side_lengths(my).astype(np.int64)
    orig = np.array(grid.origin_m, dtype=float)
    hi_map = np.array(grid.bounds[2:], dtype=float)
    block = np.zeros((my * f, mx * f))
    speed_arr = np.array([speeds.out, speeds.line, speeds.home])
    half_turn = math.pi / turn_rate  # a half-turn at a line end (the box search's estimate)

    angles = (0.0, *(float(a) for a in ANGLES))
    turned: dict[float, tuple[np.ndarray, np.ndarray]] = {}
    side_cache: dict[int, np.ndarray] = {}

    def turned_of(a: float) -> tuple[np.ndarray, np.ndarray]:
        if a not in turned:
            turned[a] = turned_raster(grid, f, a)
        return turned[a]

    def sides_of(m: int) -> np.ndarray:
        if m not in side_cache:
            side_cache[m] = _side_lengths(m).astype(np.int64)
        return side_cache[m]

    def gain_table(cov: np.ndarray, base: np.ndarray, s: float, angle: float = 0.0) -> np.ndarray:
        """Step 1: the summed-area table (on ``f x f`` blocks; turned by ``angle``,
        :func:`turned_raster`) of the gains of lines ``s`` sweep widths apart against the
        coverage ``cov`` (``base`` its POD)."""
        cell_gain = prior * (pod_from_coverage(cov + 1.0 / s, law) - base)
        if angle:
            idx = turned_of(angle)[1]
            gain = np.where(idx >= 0, cell_gain.ravel()[np.maximum(idx, 0)], 0.0).sum(axis=-1)
        else:
            block[: grid.ny, : grid.nx] = cell_gain
            gain = block.reshape(my, f, mx, f).sum(axis=(1, 3))
        table = np.zeros((gain.shape[0] + 1, gain.shape[1] + 1))
        table[1:, 1:] = gain.cumsum(0).cumsum(1)
        return table

    def tables(
        cov: np.ndarray, base: np.ndarray | None = None
    ) -> Callable[[float, float], np.ndarray]:
        """The gain tables against ``cov`` by spacing, each computed on first use (the
        lawnmowers of all shares, and all second lawnmowers after one first, share one
        coverage; :data:`_SHARE_TABLES` False recomputes them per lawnmower, same routes)."""
        pod0 = pod_from_coverage(cov, law) if base is None else base
        done: dict[tuple[float, float], np.ndarray] = {}

        def get(s: float, angle: float = 0.0) -> np.ndarray:
            if (s, angle) not in done or not _SHARE_TABLES:
                done[s, angle] = gain_table(cov, pod0, s, angle)
            return done[s, angle]

        return get

    def lawn(
        k: int,
        s: float,
        tab: Callable[[float, float], np.ndarray],
        frm,
        lead: np.ndarray,
        left: float,
        angle: float = 0.0,
        window: tuple[int, int, int, int] | None = None,
    ) -> np.ndarray:
        """UAV ``k``'s lawnmower of lines ``s`` sweep widths apart of most gain in the gain
        tables ``tab`` (:func:`tables`), flown from ``frm`` after the waypoints ``lead`` with
        ``left`` seconds of the budget left there; its last lines dropped until the whole
        route keeps eq. 18; ``window`` (rows r0:r1, columns c0:c1 of the turned raster) limits
        the search of a turned box."""
        table = tab(s, angle)
        frm = np.asarray(frm, dtype=float)
        if angle:  # the box searched in the turned frame, its lines turned back and clipped
            back = rotation(-angle)
            o = turned_of(angle)[0]
            if window is not None:  # the summed-area table of the window alone
                r0, r1, c0, c1 = window
                t = table[r0 : r1 + 1, c0 : c1 + 1]
                table = t - t[:1, :] - t[:, :1] + t[0, 0]
                o = o + np.array([c0, r0]) * f * grid.cell_m
            wd, ht = sides_of(table.shape[1] - 1), sides_of(table.shape[0] - 1)
            fr, la = back @ frm, back @ landing[k]
        else:
            o, wd, ht, fr, la = orig, widths, heights, frm, landing[k]
        sp = speed_arr if not len(lead) else np.array([speeds.line, speeds.line, speeds.home])
        wps: np.ndarray = np.zeros((0, 2))
        for scale in SCALES:  # a route that does not fit eq. 18: a tighter estimate
            mass, i, j, nw, nh = _kernels.best_box(
                table, wd, ht, o, float(f * grid.cell_m), float(s * w), sp, float(half_turn),
                float(scale * (left - reserve)), fr, la,
            )  # fmt: skip
            if not mass > 0.0:
                break
            lo = o + np.array([i, j]) * f * grid.cell_m
            if angle:
                hi = lo + np.array([nw, nh]) * f * grid.cell_m
                wps = clip_lines(_lines(lo, hi, s * w, fr) @ rotation(angle).T, grid.bounds)
                if not len(wps):
                    break
            else:
                hi = np.minimum(lo + np.array([nw, nh]) * f * grid.cell_m, hi_map)
                wps = _lines(lo, hi, s * w, frm)
            full = len(wps)
            wps, kept = cut_lines(
                wps,
                lambda q: route_fits(
                    np.vstack([takeoff[k], lead, q, landing[k]]),
                    speeds,
                    turn_rate,
                    budget,
                    reserve,
                    h0[k],
                ),
                w,
            )
            if kept >= full // 2:
                break
        return wps

    ctr = np.stack(
        np.meshgrid(
            orig[0] + grid.cell_m * (np.arange(grid.nx) + 0.5),
            orig[1] + grid.cell_m * (np.arange(grid.ny) + 0.5),
        ),
        axis=-1,
    )  # cell centres (ny, nx, 2)

    def axis_box(
        cov: np.ndarray, base: np.ndarray, wps: np.ndarray
    ) -> tuple[float, tuple[int, int, int, int]] | None:
        """The principal axis (degrees modulo 90, rounded to :data:`AXIS_STEP`; None when it
        is one of the map's axes) of the gain of lines one sweep width apart in the route ``wps``'s
        bounding box grown by :data:`AXIS_GROW` a side, and that grown box's window on the
        turned raster."""
        lo, hi = wps.min(axis=0), wps.max(axis=0)
        grow = AXIS_GROW * (hi - lo) + 2 * grid.cell_m
        lo, hi = lo - grow, hi + grow
        inside = np.all((ctr >= lo) & (ctr <= hi), axis=-1)
        g = np.where(inside, prior * (pod_from_coverage(cov + 1.0, law) - base), 0.0)
        tot = float(g.sum())
        if not tot > 0.0:
            return None
        mean = np.tensordot(g, ctr, axes=([0, 1], [0, 1])) / tot
        d = ctr - mean
        dx, dy = d[..., 0], d[..., 1]
        cxx, cyy, cxy = (float(np.sum(g * a * b)) / tot for a, b in ((dx, dx), (dy, dy), (dx, dy)))
        # a frame turned by deg and one turned by deg + 90 hold the same boxes: modulo 90
        deg = math.degrees(0.5 * math.atan2(2.0 * cxy, cxx - cyy)) % 90.0
        deg = (round(deg / AXIS_STEP) * AXIS_STEP) % 90.0
        if deg == 0.0:
            return None
        o, idx = turned_of(deg)
        corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [lo[0], hi[1]], [hi[0], hi[1]]])
        q = (corners @ rotation(-deg).T - o) / (f * grid.cell_m)
        c0, r0 = (max(0, math.floor(float(v))) for v in q.min(axis=0))
        c1 = min(idx.shape[1], math.ceil(float(q[:, 0].max())))
        r1 = min(idx.shape[0], math.ceil(float(q[:, 1].max())))
        if c1 <= c0 or r1 <= r0:
            return None
        return deg, (r0, r1, c0, c1)

    def candidate(
        k: int, cov: np.ndarray, shares: tuple[float, ...] = ()
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """UAV ``k``'s best route against the coverage ``cov``: one lawnmower, or two chained
        (:data:`CHAIN`): (gain, waypoints, its coverage)."""
        base = pod_from_coverage(cov, law)
        best: tuple[float, np.ndarray, np.ndarray] = (0.0, np.zeros((0, 2)), np.zeros(grid.shape))
        none = np.zeros((0, 2))

        def score(wps: np.ndarray) -> tuple[float, np.ndarray]:
            c = _path_coverage(np.vstack([takeoff[k], wps, landing[k]]), grid, w)
            return float(np.sum(prior * (pod_from_coverage(cov + c, law) - base))), c

        firsts: list[tuple[float, float, float, tuple[int, int, int, int] | None]]
        firsts = [(s, budget, a, None) for a in angles for s in spacings]
        firsts += [(s, x * budget, a, None) for x in shares for a in angles for s in spacings]
        tab = tables(cov, base)
        n_axis = len(firsts)
        i_first = 0
        while i_first < len(firsts):
            s, share, a, win = firsts[i_first]
            i_first += 1
            wps = lawn(k, s, tab, takeoff[k], none, share, a, win)
            if not len(wps):
                continue
            if share < budget:  # a second lawnmower after this one, with the time left
                path = np.vstack([takeoff[k], wps, landing[k]])
                t_end = float(arrival_times(path, speeds, turn_rate, h0[k])[-2])
                c1 = _path_coverage(np.vstack([takeoff[k], wps, landing[k]]), grid, w)
                tab2 = tables(cov + c1)
                more = [
                    lawn(k, s2, tab2, wps[-1], wps, budget - t_end, a2)
                    for a2 in angles
                    for s2 in (CHAIN_SPACINGS or spacings)
                ]
                more = [m for m in more if len(m)]
                if not more:
                    continue
                scored = [(*score(np.vstack([wps, m])), m) for m in more]
                val, c, m = max(scored, key=lambda t: t[0])
                wps = np.vstack([wps, m])
            else:
                val, c = score(wps)
            if val > best[0]:
                best = (val, wps, c)
            if AXIS and i_first == n_axis and len(best[1]):  # then the principal axis's boxes
                turn = axis_box(cov, base, best[1])
                if turn is not None:
                    firsts += [(s, budget, turn[0], turn[1]) for s in spacings]
                    firsts += [(s, x * budget, turn[0], turn[1]) for x in shares for s in spacings]
        if EXCURSIONS:
            ex = excursion(
                prior, cov, grid, w, law, speeds, takeoff[k], landing[k], budget, turn_rate,
                reserve,
                lambda q: route_fits(
                    np.vstack([takeoff[k], q, landing[k]]), speeds, turn_rate, budget, reserve,
                    h0[k],
                ),
                score,
                lambda q, ok: cut_lines(q, ok, w)[0],
            )  # fmt: skip
            if ex[0] > best[0]:
                best = ex
        return best

    keys = [tuple(np.round(np.concatenate([takeoff[k], landing[k]]), 3)) for k in range(n)]
    routes: list[np.ndarray] = [np.zeros((0, 2)) for _ in range(n)]
    covs = [np.zeros(grid.shape) for _ in range(n)]
    total = np.zeros(grid.shape)
    left = list(range(n))
    # lazy greedy: a field's candidate is recomputed only when it may no longer be the best
    # (its gain can only fall as coverage is added: POD is concave)
    cache: dict[tuple, tuple[float, np.ndarray, np.ndarray]] = {}
    fresh: set[tuple] = set()
    while left:
        if not LAZY:
            cache.clear()
        for key in sorted({keys[j] for j in left} - set(cache)):
            cache[key] = candidate(keys.index(key), total, early)
            fresh.add(key)
        k = min(left, key=lambda j: (-cache[keys[j]][0], j))
        if keys[k] not in fresh:
            cache[keys[k]] = candidate(k, total, early)
            fresh.add(keys[k])
            continue
        val, wps, c = cache[keys[k]]
        if not val > 0.0:
            break
        routes[k], covs[k] = wps, c
        total = total + c
        left.remove(k)
        fresh.clear()
    passes = [early] * max(0, int(rounds)) + [chain] * (CHAIN_ROUNDS if chain and not early else 0)
    done: tuple[float, ...] | None = None  # a kind of pass that moved nothing: not again
    for shares in passes:
        if shares == done:
            continue
        moved = False
        for k in range(n):
            others = total - covs[k]
            base = pod_from_coverage(others, law)
            now = float(np.sum(prior * (pod_from_coverage(total, law) - base)))
            val, wps, c = candidate(k, others, shares)
            if val > now + 1e-9:
                routes[k], covs[k] = wps, c
                total = others + c
                moved = True
        if not moved:
            done = shares
    return [[[float(a), float(b)] for a, b in r] for r in routes]
