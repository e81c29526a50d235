"""Coverage boxes: one lawnmower box per UAV, its own spacing, within the flight rules."""

import numpy as np

from poc_env.agents.planning import coverage_boxes
from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.agents.planning.coverage_boxes import box_routes
from poc_env.agents.planning.flight_rules import path_coverage, plan_speeds, reserve_s
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.refine import route_fits
from poc_env.config import load_scenario
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import pod_from_coverage, sweep_track


def _inputs(name="paper_6_2", prior=None, **over):
    sc = load_scenario(name, over or None)
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map) if prior is None else prior
    to = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    la = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    return sc, grid, prior, to, la


def _routes(sc, grid, prior, to, la, **kw):
    u = sc.uav
    return box_routes(
        prior,
        grid,
        sc.sensor.sweep_width_m,
        sc.sensor.law,
        plan_speeds(sc),
        to,
        la,
        u.usable_endurance_s,
        u.max_turn_rate_rad_s,
        reserve_s(sc),
        takeoff_heading(grid.bounds, to),
        **kw,
    )


def test_every_uav_finds_mass_and_keeps_the_flight_rules():
    """paper_6_2: every UAV is given a box that finds mass (the prior has mass within every
    UAV's reach); every route fits 0.85 T with eq. 18's return rule at every waypoint; the
    lines lie inside the map."""
    sc, grid, prior, to, la = _inputs()
    routes = _routes(sc, grid, prior, to, la)
    v = plan_speeds(sc)
    heading = takeoff_heading(grid.bounds, to)
    x0, y0, x1, y1 = grid.bounds
    paths = [[to[k], *routes[k], la[k]] for k in range(len(routes))]
    pos, _ = sampled_sweep(sc, grid, prior, paths)
    for k, r in enumerate(routes):
        wps = np.asarray(r).reshape(-1, 2)
        assert len(wps) >= 2, k
        assert pos[k] > 0.0, k
        assert route_fits(
            np.vstack([to[k], wps, la[k]]),
            v,
            sc.uav.max_turn_rate_rad_s,
            sc.uav.usable_endurance_s,
            reserve_s(sc),
            heading[k],
        ), k
        assert np.all((wps[:, 0] >= x0) & (wps[:, 0] <= x1)), k
        assert np.all((wps[:, 1] >= y0) & (wps[:, 1] <= y1)), k


def test_boxes_are_deterministic_and_thin_where_mass_is_thin():
    """The same input gives the same routes; with a flat prior the boxes take wider spacings
    than W somewhere (coverage below 1 is worth more per line where mass is thin)."""
    sc, grid, _, to, la = _inputs()
    flat = np.full(grid.shape, 1.0 / grid.nx / grid.ny)
    a = _routes(sc, grid, flat, to, la)
    assert a == _routes(sc, grid, flat, to, la)
    w = sc.sensor.sweep_width_m
    gaps = []
    for r in a:
        lines = np.asarray(r).reshape(-1, 2, 2)  # (start, end) per line
        if len(lines) < 2:
            continue
        across = 1 - int(np.argmax(np.abs(lines[0, 1] - lines[0, 0])))  # lines run along x or y
        gaps += list(np.abs(np.diff(lines[:, 0, across])))
    assert max(gaps) > 1.2 * w


def test_more_gain_than_single_width_boxes():
    """Choosing the spacing per UAV finds at least as much (eq. 10 per cell) as boxes at
    spacing W only, on the scenario prior."""
    sc, grid, prior, to, la = _inputs()
    law = sc.sensor.law
    w = sc.sensor.sweep_width_m

    def score(routes):
        cov = sum(path_coverage([to[k], *r, la[k]], grid, w) for k, r in enumerate(routes) if r)
        return float(np.sum(prior * pod_from_coverage(cov, law)))

    one = score(_routes(sc, grid, prior, to, la, spacings=(1.0,)))
    assert score(_routes(sc, grid, prior, to, la)) >= one - 1e-12


