"""The planner's eq. 25-26 objective: equal to the slow reference, honest, and well guarded."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import shapely

from poc_env.agents.planning.objective import (
    PlanObjective,
    area_fractions,
    exclusive_fractions,
    flown_rectangle,
    lawnmower,
)
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.geometry import covers_points, rectangle_polygon
from poc_env.theory.patterns import parallel_line_search, parallel_search
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import pod_from_coverage, pod_parallel
from poc_env.theory.timing import flight_time_s


@pytest.fixture(scope="module")
def small():
    return PlanObjective("small")


@pytest.fixture(scope="module")
def paper():
    return PlanObjective("paper_6_2")


def _population(obj: PlanObjective, size: int, seed: int, *, compact: bool = True) -> np.ndarray:
    """Random individuals; ``compact`` ones (sides up to a quarter of the map) are mostly
    feasible, so that J -- not the penalty -- dominates their values."""
    rng = np.random.default_rng(seed)
    lo, hi = obj.bounds.T
    x = (lo + rng.random((size, obj.dim)) * (hi - lo)).reshape(size, obj.n, 6)
    if compact:
        side_hi = lo[2] + 0.25 * (hi[2] - lo[2])
        x[..., 2:4] = rng.uniform(lo[2], side_hi, (size, obj.n, 2))
        x[..., 5] = rng.uniform(0.6, 3.0, (size, obj.n)) * obj.sweep_width_m
    return x.reshape(size, obj.dim)


# --------------------------------------------------------------------------- geometry


def test_closed_form_lawnmower_equals_generated_track():
    rng = np.random.default_rng(0)
    for _ in range(300):
        c = rng.uniform(-1e5, 1e5, 2)
        ln, wd = rng.uniform(1e3, 8e4, 2)
        if rng.random() < 0.3:  # thinner than the spacing: one line through the middle
            wd = rng.uniform(100, 900)
        th = rng.uniform(0, np.pi)
        d = rng.uniform(1e3, 2e4)
        start = rng.uniform(-2e5, 2e5, 2)
        track = parallel_line_search(c, ln, wd, th, d, start=start)
        m = lawnmower(c, ln, wd, th, d, start)
        assert m.track_m == pytest.approx(track.length_m, rel=1e-6)
        assert m.search_m == pytest.approx(track.search_length_m, rel=1e-6)
        assert int(m.n_lines) == len(track.search_legs())
        np.testing.assert_allclose(m.first_m, track.waypoints[0], atol=1e-6)
        np.testing.assert_allclose(m.last_m, track.waypoints[-1], atol=1e-6)


def test_line_count_rule():
    # n = max(1, ceil(E/d - 1/2)): lines d/2, 3d/2, ... from one edge while inside
    for short, n in [(0.3, 1), (0.99, 1), (1.0, 1), (1.4, 1), (1.6, 2), (2.4, 2), (2.6, 3)]:
        m = lawnmower((0.0, 0.0), 50.0, short * 10.0, 0.3, 10.0, (0.0, -100.0))
        assert int(m.n_lines) == n, short
        track = parallel_line_search((0.0, 0.0), 50.0, short * 10.0, 0.3, 10.0)
        assert len(track.search_legs()) == n


def test_area_fractions_are_exact():
    grid = Grid(12, 9, 5000.0, (-10000.0, 2000.0))
    boxes = np.array(grid.cell_boxes(), dtype=object)
    rng = np.random.default_rng(3)
    thetas = [0.0, np.pi / 2, np.pi / 4, np.pi, 1e-12, *rng.uniform(0, np.pi, 40)]
    for th in thetas:
        c = rng.uniform((-20000, -5000), (60000, 50000))  # some reach beyond the map
        ln, wd = rng.uniform(500, 40000, 2)
        got = area_fractions(grid, c, ln, wd, th)
        rect = rectangle_polygon(c, ln, wd, th)
        want = shapely.area(shapely.intersection(rect, boxes)) / grid.cell_area_m2
        np.testing.assert_allclose(got, want.reshape(grid.shape), rtol=0, atol=1e-9)


def test_exclusive_fractions_are_exact_under_heavy_overlap():
    grid = Grid(10, 8, 5000.0, (0.0, 0.0))
    boxes = np.array(grid.cell_boxes(), dtype=object)
    rng = np.random.default_rng(4)
    for trial in range(60):
        n = int(rng.integers(2, 8))
        c = rng.uniform((5000, 5000), (45000, 35000), (n, 2))
        ln, wd = rng.uniform(1000, 40000, (2, n))
        th = rng.uniform(0, np.pi, n) if trial % 4 else rng.choice([0, np.pi / 4, np.pi / 2], n)
        for i in range(1, n):  # copies, hair-breadth copies and near copies of earlier UAVs
            if rng.random() < 0.4:
                k = rng.integers(0, i)
                c[i] = c[k] + rng.choice([0.0, 1e-6, 300.0])
                ln[i], wd[i], th[i] = ln[k], wd[k], th[k] + rng.choice([0.0, 1e-9, 0.1])
        got = exclusive_fractions(grid, c[None], ln[None], wd[None], th[None])[0]
        rects = [rectangle_polygon(c[i], ln[i], wd[i], th[i]) for i in range(n)]
        for i in range(n):
            own = rects[i].difference(shapely.union_all(rects[:i])) if i else rects[i]
            want = shapely.area(shapely.intersection(own, boxes)) / grid.cell_area_m2
            np.testing.assert_allclose(got[i], want.reshape(grid.shape), rtol=0, atol=1e-9)
        assert np.all(got.sum(axis=0) <= 1 + 1e-12)


# --------------------------------------------------------------------------- objective


def test_objective_equals_scalar_reference_small():
    obj = PlanObjective("small", beta=0.3)
    x = np.vstack([_population(obj, 12, 1), _population(obj, 4, 2, compact=False)])
    fast = obj(x)
    slow = np.array([obj.scalar_score(xi) for xi in x])
    np.testing.assert_allclose(fast, slow, rtol=1e-9, atol=1e-12)
    assert np.sum(obj.evaluate(x).overtime_s.sum(axis=1) == 0) >= 6  # J-dominated cases


def test_objective_equals_scalar_reference_paper(paper):
    x = _population(paper, 6, 5)
    # overlapping rectangles exercise the overlap rule
    x[0, 6:12] = x[0, 0:6] + np.array([3000.0, -2000.0, 0.0, 0.0, 0.2, 0.0])
    fast = paper(x)
    slow = np.array([paper.scalar_score(xi) for xi in x])
    np.testing.assert_allclose(fast, slow, rtol=1e-9, atol=1e-12)


def test_objective_is_eq_26(small):
    obj = PlanObjective("small", beta=0.5)
    x = np.vstack([_population(obj, 5, 7), _population(obj, 5, 8, compact=False)])
    sc = obj.evaluate(x)
    usable = 0.85 * obj.endurance_s
    posc = np.sum(sc.poc * sc.pod, axis=1)
    j = obj.alpha * posc - obj.beta * np.mean(sc.time_s / usable, axis=1)
    phi = np.maximum(0.0, sc.time_s - usable)
    assert np.any(phi > 0) and np.any(phi.sum(axis=1) == 0)
    np.testing.assert_allclose(sc.objective, -j + obj.penalty_m * phi.sum(axis=1), rtol=1e-12)
    assert obj(x[0]) == pytest.approx(sc.objective[0], rel=1e-12)
    assert isinstance(obj(x[0]), float)


def test_flight_time_is_eq_17_of_the_generated_track(paper):
    x = _population(paper, 1, 11)[0]
    for uav in paper.decode(x):
        t = flight_time_s(
            uav["takeoff_m"],
            uav["waypoints_m"],
            uav["landing_m"],
            paper.cruise_speed_mps,
            paper.search_speed_mps,
        )
        assert uav["flight_time_s"] == pytest.approx(t, rel=1e-9)
        assert uav["feasible"] == (t <= 0.85 * paper.endurance_s)


@pytest.mark.parametrize("seed", range(4))
def test_reflying_the_flown_rectangle_gives_the_plans_flight_time(paper, seed, usual_lawnmower):
    """Deliverable 5: the exported strip, flown by the documented rule with the project's
    generator and by the usual ceil(E/d) lawnmower, gives the plan's eq. 17 time (1e-6 rel)."""
    x = _population(paper, 1, 100 + seed, compact=seed % 2 == 0)[0]
    for uav in paper.decode(x):
        fr = uav["flown_rectangle"]
        c, line_length = np.asarray(fr["center_m"]), fr["line_length_m"]
        strip, alpha, d = fr["strip_width_m"], fr["lines_theta_rad"], uav["spacing_m"]
        rect = rectangle_polygon(c, line_length, strip, alpha)
        track = parallel_search(rect, d, 0.5 * np.pi - alpha, start=uav["takeoff_m"])
        n_usual, usual = usual_lawnmower(c, line_length, strip, alpha, d, uav["takeoff_m"])
        assert n_usual == uav["n_lines"] == len(track.search_legs())
        for wp in (track.waypoints, usual):
            t = flight_time_s(
                uav["takeoff_m"],
                wp,
                uav["landing_m"],
                paper.cruise_speed_mps,
                paper.search_speed_mps,
            )
            assert uav["flight_time_s"] == pytest.approx(t, rel=1e-6)


