"""Lanes round the no-fly zones: eq. 21 at a route plan's planned positions (i24-deconflict).

The zone router (:class:`poc_env.sim.routing.ZoneRouter`) gives every UAV the same shortest
way round a zone, through the same vertices of its ring (the zone grown by the clearance), so
field-mates flying out or home together flew it within ``d_s`` of each other (the scale audit:
445 collision steps at 24 UAVs, results/audit/scale/README.md). :func:`in_lanes` routes the
UAVs round the zones one after the other, each in the lowest lane (:func:`lanes`: its ring
vertices moved ``lane x LANE x d_s`` away from the zone) whose planned flight
(:func:`planned_positions`, the follower's timing every ``dt``) keeps eq. 21 with the UAVs
routed before it (:func:`conflicts`: closer than ``d_s`` at planned times at most
:data:`SLACK_S` apart, away from the airfields). Lanes stay out of the zones and inside eq.
20's operating area, and a lane is taken only if eq. 17-18 (:func:`~poc_env.agents.planning.
refine.route_fits`) cut no more of the route than the router's own way does. Routes without a
conflict keep the router's way (lane 0), so plans without zones, or without shared ways round
them, do not change.
"""

from __future__ import annotations

import numpy as np
import shapely

from poc_env.agents.planning.flight_rules import Speeds
from poc_env.agents.planning.refine import track
from poc_env.config import Scenario
from poc_env.sim.autopilot import FAN_DEG
from poc_env.sim.core import operating_area, takeoff_heading
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import Grid

#: the width of a lane round a zone, in units of ``d_s`` (:func:`lanes`).
LANE = 1.5
#: planned times (s) within which two UAVs at the same place conflict: the follower's timing
#: drifts from the planned one (1-2 min on paper_6_2, docs/PLANNER.md).
SLACK_S = 120.0
#: lanes tried per UAV (:func:`in_lanes`): lane ``l`` lies ``l x LANE x d_s`` out.
MAX_LANES = 4


