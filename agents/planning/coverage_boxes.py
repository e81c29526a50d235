"""Coverage boxes: each UAV its own rectangle, line spacing and share of the mass (issue 24).

A start for the allocation planner's refinement (:mod:`poc_env.agents.planning.allocation`) on
maps where one chained route cut into pieces spends much of each UAV's time in transit. It
assigns each UAV its own region of the map and its own coverage there, as the allocation asks
(thin coverage where the mass is thin or far, dense where it is dense and near):

1. **Marginal gain per spacing.** With the swarm's coverage ``C`` so far (eq. 10 per cell, the
   refinement's score), a lawnmower of lines ``s`` apart adds ``W / s`` to the cells it crosses
   (eq. 10: ``C = W / d``), so cell ``j`` gains ``p_j (POD(C_j + W / s) - POD(C_j))``. For each
   spacing of ``PlanOptions.spacings`` (in sweep widths; and ``dense_spacings`` on maps of at
   most ``max_cells`` cells a side) these gains go in a summed-area table.
2. **Best box per UAV.** For every UAV the compiled box search of the greedy rectangles
   (:func:`poc_env.agents.planning._kernels.best_box`: every position of a set of side lengths,
   kept when a lower bound of its flight time fits 0.85 T) finds the box of most gain at each
   spacing (boxes of whole blocks of ``f x f`` cells, ``f`` the least that leaves at most
   ``max_cells`` blocks a side); its lawnmower
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
   others' coverage (steps 1-2), if it gains more; ``rounds`` passes or until none moves.
5. **Two lawnmowers per UAV.** ``chain_rounds`` more exchange passes (until none moves)
   in which a UAV's candidates also include two chained lawnmowers: the first searched as
   in step 2 with a share (``chain``) of 0.85 T, the second from the first's last
   waypoint with the time left there, its gains against the first's coverage added (so it
   may lie over the first: a denser core inside a sparse box, or a second blob). The whole
   route is cut to eq. 18 as in step 2. One box per UAV spends its time on one region; on
   priors with several blobs, or a core denser than its surroundings, the allocation asks
   for more than one (issue 24, docs/PLANNER.md). Chains only enter after the single-box
   exchange, so they never lower the start's gain (each pass takes a move only if it gains).

6. **Graded lines, scored as the environment scores them** (issue 24, i24-quality3; on maps
   searched cell by cell, :func:`sampled_boxes`; options ``graded``, ``sampled``, off by
   default). A box's lines are not laid at one spacing: as many lines as at spacing ``s``
   are split among the box's rows of cells by marginal
   gain (:func:`graded_offsets`: water-filling on the concave ``POD``, in quarter lines per
   row) and placed at the mid-quantiles of that density, denser over the core, sparser at
   the rim, as the relaxed allocation's graded coverage asks. W x length per cell cannot
   tell such lines apart where cells are a sweep width wide (each line counts whole in the
   row it crosses), so every candidate route (each spacing, share, second lawnmower) is
   scored by the environment's detection model when the caller gives the sample points
   (``sampled``: eq. 14 with the sensor's lateral law and cut-off, as the planner's
   ``posc``), the others' routes entering as the mass they leave per sample point; the box
   search keeps its per-cell gain tables. Validation priors (planned POS_C over the
   rule-aware bound, against main): graded lines scored per cell -0.003 (`paper_6_2`, 4 / 1
   / 7), the sampled score alone +0.0095 (11 / 0 / 1), both +0.012 (12 / 0 / 0);
   docs/PLANNER.md.

Deterministic: no clock, no random draw. No-fly zones: the start is flown around them by the
allocation planner like its other starts.

Options tried for issue 24 and left off (docs/PLANNER.md, "Excursions, turned boxes, and the
bound with three airfields": none gained +0.02 of the rule-aware bound on both maps'
validation priors): ``angles`` (boxes turned by given angles, searched on the gain table
resampled onto a turned raster), ``axis`` (one turned box per candidate, along the gain's
principal axis around its axis-aligned box) and ``excursions`` (routes out to a point,
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
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.refine import TURN_SHARE, arrival_times, route_fits
from poc_env.theory.bound import field_key
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import pod_from_coverage, sweep_segments

#: the options these functions fall back on (the planner's defaults).
_DEFAULT = PlanOptions()


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


def cut_lines(
    wps, fits, min_part: float = 0.0, options: PlanOptions | None = None
) -> tuple[np.ndarray, int]:
    """A lawnmower ``wps`` (a line = two waypoints) cut until ``fits(waypoints)``: its last lines
    dropped, then the first dropped line flown in part, as far as still fits (bisection to
    ``options.part_steps`` halvings of its length), if that part is at least ``min_part`` long
    (``options.part`` False: dropped whole).
    Returns the waypoints and the number of whole lines' waypoints kept."""
    wps = np.asarray(wps, dtype=float).reshape(-1, 2)
    kept = len(wps) - len(wps) % 2
    while kept and not fits(wps[:kept]):
        kept -= 2
    out = wps[:kept]
    opt = _DEFAULT if options is None else options
    if opt.part and kept + 1 < len(wps):
        a, b = wps[kept], wps[kept + 1]

        def part(t: float) -> np.ndarray:
            return np.vstack([out, a, a + t * (b - a)])

        if fits(part(0.0)):
            lo, hi = 0.0, 1.0
            for _ in range(opt.part_steps):
                mid = 0.5 * (lo + hi)
                if fits(part(mid)):
                    lo = mid
                else:
                    hi = mid
            if lo * float(np.hypot(*(b - a))) >= max(min_part, 1e-9):
                out = part(lo)
    return out, kept