def test_flown_rectangle_of_a_narrow_and_a_wide_rectangle():
    d = 10.0
    c, ln, strip, alpha = flown_rectangle((0.0, 0.0), 100.0, 4.0, 0.0, d)  # one middle line
    assert (ln, strip, alpha) == (100.0, d, 0.0) and np.allclose(c, 0.0)
    c, ln, strip, alpha = flown_rectangle((0.0, 0.0), 100.0, 34.0, 0.0, d)  # n = 3, +y edge
    assert (ln, strip) == (100.0, 30.0) and np.allclose(c, [0.0, 2.0])


@pytest.mark.parametrize("seed", range(3))
def test_every_waypoint_lies_in_the_map(paper, seed):
    """Deliverable 5: the map repair keeps every rectangle, line and waypoint in the map."""
    x0, y0, x1, y1 = paper.grid.bounds
    x = _population(paper, 20, 200 + seed, compact=False)
    for xi in x:
        for uav in paper.decode(xi):
            wp = np.asarray(uav["waypoints_m"])
            assert (wp[:, 0] >= x0 - 1).all() and (wp[:, 0] <= x1 + 1).all()
            assert (wp[:, 1] >= y0 - 1).all() and (wp[:, 1] <= y1 + 1).all()


def test_map_repair_leaves_inside_rectangles_alone(paper):
    x = _population(paper, 1, 300)[0].reshape(paper.n, 6)
    cx, cy = np.mean(np.asarray(paper.grid.bounds).reshape(2, 2), axis=0)
    x[:, 0:2] = (cx, cy)
    x[:, 2:4] = 1000.0
    f = paper.split(x.reshape(-1))
    assert np.array_equal(np.stack([f[k][0] for k in ("x_c", "y_c", "l", "w")], -1), x[:, :4])
    x[:, 0] = paper.grid.bounds[2] + 5000.0  # centre east of the map: pulled back inside
    f = paper.split(x.reshape(-1))
    assert np.allclose(
        f["x_c"][0]
        + 0.5
        * (f["l"][0] * np.abs(np.cos(f["theta"][0])) + f["w"][0] * np.abs(np.sin(f["theta"][0]))),
        paper.grid.bounds[2],
    )


