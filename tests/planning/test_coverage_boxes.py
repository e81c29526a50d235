"""Coverage boxes: one lawnmower box per UAV, its own spacing, within the flight rules."""

import numpy as np

from poc_env.agents.planning import coverage_boxes
from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.agents.planning.coverage_boxes import box_routes
from poc_env.agents.planning.flight_rules import path_coverage, plan_speeds, reserve_s
from poc_env.agents.planning.refine import route_fits
from poc_env.config import load_scenario
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import pod_from_coverage


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


def test_lazy_greedy_gives_the_eager_greedys_routes(monkeypatch):
    """Recomputing every field's candidate each round (eager) gives the same routes as the lazy
    recomputation (gains only fall as coverage is added)."""
    sc, grid, prior, to, la = _inputs("large_400", None, **{"map.cell_km": 20})
    lazy = _routes(sc, grid, prior, to, la, rounds=0)
    monkeypatch.setattr(coverage_boxes, "LAZY", False)
    assert _routes(sc, grid, prior, to, la, rounds=0) == lazy


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
    bisection's resolution; with ``PART`` off the fourth line is dropped whole."""
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
    step = 10_000.0 / 2**coverage_boxes.PART_STEPS
    assert 35_000.0 - step <= length(out) <= 35_000.0
    # a part shorter than min_part is not flown
    short, _ = coverage_boxes.cut_lines(wps, fits, min_part=2500.0)
    assert len(short) == 6
    # every line fits: nothing cut
    same, kept = coverage_boxes.cut_lines(wps, lambda q: True)
    assert kept == 8 and np.array_equal(same, wps)


def test_cut_lines_without_parts_drops_whole_lines(monkeypatch):
    monkeypatch.setattr(coverage_boxes, "PART", False)
    wps = np.array([[0.0, 0.0], [10_000.0, 0.0], [10_000.0, 1000.0], [0.0, 1000.0]])
    out, kept = coverage_boxes.cut_lines(
        wps, lambda q: float(np.hypot(*np.diff(q, axis=0).T).sum()) <= 15_000.0
    )
    assert kept == 2 and len(out) == 2


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


def test_shared_gain_tables_give_the_per_lawnmower_routes(monkeypatch):
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
    monkeypatch.setattr(coverage_boxes, "_SHARE_TABLES", False)
    for c, got in zip(cases, shared, strict=True):
        assert _routes(*c, rounds=1) == got


def test_a_compact_blob_gets_lines_closer_than_a_sweep_width():
    """Spacings below one sweep width (:data:`coverage_boxes.DENSE_SPACINGS`, 0.75 W: coverage
    4/3): a lone UAV with time to spare over a compact blob lays its lines 0.75 W apart, and
    finds more than with the spacings of W and wider only (the environment's detection
    model)."""
    sc, grid, _, to, la = _inputs(**{"fleet": [{"takeoff": "A", "count": 1}]})
    ys, xs = np.mgrid[0 : grid.ny, 0 : grid.nx]
    prior = np.exp(-((xs * 5.0 + 2.5 - 40.0) ** 2 + (ys * 5.0 + 2.5 - 30.0) ** 2) / (2 * 8.0**2))
    prior = prior / prior.sum()
    assert min(coverage_boxes.DENSE_SPACINGS) < 1.0
    wide = coverage_boxes.SPACINGS
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


def test_turned_boxes_follow_a_diagonal_ridge(monkeypatch):
    """A lone UAV over a thin ridge at 45 degrees: with boxes turned by 45 and 135 degrees
    (:data:`coverage_boxes.ANGLES`), or to the gain's principal axis (:data:`coverage_boxes.
    AXIS`), its lines run along the ridge and it finds more (the
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
        monkeypatch.setattr(coverage_boxes, "ANGLES", angles)
        monkeypatch.setattr(coverage_boxes, "AXIS", axis)
        r = _routes(sc, grid, prior, to, la, chain=())
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
    # the principal axis of the gain around the axis-aligned box (coverage_boxes.AXIS): the
    # same direction, found without trying every angle
    assert np.allclose(dirs["axis"], 45.0, atol=1.0), dirs["axis"]
    assert found["axis"] > found["axes"] + 0.02, found


def test_excursions_fan_out_far_uavs(monkeypatch):
    """Excursions (:mod:`poc_env.agents.planning.excursions`, :data:`coverage_boxes.EXCURSIONS`):
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
        monkeypatch.setattr(coverage_boxes, "EXCURSIONS", on)
        r = _routes(sc, grid, prior, to, la)
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
