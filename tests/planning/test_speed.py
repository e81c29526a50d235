"""The planner's fast paths (i24-speed, issue 24: the 10 s target on priors of many small blobs)
give the straightforward computations' results bit for bit, on random inputs: so the plans do
not change (docs/PLANNER.md, "Faster planning on priors of many small blobs")."""

import functools
import math

import numpy as np

from poc_env.agents.planning import _kernels
from poc_env.agents.planning.allocation import nearest_field
from poc_env.agents.planning.coverage_boxes import (
    added_gain,
    block_sums,
    box_routes,
    cut_lines,
    cut_route,
)
from poc_env.agents.planning.flight_rules import Speeds, plan_speeds, reserve_s
from poc_env.agents.planning.greedy_rectangles import _lines, _side_lengths
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.refine import (
    Airspace,
    AirspaceCount,
    candidate_edits,
    move_gains,
    route_fits,
    route_time,
    swarm_violations,
)
from poc_env.config import load_scenario
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import pod_from_coverage


def test_nearest_field_is_the_line_by_line_field():
    """Each line's field in one pass equals the field found line by line (the old
    ``field_of``: out-and-back distance to the line's midpoint, ties to the lower index)."""
    rng = np.random.default_rng(0)
    for trial in range(30):
        f = int(rng.integers(1, 5))
        heads = rng.uniform(0, 4e5, (f, 2, 2))
        if f > 1 and trial % 3 == 0:
            heads[1] = heads[0]  # two fields at the same place: the tie goes to the first
        lines = []
        for _ in range(int(rng.integers(0, 40))):
            y, a, b = rng.uniform(0, 4e5, 3)
            lines.append((float(y), np.float64(a), np.float64(b), int(rng.integers(0, 80))))
        got = nearest_field(lines, heads)
        want = []
        for ln in lines:
            mid = np.array([0.5 * (ln[1] + ln[2]), ln[0]])
            d = np.hypot(*(heads[:, 0] - mid).T) + np.hypot(*(heads[:, 1] - mid).T)
            want.append(int(np.argmin(d)))
        assert got.tolist() == want, trial


def _edits_by_loop(path, i, offsets, across, lo, hi):
    """The refinement's candidate edits built candidate by candidate (before i24-speed)."""
    qs, ops, starts, ends, rows, kinds = [], [], [], [], [], []

    def add(q, op, legs, kind):  # one candidate: its point, operation, legs and kind
        qs.append(q)
        ops.append(op)
        for start, end in legs:
            starts.append(start)
            ends.append(end)
            rows.append(len(kinds))
        kinds.append(kind)

    a, b = path[i - 1], path[i]
    if i < len(path) - 1:
        nxt = path[i + 1]
        for off in offsets:
            q = np.clip(b + off, lo, hi)
            add(q, 0, [(a, q), (q, nxt)], 0)
        add(b, 1, [(a, nxt)], 0)
    d = b - a
    length = float(np.hypot(*d))
    normal = np.array([-d[1], d[0]]) / length if length > 0 else np.zeros(2)
    for s in across:
        q = np.clip(0.5 * (a + b) + s * normal, lo, hi)
        add(q, 2, [(a, q), (q, b)], 1)
    return [np.array(x) for x in (qs, ops, starts, ends, rows, kinds)]


def test_candidate_edits_are_the_loops():
    """The candidate moves, deletions and insertions of a waypoint built in one numpy pass are
    the loop's, bit for bit (points clipped at the map's edge, the landing only inserted
    before, a zero-length leg)."""
    rng = np.random.default_rng(1)
    lo, hi = np.array([0.0, 0.0]), np.array([2e5, 1.5e5])
    radii = np.array([0.5, 1.0, 2.0, 4.0]) * 5000.0
    dirs = np.array([[np.cos(a), np.sin(a)] for a in np.arange(8) * np.pi / 4])
    offsets = (radii[:, None, None] * dirs[None]).reshape(-1, 2)
    across = np.concatenate([[0.0], radii, -radii])
    for trial in range(40):
        path = rng.uniform(-1e4, 2.1e5, (int(rng.integers(2, 9)), 2))
        if trial % 5 == 0:
            path[1] = path[0]  # a zero-length leg
        for i in range(1, len(path)):
            got = candidate_edits(path, i, offsets, across, lo, hi)
            want = _edits_by_loop(path, i, offsets, across, lo, hi)
            for g, x in zip(got, want, strict=True):
                assert g.shape == x.shape and np.array_equal(g, x), (trial, i)