def cut_route(
    head,
    wps,
    landing,
    speeds: Speeds,
    turn_rate: float,
    budget: float,
    reserve: float,
    heading0: float | None = None,
    min_part: float = 0.0,
    options: PlanOptions | None = None,
) -> tuple[np.ndarray, int]:
    """:func:`cut_lines` of the lawnmower ``wps`` flown after ``head`` (take-off and any
    waypoints before it) and home to ``landing`` with the fit of
    :func:`~poc_env.agents.planning.refine.route_fits` (``speeds``, ``turn_rate``, ``budget``,
    ``reserve``, ``heading0``): the same waypoints bit for bit, its fits in one compiled pass
    (:func:`poc_env.agents.planning._kernels.cut_fit`; tests/planning/test_speed.py)."""
    wps = np.asarray(wps, dtype=float).reshape(-1, 2)
    opt = _DEFAULT if options is None else options
    h0 = np.nan if heading0 is None else float(heading0)
    kept, lo = _kernels.cut_fit(
        np.ascontiguousarray(np.asarray(head, dtype=float).reshape(-1, 2)),
        np.ascontiguousarray(wps),
        np.ascontiguousarray(np.asarray(landing, dtype=float)),
        speeds.out, speeds.line, speeds.home, TURN_SHARE / turn_rate, float(budget),
        float(reserve), h0, bool(opt.part), int(opt.part_steps),
    )  # fmt: skip
    kept = int(kept)
    out = wps[:kept]
    if lo >= 0.0:
        a, b = wps[kept], wps[kept + 1]
        if lo * float(np.hypot(*(b - a))) >= max(min_part, 1e-9):
            out = np.vstack([out, a, a + lo * (b - a)])
    return out, kept