def test_uav_out_of_reach_gets_no_route_and_the_others_still_do():
    """Mass only in the map's top row: UAVs from a far field with a short endurance reach
    none of it and get empty routes; with the paper's endurance every UAV gets one."""
    sc, grid, _, to, la = _inputs()
    prior = np.zeros(grid.shape)
    prior[-1, :] = 1.0 / grid.nx
    short = load_scenario("paper_6_2", {"uav.endurance_h": 0.5})
    assert all(r == [] for r in _routes(short, grid, prior, to, la))
    assert all(len(r) >= 2 for r in _routes(sc, grid, prior, to, la))


def test_lazy_greedy_gives_the_eager_greedys_routes():
    """Recomputing every field's candidate each round (eager) gives the same routes as the lazy
    recomputation (gains only fall as coverage is added)."""
    sc, grid, prior, to, la = _inputs("large_400", None, **{"map.cell_km": 20})
    lazy = _routes(sc, grid, prior, to, la, rounds=0)
    eager = PlanOptions(lazy=False)
    assert _routes(sc, grid, prior, to, la, rounds=0, options=eager) == lazy


def test_allocation_plan_records_its_start():
    plan = make_allocation_plan("small")
    assert plan["start"] in ("allocation", "greedy_rectangles", "boxes")
    without = make_allocation_plan("small", box_start=False)
    assert without["start"] != "boxes"


def test_allocation_plan_takes_the_boxes_when_they_win():
    """On a random prior where the boxes' start wins, the plan says so and reaches at least
    the planned POS without the boxes (the refined best of a superset of starts)."""
    from poc_env.agents.experiments.evaluate import episode_prior

    sc = load_scenario("paper_6_2")
    prior = episode_prior(sc, 4)
    plan = make_allocation_plan(sc, prior=prior, refine=1)
    old = make_allocation_plan(sc, prior=prior, refine=1, box_start=False)
    assert plan["start"] == "boxes"
    assert plan["posc"] > old["posc"]


def test_cut_lines_flies_the_first_dropped_line_in_part():
    """A lawnmower of four 10 km lines 1 km apart under a 35 km path budget: three whole lines
    (32 km with the two 1 km steps) and 2 km of the fourth (1 km step, then the part), to the
    bisection's resolution; with ``part`` off the fourth line is dropped whole."""
    lines = []
    for i in range(4):
        ends = [[0.0, i * 1000.0], [10_000.0, i * 1000.0]]
        lines += ends if i % 2 == 0 else ends[::-1]
    wps = np.array(lines)

    def length(q):
        return float(np.hypot(*np.diff(q, axis=0).T).sum()) if len(q) > 1 else 0.0

    def fits(q):
        return length(q) <= 35_000.0

    out, kept = coverage_boxes.cut_lines(wps, fits)
    assert kept == 6
    np.testing.assert_allclose(out[:6], wps[:6])
    assert fits(out)
    step = 10_000.0 / 2 ** PlanOptions().part_steps
    assert 35_000.0 - step <= length(out) <= 35_000.0
    # a part shorter than min_part is not flown
    short, _ = coverage_boxes.cut_lines(wps, fits, min_part=2500.0)
    assert len(short) == 6
    # every line fits: nothing cut
    same, kept = coverage_boxes.cut_lines(wps, lambda q: True)
    assert kept == 8 and np.array_equal(same, wps)


def test_cut_lines_without_parts_drops_whole_lines():
    wps = np.array([[0.0, 0.0], [10_000.0, 0.0], [10_000.0, 1000.0], [0.0, 1000.0]])

    def fits(q):
        return float(np.hypot(*np.diff(q, axis=0).T).sum()) <= 15_000.0

    out, kept = coverage_boxes.cut_lines(wps, fits, options=PlanOptions(part=False))
    assert kept == 2 and len(out) == 2
    assert len(coverage_boxes.cut_lines(wps, fits)[0]) == 4  # with parts: 4 km of the second


