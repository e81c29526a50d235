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