def test_decoded_waypoints_lie_in_their_rectangles(paper):
    x = _population(paper, 1, 12)[0]
    for uav in paper.decode(x):
        rect = rectangle_polygon(uav["center_m"], uav["length_m"], uav["width_m"], uav["theta_rad"])
        assert covers_points(rect, np.asarray(uav["waypoints_m"]), tol=1e-6).all()
        assert uav["n_lines"] >= 1 and 0 <= uav["pod"] <= 1


def test_overlap_rule_a_copy_adds_nothing(small):
    x = _population(small, 1, 13)[0].reshape(small.n, 6)
    x[1] = x[0]  # UAV 1 searches exactly UAV 0's rectangle
    x[2] = x[0]
    sc = small.evaluate(x.reshape(1, -1))
    assert sc.poc[0, 0] > 0
    assert sc.poc[0, 1] == 0 and sc.poc[0, 2] == 0


# --------------------------------------------------------------------------- loopholes


def _uniform_objective(w_sweep_km: float = 2.5) -> tuple[PlanObjective, np.ndarray]:
    sc = load_scenario("small", {"sensor.sweep_width_km": w_sweep_km}).with_uavs(1)
    rng = np.random.default_rng(21)
    prior = rng.random((8, 8)) + 0.5
    return PlanObjective(sc, prior / prior.sum()), prior / prior.sum()


def test_loophole_1_edges_on_cell_centres_gain_nothing():
    obj, prior = _uniform_objective()
    c = obj.grid.cell_m
    # axis-aligned rectangle from the centre of cell 1 to the centre of cell 5 on both axes
    lo, hi = 1.5 * c, 5.5 * c
    x = np.array([0.5 * (lo + hi), 0.5 * (lo + hi), hi - lo, hi - lo, 0.0, 2500.0])
    hair = 1e-3  # metres
    shifted = [x + np.array([dx, dy, 0, 0, 0, 0]) for dx in (-hair, hair) for dy in (-hair, hair)]
    poc = obj.evaluate(np.vstack([x, *shifted])).poc[:, 0]
    # continuous: shifting by a millimetre changes POC by (almost) nothing
    assert np.max(np.abs(poc[1:] - poc[0])) < 1e-6 * poc[0]
    # and equal to the area-weighted sum: half the edge cells, a quarter of the corners
    w1 = np.array([0, 0.5, 1, 1, 1, 0.5, 0, 0])
    assert poc[0] == pytest.approx(float(w1 @ prior @ w1), rel=1e-12)
    # the "cell centre inside" rule would have credited a whole extra row and column
    centres = obj.grid.centers
    inside = (centres >= lo - 1e-9) & (centres <= hi + 1e-9)
    centre_rule = prior[inside.all(axis=-1)].sum()
    assert centre_rule > 1.15 * poc[0]