def test_move_gains_with_scratch_equal_without():
    """``move_gains`` with its scratch arrays (cells marked, not sorted) gives the same cells,
    coverage and gains bit for bit, and leaves the scratch clear."""
    sc = load_scenario("small")
    grid = Grid.from_config(sc.map)
    w, law = sc.sensor.sweep_width_m, sc.sensor.law
    rng = np.random.default_rng(2)
    p_flat = rng.gamma(0.3, size=grid.nx * grid.ny)
    x0, y0, x1, y1 = grid.bounds
    lo, hi = np.array([x0, y0]), np.array([x1, y1])
    offsets = rng.normal(0, 2 * grid.cell_m, (12, 2))
    across = rng.normal(0, 2 * grid.cell_m, 5)
    scratch = (np.zeros(p_flat.size, dtype=bool), np.zeros(p_flat.size, dtype=np.int64))
    for trial in range(30):
        path = lo - 0.1 * (hi - lo) + rng.random((5, 2)) * 1.2 * (hi - lo)
        total = rng.gamma(0.5, size=p_flat.size) * (rng.random(p_flat.size) < 0.5)
        i = int(rng.integers(1, 5))
        _, _, starts, ends, rows, kinds = candidate_edits(path, i, offsets, across, lo, hi)
        args = (total, p_flat, grid, w, law, starts, ends, rows, kinds, path[i - 1 : i + 2])
        want = move_gains(*args)
        got = move_gains(*args, scratch)
        for g, x in zip(got, want, strict=True):
            assert np.array_equal(g, x), trial
        assert not scratch[0].any()


def test_airspace_count_keeps_a_uavs_pairs_only_until_a_move_is_kept():
    """The airspace count keeps a UAV's pairs between its tried moves; once any move is kept
    they are stale: every count after tries, drops and keeps of different UAVs equals the
    full count from scratch."""
    rng = np.random.default_rng(4)
    air = Airspace(60.0, 1500.0, 5000.0, 2)
    pos = rng.normal(0, 3000.0, (40, 6, 2))
    act = rng.random((40, 6)) > 0.2
    count = AirspaceCount(air, pos, act)
    for trial, (k, keep) in enumerate(
        [(0, False), (0, False), (1, True), (0, False), (0, True), (2, False), (1, True),
         (2, False), (2, True), (0, False)]
    ):  # fmt: skip
        new_pos = rng.normal(0, 3000.0, (40, 2))
        new_act = rng.random(40) > 0.2
        value, state = count.move(k, new_pos, new_act)
        trial_pos, trial_act = pos.copy(), act.copy()
        trial_pos[:, k], trial_act[:, k] = new_pos, new_act
        assert value == swarm_violations(trial_pos, trial_act, 1500.0, 5000.0, 2), trial
        if keep:
            count.keep(state)
            pos, act = trial_pos, trial_act
        assert count.value == swarm_violations(pos, act, 1500.0, 5000.0, 2), trial


def test_cut_route_is_cut_lines():
    """A lawnmower cut to eq. 18 with its fits in one compiled pass (``cut_route``) is
    ``cut_lines`` with ``route_fits`` called per prefix and per bisection step, bit for bit:
    whole lines dropped, the first dropped one flown in part or not (``part``), a waypoint
    before the lawnmower, budgets from nothing fitting to everything fitting."""
    rng = np.random.default_rng(5)
    speeds = Speeds(40.0, 40.0, 30.0)
    turn = math.radians(20.0)
    for trial in range(60):
        lo = rng.uniform(0, 2e5, 2)
        hi = lo + rng.uniform(2e3, 6e4, 2)
        head = rng.uniform(-2e4, 2.2e5, (int(rng.integers(1, 3)), 2))
        landing = rng.uniform(-2e4, 2.2e5, 2)
        wps = _lines(lo, hi, 5000.0, head[-1])
        budget = float(rng.uniform(2e3, 2e4))
        reserve = float(rng.uniform(0, 300))
        h0 = None if trial % 4 == 0 else float(rng.uniform(-np.pi, np.pi))
        opt = PlanOptions(part=trial % 3 != 0, part_steps=int(rng.integers(1, 14)))
        min_part = float(rng.choice([0.0, 5000.0]))

        def fits(q, head=head, landing=landing, budget=budget, reserve=reserve, h0=h0):
            path = np.vstack([head, q, landing])
            return route_fits(path, speeds, turn, budget, reserve, h0)

        want, want_kept = cut_lines(wps, fits, min_part, opt)
        got, got_kept = cut_route(head, wps, landing, speeds, turn, budget, reserve, h0,
                                  min_part, opt)  # fmt: skip
        assert got_kept == want_kept, trial
        assert got.shape == want.shape and np.array_equal(got, want), trial


