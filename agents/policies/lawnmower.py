"""``lawnmower``: the classical baseline, flown through the waypoint follower.

The area's north-south lines at spacing S = W are split into N contiguous blocks (one strip per
UAV, in take-off order from west to east; with fewer lines than UAVs, one line a block, shared
by neighbouring UAVs); each UAV flies the parallel search (§2.2, eq. 5-6)
of its strip, starting at the corner nearest its airfield, then returns to land. It ignores the
prior: the reference every prior-aware method must beat.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from shapely.geometry import box

from poc_env.agents.policies.base import Policy
from poc_env.sim.autopilot import WaypointFollower
from poc_env.sim.core import Params
from poc_env.theory.patterns import parallel_search


def lawnmower_waypoints(params: Params, spacing_m: float | None = None) -> list[np.ndarray]:
    """One strip's parallel-search waypoints per UAV (see the module docstring)."""
    s = spacing_m or params.scenario.sensor.sweep_width_m
    x0, y0, x1, y1 = params.grid.bounds
    n = params.n_agents
    order = np.argsort(params.takeoff[:, 0], kind="stable")
    lines = int(np.ceil((x1 - x0) / s - 1e-9))  # the whole area's lines at spacing S ...
    blocks = min(n, lines)  # ... split into N blocks (one a line when there are fewer lines:
    edges = x0 + np.round(np.linspace(0, lines, blocks + 1)) * s  # neighbours share a block)
    edges[-1] = max(edges[-1], x1)
    out: list[np.ndarray] = [np.empty((0, 2))] * n
    for rank, agent in enumerate(order):
        strip = rank * blocks // n
        region = box(edges[strip], y0, edges[strip + 1], y1)
        out[agent] = parallel_search(region, s, 0.0, start=params.takeoff[agent]).waypoints
    return out


def lawnmower_policy(params: Params, agents) -> WaypointFollower:
    """The lawnmower's waypoints in a follower (observations in, actions out)."""
    return WaypointFollower(params, lawnmower_waypoints(params), agents)


class LawnmowerPolicy(Policy):
    """``lawnmower`` (module docstring): a fresh follower of its strips every episode."""

    name = "lawnmower"

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.follower = lawnmower_policy(env.params, env.possible_agents)

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        return self.follower.predict(observations, state)
