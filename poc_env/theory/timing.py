"""Time model of a UAV's flight (eq. 17-18).

Transit (take-off to the first waypoint, last waypoint to landing) is flown at the cruise speed
v_b; the search legs between waypoints at the search speed v_s. The plan is feasible when the
total time t_i <= 0.85 T_i (eq. 18; the fraction is ``UAVConfig.usable_fraction``).
"""

from __future__ import annotations

import numpy as np

from poc_env.geometry import polyline_length


def flight_time_from_lengths(transit_m, search_m, cruise_speed_mps, search_speed_mps):
    """t = transit / v_b + search / v_s (eq. 17), broadcast over arrays of lengths."""
    return np.asarray(transit_m, dtype=float) / cruise_speed_mps + (
        np.asarray(search_m, dtype=float) / search_speed_mps
    )


def flight_lengths(takeoff_m, waypoints_m, landing_m) -> tuple[float, float]:
    """(transit length, search length) in metres of a take-off -> waypoints -> landing flight."""
    w = np.asarray(waypoints_m, dtype=float)
    t = np.asarray(takeoff_m, dtype=float)
    ld = np.asarray(landing_m, dtype=float)
    if len(w) == 0:
        return float(np.hypot(*(ld - t))), 0.0
    transit = float(np.hypot(*(w[0] - t)) + np.hypot(*(ld - w[-1])))
    return transit, polyline_length(w)


def flight_time_s(takeoff_m, waypoints_m, landing_m, cruise_speed_mps, search_speed_mps) -> float:
    """Total flight time t_i of eq. 17 for one UAV's waypoints."""
    transit, search = flight_lengths(takeoff_m, waypoints_m, landing_m)
    return float(flight_time_from_lengths(transit, search, cruise_speed_mps, search_speed_mps))


def is_feasible(time_s, endurance_s, usable_fraction: float = 0.85):
    """Eq. 18: t_i <= 0.85 T_i (elementwise)."""
    return np.asarray(time_s) <= usable_fraction * np.asarray(endurance_s) * (1 + 1e-12)


def overtime_s(time_s, endurance_s, usable_fraction: float = 0.85):
    """phi(t_i) = max(0, t_i - 0.85 T_i), the exterior penalty term of eq. 26."""
    return np.maximum(0.0, np.asarray(time_s) - usable_fraction * np.asarray(endurance_s))