def _best_box_brute(table, widths, heights, orig, h, w, speeds, turn, budget, to, la):
    """The box search without any bound: every box in the kernel's order, kept when it fits
    and beats the best so far."""
    ny, nx = table.shape[0] - 1, table.shape[1] - 1
    best, found = 0.0, (0, 0, 0, 0)
    for nw in widths:
        for nh in heights:
            lx, ly = nw * h, nh * h
            long_, short = max(lx, ly), min(lx, ly)
            n = max(1.0, math.ceil(short / w - 1e-9))
            search = (n * long_ + (n - 1.0) * short / n) / speeds[1] + (n - 1.0) * turn
            if search > budget:
                continue
            for j in range(ny - nh + 1):
                for i in range(nx - nw + 1):
                    mass = table[j + nh, i + nw] - table[j, i + nw] - table[j + nh, i] + table[j, i]
                    if not mass > best:
                        continue
                    xlo, ylo = orig[0] + h * i, orig[1] + h * j
                    dxt = max(xlo - to[0], to[0] - xlo - lx, 0.0)
                    dxl = max(xlo - la[0], la[0] - xlo - lx, 0.0)
                    dyt = max(ylo - to[1], to[1] - ylo - ly, 0.0)
                    dyl = max(ylo - la[1], la[1] - ylo - ly, 0.0)
                    t = math.hypot(dxt, dyt) / speeds[0] + math.hypot(dxl, dyl) / speeds[2]
                    if t + search <= budget:
                        best, found = mass, (i, j, int(nw), int(nh))
    return (best, *found)


def test_box_search_bounds_skip_only_losing_boxes():
    """The compiled box search (rows and runs of positions skipped when their mass cannot
    beat the best so far) finds the box of the search without bounds: same mass, position
    and size, ties included (sparse random masses, many exact zeros and equal values)."""
    rng = np.random.default_rng(6)
    speeds = np.array([40.0, 40.0, 30.0])
    for trial in range(25):
        ny, nx = (int(x) for x in rng.integers(3, 22, 2))
        cells = rng.gamma(0.2, size=(ny, nx)) * (rng.random((ny, nx)) < 0.3)
        if trial % 4 == 0:
            cells = np.round(cells * 4) / 4  # equal masses: ties
        table = np.zeros((ny + 1, nx + 1))
        table[1:, 1:] = cells.cumsum(0).cumsum(1)
        widths = _side_lengths(nx).astype(np.int64)
        heights = _side_lengths(ny).astype(np.int64)
        h, w = 5000.0, 5000.0 * float(rng.choice([0.75, 1.0, 2.0]))
        orig = np.array([0.0, 0.0])
        to = rng.uniform(-2e4, nx * h + 2e4, 2)
        la = rng.uniform(-2e4, nx * h + 2e4, 2)
        budget = float(rng.uniform(2e3, 3e4))
        args = (table, widths, heights, orig, h, w, speeds, 60.0, budget, to, la)
        got = _kernels.best_box(*args)
        want = _best_box_brute(*args)
        assert tuple(float(x) for x in got) == tuple(float(x) for x in want), trial


