"""Issue 24's no-fly mechanisms, each on a smoke-sized case that fails without its fix.

- The waypoint follower passes a waypoint it cannot capture at its closest approach
  (:class:`~poc_env.sim.autopilot.WaypointFollower`, ``closest_approach``): with the
  half-step reach alone it orbits a waypoint that lies inside its turn circle until the return
  rule sends it home (the property test's seeds 880072468 and 2004701267: the orbit cut a zone's
  corner, or the turn home from it entered the zone).
- The follower's zone guard (:func:`~poc_env.sim.autopilot.zone_guard`, ``guard_zones``): the
  turn-rate bound makes the first step of a turn home go where the goal is not, into a zone
  beside the UAV; the guard turns the other way.
- The router keeps the clearance ``c`` itself (:class:`~poc_env.sim.routing.ZoneRouter`): its
  paths and every leg the refinement accepts (:meth:`~poc_env.sim.routing.ZoneRouter.crosses`)
  keep ``c`` from every zone (they kept 0.9 c: routes passed 0.90-0.92 c from zones, inside the
  band the follower needs).
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely

import poc_env
from poc_env.config import load_scenario
from poc_env.sim.autopilot import WaypointFollower, capture_radius, zone_guard
from poc_env.sim.constraints import NoFlyZones
from poc_env.sim.routing import ZoneRouter, clearance_m

NONE = np.zeros((0, 2))


def _fly(sc, wps, steps: int, **flags) -> tuple[list[int], np.ndarray, int, bool]:
    """UAV 0 of ``sc`` flies ``wps`` (the others stay home) for at most ``steps`` steps: its
    waypoint index after each step, its positions, the no-fly steps and whether it landed."""
    env = poc_env.parallel_env(sc)
    obs, _ = env.reset(seed=0)
    f = WaypointFollower(env.params, [np.asarray(wps, float), NONE, NONE], env.possible_agents,
                         **flags)  # fmt: skip
    index, xy, nofly = [], [np.array(env.sim_state.pos[0, 0, :2])], 0
    for _ in range(steps):
        if not env.agents:
            break
        obs, _, _, _, info = env.step(f.predict(obs)[0])
        index.append(int(f.index[0]))
        xy.append(np.array(env.sim_state.pos[0, 0, :2]))
        nofly += sum(int(i["violation_no_fly"]) for i in info.values())
    landed = bool(env.sim_state.landed[0, 0])
    env.close()
    return index, np.asarray(xy), nofly, landed


# `small`: the UAVs take off at (20, -5) km heading north. A is 20 km north; B lies 1.1 km
# behind A and to its side, inside the turn circle of a UAV that has just reached A.
A = np.array([20_000.0, 15_000.0])
B = A + np.array([-1000.0, -500.0])
ROUTE = [A, B, A + np.array([0.0, 8000.0])]


def test_follower_passes_a_waypoint_inside_its_turn_circle_at_the_closest_approach():
    sc = load_scenario("small")
    index, xy, _, _ = _fly(sc, ROUTE, 40)
    on_b = [t for t, i in enumerate(index) if i == 1]
    assert on_b, "B never became the current waypoint"
    assert len(on_b) <= 4  # passed within a turn (the old rule orbits: below)
    # passed where it came closest, and within the capture radius the turn rate allows
    d = np.hypot(*(xy[on_b[0] : on_b[-1] + 2] - B).T)
    speed = sc.uav.search_speed_mps
    assert d.min() <= capture_radius(poc_env.parallel_env(sc).params, speed) + 1e-6
    assert index[-1] >= 2  # and flies on along the route


def test_half_a_step_alone_orbits_that_waypoint():
    """The case above is one the old rule cannot capture: it orbits B for the whole run."""
    index, _, _, _ = _fly(load_scenario("small"), ROUTE, 40, closest_approach=False)
    assert index[-1] == 1 and sum(i == 1 for i in index) >= 20  # 20 steps: five orbits


# A zone east of the route's end: from the last waypoint (heading north) home is due south,
# and the turn-rate bound's first step of a right turn goes east, into the zone.
ZONE = [[21.2, 24.0], [26.0, 24.0], [26.0, 31.0], [21.2, 31.0]]
END = [[20_000.0, 30_000.0]]


@pytest.mark.parametrize("guard", [True, False])
def test_follower_turns_home_away_from_a_zone_beside_its_last_waypoint(guard):
    sc = load_scenario("small", {"map.no_fly_zones_km": [ZONE]})
    _, _, nofly, landed = _fly(sc, END, 200, guard_zones=guard)
    if guard:
        assert nofly == 0 and landed
    else:  # the case needs the guard: without it the turn home enters the zone
        assert nofly > 0


def test_zone_guard_keeps_a_safe_turn_and_replaces_one_into_a_zone():
    zones = NoFlyZones([np.array(ZONE) * 1000.0])
    m = np.pi / 2
    here, north, step = np.array([20_000.0, 30_000.0]), np.pi / 2, 1833.0
    assert zone_guard(zones, here, north, step, m / 3, m) == pytest.approx(m / 3)  # left: kept
    turn = zone_guard(zones, here, north, step, -m, m)  # right, into the zone
    assert turn != pytest.approx(-m)
    nxt = here + step * np.array([np.cos(north + turn), np.sin(north + turn)])
    assert not zones.segment_crosses(here[None], nxt[None])[0]


def test_router_paths_and_refinement_legs_keep_the_full_clearance():
    """Paths around an L-shaped zone keep c (not 0.9 c) and a leg 0.95 c from the zone is
    refused to the refinement (:meth:`ZoneRouter.crosses`); one 1.01 c away is not."""
    sc = load_scenario("small")
    c = clearance_m(sc)
    zone = np.array([[10, 10], [30, 10], [30, 14], [14, 14], [14, 30], [10, 30]]) * 1000.0
    router = ZoneRouter([zone], (-50_000, -50_000, 90_000, 90_000), c)
    poly = shapely.Polygon(zone)
    for a, b in (((0, 20_000), (40_000, 20_000)), ((20_000, 0), (20_000, 40_000)),
                 ((0, 0), (40_000, 40_000)), ((20_000, 5_000), (5_000, 20_000))):  # fmt: skip
        path = router.path(a, b)
        assert path is not None and len(path) > 2, (a, b)
        assert shapely.LineString(path).distance(poly) >= c * (1 - 1e-9), (a, b)
    y = 10_000 - 0.95 * c  # south of the zone's long edge
    assert router.crosses(np.array([[5_000.0, y]]), np.array([[35_000.0, y]]))[0]
    y = 10_000 - 1.01 * c
    assert not router.crosses(np.array([[5_000.0, y]]), np.array([[35_000.0, y]]))[0]


def test_router_vertices_keep_the_clearance_where_zones_overlap():
    """Found by the property run (seed 734423511, a triangle over an L): with the keep-out
    polygons grown only 0.1 % beyond c, GEOS's buffer fell 0.2 % short of it at a vertex
    where the two zones' keep-out areas meet; the vertex lay inside the obstacle, the graph
    lost its edges there and a UAV's way home was a straight leg through both zones."""
    tri = np.array([[11.3043, 2.7528], [18.7036, 2.7528], [12.2333, 13.9570]]) * 1000.0
    ell = np.array([[6.0223, 0.2909], [17.7181, 0.2909], [17.7181, 12.3268], [14.5577, 12.3268],
                    [14.5577, 3.4513], [9.1826, 3.4513], [9.1826, 12.3268],
                    [6.0223, 12.3268]]) * 1000.0  # fmt: skip
    c = clearance_m(load_scenario("small"))
    router = ZoneRouter([tri, ell], (-20_000, -26_000, 60_000, 50_000), c)
    both = shapely.union_all([shapely.Polygon(tri), shapely.Polygon(ell)])
    assert min(both.distance(shapely.Point(p)) for p in router.nodes) >= c
    path = router.path((17_023.0, 14_647.0), (1_253.0, -6_000.0))
    assert path is not None
    assert shapely.LineString(path).distance(both) >= c * (1 - 1e-9)
