"""Flight rules shared by the route planners (the allocation planner,
:mod:`poc_env.agents.planning.allocation`, and the greedy rectangles,
:mod:`poc_env.agents.planning.greedy_rectangles`): the speeds a route is flown at, the time kept
in hand at every waypoint and the per-cell coverage of a path."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from poc_env.agents.planning.refine import leg_coverage
from poc_env.config import Scenario
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import sweep_track

#: the default speed rule of :func:`plan_speeds`.
SPEED = "max"


@dataclass(frozen=True)
class Speeds:
    """Ground speeds (m/s) a route is planned and flown at: ``out`` from take-off to the first
    waypoint, ``line`` on the route (search lines and the connections between them), ``home``
    from the last waypoint to the landing field."""

    out: float
    line: float
    home: float

    def as_dict(self) -> dict[str, float]:
        return {"out": self.out, "line": self.line, "home": self.home}


def plan_speeds(sc: Scenario, rule: str = SPEED) -> Speeds:
    """The speeds of a route plan under ``rule``.

    ``"paper"``: eq. 17's speeds, transit at the cruise speed ``v_c`` and search at ``v_s``.
    ``"max"``: out and on the route at the eq. 19 maximum ``v_max``, home at ``v_c``. In the
    environment the sweep width W does not depend on speed (eq. 10 per unit length flown), so a
    route flown at ``v_max`` sweeps ``v_max / v_s`` (4/3 on the paper's UAV) as much ground per
    second. Home stays at ``v_c`` because eq. 18's return rule (the follower's and the
    environment's) budgets the flight home at ``v_c``. A sensor whose sweep width falls with
    speed should be planned with ``"paper"``.
    """
    u = sc.uav
    if rule == "paper":
        return Speeds(u.cruise_speed_mps, u.search_speed_mps, u.cruise_speed_mps)
    if rule == "max":
        return Speeds(u.max_speed_mps, u.max_speed_mps, u.cruise_speed_mps)
    raise ConfigError("speed", rule, "max or paper")


def reserve_s(sc: Scenario) -> float:
    """Time in hand at every waypoint: the two steps of eq. 18's return rule
    (:func:`poc_env.sim.autopilot.returning`) and one more, because the follower sees its
    position once a step and may pass a waypoint up to a step later than planned."""
    return 3.0 * sc.episode.dt_s


def path_coverage(path, grid: Grid, w: float) -> np.ndarray:
    """Coverage W x (length of the polyline ``path`` inside each cell) / area (eq. 10 per cell),
    every leg counted (transit too; :func:`poc_env.agents.planning.refine.leg_coverage`)."""
    pts = np.asarray(path, dtype=float).reshape(-1, 2)
    if len(pts) < 2:
        return np.zeros(grid.shape)
    return leg_coverage(pts[:-1], pts[1:], grid, w)[0].reshape(grid.shape)


def _swept_areas(lines: np.ndarray, spacing: float) -> list[list[list[float]]]:
    """The ground the search lines ``(L, 2, 2)`` sweep, each ``spacing`` wide (flat ends), as
    outer rings in metres (simplified to 1 m): the ``areas_m`` of plan.json schema 2, for
    people; ``waypoints_m`` is what is flown."""
    import shapely

    half = max(0.5 * spacing, 1.0)
    swaths = [shapely.LineString(seg).buffer(half, cap_style="flat") for seg in lines]
    union = shapely.union_all(swaths).simplify(1.0)
    polys = list(getattr(union, "geoms", [union]))
    return [[[float(x), float(y)] for x, y in p.exterior.coords[:-1]] for p in polys if p.area > 0]


def sampled_sweep(
    sc: Scenario, grid: Grid, prior: np.ndarray, paths
) -> tuple[list[float], list[np.ndarray]]:
    """The environment's detection model over whole flight paths: each path (take-off,
    waypoints, landing) swept in turn over the prior spread on the scenario's sample points
    (:func:`poc_env.theory.search_theory.sweep_track`, eq. 14 with the sensor's own lateral law
    and cut-off, the same compiled formula the environment steps with). Returns each path's POS
    (§3.1.6: a point is credited to the first path that finds it) and the mass each path finds
    per cell. Unlike W x length per cell (eq. 10 per cell), it does not depend on the cell size:
    a line sweeps the sample points within its lateral reach, whatever cells they lie in."""
    s = sc.sensor.samples_per_cell
    belief = np.ascontiguousarray(grid.refine(prior, s))
    w = sc.sensor.sweep_width_m
    cutoff = sc.sensor.cutoff_sweep_widths * w
    pos: list[float] = []
    found: list[np.ndarray] = []
    for path in paths:
        pts = np.asarray(path, dtype=float).reshape(-1, 2)
        if len(pts) < 2:
            pos.append(0.0)
            found.append(np.zeros(grid.shape))
            continue
        before = belief.copy()
        pos.append(sweep_track(belief, grid, s, pts, w, sc.sensor.law, cutoff, grid.cell_m))
        found.append(grid.coarsen(before - belief, s))
    return pos, found