def test_loophole_1_poc_is_continuous_for_rotated_rectangles(paper):
    x = _population(paper, 20, 14)
    bumped = x.copy()
    bumped[:, 0::6] += 1e-3  # every centre 1 mm east
    bumped[:, 4::6] += 1e-9  # every angle a nano-radian more
    a, b = paper.evaluate(x).poc, paper.evaluate(bumped).poc
    assert np.max(np.abs(a - b)) < 1e-8


def test_loophole_2_one_pass_is_not_credited_eq_10():
    obj, _ = _uniform_objective()
    w_sweep = obj.sweep_width_m
    d = 2.0 * w_sweep
    short = 1.4 * d  # wider than the spacing, but parallel_line_search flies one line
    x = np.array([20000.0, 20000.0, 30000.0, short, 0.0, d])
    assert len(parallel_line_search(x[:2], x[2], x[3], x[4], d).search_legs()) == 1
    pod = obj.evaluate(x[None]).pod[0, 0]
    eq10 = float(pod_parallel(w_sweep, d))
    flown = float(pod_from_coverage(w_sweep * 30000.0 / (30000.0 * short)))
    assert pod == pytest.approx(flown, rel=1e-12)
    assert pod < 0.75 * eq10
    # with enough lines (E = 2 d: two lines) eq. 10 is exactly what is credited
    x[3] = 2.0 * d
    assert obj.evaluate(x[None]).pod[0, 0] == pytest.approx(eq10, rel=1e-12)


def test_loophole_2_pod_never_exceeds_the_flown_effort_or_eq_10(paper):
    x = _population(paper, 50, 15, compact=False)
    sc = paper.evaluate(x)
    f = paper.split(x)
    effort = pod_from_coverage(paper.sweep_width_m * sc.search_length_m / (f["l"] * f["w"]))
    eq10 = pod_parallel(paper.sweep_width_m, f["d"])
    assert np.all(sc.pod <= effort * (1 + 1e-12))
    assert np.all(sc.pod <= eq10 * (1 + 1e-12))
    # a rectangle thinner than d (one line through its middle) gets at most eq. 10
    thin = np.array([50000.0, 50000.0, 40000.0, 3000.0, 0.7, 8000.0] * paper.n)
    assert np.allclose(paper.evaluate(thin[None]).pod, pod_parallel(paper.sweep_width_m, 8000.0))


# --------------------------------------------------------------------------- encoding, bad input


def test_bounds_document_the_encoding(paper):
    b = paper.bounds
    assert b.shape == (36, 2) and np.all(b[:, 0] < b[:, 1])
    x0, y0, x1, y1 = paper.grid.bounds
    w = paper.sweep_width_m
    np.testing.assert_allclose(
        b[:6], [[x0, x1], [y0, y1], [w / 2, 200e3], [w / 2, 200e3], [0, np.pi], [w / 2, 4 * w]]
    )


def test_zero_uavs_and_other_bad_input(small):
    with pytest.raises(ConfigError, match="uavs"):
        PlanObjective("small", uavs=0)
    with pytest.raises(ConfigError, match="uavs"):
        load_scenario("small").with_uavs(0)
    with pytest.raises(ConfigError, match="prior"):
        PlanObjective("small", prior=np.ones((3, 3)))
    with pytest.raises(ConfigError, match="x"):
        small(np.zeros((4, small.dim + 1)))
    assert PlanObjective("small", uavs=5).dim == 30


def test_unreachable_area_is_a_clear_error():
    sc = load_scenario("small")
    far = dataclasses.replace(sc.airfields[0], position_m=(20000.0, -400000.0))
    with pytest.raises(ConfigError, match="endurance"):
        PlanObjective(dataclasses.replace(sc, airfields=(far,)))