def test_chained_lawnmowers_reach_two_blobs():
    """One UAV, two small blobs at the same height 120 km apart: a single box over both wastes
    its lines on the empty ground between them, two chained lawnmowers do not; the chained
    route gains more (eq. 10 per cell), keeps eq. 18 and visits both blobs."""
    sc, grid, _, to, la = _inputs()
    one = sc.with_uavs(1)
    to1, la1 = to[:1], la[:1]
    prior = np.zeros(grid.shape)
    row = grid.ny // 2
    a, b = 6, grid.nx - 7  # cells 6 and nx - 7: 115 km apart on paper_6_2's 5 km cells
    prior[row - 1 : row + 2, a - 1 : a + 2] = 1.0
    prior[row - 1 : row + 2, b - 1 : b + 2] = 1.0
    prior /= prior.sum()
    w = sc.sensor.sweep_width_m
    law = sc.sensor.law

    def score(routes):
        cov = path_coverage([to1[0], *routes[0], la1[0]], grid, w)
        return float(np.sum(prior * pod_from_coverage(cov, law)))

    single = _routes(one, grid, prior, to1, la1, chain=())
    chained = _routes(one, grid, prior, to1, la1)
    assert score(chained) > score(single) + 0.05
    wps = np.asarray(chained[0]).reshape(-1, 2)
    cx = grid.origin_m[0] + (np.array([a, b]) + 0.5) * grid.cell_m
    assert np.min(np.abs(wps[:, 0] - cx[0])) < 2 * grid.cell_m
    assert np.min(np.abs(wps[:, 0] - cx[1])) < 2 * grid.cell_m
    assert route_fits(
        np.vstack([to1[0], wps, la1[0]]),
        plan_speeds(sc),
        sc.uav.max_turn_rate_rad_s,
        sc.uav.usable_endurance_s,
        reserve_s(sc),
        takeoff_heading(grid.bounds, to1)[0],
    )


def test_shared_gain_tables_give_the_per_lawnmower_routes():
    """The gain tables shared among the lawnmowers searched against one coverage (all shares,
    all second lawnmowers after one first) give bit for bit the routes of tables recomputed per
    lawnmower (df0f3b3's path), chains included: paper_6_2's prior, a random prior (seeded) and
    large_400 on 20 km cells."""
    rng = np.random.default_rng(24)
    cases = [_inputs(), _inputs("large_400", None, **{"map.cell_km": 20})]
    sc, grid, _, to, la = cases[0]
    rand = rng.gamma(0.3, size=grid.shape)
    cases.append((sc, grid, rand / rand.sum(), to, la))
    shared = [_routes(*c, rounds=1) for c in cases]
    apart = PlanOptions(share_tables=False)
    for c, got in zip(cases, shared, strict=True):
        assert _routes(*c, rounds=1, options=apart) == got


def test_a_compact_blob_gets_lines_closer_than_a_sweep_width():
    """Spacings below one sweep width (``PlanOptions.dense_spacings``, 0.75 W: coverage
    4/3): a lone UAV with time to spare over a compact blob lays its lines 0.75 W apart, and
    finds more than with the spacings of W and wider only (the environment's detection
    model). Lines evenly spaced (``graded`` off, the default), so the gap is the spacing."""
    sc, grid, _, to, la = _inputs(**{"fleet": [{"takeoff": "A", "count": 1}]})
    ys, xs = np.mgrid[0 : grid.ny, 0 : grid.nx]
    prior = np.exp(-((xs * 5.0 + 2.5 - 40.0) ** 2 + (ys * 5.0 + 2.5 - 30.0) ** 2) / (2 * 8.0**2))
    prior = prior / prior.sum()
    assert min(PlanOptions().dense_spacings) < 1.0
    wide = PlanOptions().spacings
    found = {}
    for name, sp in (("default", None), ("wide", wide)):
        r = _routes(sc, grid, prior, to, la, spacings=sp, chain=())
        found[name] = sampled_sweep(sc, grid, prior, [[to[0], *r[0], la[0]]])[0][0]
        wps = np.asarray(r[0]).reshape(-1, 2)
        n2 = len(wps) // 2 * 2
        mid = 0.5 * (wps[0:n2:2] + wps[1:n2:2])  # the lines' midpoints: one spacing apart
        gaps = np.abs(np.diff(mid, axis=0)).max(axis=1)
        found[name + "_gap"] = float(np.median(gaps))
    assert abs(found["default_gap"] - 0.75 * sc.sensor.sweep_width_m) < 1.0
    assert found["wide_gap"] >= sc.sensor.sweep_width_m - 1.0
    assert found["default"] > found["wide"] + 0.005