def test_block_sums_are_numpys():
    """The ``f x f`` block sums written out for ``f = 2`` are numpy's ``sum(axis=(1, 3))`` bit
    for bit (values over many magnitudes, so a different order would round differently)."""
    rng = np.random.default_rng(7)
    for f in (1, 2, 3):
        for my, mx in ((80, 80), (7, 13), (1, 1)):
            block = rng.random((my * f, mx * f)) * 10.0 ** rng.uniform(-12, 0, (my * f, mx * f))
            block[rng.random(block.shape) < 0.2] = 0.0
            want = block.reshape(my, f, mx, f).sum(axis=(1, 3))
            assert np.array_equal(block_sums(block, my, mx, f), want), (f, my, mx)


def test_added_gain_is_the_full_sum():
    """The mass a coverage adds, POD computed only where it adds, is the full array's sum bit
    for bit (``sum(prior * (POD(cov + add) - POD(cov)))``)."""
    rng = np.random.default_rng(8)
    for trial in range(30):
        shape = (int(rng.integers(1, 60)), int(rng.integers(1, 60)))
        prior = rng.gamma(0.3, size=shape)
        cov = rng.gamma(0.5, size=shape) * (rng.random(shape) < 0.6)
        add = rng.gamma(0.5, size=shape) * (rng.random(shape) < 0.1 * (trial % 10))
        base = pod_from_coverage(cov)
        want = float(np.sum(prior * (pod_from_coverage(cov + add) - base)))
        assert added_gain(prior, cov, base, add, "inverse_cube") == want, trial


def test_derived_gain_tables_give_the_recomputed_routes():
    """Second lawnmowers' gain tables derived from the first's (recomputed where the first
    flies) give the routes of tables recomputed whole (``share_tables=False``), on boxes of
    2 x 2 cells (``max_cells=20`` on ``paper_6_2``: the written-out block sums) and of single
    cells, its own prior and a random one."""
    sc = load_scenario("paper_6_2")
    grid = Grid.from_config(sc.map)
    to = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    la = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    u = sc.uav
    rand = np.random.default_rng(9).gamma(0.3, size=grid.shape)
    for prior in (build_prior(sc.map), rand / rand.sum()):
        for cells in (20, 80):

            def routes(share: bool, prior=prior, cells=cells):
                return box_routes(
                    prior, grid, sc.sensor.sweep_width_m, sc.sensor.law, plan_speeds(sc), to,
                    la, u.usable_endurance_s, u.max_turn_rate_rad_s, reserve_s(sc),
                    takeoff_heading(grid.bounds, to), rounds=1,
                    options=PlanOptions(max_cells=cells, share_tables=share),
                )  # fmt: skip

            assert routes(True) == routes(False), cells


def test_exposure_rows_are_the_scalar_loop():
    """The inverse-cube exposure of a step, row by row in the branch-free loop that vectorises
    (i24-fastpolish, ``_ic_exposure_row``), is the point-by-point definition bit for bit: for
    every sample point within the cut-off, ``sign x min(F, EXPOSURE_CAP)`` added to what it
    held (F the compiled scalar exponent of the step at the point), every other point as it
    was. Random steps (some through sample points, some off the grid, some tiny), both signs,
    a grid already holding exposure."""
    from poc_env._kernels import sensing as k

    rng = np.random.default_rng(5)
    h, ny, nx = 2500.0, 24, 31
    w = 5000.0
    cutoff = 4 * w
    px = (np.arange(nx) + 0.5) * h
    py = (np.arange(ny) + 0.5) * h
    for trial in range(40):
        ax, ay = rng.uniform(-0.2, 1.2) * nx * h, rng.uniform(-0.2, 1.2) * ny * h
        d = rng.normal(0, 4000.0, 2) * (1e-6 if trial % 13 == 0 else 1.0)
        if trial % 5 == 0:  # the step starts on a sample point: F there is infinite
            ax, ay = px[int(rng.integers(nx))], py[int(rng.integers(ny))]
        bx, by = ax + d[0], ay + d[1]
        sign = 1.0 if trial % 2 else -1.0
        expo = rng.gamma(0.5, size=(ny, nx)) * (rng.random((ny, nx)) < 0.7)
        want = expo.copy()
        ux, uy, length = k._seg_axis(ax, ay, bx, by)
        for j in range(ny):
            for i in range(nx):
                lateral, along, beyond = k._frame(px[i], py[j], ax, ay, ux, uy, length)
                if lateral * lateral + beyond * beyond <= cutoff * cutoff:
                    f = k._ic_exponent(lateral, -along, length - along, w * w)
                    want[j, i] += sign * min(f, k.EXPOSURE_CAP)
        box = np.array([ny, 0, nx, 0])
        k.leg_exposure(k.INVERSE_CUBE, ax, ay, bx, by, w, cutoff, cutoff, 5000.0, h, sign,
                       expo, box)  # fmt: skip
        assert np.array_equal(expo, want), trial


