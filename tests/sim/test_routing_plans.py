"""Plans with no-fly zones are the same, waypoint for waypoint, through the fast router
(compiled edge tests, remembered answers, batched clipping, straight runs of clear legs;
issue 24's planning time) and through its shapely-only reference (``ZoneRouter.reference``):
the allocation plan on ``small`` and ``paper_6_2`` with 1-4 zones and with a zone near an
airfield, and every ``reroute`` a fast plan makes answered as a fresh reference router
answers it."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from poc_env.agents.benchmarks.plan_scale import random_zones
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.sim.routing import ZoneRouter, clearance_m

#: label -> (scenario, zones (km) or (count, seed) of random zones, UAVs)
CASES = {
    "small_2": ("small", (2, 11), None),
    "paper_1": ("paper_6_2", (1, 1), 3),
    "paper_2": ("paper_6_2", (2, 2), 3),
    "paper_3": ("paper_6_2", (3, 3), 3),
    "paper_4": ("paper_6_2", (4, 0), 3),
    # 2.1 km from the field at (20, -60) km (inside its c = 3.3 km ring), across its way out
    "paper_near_field": ("paper_6_2", [[[21.5, -58.5], [30, -58.5], [30, -50], [21.5, -50]]], 3),
}


def _scenario(name: str, zones, uavs):
    m = load_scenario(name).map
    if isinstance(zones, tuple):
        n, seed = zones
        ox, oy = (v / 1000 for v in m.origin_m)
        drawn = random_zones(m.width_m / 1000, m.height_m / 1000, n, np.random.default_rng(seed))
        zones = [[[x + ox, y + oy] for x, y in z] for z in drawn]
    return load_scenario(name, {"map.no_fly_zones_km": zones}), uavs


@pytest.mark.parametrize("label", list(CASES))
def test_plan_with_zones_is_the_reference_routers(label, monkeypatch):
    sc, uavs = _scenario(*CASES[label])
    calls: list[tuple[ZoneRouter, np.ndarray, np.ndarray]] = []
    real = ZoneRouter.reroute

    def recorded(self, points):
        got = real(self, points)
        calls.append((self, np.array(points, dtype=float), got))
        return got

    plans = {}
    for ref in (True, False):
        monkeypatch.setattr(ZoneRouter, "reference", ref)
        monkeypatch.setattr(ZoneRouter, "reroute", real if ref else recorded)
        plans[ref] = make_allocation_plan(sc, uavs=uavs, refine=1)
    for u, v in zip(plans[True]["uavs"], plans[False]["uavs"], strict=True):
        np.testing.assert_array_equal(u["waypoints_m"], v["waypoints_m"])
    assert plans[False]["posc"] == plans[True]["posc"] > 0
    # every answer of the fast routers (their memory included) is the reference's
    assert len(calls) > 10
    ref = ZoneRouter.for_scenario(sc)
    ref.reference = True
    for _, points, got in list(calls):
        np.testing.assert_array_equal(got, real(ref, points))
    if label == "paper_near_field":  # the case is what it says: the field inside its ring
        field = np.asarray(sc.airfields[0].position_m)
        d = shapely.Point(field).distance(shapely.union_all(ref.zones))
        assert 0 < d < clearance_m(sc)


def test_remembered_routes_are_the_references():
    """Routes that share their first points or their ends (the eq. 18 bisection's cuts of a
    route, each cut with another landing), asked twice: the fast router's remembered answers
    are the reference's."""
    sc, _ = _scenario("paper_6_2", (4, 0), None)
    fast = ZoneRouter.for_scenario(sc)
    ref = ZoneRouter.for_scenario(sc)
    ref.reference = True
    x0, y0, x1, y1 = fast.area
    rng = np.random.default_rng(7)
    routes = [rng.uniform([x0, y0], [x1, y1], (8, 2)) for _ in range(6)]
    others = rng.uniform([x0, y0], [x1, y1], (6, 2))
    cuts = [
        np.vstack([route[: m + 1], end])
        for route, other in zip(routes, others, strict=True)
        for m in range(len(route) - 1)
        for end in (route[-1], other)
    ]
    for _ in range(2):  # the second time from memory
        for cut in cuts:
            np.testing.assert_array_equal(fast.reroute(cut), ref.reroute(cut))
