"""Tests of the §3.2.3 safety constraints (eq. 20-23) and the safety shield."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Polygon

from poc_env.config import MapConfig, ThreatPeak
from poc_env.errors import GeometryError
from poc_env.sim.constraints import (
    NoFlyZones,
    outside_boundary,
    separation_violations,
    shield_heading,
    terrain_threat,
    threat_arrays,
    threat_violation,
)

SQUARE = [(0, 0), (4000, 0), (4000, 4000), (0, 4000)]
CONVEX = [(0, 0), (9000, 1000), (10000, 6000), (4000, 8000), (-1000, 4000)]
L_SHAPE = [(0, 0), (8000, 0), (8000, 3000), (3000, 3000), (3000, 8000), (0, 8000)]
STAR = [
    (5000 + r * math.cos(a), 5000 + r * math.sin(a))
    for k in range(10)
    for a, r in [(k * math.pi / 5, 4500 if k % 2 == 0 else 1500)]
]


@pytest.mark.parametrize("poly", [CONVEX, L_SHAPE, STAR], ids=["convex", "L", "star"])
def test_inside_matches_shapely(poly):
    rng = np.random.default_rng(1)
    pts = rng.uniform(-2000, 11000, size=(40, 50, 2))
    zones = NoFlyZones([poly])
    got = zones.inside(pts)
    want = shapely.contains_xy(Polygon(poly), pts[..., 0], pts[..., 1])
    assert got.shape == (40, 50)
    assert 100 < want.sum() < 1900  # the sample really straddles the polygon
    np.testing.assert_array_equal(got, want)


def test_inside_union_of_overlapping_zones_and_hole():
    # two overlapping squares: the overlap is inside (per-zone parity, not global parity)
    a = [(0, 0), (2000, 0), (2000, 2000), (0, 2000)]
    b = [(1000, 1000), (3000, 1000), (3000, 3000), (1000, 3000)]
    holed = Polygon(
        [(5000, 0), (9000, 0), (9000, 4000), (5000, 4000)],
        [[(6000, 1000), (8000, 1000), (8000, 3000), (6000, 3000)]],
    )
    zones = NoFlyZones([a, b, holed])
    pts = np.array([[1500, 1500], [500, 500], [2500, 2500], [3500, 500], [7000, 2000], [5500, 500]])
    np.testing.assert_array_equal(zones.inside(pts), [True, True, True, False, False, True])


def test_no_zones_and_invalid_zone():
    zones = NoFlyZones([])
    assert not zones.inside(np.zeros((3, 2, 2))).any()
    assert not zones.segment_crosses(np.zeros((3, 2)), np.ones((3, 2))).any()
    assert np.isinf(zones.distance(np.zeros((4, 2)))).all()
    with pytest.raises(GeometryError):
        NoFlyZones([[(0, 0), (1, 1), (1, 0), (0, 1)]])  # bow tie


def test_from_config_uses_metres():
    cfg = MapConfig(width_m=10_000, height_m=10_000, cell_m=1000, no_fly_zones_m=(tuple(SQUARE),))
    zones = NoFlyZones.from_config(cfg)
    assert zones.n_zones == 1
    np.testing.assert_array_equal(zones.inside(np.array([[2000, 2000], [5000, 2000]])), [1, 0])


def test_segment_crosses_thin_zone():
    thin = [(1000, -5000), (1010, -5000), (1010, 5000), (1000, 5000)]  # 10 m wide wall
    zones = NoFlyZones([thin])
    a = np.array([[[0.0, 0.0], [0.0, 0.0], [2000.0, 0.0], [0.0, 6000.0]]])
    b = np.array([[[2000.0, 0.0], [900.0, 0.0], [3000.0, 100.0], [2000.0, 6000.0]]])
    assert not zones.inside(a).any() and not zones.inside(b).any()
    got = zones.segment_crosses(a, b)
    np.testing.assert_array_equal(got, [[True, False, False, False]])
    # matches shapely on random segments around a non-convex zone
    rng = np.random.default_rng(2)
    z = NoFlyZones([L_SHAPE])
    p, q = rng.uniform(-2000, 10000, (2, 300, 2))
    want = [LineString([s, t]).intersects(Polygon(L_SHAPE)) for s, t in zip(p, q)]
    np.testing.assert_array_equal(z.segment_crosses(p, q), want)


def test_distance():
    zones = NoFlyZones([SQUARE])
    pts = np.array([[2000, 2000], [5000, 2000], [7000, 8000], [-300, -400]], dtype=float)
    np.testing.assert_allclose(zones.distance(pts), [0, 1000, 5000, 500])


def test_outside_boundary():
    b = (0.0, 0.0, 10_000.0, 5_000.0)
    pts = np.array([[[0, 0], [10_000, 5_000], [5000, 2500], [-1, 10], [5000, 5001]]], float)
    np.testing.assert_array_equal(outside_boundary(pts, b), [[False, False, False, True, True]])


def test_separation_violations():
    d_s = 1000.0
    xy = np.array(
        [
            [[0, 0], [600, 0], [50_000, 0]],  # 0 and 1 too close, 2 far
            [[0, 0], [600, 0], [300, 300]],  # all close, but agent 1 is inactive
        ],
        dtype=float,
    )
    active = np.array([[True, True, True], [True, False, True]])
    per_agent, pairs = separation_violations(xy, d_s, active)
    np.testing.assert_array_equal(per_agent, [[True, True, False], [True, False, True]])
    assert pairs.shape == (2, 3, 3)
    np.testing.assert_array_equal(pairs, np.swapaxes(pairs, -1, -2))
    assert not pairs[:, [0, 1, 2], [0, 1, 2]].any()
    assert not pairs[1, 1].any() and pairs[1, 0, 2]
    per_all, _ = separation_violations(xy, d_s)
    assert per_all[1].all()  # without the mask the inactive UAV counts


def test_terrain_threat_squared_form():
    centers = np.array([[1000.0, 2000.0], [0.0, 0.0]])
    lambdas = np.array([1e-6, 4e-6])
    f = terrain_threat(np.array([1300.0, 2400.0]), centers, lambdas)
    assert f.shape == (2,)
    # hand value: distance^2 = 300^2 + 400^2 = 250000 -> exp(-0.25)
    assert f[0] == pytest.approx(math.exp(-0.25))
    # 1 at the centre, symmetric about it, decaying with distance
    off = np.array([[500.0, 0.0], [-500.0, 0.0], [0.0, -500.0], [-300.0, 400.0]])
    vals = terrain_threat(centers[0] + off, centers[:1], lambdas[:1])[:, 0]
    np.testing.assert_allclose(vals, vals[0])
    assert terrain_threat(centers[0], centers[:1], lambdas[:1])[0] == pytest.approx(1.0)
    radii = np.linspace(0, 5000, 20)
    ring = terrain_threat(np.stack([1000 + radii, 2000 + 0 * radii], -1), centers[:1], lambdas[:1])
    assert np.all(np.diff(ring[:, 0]) < 0)
    # the paper's printed exponent -lambda[(x-xp)+(y-yp)] is not symmetric: guard against it
    unsquared = np.exp(-lambdas[0] * (off[:, 0] + off[:, 1]))
    assert not np.allclose(unsquared, unsquared[0])


def test_threat_violation_and_config_peaks():
    peaks = (ThreatPeak(center_m=(5000.0, 5000.0), lambda_per_m2=1e-6),)
    centers, lambdas = threat_arrays(peaks)
    xy = np.array([[[5000, 5000], [5500, 5000], [8000, 5000]]], dtype=float)
    # f = 1, exp(-0.25) = 0.78, exp(-9) ~ 1e-4
    np.testing.assert_array_equal(threat_violation(xy, centers, lambdas, 0.5), [[1, 1, 0]])
    np.testing.assert_array_equal(threat_violation(xy, centers, lambdas, 0.9), [[1, 0, 0]])
    empty_c, empty_l = threat_arrays(())
    assert terrain_threat(xy, empty_c, empty_l).shape == (1, 3, 0)
    assert not threat_violation(xy, empty_c, empty_l, 0.5).any()


# ------------------------------------------------------------------ shield

BOUNDS = (0.0, 0.0, 100_000.0, 100_000.0)
MAX_TURN = math.radians(30)


def _next(xy, heading, turn, step):
    a = heading + turn
    return xy + step * np.stack([np.cos(a), np.sin(a)], -1)


def test_shield_turns_away_from_zone():
    # UAV at (10 km, 50 km) heading east; a zone starts 500 m ahead; step 1 km
    zone = [(10_500, 49_900), (12_000, 49_900), (12_000, 50_100), (10_500, 50_100)]
    zones = NoFlyZones([zone])
    xy = np.array([[[10_000.0, 50_000.0]]])
    heading = np.zeros((1, 1))
    speed = np.full((1, 1), 100.0)
    res = shield_heading(
        xy, heading, speed, 10.0, np.zeros((1, 1)), MAX_TURN, zones=zones, bounds=BOUNDS
    )
    assert res.shielded[0, 0] and not res.no_safe_option[0, 0]
    assert abs(res.turn[0, 0]) <= MAX_TURN + 1e-12
    nxt = _next(xy, heading, res.turn, 1000.0)
    assert not zones.segment_crosses(xy, nxt).any()
    # the proposal itself would have entered the zone
    assert zones.segment_crosses(xy, _next(xy, heading, 0.0, 1000.0)).all()
    # closest admissible candidate: clearing 100 m at 500 m ahead needs > 11.3 deg; the
    # candidate grid has steps of 60/14 deg, so 3 steps = 12.86 deg
    assert abs(res.turn[0, 0]) == pytest.approx(math.radians(60 / 14 * 3))


def test_shield_leaves_safe_actions_unchanged():
    rng = np.random.default_rng(3)
    heading = rng.uniform(-np.pi, np.pi, size=(8, 4))
    prop = rng.uniform(-MAX_TURN, MAX_TURN, size=(8, 4))
    zones = NoFlyZones([[(0, 0), (1000, 0), (1000, 1000), (0, 1000)]])  # far away
    # spread agents so that nobody is near anybody
    xy = np.stack(
        [np.broadcast_to(np.arange(4) * 10_000.0 + 20_000, (8, 4)), np.full((8, 4), 50_000.0)],
        -1,
    )
    res = shield_heading(
        xy, heading, 100.0, 10.0, prop, MAX_TURN, zones=zones, bounds=BOUNDS, d_s=1000.0
    )
    np.testing.assert_array_equal(res.turn, prop)
    assert not res.shielded.any() and not res.no_safe_option.any()


def test_shield_no_safe_option():
    # a UAV boxed in: zone wraps around it except for its own cell, step too long to escape
    ring = Polygon([(0, 0), (40_000, 0), (40_000, 40_000), (0, 40_000)]).difference(
        Polygon([(19_900, 19_900), (20_100, 19_900), (20_100, 20_100), (19_900, 20_100)])
    )
    zones = NoFlyZones([ring])
    xy = np.array([[[20_000.0, 20_000.0]]])
    res = shield_heading(xy, 0.0, 100.0, 10.0, np.zeros((1, 1)), MAX_TURN, zones=zones)
    assert res.no_safe_option[0, 0]
    assert abs(res.turn[0, 0]) <= MAX_TURN + 1e-12
    # at the boundary corner heading out with a small turn limit: no admissible turn
    res = shield_heading(
        np.array([[[100.0, 100.0]]]), np.pi * 1.25, 100.0, 10.0, 0.0, 0.1, bounds=BOUNDS
    )
    assert res.no_safe_option[0, 0]


def test_shield_separation_and_batching():
    # two UAVs flying head-on, 1.5 km apart, steps of 500 m: proposals leave 500 m < d_s
    d_s = 800.0
    xy = np.array([[[50_000.0, 50_000.0], [51_500.0, 50_000.0], [10_000.0, 10_000.0]]])
    xy = np.repeat(xy, 3, axis=0)
    heading = np.array([[0.0, np.pi, 0.0]]).repeat(3, axis=0)
    active = np.array([[True, True, True], [True, False, True], [True, True, True]])
    prop = np.zeros((3, 3))
    res = shield_heading(
        xy, heading, 50.0, 10.0, prop, MAX_TURN, bounds=BOUNDS, d_s=d_s, active=active
    )
    nxt = _next(xy, heading, res.turn, 500.0)
    for e in (0, 2):
        assert np.hypot(*(nxt[e, 0] - nxt[e, 1])) >= d_s
        assert res.shielded[e, :2].any() and not res.no_safe_option[e].any()
    # env 1: the partner is inactive, nothing to avoid
    assert not res.shielded[1].any()
    np.testing.assert_array_equal(res.turn[1], 0.0)
    # the lone third UAV is untouched everywhere
    assert not res.shielded[:, 2].any()
    per_agent, _ = separation_violations(nxt, d_s, active)
    assert not per_agent.any()


def test_shield_random_swarms_end_safe_when_reported_safe():
    rng = np.random.default_rng(7)
    n_envs, n = 64, 6
    zones = NoFlyZones([[(4000, 4000), (6000, 4000), (6000, 6000), (4000, 6000)]])
    bounds = (0.0, 0.0, 10_000.0, 10_000.0)
    peaks = (np.array([[8000.0, 2000.0]]), np.array([1e-6]), 0.5)
    xy = rng.uniform(500, 9500, size=(n_envs, n, 2))
    heading = rng.uniform(-np.pi, np.pi, size=(n_envs, n))
    prop = rng.uniform(-MAX_TURN, MAX_TURN, size=(n_envs, n))
    active = rng.random((n_envs, n)) > 0.1
    res = shield_heading(
        xy,
        heading,
        40.0,
        10.0,
        prop,
        MAX_TURN,
        zones=zones,
        bounds=bounds,
        d_s=700.0,
        active=active,
        threat=peaks,
    )
    assert res.shielded.any() and not res.shielded[~active].any()
    assert np.all(np.abs(res.turn) <= MAX_TURN + 1e-12)
    nxt = _next(xy, heading, res.turn, 400.0)
    ok = active & ~res.no_safe_option
    assert ok.sum() > n_envs * n // 2
    assert not outside_boundary(nxt, bounds)[ok].any()
    assert not zones.segment_crosses(xy, nxt)[ok].any()
    assert not threat_violation(nxt, *peaks)[ok].any()
    # separation holds in every env where nobody reported 'no safe option'
    clean = ~res.no_safe_option.any(axis=-1)
    per_agent, _ = separation_violations(nxt, 700.0, active)
    assert clean.sum() > 10
    assert not per_agent[clean].any()
    # unshielded agents kept their proposal exactly
    np.testing.assert_array_equal(res.turn[~res.shielded], prop[~res.shielded])
