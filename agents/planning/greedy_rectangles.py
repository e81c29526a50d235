"""The greedy rectangle planner: a simple baseline for the allocation planner (issue 24).

Each UAV in fleet order takes the axis-aligned rectangle of whole cells that holds the most
*remaining* prior mass among those it can search and still be home within the usable endurance
0.85 T (eq. 18), flies it as a lawnmower (parallel lines ``W`` apart along the rectangle's
longer side, boustrophedon, from the end nearer its take-off field), and the rectangle's cells
are then taken out of the remaining mass. Speeds are the allocation planner's
(:func:`poc_env.agents.planning.flight_rules.plan_speeds`, ``max``: out and on the lines at
``v_max``, home at ``v_c``).

The rectangles are searched over every position of a set of side lengths (every length up to
:data:`SIDES` cells, a geometric series above) with summed-area tables, in one compiled pass
(:func:`poc_env.agents.planning._kernels.best_box`); a rectangle is kept
when a lower bound of its flight time (straight transit to its nearest point and back from it,
the lines, a half-turn per line end) fits; the route it gives is then checked with eq. 18's
return rule (:func:`poc_env.agents.planning.refine.route_fits`) and its last lines dropped until
it fits. No-fly zones are flown around as the allocation planner does
(:meth:`poc_env.sim.routing.ZoneRouter.reroute`: search legs clipped to searchable airspace,
transit around), the lines dropped until the rerouted route fits; the cells the kept lines
cover as laid are taken (i24-fleet: taken as flown, a rectangle inside or behind a zone was
never taken, and the next UAVs of the field flew the same route).

:func:`make_greedy_rectangles_plan` returns the fields a
:class:`~poc_env.agents.policies.base.PlanPolicy` flies (``uavs[*].waypoints_m``,
``speeds_mps``) and the planned POS (``posc``: eq. 10 per cell over the whole flight path, as
the allocation planner counts it); the ``greedy_rectangles`` policy flies it.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from poc_env.agents.planning import _kernels
from poc_env.agents.planning.flight_rules import path_coverage as _path_coverage
from poc_env.agents.planning.flight_rules import plan_speeds
from poc_env.agents.planning.flight_rules import reserve_s as _reserve
from poc_env.agents.planning.geography import zone_prior
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.refine import route_fits
from poc_env.config import Scenario, load_scenario
from poc_env.errors import ConfigError, as_int
from poc_env.sim.core import takeoff_heading
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import pod_from_coverage

#: every side length up to this many cells is tried, a geometric series (x 1.25) above it.
SIDES = 12
#: shares of the time budget the box search is run with, in turn, until the route it gives
#: keeps at least half its lines under eq. 18.
SCALES = (1.0, 0.9, 0.8, 0.7, 0.6, 0.5)


def _side_lengths(n: int) -> np.ndarray:
    """Side lengths (cells) tried on an axis of ``n`` cells."""
    sides = set(range(1, min(n, SIDES) + 1))
    s = float(SIDES)
    while s < n:
        s *= 1.25
        sides.add(min(round(s), n))
    return np.array(sorted(sides))


def _lines(lo, hi, w: float, start, offsets=None) -> np.ndarray:
    """Boustrophedon waypoints over the box ``lo``-``hi`` (x, y): lines ``w`` apart along its
    longer side, centred across it, from the corner nearest ``start``; or, given ``offsets``
    (increasing positions across the box, m), lines at those positions."""
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    size = hi - lo
    along = 0 if size[0] >= size[1] else 1
    across = 1 - along
    if offsets is None:
        n = max(1, math.ceil(size[across] / w - 1e-9))
        offsets = lo[across] + (np.arange(n) + 0.5) * size[across] / n
    offsets = np.asarray(offsets, dtype=float)
    if abs(start[across] - hi[across]) < abs(start[across] - lo[across]):
        offsets = offsets[::-1]
    ends = [lo[along], hi[along]]
    if abs(start[along] - hi[along]) < abs(start[along] - lo[along]):
        ends = ends[::-1]
    pts = []
    for m, off in enumerate(offsets):
        a, b = ends if m % 2 == 0 else ends[::-1]
        for t in (a, b):
            p = [0.0, 0.0]
            p[along], p[across] = t, off
            pts.append(p)
    return np.array(pts)


def _best_box(remaining, grid: Grid, widths, heights, w, v, turn, budget, takeoff, landing):
    """The box (``lo``, ``hi`` corners, m) of whole cells of most ``remaining`` mass whose
    flight time estimate (straight to its nearest point and back from it, the lines and a
    half-turn per line end) is within ``budget``; None when none is."""
    h = grid.cell_m
    ox, oy = grid.origin_m
    table = np.zeros((grid.ny + 1, grid.nx + 1))
    table[1:, 1:] = remaining.cumsum(0).cumsum(1)
    mass, i, j, nw, nh = _kernels.best_box(
        table,
        np.asarray(widths, dtype=np.int64),
        np.asarray(heights, dtype=np.int64),
        np.array([ox, oy]),
        float(h),
        float(w),
        np.array([v.out, v.line, v.home]),
        float(turn),
        float(budget),
        np.asarray(takeoff, dtype=float),
        np.asarray(landing, dtype=float),
    )
    if not mass > 0.0:
        return None
    lo = (ox + i * h, oy + j * h)
    return lo, (lo[0] + nw * h, lo[1] + nh * h)


def make_greedy_rectangles_plan(
    scenario: Scenario | str = "paper_6_2",
    *,
    prior: np.ndarray | None = None,
    uavs: int | None = None,
    seed: int = 0,
    speed: str = "max",
    zone_reach: float | None = None,
) -> dict[str, Any]:
    """The greedy rectangle plan of ``scenario`` on ``prior`` (module docstring); ``speed`` the
    rule of :func:`~poc_env.agents.planning.flight_rules.plan_speeds`; ``zone_reach`` the zone
    discount's reach in sweep widths (:func:`~poc_env.agents.planning.geography.zone_prior`;
    default the allocation's ``PlanOptions.zone_reach``, which its greedy start passes).
    Deterministic (``seed`` is recorded only)."""
    t0 = time.perf_counter()
    sc = load_scenario(scenario)
    if uavs is not None:
        sc = sc.with_uavs(as_int("uavs", uavs, 1, 64))
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map) if prior is None else np.asarray(prior, dtype=float)
    if prior.shape != grid.shape:
        raise ConfigError("prior", prior.shape, f"an array of the grid's shape {grid.shape}")
    if not np.all(np.isfinite(prior)) or np.any(prior < 0):
        raise ConfigError("prior", "array", "finite cell masses >= 0")
    if zone_reach is not None:  # validated as the allocation's option
        zone_reach = PlanOptions(zone_reach=zone_reach).zone_reach
    router = ZoneRouter.for_scenario(sc)
    prior = zone_prior(sc, prior, router, zone_reach)
    u = sc.uav
    w = sc.sensor.sweep_width_m
    v = plan_speeds(sc, speed)
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    heading0 = takeoff_heading(grid.bounds, takeoff)
    budget = u.usable_endurance_s - _reserve(sc)
    turn = math.pi / u.max_turn_rate_rad_s  # a half-turn at a line end
    remaining = prior.copy()
    widths = _side_lengths(grid.nx)
    heights = _side_lengths(grid.ny)
    routes: list[list[list[float]]] = []
    for k in range(len(takeoff)):

        def fits(p, k=k):
            return route_fits(
                p, v, u.max_turn_rate_rad_s, u.usable_endurance_s, _reserve(sc), heading0[k]
            )

        wps: np.ndarray = np.zeros((0, 2))
        lines: np.ndarray = np.zeros((0, 2))
        for scale in SCALES:  # a route that does not fit eq. 18: a tighter estimate
            box = _best_box(remaining, grid, widths, heights, w, v, turn, scale * budget,
                            takeoff[k], landing[k])  # fmt: skip
            if box is None:
                break
            lines = _lines(box[0], box[1], w, takeoff[k])
            full = len(lines)
            wps = np.zeros((0, 2))
            while len(lines):
                path = np.vstack([takeoff[k], lines, landing[k]])
                if router.active:  # the whole route round the zones, cut below by lines
                    path = router.reroute(path)
                if fits(path):
                    wps = path[1:-1]
                    break
                lines = lines[:-2]  # drop the last line
            if len(lines) >= full // 2:  # lines kept, not the waypoints round the zones
                break
        if len(wps):  # the cells its lines cover are taken (i24-fleet: the lines as laid,
            # not as flown round a zone, else the next UAV takes the same rectangle again)
            cov = _path_coverage(lines, grid, w)
            remaining[cov >= 0.5] = 0.0
        routes.append([[float(a), float(b)] for a, b in wps])
    cov = sum(
        (
            _path_coverage([takeoff[k], *routes[k], landing[k]], grid, w)
            for k in range(len(routes))
            if routes[k]
        ),
        np.zeros(grid.shape),
    )
    posc = float(np.sum(prior * pod_from_coverage(cov, sc.sensor.law)))
    return {
        "planner": "greedy_rectangles",
        "scenario": sc.name,
        "seed": int(seed),
        "route": True,
        "speeds_mps": v.as_dict(),
        "posc": posc,
        "runtime_s": time.perf_counter() - t0,
        "uavs": [
            {
                "id": k + 1,
                "takeoff_m": [float(c) for c in takeoff[k]],
                "landing_m": [float(c) for c in landing[k]],
                "waypoints_m": routes[k],
            }
            for k in range(len(routes))
        ],
    }