def test_clip_lines_keeps_the_parts_inside_the_map():
    """Lines clipped to a rectangle: a crossing line is cut at both edges, a line inside is
    kept, one outside (or left shorter than 1 m) is dropped, the order is kept."""
    wps = np.array([[-10.0, 5.0], [30.0, 5.0], [2.0, 2.0], [8.0, 8.0], [50.0, 50.0], [60.0, 60.0]])
    got = coverage_boxes.clip_lines(wps, (0.0, 0.0, 20.0, 10.0))
    assert np.allclose(got, [[0.0, 5.0], [20.0, 5.0], [2.0, 2.0], [8.0, 8.0]])
    assert len(coverage_boxes.clip_lines(wps[4:], (0.0, 0.0, 20.0, 10.0))) == 0


def test_turned_raster_carries_the_map_cells():
    """The turned raster's sub-cells sample each map cell about once (a turn keeps areas): the
    gains summed over the raster are the map's to a few cells' worth, at 0, 30 and 45 degrees,
    with blocks of one cell and of two."""
    _, grid, prior, _, _ = _inputs()
    for f in (1, 2):
        for deg in (0.0, 30.0, 45.0):
            _, idx = coverage_boxes.turned_raster(grid, f, deg)
            got = np.where(idx >= 0, prior.ravel()[np.maximum(idx, 0)], 0.0).sum()
            assert abs(got - 1.0) < 0.03, (f, deg, got)


def test_turned_boxes_follow_a_diagonal_ridge():
    """A lone UAV over a thin ridge at 45 degrees: with boxes turned by 45 and 135 degrees
    (``PlanOptions.angles``), or to the gain's principal axis (``PlanOptions.axis``), its
    lines run along the ridge and it finds more (the
    environment's detection model) than with axis-aligned boxes only; the lines lie in the map
    and the route keeps eq. 18."""
    sc, grid, _, to, la = _inputs(**{"fleet": [{"takeoff": "A", "count": 1}]})
    ys, xs = np.mgrid[0 : grid.ny, 0 : grid.nx]
    x, y = xs * 5.0 + 2.5 - 60.0, ys * 5.0 + 2.5 - 60.0  # km from the ridge's centre
    along, across = (x + y) / np.sqrt(2), (y - x) / np.sqrt(2)
    prior = np.exp(-(along**2) / (2 * 35.0**2) - across**2 / (2 * 4.0**2))
    prior = prior / prior.sum()
    found, dirs = {}, {}
    for name, angles, axis in (("axes", (), False), ("turned", (45.0, 135.0), False),
                               ("axis", (), True)):  # fmt: skip
        opt = PlanOptions(angles=angles, axis=axis)
        r = _routes(sc, grid, prior, to, la, chain=(), options=opt)
        found[name] = sampled_sweep(sc, grid, prior, [[to[0], *r[0], la[0]]])[0][0]
        wps = np.asarray(r[0]).reshape(-1, 2)
        n2 = len(wps) // 2 * 2
        d = wps[1:n2:2] - wps[0:n2:2]  # the lines
        dirs[name] = np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 180.0
        x0, y0, x1, y1 = grid.bounds
        assert np.all((wps >= [x0 - 1e-6, y0 - 1e-6]) & (wps <= [x1 + 1e-6, y1 + 1e-6]))
        assert route_fits(
            np.vstack([to[0], wps, la[0]]),
            plan_speeds(sc),
            sc.uav.max_turn_rate_rad_s,
            sc.uav.usable_endurance_s,
            reserve_s(sc),
            takeoff_heading(grid.bounds, to)[0],
        )
    assert np.allclose(dirs["turned"], 45.0, atol=1.0), dirs["turned"]
    assert found["turned"] > found["axes"] + 0.02, found
    # the principal axis of the gain around the axis-aligned box (options.axis): the
    # same direction, found without trying every angle
    assert np.allclose(dirs["axis"], 45.0, atol=1.0), dirs["axis"]
    assert found["axis"] > found["axes"] + 0.02, found