def test_framed_candidates_are_the_stacked_ones():
    """The polish's candidates built as views of one array (i24-fastpolish, ``_framed``)
    are the points ``np.vstack([head, body[c], tail])`` gives, candidate by candidate, for
    bodies and tails of every length the polish uses (a tail of none to two points)."""
    from poc_env.agents.planning.polish import _framed

    rng = np.random.default_rng(6)
    for trial in range(30):
        c, n, t = int(rng.integers(1, 20)), int(rng.integers(1, 9)), int(rng.integers(0, 3))
        head = rng.normal(0, 1e5, 2)
        body = rng.normal(0, 1e5, (c, n, 2))
        tail = rng.normal(0, 1e5, (t, 2))
        got = _framed(head, body, tail)
        assert len(got) == c, trial
        for q, b in zip(got, body, strict=True):
            assert np.array_equal(q, np.vstack([head, b, tail])), trial


def _steps_reference(a, b, origin, cell):
    """The polish's legs cut into steps as numpy expressions (``Exposure.steps`` before
    i24-cheapolish compiled it)."""
    a = np.asarray(a, dtype=float).reshape(-1, 2) - origin
    b = np.asarray(b, dtype=float).reshape(-1, 2) - origin
    d = b - a
    n = np.maximum(1, np.ceil(np.hypot(d[:, 0], d[:, 1]) / cell)).astype(np.int64)
    leg = np.repeat(np.arange(len(a)), n)
    j = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
    nl = n[leg].astype(float)
    t0 = (j / nl)[:, None]
    t1 = ((j + 1) / nl)[:, None]
    return a[leg] + t0 * d[leg], a[leg] + t1 * d[leg], n


def test_compiled_steps_are_the_numpy_steps():
    """The polish's compiled step cutting (i24-cheapolish, ``_kernels.sensing.cut_steps``)
    gives the numpy expressions' steps bit for bit: random legs of every scale (none, shorter
    than a cell, exact multiples of it, across the map), a random origin, through
    ``Exposure.steps`` as the polish calls it."""
    from poc_env._kernels.sensing import cut_steps
    from poc_env.agents.planning.polish import Exposure
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import Grid, build_prior

    rng = np.random.default_rng(11)
    cell = 5000.0
    for trial in range(60):
        m = int(rng.integers(1, 12))
        a = rng.uniform(-3e5, 3e5, (m, 2))
        scale = [0.0, 1e-3, 0.7 * cell, 3 * cell, 2e5][trial % 5]
        d = rng.normal(0, 1, (m, 2)) * scale
        if trial % 7 == 0:  # exact multiples of the cell along an axis
            d = np.zeros((m, 2))
            d[:, trial % 2] = cell * rng.integers(0, 5, m)
        b = a + d
        origin = rng.uniform(-1e5, 1e5, 2)
        got = cut_steps(a, b, origin[0], origin[1], cell)
        want = _steps_reference(a, b, origin, cell)
        for g, w_ in zip(got, want, strict=True):
            assert g.dtype == w_.dtype and np.array_equal(g, w_), trial
    sc = load_scenario("paper_6_2")
    grid = Grid.from_config(sc.map)
    ex = Exposure(grid, 2, 10000.0, "inverse_cube", 30000.0, grid.refine(build_prior(sc.map), 2))
    a = rng.uniform(0, 2e5, (9, 2))
    b = rng.uniform(0, 2e5, (9, 2))
    for g, w_ in zip(
        ex.steps(a[:, :], b), _steps_reference(a, b, ex.origin, grid.cell_m), strict=True
    ):
        assert np.array_equal(g, w_)


