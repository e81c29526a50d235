"""The check every route-editing planner test makes of its output (polish, regrade).

:func:`assert_flyable_inside`: every route fits eq. 17-18 from its take-off heading
(:func:`~poc_env.agents.planning.refine.route_fits`, the planner's own rule) and every
waypoint the move placed -- one not among the route's waypoints before -- lies inside the map.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def assert_flyable_inside(
    sc: Any, grid: Any, takeoff: np.ndarray, landing: np.ndarray, new_routes: Sequence,
    old_routes: Sequence,
) -> None:  # fmt: skip
    """Assert it for each UAV ``k`` of ``new_routes`` (``len(new_routes)`` may be a multiple of
    the fleet: route ``j`` is UAV ``j mod n``'s, compared with ``old_routes[j mod n]``)."""
    from poc_env.agents.planning.flight_rules import plan_speeds, reserve_s
    from poc_env.agents.planning.refine import route_fits
    from poc_env.sim.core import takeoff_heading

    v = plan_speeds(sc)
    heading = takeoff_heading(grid.bounds, takeoff)
    x0, y0, x1, y1 = grid.bounds
    n = len(takeoff)
    for j, r in enumerate(new_routes):
        k = j % n
        new = np.asarray(r, dtype=float).reshape(-1, 2)
        path = np.vstack([takeoff[k], new, landing[k]])
        fits = route_fits(path, v, sc.uav.max_turn_rate_rad_s, sc.uav.usable_endurance_s,
                          reserve_s(sc), heading[k])  # fmt: skip
        assert fits, f"route {j} does not fit eq. 17-18"
        moved = ~np.isin(new, np.asarray(old_routes[k], dtype=float).reshape(-1, 2)).all(axis=1)
        assert np.all((new[moved] >= [x0, y0]) & (new[moved] <= [x1, y1])), (
            f"route {j} leaves the map"
        )
