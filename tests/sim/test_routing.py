"""The zone router's fast path (compiled edge test, remembered answers) against its shapely-only
reference, and routes from a field inside the clearance ring (poc_env.sim.routing)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import shapely

from poc_env.agents.benchmarks.plan_scale import random_zones
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.sim.routing import ZoneRouter, _Edges

AREA = (0.0, 0.0, 40_000.0, 30_000.0)


def _zones(seed: int, n: int = 4) -> list:
    return [
        [[1000 * x, 1000 * y] for x, y in z]
        for z in random_zones(40, 30, n, np.random.default_rng(seed))
    ]


def _segments(geom, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Random segments over ``geom``'s box and degenerate ones: vertex to vertex (touching,
    along edges), points on edges, zero length."""
    x0, y0, x1, y1 = geom.bounds
    lo, hi = np.array([x0 - 2000, y0 - 2000]), np.array([x1 + 2000, y1 + 2000])
    a = rng.uniform(lo, hi, (400, 2))
    b = rng.uniform(lo, hi, (400, 2))
    v = shapely.get_coordinates(geom.boundary)
    i, j = rng.integers(len(v), size=(2, 300))
    mid = 0.5 * (v[i] + v[np.minimum(i + 1, len(v) - 1)])  # on an edge (up to rounding)
    k = rng.integers(len(v), size=50)
    # along edges: whole, in part, overrunning both ends, beyond one end (collinear)
    e0, e1 = v[k], v[np.minimum(k + 1, len(v) - 1)]
    d = e1 - e0
    starts = np.vstack([a, v[i], mid, v[k], a[:50], e0, e0 + 0.25 * d, e0 - d, e1 + 0.5 * d])
    ends = np.vstack([b, v[j], v[j], v[k], v[k], e1, e0 + 0.75 * d, e1 + d, e1 + 2 * d])
    return starts, ends


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_compiled_edge_test_is_shapelys_intersects(seed):
    rng = np.random.default_rng(seed)
    r = ZoneRouter(_zones(seed), AREA, 1500.0)
    for geom in (r.obstacle, r.keep_out, r.raw):
        a, b = _segments(geom, rng)
        want = shapely.intersects(shapely.linestrings(np.stack([a, b], axis=1)), geom)
        np.testing.assert_array_equal(_Edges(geom).hits(a, b), want)
        assert want.any() and not want.all()


def test_compiled_edge_test_decides_most_segments_itself(monkeypatch):
    """Random segments are settled by the compiled test, not handed to shapely."""
    r = ZoneRouter(_zones(0), AREA, 1500.0)
    a, b = _segments(r.obstacle, np.random.default_rng(5))
    calls = []
    real = shapely.intersects
    monkeypatch.setattr(shapely, "intersects", lambda g, o: calls.append(len(g)) or real(g, o))
    _Edges(r.obstacle).hits(a[:400], b[:400])
    assert sum(calls) < 0.05 * 400


@pytest.mark.parametrize("seed", [0, 3])
def test_fast_router_answers_as_the_reference(seed):
    rng = np.random.default_rng(seed)
    zones = _zones(seed, 5)
    fast = ZoneRouter(zones, AREA, 1500.0)
    ref = ZoneRouter(zones, AREA, 1500.0, reference=True)
    np.testing.assert_array_equal(fast.dist, ref.dist)
    pts = rng.uniform(AREA[:2], AREA[2:], (60, 2))
    for _ in range(2):  # the second time from the fast router's memory
        for p, q in itertools.pairwise(pts):
            got, want = fast.path(p, q), ref.path(p, q)
            assert (got is None) == (want is None)
            if want is not None:
                np.testing.assert_array_equal(got, want)
        for k in range(0, 50, 7):
            line = rng.uniform(AREA[:2], AREA[2:], (6, 2))
            line[0], line[-1] = pts[k], pts[k + 1]
            np.testing.assert_array_equal(fast.reroute(line), ref.reroute(line))


def test_allocation_plan_is_the_reference_routers(monkeypatch):
    ox, oy = (v / 1000 for v in load_scenario("paper_6_2").map.origin_m)
    zones = [[[x / 1000 + ox, y / 1000 + oy] for x, y in z] for z in _zones(0)]
    sc = load_scenario("paper_6_2", {"map.no_fly_zones_km": zones})
    plans = {}
    for ref in (True, False):
        monkeypatch.setattr(ZoneRouter, "reference", ref)
        plans[ref] = make_allocation_plan(sc, uavs=3, refine=1)
    for u, v in zip(plans[True]["uavs"], plans[False]["uavs"]):
        np.testing.assert_array_equal(u["waypoints_m"], v["waypoints_m"])
    assert plans[False]["posc"] == plans[True]["posc"] > 0


@pytest.mark.parametrize("reference", [False, True])
def test_route_from_a_field_inside_the_ring_keeps_the_fields_distance(reference):
    """A field 0.86 c from a zone's corner: the way round leaves it without cutting the ring
    any deeper (before: straight to the next keep-out vertex, 0.82 c from the corner)."""
    zone = [(0, 0), (10_000, 0), (10_000, 10_000), (0, 10_000)]
    r = ZoneRouter([zone], (-20_000, -20_000, 30_000, 30_000), 1000.0, reference=reference)
    field = np.array([-500.0, -700.0])
    poly = shapely.Polygon(zone)
    d_field = poly.distance(shapely.Point(field))
    for goal in ([5000.0, 12_000.0], [-3000.0, 9000.0], [12_000.0, 5000.0]):
        for path in (r.path(field, goal), r.path(goal, field)[::-1]):
            assert path is not None
            assert shapely.LineString(path).distance(poly) >= d_field * (1 - 1e-6)
            # no long detour: within 5 % of the way that only misses the zone
            loose = r._shortest(field, np.asarray(goal), False)
            assert shapely.LineString(path).length <= 1.05 * shapely.LineString(loose).length
        line = r.reroute([field, goal, field])
        assert shapely.LineString(line).distance(poly) >= d_field * (1 - 1e-6)


def test_a_densely_drawn_zone_keeps_a_small_graph():
    """Audit i24: a circular restricted area digitised with 2,000 vertices (as an AIP circle
    often is) gave the visibility graph one node per vertex of its keep-out polygon: the
    allocation plan took 263 s and 1.25 GB instead of 1.8 s (64 vertices), the same POS. A
    keep-out polygon of more than ``MAX_KEEP_OUT_VERTICES`` vertices is simplified outwards
    (it still holds the plain keep-out: every path keeps ``c``); a zone of few vertices keeps
    its keep-out polygon exactly (plans unchanged)."""
    from poc_env.sim.routing import _GROW, MAX_KEEP_OUT_VERTICES, QUAD_SEGS

    c = 3300.0
    t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    circle = np.column_stack([20e3 + 8e3 * np.cos(t), 20e3 + 8e3 * np.sin(t)])
    r = ZoneRouter([circle], None, c)
    plain = shapely.Polygon(circle).buffer(_GROW * c, quad_segs=QUAD_SEGS)
    assert len(r.nodes) <= MAX_KEEP_OUT_VERTICES < len(plain.exterior.coords) - 1
    assert r.keep_out.buffer(1e-6).covers(plain)  # outwards only
    assert r.keep_out.hausdorff_distance(plain) < 0.05 * c  # and not much more
    rect = [[0, 0], [10e3, 0], [10e3, 5e3], [0, 5e3]]
    r = ZoneRouter([rect], None, c)
    assert r.keep_out.equals_exact(shapely.Polygon(rect).buffer(_GROW * c, quad_segs=QUAD_SEGS), 0)