def test_graded_candidates_are_the_listed_ones():
    """The grade moves' windows built in one expression (i24-cheapolish, ``polish._graded``)
    equal the list of one clipped array per pivot and factor the polish built before, bit for
    bit, on random windows (some clipped at the map's edge) and directions; and
    ``_framed_array`` holds the candidates ``_framed`` lists."""
    from poc_env.agents.planning.polish import GRADE_SCALES, _framed, _framed_array, _graded

    rng = np.random.default_rng(12)
    for trial in range(40):
        m = int(rng.integers(2, 9))
        pts = rng.uniform(-1e5, 3e5, (m, 2))
        ang = rng.uniform(0, 2 * np.pi)
        tan = np.array([np.cos(ang), np.sin(ang)])
        lo, hi = np.zeros(2), np.array([2e5, 1.5e5])
        nrm = np.array([-tan[1], tan[0]])
        off = (pts - pts[0]) @ nrm
        want = [
            np.clip(pts + ((f - 1.0) * (off - pivot))[:, None] * nrm[None], lo, hi)
            for pivot in (0.0, float(off[-1]))
            for f in GRADE_SCALES
        ]
        got = _graded(pts, tan, lo, hi)
        assert got.shape == (len(want), m, 2), trial
        for g, w_ in zip(got, want, strict=True):
            assert np.array_equal(g, w_), trial
        head, tail = rng.normal(0, 1e5, 2), rng.normal(0, 1e5, (trial % 3, 2))
        assert np.array_equal(_framed_array(head, got, tail), np.stack(_framed(head, got, tail)))


@functools.cache
def _gains_reference_kernel():
    """The polish's candidate gains as ``exposure_gains`` computed them before i24-budget kept
    the old steps' values: the old steps taken out, then every candidate step computed, each
    point's ``live (1 - exp(-d))`` summed in row-major order (the same compiled
    ``leg_exposure`` and ``expm1``)."""
    from numba import njit

    from poc_env._kernels import sensing as k

    @njit(error_model="numpy")
    def run(live, old_a, old_b, new_a, new_b, first, law, w, cutoff, reach, cell, h, out):
        ny, nx = live.shape
        base = np.zeros((ny, nx))
        box_o = np.array([ny, 0, nx, 0])
        for o in range(old_a.shape[0]):
            k.leg_exposure(law, old_a[o, 0], old_a[o, 1], old_b[o, 0], old_b[o, 1], w, cutoff,
                           reach, cell, h, -1.0, base, box_o)  # fmt: skip
        for c in range(first.shape[0] - 1):
            work = base.copy()
            box = box_o.copy()
            for i in range(first[c], first[c + 1]):
                k.leg_exposure(law, new_a[i, 0], new_a[i, 1], new_b[i, 0], new_b[i, 1], w,
                               cutoff, reach, cell, h, 1.0, work, box)  # fmt: skip
            g = 0.0
            for j in range(ny):
                for m in range(nx):
                    if work[j, m] != 0.0:
                        g += live[j, m] * -math.expm1(-work[j, m])
            out[c] = g

    return run


def _gains_reference(live, old_a, old_b, new_a, new_b, first, law, w, cutoff, reach, cell, h):
    """:func:`_gains_reference_kernel`'s gains of the candidates."""
    out = np.empty(len(first) - 1)
    _gains_reference_kernel()(live, old_a, old_b, new_a, new_b, first, law, w, cutoff, reach,
                              cell, h, out)  # fmt: skip
    return out