def test_excursions_fan_out_far_uavs():
    """Excursions (:mod:`poc_env.agents.planning.excursions`, ``PlanOptions.excursions``):
    two UAVs whose field is just within reach of a blob's rim find more with excursions among
    their candidates than with boxes only (W x length per cell, the candidates' score), and
    their routes keep eq. 18."""
    sc, grid, _, to, la = _inputs("large_400", None, **{"map.cell_km": 10})
    keep = [0, 1]
    to, la = to[keep], la[keep]
    ys, xs = np.mgrid[0 : grid.ny, 0 : grid.nx]
    cx, cy = 210.0, 290.0  # km: the rim ~ 250 km from the field at (80, -30)
    prior = np.exp(-((xs * 10.0 + 5 - cx) ** 2 + (ys * 10.0 + 5 - cy) ** 2) / (2 * 30.0**2))
    prior = prior / prior.sum()
    w, law = sc.sensor.sweep_width_m, sc.sensor.law
    found = {}
    for name, on in (("boxes", False), ("excursions", True)):
        r = _routes(sc, grid, prior, to, la, options=PlanOptions(excursions=on))
        cov = sum(path_coverage([to[k], *r[k], la[k]], grid, w) for k in range(2))
        found[name] = float(np.sum(prior * pod_from_coverage(cov, law)))
        for k in range(2):
            assert route_fits(
                np.vstack([to[k], np.asarray(r[k]).reshape(-1, 2), la[k]]),
                plan_speeds(sc),
                sc.uav.max_turn_rate_rad_s,
                sc.uav.usable_endurance_s,
                reserve_s(sc),
                takeoff_heading(grid.bounds, to)[k],
            )
    assert found["excursions"] > found["boxes"] * 1.05, found


def _blob(grid, cx, cy, sigma):
    ys, xs = np.mgrid[0 : grid.ny, 0 : grid.nx]
    c = grid.cell_m
    p = np.exp(-((xs * c + c / 2 - cx) ** 2 + (ys * c + c / 2 - cy) ** 2) / (2 * sigma**2))
    return p / p.sum()


def test_graded_lines_are_denser_over_the_core_and_find_more():
    """``graded_offsets``: six lines across a 60 x 30 km box over a blob (sigma 6 km) are laid
    closer over its core than at its rim and drawn in from the rim, and find more by the
    environment's detection model (``sampled_sweep``, lines only) than six lines evenly spaced
    over the same box; on a flat box they stay within half a spacing of the even positions."""
    sc, grid, _, _, _ = _inputs()
    w, law, c = sc.sensor.sweep_width_m, sc.sensor.law, grid.cell_m
    prior = _blob(grid, 100e3, 75e3, 6e3)
    lo, hi = np.array([70e3, 60e3]), np.array([130e3, 90e3])
    sl = np.s_[12:18, 14:26]  # the box's cells: rows across (y), cells along (x)
    zero = np.zeros((6, 12))
    off = coverage_boxes.graded_offsets(prior[sl], zero, zero, 6, c, w, law)
    assert len(off) == 6 and np.all(np.diff(off) > 0) and off[0] > 0 and off[-1] < 30e3
    gaps = np.diff(off)
    assert gaps[2] < 0.9 * gaps[0] and gaps[2] < 0.9 * gaps[-1]  # closer over the core
    assert off[-1] - off[0] < 0.8 * 25e3  # drawn in from the rim (even: 25 km first to last)
    even = (np.arange(6) + 0.5) * 5e3

    def found(offsets):
        paths = [[[lo[0], lo[1] + y], [hi[0], lo[1] + y]] for y in offsets]
        return sum(sampled_sweep(sc, grid, prior, paths)[0])

    assert found(off) > found(even) + 0.01
    flat = coverage_boxes.graded_offsets(np.ones((6, 12)), zero, zero, 6, c, w, law)
    assert len(flat) == 6 and np.max(np.abs(flat - even)) <= 2.5e3


