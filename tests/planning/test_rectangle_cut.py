"""Tests of poc_env.agents.planning.rectangle_cut: the rectangle-cut allocation of §2.1 (n
rectangles of 1.3 S_u maximising eq. 4, a polygon derived inside each)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from poc_env.agents.planning.rectangle_cut import Allocation, rectangle_cut_allocation
from poc_env.config import GaussianComponent
from poc_env.errors import ConfigError
from poc_env.geometry import rectangle_polygon
from poc_env.theory.probability_map import Grid, gaussian_mixture
from poc_env.theory.regions import PolygonRegion, average_poc, region_poc

BLOB_GRID = Grid(24, 24, 1000.0)  # 24 km x 24 km
BLOBS = ((5000.0, 5000.0), (18000.0, 8000.0), (9000.0, 19000.0))
S_U = 12e6  # 12 km^2 per UAV; rectangles of 15.6 km^2


@pytest.fixture(scope="module")
def blob_prior():
    comps = [
        GaussianComponent(mean_m=m, sigma_m=(1500.0, 900.0), rotation_rad=r)
        for m, r in zip(BLOBS, (0.3, 1.2, 2.5), strict=True)
    ]
    return gaussian_mixture(BLOB_GRID, comps, background=0.01)


@pytest.fixture(scope="module")
def allocation(blob_prior) -> Allocation:
    return rectangle_cut_allocation(BLOB_GRID, blob_prior, 3, S_U, np.random.default_rng(11))


def test_rectangles_have_area_factor_times_usable(allocation):
    assert len(allocation.rectangles) == len(allocation.rectangle_polygons) == 3
    assert allocation.rectangle_area_m2 == pytest.approx(1.3 * S_U, rel=1e-12)
    x0, y0, x1, y1 = BLOB_GRID.bounds
    for (center, length, width, theta), poly in zip(
        allocation.rectangles, allocation.rectangle_polygons, strict=True
    ):
        assert length * width == pytest.approx(1.3 * S_U, rel=1e-9)
        assert poly.area == pytest.approx(1.3 * S_U, rel=1e-9)
        assert 1.0 - 1e-12 <= length / width <= 3.0 + 1e-9
        assert 0.0 <= theta < math.pi
        assert x0 <= center[0] <= x1 and y0 <= center[1] <= y1
        assert poly.equals_exact(rectangle_polygon(center, length, width, theta), 1e-6)


def test_reported_values_are_exact_eq4(allocation, blob_prior):
    union = shapely.union_all(list(allocation.rectangle_polygons))
    assert allocation.union_poc == pytest.approx(region_poc(union, BLOB_GRID, blob_prior))
    assert allocation.average_poc == pytest.approx(
        average_poc(list(allocation.rectangle_polygons), BLOB_GRID, blob_prior), rel=1e-9
    )
    assert allocation.average_poc == pytest.approx(allocation.union_poc / (3 * 1.3 * S_U))
    assert allocation.polygon_average_poc == pytest.approx(
        average_poc(list(allocation.polygons), BLOB_GRID, blob_prior), rel=1e-9
    )


def test_allocation_beats_best_of_50_random_placements(allocation, blob_prior):
    rng = np.random.default_rng(2024)
    area = 1.3 * S_U
    x0, y0, x1, y1 = BLOB_GRID.bounds
    best = 0.0
    for _ in range(50):
        rects = []
        for _ in range(3):
            aspect = rng.uniform(1.0, 3.0)
            center = (rng.uniform(x0, x1), rng.uniform(y0, y1))
            length, width = math.sqrt(area * aspect), math.sqrt(area / aspect)
            rects.append(rectangle_polygon(center, length, width, rng.uniform(0, math.pi)))
        best = max(best, region_poc(shapely.union_all(rects), BLOB_GRID, blob_prior))
    assert best > 0.2  # the random baseline is not a straw man
    assert allocation.union_poc > best
    # each blob's centre lies in some rectangle: one rectangle per cluster
    for m in BLOBS:
        assert any(p.contains(shapely.Point(m)) for p in allocation.rectangle_polygons)


def test_same_seed_gives_identical_allocation(allocation, blob_prior):
    again = rectangle_cut_allocation(BLOB_GRID, blob_prior, 3, S_U, np.random.default_rng(11))
    assert again.rectangles == allocation.rectangles
    assert [p.vertices for p in again.polygons] == [p.vertices for p in allocation.polygons]
    assert again.union_poc == allocation.union_poc
    assert again.evaluations == allocation.evaluations > 0


def test_derived_polygons_lie_in_rectangles_with_area_near_su(allocation):
    assert len(allocation.polygons) == 3
    for poly, rect in zip(allocation.polygons, allocation.rectangle_polygons, strict=True):
        assert isinstance(poly, PolygonRegion)
        assert poly.geometry.is_valid
        assert not poly.holes
        assert poly.geometry.difference(rect).area <= 1e-6 * S_U
        assert poly.area_m2 == pytest.approx(S_U, rel=0.10)
    assert allocation.polygon_average_poc >= allocation.average_poc


def test_allocation_at_paper_scale():
    """30 x 40 cells of 5 km (the paper's second case), six UAVs, five clusters."""
    grid = Grid(30, 40, 5000.0)
    comps = [
        GaussianComponent(mean_m=(30e3, 40e3), sigma_m=(8e3, 15e3), rotation_rad=0.5),
        GaussianComponent(mean_m=(110e3, 60e3), sigma_m=(10e3, 6e3)),
        GaussianComponent(mean_m=(70e3, 150e3), sigma_m=(12e3, 12e3)),
        GaussianComponent(mean_m=(120e3, 170e3), sigma_m=(6e3, 14e3)),
        GaussianComponent(mean_m=(40e3, 110e3), sigma_m=(9e3, 9e3), weight=0.5),
    ]
    prior = gaussian_mixture(grid, comps, background=0.02)
    s_u = 1500e6
    alloc = rectangle_cut_allocation(grid, prior, 6, s_u, np.random.default_rng(0))
    assert len(alloc.rectangles) == 6
    # 6 x 1.3 x 1500 km^2 is 39 % of the map; the rectangles hold far more than 39 % of the POC
    assert alloc.union_poc > 0.85
    for poly, rect in zip(alloc.polygons, alloc.rectangle_polygons, strict=True):
        assert poly.geometry.difference(rect).area <= 1e-6 * s_u
        assert poly.area_m2 == pytest.approx(s_u, rel=0.10)
    assert alloc.polygon_average_poc >= alloc.average_poc
    # differential evolution earns its budget: one generation (about the greedy start) is worse
    quick = rectangle_cut_allocation(grid, prior, 6, s_u, np.random.default_rng(0), max_iter=1)
    assert alloc.union_poc > quick.union_poc + 0.01
    assert alloc.evaluations > quick.evaluations


def test_aspect_range_is_respected(blob_prior):
    alloc = rectangle_cut_allocation(
        BLOB_GRID, blob_prior, 2, S_U, np.random.default_rng(3), aspect_range=(2.0, 2.0), max_iter=5
    )
    for _, length, width, _ in alloc.rectangles:
        assert length / width == pytest.approx(2.0, rel=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"n": 0}, "n"),
        ({"n": 2.5}, "n"),
        ({"usable_area_m2": 0.0}, "usable_area_m2"),
        ({"usable_area_m2": -5.0}, "usable_area_m2"),
        ({"usable_area_m2": 576e6 / 1.3 * 1.01}, "usable_area_m2"),  # rectangle > whole grid
        ({"aspect_range": (0.5, 2.0)}, "aspect_range"),
        ({"rng": None}, "rng"),
        ({"max_iter": 0}, "max_iter"),
    ],
)
def test_bad_allocation_arguments_raise_config_error(blob_prior, kwargs, field):
    args = {"n": 3, "usable_area_m2": S_U, "rng": np.random.default_rng(0)} | kwargs
    with pytest.raises(ConfigError) as err:
        rectangle_cut_allocation(BLOB_GRID, blob_prior, **args)
    assert err.value.field == field