def test_gains_with_kept_steps_are_the_computed_ones():
    """``exposure_gains`` adds a kept old step's values where a candidate keeps that step
    (i24-budget) and gives the gains of computing every step, bit for bit: random old legs and
    candidates of 1-4 legs, some keeping old steps (first, last or inner ones, as the polish's
    moves keep the legs around the waypoint moved), under every detection law; and the scratch
    arrays are zero again."""
    from poc_env._kernels import sensing as k

    rng = np.random.default_rng(24)
    h, ny, nx = 2500.0, 30, 40
    w = 5000.0
    for trial in range(24):
        law = (k.INVERSE_CUBE, k.EXPONENTIAL, k.DEFINITE_RANGE)[trial % 3]
        cutoff = 4 * w
        reach = cutoff if law == k.INVERSE_CUBE else 2 * w
        live = rng.gamma(0.5, size=(ny, nx)) * (rng.random((ny, nx)) < 0.8)
        pts = rng.uniform(-0.1, 1.1, (int(rng.integers(2, 6)), 2)) * [nx * h, ny * h]
        old_a, old_b, _ = k.cut_steps(pts[:-1], pts[1:], 0.0, 0.0, 2 * h)
        cands = []
        for _ in range(int(rng.integers(1, 12))):
            n_new = int(rng.integers(1, 5))
            sa, sb, _ = k.cut_steps(
                *(lambda q: (q[:-1], q[1:]))(
                    rng.uniform(-0.1, 1.1, (n_new + 1, 2)) * [nx * h, ny * h]
                ),
                0.0, 0.0, 2 * h,
            )  # fmt: skip
            keep = rng.choice(len(old_a), size=min(len(old_a), int(rng.integers(0, 4))),
                              replace=False)  # fmt: skip
            at = rng.integers(0, len(sa) + 1, size=len(keep))
            a_list, b_list = list(sa), list(sb)
            for o, pos in sorted(zip(keep, at), key=lambda t: -t[1]):
                a_list.insert(int(pos), old_a[o])
                b_list.insert(int(pos), old_b[o])
            cands.append((np.array(a_list), np.array(b_list)))
        new_a = np.vstack([c[0] for c in cands])
        new_b = np.vstack([c[1] for c in cands])
        first = np.concatenate([[0], np.cumsum([len(c[0]) for c in cands])]).astype(np.int64)
        base, work = np.zeros((ny, nx)), np.zeros((ny, nx))
        got = np.empty(len(cands))
        k.exposure_gains(live, old_a, old_b, new_a, new_b, first, law, w, cutoff, reach,
                         2 * h, h, base, work, got)  # fmt: skip
        want = _gains_reference(live, old_a, old_b, new_a, new_b, first, law, w, cutoff,
                                reach, 2 * h, h)  # fmt: skip
        assert np.array_equal(got.view(np.int64), want.view(np.int64)), trial
        assert not base.any() and not work.any(), trial


def test_first_fitting_is_route_fits_in_turn():
    """``_kernels.first_fitting`` (i24-budget: the polish's fit checks in one call) returns the
    first position in the order from ``t0`` whose candidate ``route_fits`` accepts, or the end,
    on random paths, candidate windows of several lengths (some deleting points, some
    inserting), budgets some candidates keep and some break, with and without a heading."""
    rng = np.random.default_rng(25)
    speeds = Speeds(out=61.0, line=50.0, home=61.0)
    turn = 0.2
    for trial in range(60):
        m = int(rng.integers(3, 9))
        path = rng.uniform(0, 1e5, (m, 2))
        i0 = int(rng.integers(0, m - 2))
        i1 = int(rng.integers(i0 + 1, m))
        cands = [
            np.vstack([path[i0], rng.uniform(0, 1e5, (int(rng.integers(0, 4)), 2)), path[i1]])
            for _ in range(int(rng.integers(1, 15)))
        ]
        pts = np.concatenate(cands)
        off = np.concatenate([[0], np.cumsum([len(q) for q in cands])]).astype(np.int64)
        order = rng.permutation(len(cands)).astype(np.int64)
        heading = None if trial % 2 else float(rng.uniform(-np.pi, np.pi))
        times = sorted(
            route_time(np.concatenate([path[:i0], q, path[i1 + 1 :]]), speeds, turn, heading)
            for q in cands
        )
        budget = float(times[len(times) // 2]) + 1.0  # about half the candidates fit
        reserve = float(rng.uniform(0, 600))
        for t0 in range(len(cands) + 1):
            want = len(cands)
            for t in range(t0, len(cands)):
                cand = np.concatenate([path[:i0], cands[order[t]], path[i1 + 1 :]])
                if route_fits(cand, speeds, turn, budget, reserve, heading):
                    want = t
                    break
            got = _kernels.first_fitting(
                path, i0, i1, pts, off, order, t0, len(cands), speeds.out, speeds.line,
                speeds.home, 0.5 / turn, budget, reserve,
                np.nan if heading is None else heading,
            )  # fmt: skip
            assert got == want, (trial, t0)
