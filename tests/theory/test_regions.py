"""Tests of poc_env.theory.regions: regions (eq. 1-2), area-weighted POC, eq. 3-4, rectangle mass
(the rectangle-cut allocation: tests/planning/test_rectangle_cut.py)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely
from shapely.geometry import box

from poc_env.config import GaussianComponent
from poc_env.errors import ConfigError, GeometryError
from poc_env.geometry import rectangle_polygon
from poc_env.theory.probability_map import Grid, gaussian_mixture
from poc_env.theory.regions import (
    CircleRegion,
    PolygonRegion,
    average_poc,
    cell_overlap,
    rectangle_mass,
    region_poc,
    region_pocs,
)

SMALL = Grid(4, 3, 10.0)  # cells of 10 m; x in [0, 40], y in [0, 30]


def square(x0, y0, x1, y1, name="square"):
    return PolygonRegion(((x0, y0), (x1, y0), (x1, y1), (x0, y1)), name=name)


# --------------------------------------------------------------------------- regions


def test_polygon_region_stores_floats_area_and_holes():
    r = PolygonRegion([[0, 0], [4, 0], [4, 4], [0, 4]], holes=[[[1, 1], [2, 1], [2, 2], [1, 2]]])
    assert r.vertices == ((0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0))
    assert isinstance(r.vertices[0][0], float)
    assert r.area_m2 == pytest.approx(15.0)
    assert r.geometry.area == pytest.approx(15.0)
    back = PolygonRegion.from_geometry(r.geometry)
    assert back.area_m2 == pytest.approx(15.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.vertices = ()  # type: ignore[misc]


def test_circle_region_area_and_geometry():
    c = CircleRegion((3.0, -2.0), 50.0)
    assert c.area_m2 == pytest.approx(math.pi * 2500.0, rel=1e-15)
    assert c.geometry.area == pytest.approx(math.pi * 2500.0, rel=1e-3)
    assert c.geometry.centroid.x == pytest.approx(3.0, abs=1e-9)
    # the polygon hugs the circle: every vertex within 0.1 % of r of the circle
    xy = np.asarray(c.geometry.exterior.coords)
    r = np.hypot(xy[:, 0] - 3.0, xy[:, 1] + 2.0)
    assert np.all(np.abs(r - 50.0) < 0.05)


@pytest.mark.parametrize(
    ("vertices", "match"),
    [
        ([(0, 0), (2, 2), (2, 0), (0, 1)], "Self-intersection"),  # lopsided bow-tie
        ([(0, 0), (1, 1), (1, 0), (0, 1)], "zero area|invalid"),  # symmetric bow-tie
        ([(0, 0), (1, 1)], "at least 3"),
        ([(0, 0), (1, 1), (2, 2)], "zero area"),
        ([(0, 0), (1, 0), (1, 1), (0, 0), (1, 0), (1, 1)], "zero area|invalid"),
    ],
)
def test_bad_polygons_raise_geometry_error_naming_the_region(vertices, match):
    with pytest.raises(GeometryError, match=match) as err:
        PolygonRegion(vertices, name="zone A")
    assert "zone A" in str(err.value)


@pytest.mark.parametrize("radius", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_circle_radius_raises_geometry_error(radius):
    with pytest.raises(GeometryError, match="radius_m") as err:
        CircleRegion((0.0, 0.0), radius)
    assert repr(float(radius)) in str(err.value) or str(radius) in str(err.value)


def test_bad_circle_center_raises():
    with pytest.raises(GeometryError, match="center_m"):
        CircleRegion((0.0, float("nan")), 1.0)
    with pytest.raises(GeometryError, match="center_m"):
        CircleRegion("ab", 1.0)  # type: ignore[arg-type]


# --------------------------------------------------------------------------- cell overlap


def test_overlap_of_one_cell_is_one_there_and_zero_elsewhere():
    ov = cell_overlap(square(20, 10, 30, 20), SMALL)
    want = np.zeros((3, 4))
    want[1, 2] = 1.0  # row 1 from the south, column 2 from the west
    np.testing.assert_allclose(ov, want, atol=1e-12)


def test_overlap_respects_grid_origin():
    grid = Grid(3, 2, 10.0, origin_m=(100.0, -50.0))
    ov = cell_overlap(box(110, -40, 120, -30), grid)  # shapely input, cell (j=1, i=1)
    want = np.zeros((2, 3))
    want[1, 1] = 1.0
    np.testing.assert_allclose(ov, want, atol=1e-12)


def test_overlap_of_half_cell_triangle_is_half():
    ov = cell_overlap(PolygonRegion([(20, 10), (30, 10), (30, 20)]), SMALL)
    want = np.zeros((3, 4))
    want[1, 2] = 0.5
    np.testing.assert_allclose(ov, want, atol=1e-12)


def test_overlap_of_whole_grid_is_all_ones_and_outside_part_is_ignored():
    np.testing.assert_allclose(cell_overlap(square(0, 0, 40, 30), SMALL), 1.0, atol=1e-12)
    # a square sticking out of the south-west corner covers a quarter of cell (0, 0)
    ov = cell_overlap(square(-20, -20, 5, 5), SMALL)
    want = np.zeros((3, 4))
    want[0, 0] = 0.25
    np.testing.assert_allclose(ov, want, atol=1e-12)
    # a region entirely off the grid overlaps nothing
    assert not np.any(cell_overlap(square(100, 100, 110, 110), SMALL))


def test_circle_overlap_sums_to_its_area():
    grid = Grid(20, 20, 10.0)
    c = CircleRegion((101.3, 97.2), 63.0)  # off-centre so that cells are cut unevenly
    ov = cell_overlap(c, grid)
    assert ov.min() >= 0.0 and ov.max() <= 1.0
    assert ov[9, 10] == 1.0  # a cell well inside
    assert ov.sum() * grid.cell_area_m2 == pytest.approx(math.pi * 63.0**2, rel=2e-3)
    # some cells are cut: overlap is not just 0 / 1
    assert np.sum((ov > 0.01) & (ov < 0.99)) > 10


# --------------------------------------------------------------------------- POC


@pytest.fixture
def hot_prior():
    p = np.zeros(SMALL.shape)
    p[1, 2] = 0.6  # the hot cell [20, 30] x [10, 20], centre (25, 15)
    p[0, 0] = 0.4  # cell [0, 10] x [0, 10]
    return p


def test_region_poc_is_area_weighted_not_centre_tested(hot_prior):
    # bottom quarter of the hot cell: its centre is outside, a centre test would give 0
    assert region_poc(square(20, 10, 30, 12.5), SMALL, hot_prior) == pytest.approx(0.15)
    # bottom three quarters: its centre is inside, a centre test would give 0.6
    assert region_poc(square(20, 10, 30, 17.5), SMALL, hot_prior) == pytest.approx(0.45)
    # a quarter of each of the two hot cells: 0.25 * 0.4 + 0.25 * 0.6
    assert region_poc(square(5, 5, 25, 15), SMALL, hot_prior) == pytest.approx(0.25)
    # a circle of radius 2 m inside the hot cell: pi * 4 / 100 of it
    c = CircleRegion((24.0, 16.0), 2.0)
    assert region_poc(c, SMALL, hot_prior) == pytest.approx(0.6 * math.pi * 4 / 100, rel=1e-3)


def test_region_poc_of_whole_grid_is_one():
    grid = Grid(12, 9, 100.0)
    prior = gaussian_mixture(
        grid, [GaussianComponent(mean_m=(400.0, 300.0), sigma_m=(200.0, 150.0))], background=0.1
    )
    assert region_poc(grid.polygon(), grid, prior) == pytest.approx(1.0, abs=1e-12)
    assert region_poc(square(0, 0, 600, 900), grid, prior) < 1.0


def test_region_pocs_counts_each_region(hot_prior):
    pocs = region_pocs([square(20, 10, 30, 20), square(20, 10, 25, 20)], SMALL, hot_prior)
    np.testing.assert_allclose(pocs, [0.6, 0.3])


def test_prior_of_wrong_shape_is_a_config_error():
    with pytest.raises(ConfigError, match="prior") as err:
        region_poc(square(0, 0, 10, 10), SMALL, np.ones((4, 3)) / 12)
    assert err.value.field == "prior"


# --------------------------------------------------------------------------- eq. 3 and eq. 4


def test_average_poc_eq4_counts_overlap_once_in_poc_and_twice_in_area():
    grid = Grid(10, 10, 10.0)
    prior = np.full(grid.shape, 0.01)  # uniform: 1e-4 per square metre
    a = square(0, 0, 40, 40)  # 1600 m^2
    b = square(20, 20, 60, 60)  # 1600 m^2, overlap [20, 40]^2 = 400 m^2
    # union 2800 m^2 -> POC 0.28; denominator 1600 + 1600 = 3200 m^2
    assert average_poc([a, b], grid, prior) == pytest.approx(0.28 / 3200, rel=1e-12)
    # the two wrong readings of eq. 4 differ from it
    assert not math.isclose(average_poc([a, b], grid, prior), 0.32 / 3200, rel_tol=1e-6)
    assert not math.isclose(average_poc([a, b], grid, prior), 0.28 / 2800, rel_tol=1e-6)
    # disjoint regions: plain sums
    c = square(60, 60, 80, 70)  # 200 m^2
    assert average_poc([a, c], grid, prior) == pytest.approx(0.18 / 1800, rel=1e-12)


def test_average_poc_of_one_region_is_eq3(hot_prior):
    r = square(5, 5, 25, 15)  # 200 m^2 holding 0.25
    assert average_poc(r, SMALL, hot_prior) == pytest.approx(0.25 / 200, rel=1e-12)
    assert average_poc([r], SMALL, hot_prior) == pytest.approx(0.25 / 200, rel=1e-12)
    c = CircleRegion((24.0, 16.0), 2.0)
    assert average_poc(c, SMALL, hot_prior) == pytest.approx(0.6 / 100, rel=1e-3)


def test_average_poc_rejects_no_regions(hot_prior):
    with pytest.raises(ConfigError, match="regions"):
        average_poc([], SMALL, hot_prior)


# --------------------------------------------------------------------------- rectangle mass


def _rect_params(rng, grid, k):
    x0, y0, x1, y1 = grid.bounds
    center = np.stack([rng.uniform(x0, x1, k), rng.uniform(y0, y1, k)], axis=-1)
    return center, rng.uniform(500, 9000, k), rng.uniform(500, 6000, k), rng.uniform(0, 4, k)


def test_rectangle_mass_centre_rule_matches_a_numpy_point_test():
    """The kernel's centre rule against the plain test of eq. 6 on every cell centre; the
    exclusive masses of an individual add up to the mass of the union of its rectangles."""
    grid = Grid(37, 23, 400.0, origin_m=(-300.0, 1700.0))
    rng = np.random.default_rng(8)
    w = rng.random(grid.shape)
    pts = grid.centers
    for _ in range(30):
        center, ln, wd, th = _rect_params(rng, grid, 4)
        ins = []
        for k in range(4):
            d = pts - center[k]
            u = d[..., 0] * np.cos(th[k]) + d[..., 1] * np.sin(th[k])
            v = d[..., 1] * np.cos(th[k]) - d[..., 0] * np.sin(th[k])
            ins.append((np.abs(u) <= ln[k] / 2) & (np.abs(v) <= wd[k] / 2))
        got = rectangle_mass(grid, center, ln, wd, th, exclusive=False, centres=True)
        np.testing.assert_array_equal(got, np.array(ins, dtype=float))
        mass = rectangle_mass(grid, center, ln, wd, th, exclusive=False, centres=True, weights=w)
        np.testing.assert_allclose(mass, [np.sum(w[m]) for m in ins], rtol=1e-12)
        union = np.logical_or.reduce(ins)
        excl = rectangle_mass(grid, center, ln, wd, th, exclusive=True, centres=True, weights=w)
        np.testing.assert_allclose(excl.sum(), np.sum(w[union]), rtol=1e-12)


def test_rectangle_mass_area_rule_matches_cell_overlap():
    """Exact area fractions of rectangles: the kernel against shapely (cell_overlap), and the
    weighted form against the fractions times the weights."""
    grid = Grid(19, 13, 1000.0, origin_m=(200.0, -500.0))
    rng = np.random.default_rng(9)
    w = rng.random(grid.shape)
    for _ in range(20):
        center, ln, wd, th = _rect_params(rng, grid, 3)
        frac = rectangle_mass(grid, center, ln, wd, th, exclusive=False)
        for k in range(3):
            ref = cell_overlap(rectangle_polygon(center[k], ln[k], wd[k], th[k]), grid)
            np.testing.assert_allclose(frac[k], ref, rtol=0, atol=1e-9)  # shapely's rounding
        mass = rectangle_mass(grid, center, ln, wd, th, exclusive=False, weights=w)
        np.testing.assert_allclose(mass, np.sum(frac * w, axis=(-2, -1)), rtol=1e-12)
        union = cell_overlap(
            shapely.union_all([rectangle_polygon(*a) for a in zip(center, ln, wd, th)]), grid
        )
        excl = rectangle_mass(grid, center, ln, wd, th, exclusive=True, weights=w)
        np.testing.assert_allclose(excl.sum(), np.sum(union * w), rtol=1e-9)


def test_rectangle_mass_is_deterministic():
    grid = Grid(11, 9, 1000.0)
    center, ln, wd, th = _rect_params(np.random.default_rng(1), grid, 5)
    one = rectangle_mass(grid, center, ln, wd, th, exclusive=True)
    two = rectangle_mass(grid, center, ln, wd, th, exclusive=True)
    assert one.tobytes() == two.tobytes()