def planned_positions(
    sc: Scenario, routes, v: Speeds, dt_s: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times ``(S,)``, positions ``(S, n, 2)`` and flying flags ``(S, n)`` of ``routes``
    (waypoints per UAV between its take-off and landing) every ``dt_s`` (default the
    episode's) over the usable endurance, as the follower is planned to fly them
    (:func:`~poc_env.agents.planning.refine.track`)."""
    u = sc.uav
    dt = sc.episode.dt_s if dt_s is None else float(dt_s)
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    n = len(takeoff)
    heading0 = takeoff_heading(Grid.from_config(sc.map).bounds, takeoff)
    times = np.arange(int(np.ceil(u.usable_endurance_s / dt)) + 1) * dt
    pos = np.zeros((len(times), n, 2))
    act = np.zeros((len(times), n), dtype=bool)
    for k in range(n):
        if len(routes[k]):
            path = np.vstack([takeoff[k], np.asarray(routes[k], dtype=float), landing[k]])
            pos[:, k], act[:, k] = track(path, v, u.max_turn_rate_rad_s, times, heading0[k])
    return times, pos, act


def _away(sc: Scenario, pos: np.ndarray, act: np.ndarray, within: float = 1.0) -> np.ndarray:
    """``act`` where the UAV ``(..., n, 2)`` is farther than ``within x d_s / sin(FAN_DEG)``
    from its take-off and landing fields (field-mates take off and land together; the fan-out
    spreads them from there: legs ``FAN_DEG`` apart are ``within x d_s`` apart from there)."""
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    near = within * sc.constraints.safety_distance_m / np.sin(np.radians(FAN_DEG))
    return (
        act
        & (np.hypot(*np.moveaxis(pos - takeoff, -1, 0)) > near)
        & (np.hypot(*np.moveaxis(pos - landing, -1, 0)) > near)
    )


def conflicts(
    sc: Scenario, pos: np.ndarray, act: np.ndarray, one: int | None = None, within: float = 1.0
) -> np.ndarray:
    """Conflict steps ``(S, n, n)`` (symmetric): two flying UAVs closer than ``d_s`` (eq. 21)
    at planned times at most :data:`SLACK_S` apart (the follower's timing drifts from the
    planned one), neither within ``d_s / sin(FAN_DEG)`` of its fields (:func:`_away`).
    ``one``: only the pairs of UAV ``one`` with the others (the rest False); ``within``:
    closer than ``within x d_s`` instead (and away from the fields by ``within`` times as
    much)."""
    d_s = sc.constraints.safety_distance_m * within
    ok = _away(sc, pos, act, within)
    n_s, n = ok.shape
    rows = np.arange(n) if one is None else np.array([one])
    close = np.zeros((n_s, n, n), dtype=bool)
    for lag in range(int(SLACK_S // sc.episode.dt_s) + 1):  # the other ``lag`` steps later
        for a, b in (
            (slice(0, n_s - lag), slice(lag, n_s)),
            (slice(lag, n_s), slice(0, n_s - lag)),
        ):
            d = np.hypot(*np.moveaxis(pos[a][:, rows, None] - pos[b][:, None, :], -1, 0))
            c = (d < d_s) & ok[a][:, rows, None] & ok[b][:, None, :]
            close[a, rows] |= c
    close |= close.transpose(0, 2, 1)
    close[:, np.arange(n), np.arange(n)] = False
    return close


def _lane_normals(path: np.ndarray) -> np.ndarray:
    """Per inner point of ``path`` (take-off, waypoints, landing) the left offset vector that
    moves both legs at it one unit sideways (the miter of the legs' left normals, at most 2
    long)."""
    d = np.diff(path, axis=0)
    length = np.hypot(*d.T)
    unit = np.where(length[:, None] > 1e-9, d / np.maximum(length, 1e-9)[:, None], 0.0)
    left = np.stack([-unit[:, 1], unit[:, 0]], axis=1)
    m = left[:-1] + left[1:]
    norm = np.hypot(*m.T)
    m = np.where(norm[:, None] > 1e-9, m / np.maximum(norm, 1e-9)[:, None], left[1:])
    cos = np.maximum(np.sum(m * left[1:], axis=1), 0.5)
    return m / cos[:, None]


def lanes(path, lane: int, d_s: float, router: ZoneRouter) -> np.ndarray:
    """``path`` (take-off, waypoints, landing, rerouted by ``router``) in lane ``lane``: its
    points on the router's rings round the zones (its graph's vertices, where it gives every
    UAV the same way round) moved away from the zones by ``lane x LANE x d_s`` (each leg
    between two of them moved that far sideways), so UAVs in different lanes fly the same way
    round at least ``LANE x d_s`` apart whatever their timing (eq. 21). Lane 0, a path off the
    rings, or a lane that would enter a zone (the router's grown zones) or leave the router's
    area (eq. 20's operating area): ``path`` itself."""
    p = np.asarray(path, dtype=float).reshape(-1, 2)
    if lane <= 0 or not router.active or len(p) < 3 or not len(router.nodes):
        return p
    inner = p[1:-1]
    gap = np.hypot(*(inner[:, None] - router.nodes[None]).transpose(2, 0, 1)).min(axis=1)
    on = np.flatnonzero(gap < 1e-3)
    if not len(on):
        return p
    zones = shapely.union_all(router.zones)
    m = _lane_normals(p)[on] * lane * LANE * d_s
    pts = inner[on]
    left = shapely.distance(zones, shapely.points(pts + m))
    right = shapely.distance(zones, shapely.points(pts - m))
    out = p.copy()
    out[1:-1][on] = np.where((left >= right)[:, None], pts + m, pts - m)
    if router.area is not None:
        x0, y0, x1, y1 = router.area
        if np.any((out[:, 0] < x0) | (out[:, 0] > x1) | (out[:, 1] < y0) | (out[:, 1] > y1)):
            return p
    if router.crosses(out[:-1], out[1:]).sum() > router.crosses(p[:-1], p[1:]).sum():
        return p
    return out


def _on_path(wps: np.ndarray, other, takeoff, landing, d_s: float) -> bool:
    """Whether most of the waypoints ``wps`` ``(m, 2)`` lie within ``d_s`` of the flight path of
    the route ``other`` (take-off, waypoints, landing): the same box, or the same lines."""
    if not len(other):
        return False
    path = np.vstack([takeoff, np.asarray(other, dtype=float).reshape(-1, 2), landing])
    a, b = path[:-1], path[1:]
    d = b - a
    t = np.einsum("mpk,pk->mp", wps[:, None] - a[None], d) / np.maximum(np.sum(d * d, 1), 1e-12)
    near = a[None] + np.clip(t, 0.0, 1.0)[..., None] * d[None]
    gap = np.hypot(*np.moveaxis(wps[:, None] - near, -1, 0)).min(axis=1)
    return bool(np.mean(gap < d_s) > 0.5)


def in_lanes(sc: Scenario, routes, v: Speeds, around) -> list[list[list[float]]]:
    """``routes`` made flyable round the zones UAV by UAV, each in the lowest lane
    (:func:`lanes`) whose planned flight has no conflict (:func:`conflicts`) with the UAVs
    before it; failing that, the same in reverse (two UAVs given the same lines fly them from
    opposite ends); failing that, if most of its waypoints lie on the path of a UAV before it
    (the same box twice, :func:`_on_path`), the whole route moved by ``LANE x d_s`` or twice
    that along x or y (two interleaved boxes); failing that, the
    candidate of fewest conflicts (the first on ties: lane 0 before the others). A candidate is
    taken only if eq. 17-18 cut no more of the route than in lane 0 (a lane costs a little
    transit, never search) and the moved route stays in eq. 20's operating area.
    ``around(k, waypoints, lane)``: UAV ``k``'s waypoints made flyable in lane ``lane`` (cut to
    fit eq. 17-18). A route without conflicts keeps lane 0, the router's own way."""
    u = sc.uav
    d_s = sc.constraints.safety_distance_m
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    heading0 = takeoff_heading(Grid.from_config(sc.map).bounds, takeoff)
    x0, y0, x1, y1 = operating_area(sc)
    n = len(takeoff)
    times, pos, act = planned_positions(sc, [[] for _ in range(n)], v)
    shifts = [
        np.array(d) * m * LANE * d_s
        for m in (1, 2)
        for d in ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0))
    ]
    out: list[list[list[float]]] = []
    for k in range(n):
        if not len(routes[k]):
            out.append([])
            continue
        wps0 = np.asarray(routes[k], dtype=float).reshape(-1, 2)
        cands = [(lane, q) for q in (wps0, wps0[::-1]) for lane in range(MAX_LANES)]
        if any(_on_path(wps0, out[j], takeoff[j], landing[j], d_s) for j in range(k)):
            cands += [(0, wps0 + s) for s in shifts]  # the same box as a UAV before it
        best: tuple[int, list, np.ndarray, np.ndarray] | None = None
        for lane, q in cands:
            if np.any((q[:, 0] < x0) | (q[:, 0] > x1) | (q[:, 1] < y0) | (q[:, 1] > y1)):
                continue
            wps = around(k, q, lane)
            if best is not None and len(wps) < len(best[1]):
                continue  # the lane's length would cost search (eq. 18 cuts the route)
            path = np.vstack([takeoff[k], np.asarray(wps, dtype=float).reshape(-1, 2), landing[k]])
            pos[:, k], act[:, k] = track(path, v, u.max_turn_rate_rad_s, times, heading0[k])
            count = int(conflicts(sc, pos, act, one=k)[:, k].sum()) if k else 0
            if best is None or count < best[0]:
                best = (count, wps, pos[:, k].copy(), act[:, k].copy())
            if count == 0:
                break
        assert best is not None
        out.append(best[1])
        pos[:, k], act[:, k] = best[2], best[3]
    return out


def apart(
    sc: Scenario, routes, v: Speeds, order, alternatives=None, within: float = LANE
) -> tuple[list[list[list[float]]], dict[int, np.ndarray]]:
    """``routes`` with the UAVs of ``order`` (each with a route, the others' routes fixed)
    taken in turn, each kept only if its planned flight (:func:`planned_positions`) keeps eq.
    21 (:func:`conflicts`, ``within``: ``LANE x d_s`` by default, a lane's margin for the
    follower's drift) with the fixed UAVs and those of ``order`` kept before it (i24-stagger).
    ``alternatives(k, waypoints)``: other waypoint lists for UAV ``k``'s route (e.g. the same
    box entered from its other end), tried in turn before the UAV is dropped. Returns the
    routes (dropped UAVs without a route, kept ones as taken) and, per dropped UAV, its
    planned positions ``(m, 2)`` in conflict (those of its route as given)."""
    u = sc.uav
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    heading0 = takeoff_heading(Grid.from_config(sc.map).bounds, takeoff)
    times, pos, act = planned_positions(sc, routes, v)
    order = [k for k in order if len(routes[k])]
    act[:, order] = False
    out = [list(r) for r in routes]
    where: dict[int, np.ndarray] = {}
    for k in order:
        wps0 = out[k]
        cands = [wps0] + (list(alternatives(k, wps0)) if alternatives is not None else [])
        first = np.zeros((0, 2))
        for i, wps in enumerate(cands):
            path = np.vstack([takeoff[k], np.asarray(wps, dtype=float).reshape(-1, 2), landing[k]])
            pos[:, k], act[:, k] = track(path, v, u.max_turn_rate_rad_s, times, heading0[k])
            hit = conflicts(sc, pos, act, one=k, within=within)[:, k].any(axis=1)
            if i == 0:
                first = pos[hit, k].copy()
            if not hit.any():
                out[k] = [list(map(float, q)) for q in wps]
                break
        else:
            act[:, k] = False
            out[k] = []
            where[k] = first
    return out, where