def test_cell_steps_sweep_as_sweep_track():
    """The candidates' sampled score (legs cut into steps of at most a cell in one go,
    ``cell_steps``) equals ``sweep_track`` with ``step_m`` a cell, found mass and mass left."""
    sc, grid, prior, _, _ = _inputs()
    rng = np.random.default_rng(7)
    s = sc.sensor.samples_per_cell
    cut = sc.sensor.cutoff_sweep_widths * sc.sensor.sweep_width_m
    from poc_env.theory.search_theory import sweep_segments

    for _ in range(5):
        path = rng.uniform([-10e3, -10e3], [210e3, 160e3], size=(6, 2))
        b1 = grid.refine(prior, s)
        f1 = sweep_track(b1, grid, s, path, 5e3, sc.sensor.law, cut, grid.cell_m)
        b2 = grid.refine(prior, s)
        a, b = coverage_boxes.cell_steps(path, grid.cell_m)
        assert np.all(np.hypot(*(b - a).T) <= grid.cell_m + 1e-6)
        f2 = sweep_segments(b2[None], grid, s, a[None], b[None], 5e3, sc.sensor.law, cut).sum()
        assert abs(f1 - f2) < 1e-12 and np.allclose(b1, b2, rtol=0, atol=1e-15)


def test_sampled_scoring_picks_what_the_environment_finds_more_of():
    """One UAV, one lawnmower, no exchange: the candidates are the same with either score, so
    scored by the environment's model (``sampled``) the route finds at least as much by that
    model as the route W x length per cell picks; on a seeded random prior strictly more."""
    sc, grid, _, to, la = _inputs(**{"fleet": [{"takeoff": "A", "count": 1}]})
    s = sc.sensor.samples_per_cell
    cut = sc.sensor.cutoff_sweep_widths * sc.sensor.sweep_width_m
    rng = np.random.default_rng(3)
    on = PlanOptions(sampled=True)
    gains = []
    for _ in range(3):
        prior = rng.gamma(0.3, size=grid.shape)
        prior /= prior.sum()
        got = {}
        for name, smp in (("cell", None), ("sampled", (grid.refine(prior, s), s, cut))):
            r = _routes(sc, grid, prior, to, la, chain=(), rounds=0, sampled=smp, options=on)
            got[name] = sampled_sweep(sc, grid, prior, [[to[0], *r[0], la[0]]])[0][0]
        gains.append(got["sampled"] - got["cell"])
    assert min(gains) >= -1e-12 and max(gains) > 1e-4


def test_violation_penalty_prices_field_mates_flying_together():
    """``allocation.violation_penalty``: every UAV on one route (field-mates together within
    d_s, eq. 21) is priced at the reward's rate, ``violation_penalty`` x UAV-steps / (alpha x
    UAVs): positive, twice as much at twice the penalty weight, half at twice alpha, none with
    no route."""
    from poc_env.agents.planning.allocation import violation_penalty

    sc = load_scenario("small")
    grid = Grid.from_config(sc.map)
    x0, y0, x1, y1 = grid.bounds
    same = [
        [[x0 + 0.3 * (x1 - x0), y0 + 0.5 * (y1 - y0)], [x0 + 0.7 * (x1 - x0), y0 + 0.5 * (y1 - y0)]]
    ]
    routes = same * len(sc.takeoff_m)
    p = violation_penalty(sc, routes)
    rw = sc.reward
    assert p > 0.0
    double = load_scenario("small", {"reward.violation_penalty": 2 * rw.violation_penalty})
    assert abs(violation_penalty(double, routes) - 2 * p) < 1e-12
    alpha = load_scenario("small", {"reward.alpha": 2 * rw.alpha})
    assert abs(violation_penalty(alpha, routes) - p / 2) < 1e-12
    assert violation_penalty(sc, [[] for _ in routes]) == 0.0