def graded_offsets(
    prior: np.ndarray,
    cov: np.ndarray,
    base: np.ndarray,
    n: int,
    cell: float,
    w: float,
    law: str,
    step: float = _DEFAULT.graded_step,
    least: float = _DEFAULT.graded_min,
) -> np.ndarray:
    """Positions (m from the box's edge, increasing) of ``n`` lines across a box whose cells
    are ``prior``, ``cov`` and ``base`` (the coverage so far and its POD), shape (rows across,
    cells along), rows ``cell`` m wide: the lines a row gets are water-filled by marginal gain
    (a row's ``q`` lines add ``q W / cell`` to each of its cells, eq. 10; POD is concave, so
    the ``step``-steps (lines) of most gain give the best split of ``n`` lines among the
    rows, at most ``cell / (least W)`` per row), then placed at the mid-quantiles of
    their cumulative density, so the spacing follows the wanted coverage across the box
    instead of one spacing over all of it. Fewer than ``n`` lines if fewer steps gain."""
    rows = prior.shape[0]
    m = max(1, int(cell / (least * w) / step + 1e-9))
    q = step * np.arange(1, m + 1)
    gain = np.einsum(
        "rlq->rq",
        prior[..., None]
        * (pod_from_coverage(cov[..., None] + q * w / cell, law) - base[..., None]),
    )
    marg = np.diff(gain, axis=1, prepend=0.0).ravel()
    k = min(round(n / step), int(np.count_nonzero(marg > 0.0)), marg.size)
    if k <= 0:
        return np.zeros(0)
    top = np.argpartition(-marg, k - 1)[:k]
    counts = np.bincount(top // m, minlength=rows) * step
    cum = np.concatenate([[0.0], np.cumsum(counts)])
    lines = math.floor(cum[-1] + 1e-9)
    t = np.arange(lines) + 0.5
    r = np.searchsorted(cum, t, side="left") - 1
    return (r + (t - cum[r]) / counts[r]) * cell


def block_sums(block: np.ndarray, my: int, mx: int, f: int) -> np.ndarray:
    """The sums of the ``f x f`` blocks of ``block`` ``(my f, mx f)``: ``block.reshape(my, f,
    mx, f).sum(axis=(1, 3))``, whose order numpy sums in (a row's pair first, then the two
    rows) is written out for ``f = 2`` (12 times faster on 80 x 80 blocks; the same sums bit
    for bit: tests/planning/test_speed.py)."""
    b = block.reshape(my, f, mx, f)
    if f != 2:
        return b.sum(axis=(1, 3))
    return (b[:, 0, :, 0] + b[:, 0, :, 1]) + (b[:, 1, :, 0] + b[:, 1, :, 1])


def added_gain(
    prior: np.ndarray, cov: np.ndarray, base: np.ndarray, add: np.ndarray, law: str
) -> float:
    """``sum(prior * (POD(cov + add) - base))`` (``base`` = POD(cov), eq. 10 per cell): the
    mass coverage ``add`` finds beyond ``cov``. POD is computed only where ``add`` is not 0
    (elsewhere the term is exactly 0) and the same full array summed, so the sum is the
    straightforward one's bit for bit (tests/planning/test_speed.py)."""
    m = add != 0.0
    g = np.zeros(np.shape(prior))
    g[m] = prior[m] * (pod_from_coverage(cov[m] + add[m], law) - base[m])
    return float(np.sum(g))


def sampled_boxes(grid: Grid, options: PlanOptions | None = None) -> bool:
    """Whether the boxes may lay graded lines (``options.graded``) and score their candidates
    by the environment's model (``options.sampled``) on ``grid``: maps searched cell by cell (at
    most ``options.max_cells`` cells a side). On 24 UAVs over 160 x 160 cells the sampled
    scores took 3.5 times the planning time (39.5 s against 11.3 s, one pair at load 4-5)."""
    return (_DEFAULT if options is None else options).sampled_here(grid.nx, grid.ny)


def cell_steps(path, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The legs of ``path`` cut into equal steps of at most ``step`` m (as
    :func:`~poc_env.theory.search_theory.sweep_track` with ``step_m``): starts and ends (N, 2)."""
    p = np.asarray(path, dtype=float).reshape(-1, 2)
    d = p[1:] - p[:-1]
    m = np.maximum(1, np.ceil(np.hypot(d[:, 0], d[:, 1]) / step)).astype(np.int64)
    leg = np.repeat(np.arange(len(d)), m)
    i = np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m)
    t0 = i / m[leg]
    t1 = (i + 1) / m[leg]
    return p[leg] + t0[:, None] * d[leg], p[leg] + t1[:, None] * d[leg]


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
    sampled: tuple[np.ndarray, int, float] | None = None,
    options: PlanOptions | None = None,
) -> list[list[list[float]]]:
    """Each UAV's waypoints (between ``takeoff[k]`` and ``landing[k]``): one lawnmower box per
    UAV (module docstring). ``budget`` the usable endurance 0.85 T and ``reserve`` the time kept
    in hand at every waypoint (:func:`~poc_env.agents.planning.refine.route_fits`), ``turn_rate``
    the maximum turn rate (rad/s), ``headings`` the take-off headings (rad) or None. A UAV that
    can search nothing gets an empty list. ``sampled``: (the prior on the environment's sample
    points, samples per cell side, the sensor's cut-off in m); given (and ``options.sampled``),
    candidate routes are scored by the environment's detection model
    (:func:`poc_env.theory.search_theory.sweep_track`, as the planner's ``posc``) instead of
    W x length per cell; the box search keeps its per-cell gain tables. ``options``: the
    knobs (:class:`~poc_env.agents.planning.options.PlanOptions`; ``spacings``, ``rounds`` and
    ``chain`` given here override its fields)."""
    opt = _DEFAULT if options is None else options
    default = spacings is None
    spacings = opt.spacings if spacings is None else tuple(spacings)
    rounds = opt.rounds if rounds is None else int(rounds)
    chain = opt.chain if chain is None else tuple(chain)
    early = chain if opt.chain_early else ()
    takeoff = np.asarray(takeoff, dtype=float).reshape(-1, 2)
    landing = np.asarray(landing, dtype=float).reshape(-1, 2)
    prior = np.asarray(prior, dtype=float)
    n = len(takeoff)
    h0 = [None] * n if headings is None else [float(x) for x in headings]
    f = max(1, math.ceil(max(grid.nx, grid.ny) / opt.max_cells))  # boxes on f x f blocks of cells
    if default and f == 1:
        spacings = tuple(opt.dense_spacings) + spacings
    mx, my = math.ceil(grid.nx / f), math.ceil(grid.ny / f)
    widths = _side_lengths(mx).astype(np.int64)
    heights = _side_lengths(my).astype(np.int64)
    orig = np.array(grid.origin_m, dtype=float)
    hi_map = np.array(grid.bounds[2:], dtype=float)
    block = np.zeros((my * f, mx * f))
    speed_arr = np.array([speeds.out, speeds.line, speeds.home])
    half_turn = math.pi / turn_rate  # a half-turn at a line end (the box search's estimate)

    angles = (0.0, *(float(a) for a in opt.angles))
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

    def cell_gains(cov: np.ndarray, base: np.ndarray, s: float) -> np.ndarray:
        """Step 1 per cell: the gain of lines ``s`` sweep widths apart against the coverage
        ``cov`` (``base`` its POD), eq. 10."""
        return prior * (pod_from_coverage(cov + 1.0 / s, law) - base)

    def gain_table(cell_gain: np.ndarray, angle: float = 0.0) -> np.ndarray:
        """Step 1: the summed-area table (on ``f x f`` blocks; turned by ``angle``,
        :func:`turned_raster`) of the gains ``cell_gain`` per cell (:func:`cell_gains`)."""
        if angle:
            idx = turned_of(angle)[1]
            gain = np.where(idx >= 0, cell_gain.ravel()[np.maximum(idx, 0)], 0.0).sum(axis=-1)
        else:
            block[: grid.ny, : grid.nx] = cell_gain
            gain = block_sums(block, my, mx, f)
        table = np.zeros((gain.shape[0] + 1, gain.shape[1] + 1))
        table[1:, 1:] = gain.cumsum(0).cumsum(1)
        return table

    class Tables:
        """The gain tables against ``cov`` by spacing (called with a spacing and an angle),
        each computed on first use (the lawnmowers of all shares, and all second lawnmowers
        after one first, share one coverage; ``options.share_tables`` False recomputes them
        per lawnmower, same routes). With ``parent`` (the tables of a coverage that differs
        from ``cov`` only in the cells ``changed``), a spacing's gains per cell are the
        parent's with those cells recomputed: elementwise the same operations on the same
        numbers, so the same tables bit for bit (a second lawnmower's coverage differs from
        the first's only where the first flies)."""

        def __init__(
            self,
            cov: np.ndarray,
            base: np.ndarray | None = None,
            parent: Tables | None = None,
            changed: np.ndarray | None = None,
        ) -> None:
            self.cov = cov
            self.base = pod_from_coverage(cov, law) if base is None else base
            self.parent, self.changed = parent, changed
            self.cells: dict[float, np.ndarray] = {}
            self.done: dict[tuple[float, float], np.ndarray] = {}

        def cell(self, s: float) -> np.ndarray:
            if s not in self.cells:
                if self.parent is None or self.changed is None:
                    self.cells[s] = cell_gains(self.cov, self.base, s)
                else:
                    m = self.changed
                    g = self.parent.cell(s).copy()
                    g[m] = prior[m] * (pod_from_coverage(self.cov[m] + 1.0 / s, law) - self.base[m])
                    self.cells[s] = g
            return self.cells[s]

        def __call__(self, s: float, angle: float = 0.0) -> np.ndarray:
            if not opt.share_tables:
                return gain_table(cell_gains(self.cov, self.base, s), angle)
            if (s, angle) not in self.done:
                self.done[s, angle] = gain_table(self.cell(s), angle)
            return self.done[s, angle]

    def tables(cov: np.ndarray, base: np.ndarray | None = None) -> Tables:
        """The gain tables against ``cov`` (:class:`Tables`)."""
        return Tables(cov, base)

    def graded(lo, hi, s: float, frm, cov: np.ndarray, base: np.ndarray) -> np.ndarray:
        """The box's lawnmower with its lines at graded spacing (:func:`graded_offsets`), as
        many as at ``s`` sweep widths evenly."""
        (i0, j0), (i1, j1) = (np.rint((np.array([lo, hi]) - orig) / grid.cell_m)).astype(int)
        size = hi - lo
        across = 1 if size[0] >= size[1] else 0
        sl = np.s_[j0:j1, i0:i1]
        p_, c_, b_ = (a[sl] if across == 1 else a[sl].T for a in (prior, cov, base))
        n_even = max(1, math.ceil(size[across] / (s * w) - 1e-9))
        off = graded_offsets(
            p_, c_, b_, n_even, grid.cell_m, w, law, opt.graded_step, opt.graded_min
        )
        if not len(off):
            return _lines(lo, hi, s * w, frm)
        return _lines(lo, hi, s * w, frm, lo[across] + off)

    def lawn(
        k: int,
        s: float,
        tab: Callable[[float, float], np.ndarray],
        frm,
        lead: np.ndarray,
        left: float,
        angle: float = 0.0,
        window: tuple[int, int, int, int] | None = None,
        cov: np.ndarray | None = None,
        base: np.ndarray | None = None,
        grade: bool = False,
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
            elif grade and cov is not None and base is not None:
                hi = np.minimum(lo + np.array([nw, nh]) * f * grid.cell_m, hi_map)
                wps = graded(lo, hi, s, frm, cov, base)
            else:
                hi = np.minimum(lo + np.array([nw, nh]) * f * grid.cell_m, hi_map)
                wps = _lines(lo, hi, s * w, frm)
            full = len(wps)
            wps, kept = cut_route(
                np.vstack([takeoff[k], lead]), wps, landing[k], speeds, turn_rate, budget,
                reserve, h0[k], w, opt,
            )  # fmt: skip
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
        """The principal axis (degrees modulo 90, rounded to ``options.axis_step``; None when it
        is one of the map's axes) of the gain of lines one sweep width apart in the route ``wps``'s
        bounding box grown by ``options.axis_grow`` a side, and that grown box's window on the
        turned raster."""
        lo, hi = wps.min(axis=0), wps.max(axis=0)
        grow = opt.axis_grow * (hi - lo) + 2 * grid.cell_m
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
        deg = (round(deg / opt.axis_step) * opt.axis_step) % 90.0
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

    use_sampled = sampled is not None and opt.sampled and sampled_boxes(grid, opt)
    graded_here = sampled_boxes(grid, opt)

    def swept(bel: np.ndarray, path: np.ndarray) -> tuple[float, np.ndarray]:
        """The mass ``path`` finds on the sample points' mass ``bel`` and what it leaves: as
        :func:`~poc_env.theory.search_theory.sweep_track` with steps of at most a cell (the
        planner's ``posc``), its legs cut into steps in one go."""
        assert sampled is not None
        out = bel.copy()
        a, b = cell_steps(path, grid.cell_m)
        found = sweep_segments(out[None], grid, sampled[1], a[None], b[None], w, law, sampled[2])
        return float(found.sum()), out

    def path_of(j: int) -> np.ndarray:
        return np.vstack([takeoff[j], routes[j], landing[j]])

    def candidate(
        k: int, cov: np.ndarray, shares: tuple[float, ...] = (), bel: np.ndarray | None = None
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """UAV ``k``'s best route against the coverage ``cov``: one lawnmower, or two chained
        (``chain``): (gain, waypoints, its coverage). ``bel``: the sample points' mass
        left by the others' routes (``sampled``), the gain then by the environment's model."""
        base = pod_from_coverage(cov, law)
        best: tuple[float, np.ndarray, np.ndarray] = (0.0, np.zeros((0, 2)), np.zeros(grid.shape))
        none = np.zeros((0, 2))

        def score(wps: np.ndarray, cell: bool = False) -> tuple[float, np.ndarray]:
            path = np.vstack([takeoff[k], wps, landing[k]])
            c = _path_coverage(path, grid, w)
            if bel is not None and not cell:
                return swept(bel, path)[0], c
            return added_gain(prior, cov, base, c, law), c

        modes = (False, True) if opt.graded == "both" else (bool(opt.graded),)
        if not graded_here:
            modes = (False,)
        firsts: list[tuple[float, float, float, tuple[int, int, int, int] | None, bool]]
        firsts = [(s, budget, a, None, g) for g in modes for a in angles for s in spacings]
        firsts += [
            (s, x * budget, a, None, g)
            for g in modes
            for x in shares
            for a in angles
            for s in spacings
        ]
        tab = tables(cov, base)
        n_axis = len(firsts)
        i_first = 0
        while i_first < len(firsts):
            s, share, a, win, g = firsts[i_first]
            i_first += 1
            wps = lawn(k, s, tab, takeoff[k], none, share, a, win, cov, base, g and not a)
            if not len(wps):
                continue
            if share < budget:  # a second lawnmower after this one, with the time left
                path = np.vstack([takeoff[k], wps, landing[k]])
                t_end = float(arrival_times(path, speeds, turn_rate, h0[k])[-2])
                c1 = _path_coverage(np.vstack([takeoff[k], wps, landing[k]]), grid, w)
                cov2 = cov + c1
                if opt.share_tables:  # the POD changes where the first lawnmower flies only
                    flown = c1 != 0.0
                    base2 = base.copy()
                    base2[flown] = pod_from_coverage(cov2[flown], law)
                    tab2 = Tables(cov2, base2, tab, flown)
                else:  # all of it recomputed (the same numbers; for the tests)
                    base2 = pod_from_coverage(cov2, law)
                    tab2 = tables(cov2, base2)
                more = [
                    lawn(
                        k,
                        s2,
                        tab2,
                        wps[-1],
                        wps,
                        budget - t_end,
                        a2,
                        None,
                        cov2,
                        base2,
                        g2 and not a2,
                    )
                    for a2 in angles
                    for s2 in (opt.chain_spacings or spacings)
                    for g2 in modes
                ]
                more = [m for m in more if len(m)]
                if not more:
                    continue
                scored = [(*score(np.vstack([wps, m]), True), m) for m in more]
                if bel is not None:  # the best few by the cell model, then the sampled one
                    scored.sort(key=lambda t: -t[0])
                    scored = [
                        (score(np.vstack([wps, m]))[0], c, m)
                        for _, c, m in scored[: opt.sampled_top]
                    ]
                val, c, m = max(scored, key=lambda t: t[0])
                wps = np.vstack([wps, m])
            else:
                val, c = score(wps)
            if val > best[0]:
                best = (val, wps, c)
            if opt.axis and i_first == n_axis and len(best[1]):  # then the principal axis's boxes
                turn = axis_box(cov, base, best[1])
                if turn is not None:
                    firsts += [(s, budget, turn[0], turn[1], False) for s in spacings]
                    firsts += [
                        (s, x * budget, turn[0], turn[1], False) for x in shares for s in spacings
                    ]
        if opt.excursions:
            ex = excursion(
                prior, cov, grid, w, law, speeds, takeoff[k], landing[k], budget, turn_rate,
                reserve,
                lambda q: route_fits(
                    np.vstack([takeoff[k], q, landing[k]]), speeds, turn_rate, budget, reserve,
                    h0[k],
                ),
                score,
                lambda q, ok: cut_lines(q, ok, w, opt)[0],
                opt.excursion_top,
                opt.excursion_exact,
            )  # fmt: skip
            if ex[0] > best[0]:
                best = ex
        return best

    keys = [field_key(takeoff[k], landing[k]) for k in range(n)]
    routes: list[np.ndarray] = [np.zeros((0, 2)) for _ in range(n)]
    covs = [np.zeros(grid.shape) for _ in range(n)]
    total = np.zeros(grid.shape)
    left = list(range(n))
    # lazy greedy: a field's candidate is recomputed only when it may no longer be the best
    # (its gain can only fall as coverage is added: POD is concave)
    cache: dict[tuple, tuple[float, np.ndarray, np.ndarray]] = {}
    fresh: set[tuple] = set()
    bel_total = np.array(sampled[0], dtype=float) if use_sampled and sampled is not None else None
    # per UAV the share of each sample point's mass its route leaves (sampled)
    surv: list[np.ndarray | None] = [None] * n
    ones = np.ones_like(bel_total) if bel_total is not None else np.ones(0)
    while left:
        if not opt.lazy:
            cache.clear()
        for key in sorted({keys[j] for j in left} - set(cache)):
            cache[key] = candidate(keys.index(key), total, early, bel_total)
            fresh.add(key)
        k = min(left, key=lambda j: (-cache[keys[j]][0], j))
        if keys[k] not in fresh:
            cache[keys[k]] = candidate(k, total, early, bel_total)
            fresh.add(keys[k])
            continue
        val, wps, c = cache[keys[k]]
        if not val > 0.0:
            break
        routes[k], covs[k] = wps, c
        total = total + c
        if bel_total is not None:
            surv[k] = swept(ones, path_of(k))[1]
            bel_total = bel_total * surv[k]
        left.remove(k)
        fresh.clear()
    n_chain = opt.chain_rounds if chain and not early else 0
    passes = [early] * max(0, int(rounds)) + [chain] * n_chain
    done: tuple[float, ...] | None = None  # a kind of pass that moved nothing: not again
    for shares in passes:
        if shares == done:
            continue
        moved = False
        for k in range(n):
            others = total - covs[k]
            base = pod_from_coverage(others, law)
            bel = None
            if bel_total is not None and sampled is not None:
                # the others' survival multiplied (eq. 14 multiplies the mass left per point)
                bel = np.array(sampled[0], dtype=float)
                for j in range(n):
                    if j != k and surv[j] is not None:
                        bel = bel * surv[j]
                now = swept(bel, path_of(k))[0] if len(routes[k]) else 0.0
            else:
                now = float(np.sum(prior * (pod_from_coverage(total, law) - base)))
            val, wps, c = candidate(k, others, shares, bel)
            if val > now + 1e-9:
                routes[k], covs[k] = wps, c
                total = others + c
                if bel_total is not None:
                    surv[k] = swept(ones, path_of(k))[1]
                moved = True
        if not moved:
            done = shares
    return [[[float(a), float(b)] for a, b in r] for r in routes]