def test_planner_weights_are_its_own_not_the_rl_rewards(small):
    """A training override of the RL reward leaves every plan's objective as it was; the
    scenario's ``planner.alpha`` / ``planner.beta`` are eq. 25's weights."""
    x = np.vstack([_population(small, 6, 9), _population(small, 2, 10, compact=False)])
    rl = PlanObjective(load_scenario("small", {"reward.alpha": 100.0, "reward.beta": 5.0}))
    assert (rl.alpha, rl.beta) == (small.alpha, small.beta) == (1.0, 0.0)
    np.testing.assert_array_equal(rl(x), small(x))
    sc = load_scenario("small", {"planner.alpha": 2.0, "planner.beta": 0.5})
    weighted = PlanObjective(sc)
    assert (weighted.alpha, weighted.beta) == (2.0, 0.5)
    s = small.evaluate(x)
    share = np.mean(s.time_s / (0.85 * small.endurance_s), axis=1)
    phi = small.penalty_m * np.maximum(0.0, s.time_s - 0.85 * small.endurance_s).sum(axis=1)
    posc = np.sum(s.poc * s.pod, axis=1)
    np.testing.assert_allclose(weighted(x), -(2.0 * posc - 0.5 * share) + phi, rtol=1e-12)
    assert np.all(weighted(x) != small(x))
    assert PlanObjective(sc, alpha=1.0, beta=0.0)(x[0]) == small(x[0])  # arguments win
    for key, bad in (("planner.alpha", -1.0), ("planner.beta", float("nan"))):
        with pytest.raises(ConfigError, match=key):
            load_scenario("small", {key: bad})


def test_compiled_plan_pass_equals_split_lawnmower_and_exclusive_masses(paper):
    """``plan_rectangles`` (compiled passes per population: map repair, lawnmower,
    transit and the exclusive prior masses by boundary integrals) against the numpy steps:
    ``split``, :func:`lawnmower`, the transit lengths and the dense exclusive fractions times
    the prior, to 1e-12 (masses: of the rectangle's plain mass)."""
    from poc_env.agents.planning.objective import plan_rectangles

    x = np.vstack([_population(paper, 40, 8), _population(paper, 40, 9, compact=False)])
    x[:10, 6:12] = x[:10, 0:6]  # copies of the UAV before
    geo = np.empty((len(x), paper.n, 5))
    terms = np.empty((len(x), paper.n, 6))
    plan_rectangles(
        np.ascontiguousarray(x),
        np.array(paper.grid.bounds, dtype=float),
        paper.takeoff_m,
        paper.landing_m,
        *map(float, paper.grid.origin_m),
        paper.grid.cell_m,
        paper.prior,
        geo,
        terms,
    )
    f = paper.split(x)
    for k, name in enumerate(("x_c", "y_c", "l", "w", "theta")):
        np.testing.assert_allclose(geo[..., k], f[name], rtol=1e-12, atol=0)
    center = np.stack([f["x_c"], f["y_c"]], axis=-1)
    mower = lawnmower(center, f["l"], f["w"], f["theta"], f["d"], paper.takeoff_m[None])
    transit = np.linalg.norm(mower.first_m - paper.takeoff_m, axis=-1) + np.linalg.norm(
        paper.landing_m - mower.last_m, axis=-1
    )
    want = [mower.n_lines, mower.line_length_m, mower.search_m, mower.track_m, transit]
    for k, w in enumerate(want):
        np.testing.assert_allclose(terms[..., k], w, rtol=1e-12, atol=0)
    args = (paper.grid, center, f["l"], f["w"], f["theta"])
    prior = paper.prior[None, None]
    plain = np.sum(area_fractions(*args) * prior, axis=(-2, -1))
    excl = np.sum(exclusive_fractions(*args) * prior, axis=(-2, -1))
    assert np.all(excl[:10, 1] < 1e-9 * plain[:10, 1]) and np.all(plain[:10, 1] > 0)
    assert np.all(np.abs(terms[..., 5] - excl) <= 1e-12 * plain)


def test_a_sweep_width_too_narrow_for_the_line_limit_is_refused_naming_it():
    """W = 1 mm on a 40 km map: the DE plan's lines at d >= W/2 could number millions; the
    plan was optimised, then decoding it failed naming ``spacing_m``, an internal value the
    user never set (config-audit). Refused when the objective is built, naming the sensor."""
    narrow = load_scenario("small", {"sensor.sweep_width_km": 1e-6})
    with pytest.raises(ConfigError, match=r"sensor\.sweep_width_km: .*allowed: at least 0\.00113"):
        PlanObjective(narrow)
    PlanObjective(load_scenario("small", {"sensor.sweep_width_km": 0.0012}))  # just enough
