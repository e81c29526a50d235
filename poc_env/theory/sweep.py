"""The sensor model: the sweep width W from the search height and the sensor (issue 24).

One implementation, read once when a scenario loads
(:meth:`poc_env.config.Scenario._resolve_sweep_width` writes it into
``sensor.sweep_width_m``), so the planner, the bounds and the environment all use the same W.

Models (``sensor.model``):

``fixed``
    ``W = sweep_width_km``, whatever the height: the paper's §6 (W = 5 km). The default; every
    registered task keeps it.
``camera``
    A downward camera (or any nadir sensor) of cross-track field of view ``fov``: at a height
    ``h`` above the ground its footprint is ``2 h tan(fov / 2)`` wide, and the effective sweep
    width is that footprint times ``detection_factor`` ``k`` in (0, 1],

    .. math:: W = k \\cdot 2 h \\tan(\\mathrm{fov}/2),

    ``k`` being the share of the footprint over which the target class is detected as the
    detection law assumes (1: the whole footprint; lower for small targets or poor resolution
    at the edges). ``h`` is the search height above ground, ``uav.cruise_altitude_m``; with a
    DEM, missions fly that height above the ground where eq. 19's climb limit allows
    (:mod:`poc_env.agents.mission.terrain`), higher over ridges (a wider footprint then).
"""

from __future__ import annotations

import math
from typing import Any

from poc_env.errors import ConfigError

#: ``sensor.sweep_width_km``'s default (5 km, the paper's §6), in metres.
DEFAULT_SWEEP_WIDTH_M = 5000.0


def camera_sweep_width(height_m: float, fov_deg: float, detection_factor: float = 1.0) -> float:
    """``W = k 2 h tan(fov / 2)`` (module docstring), metres."""
    if not (height_m > 0 and 0 < fov_deg < 180 and 0 < detection_factor <= 1):
        raise ConfigError(
            "sensor", [height_m, fov_deg, detection_factor],
            "height > 0 m, 0 < fov_deg < 180, 0 < detection_factor <= 1",
        )  # fmt: skip
    return detection_factor * 2.0 * height_m * math.tan(math.radians(fov_deg) / 2.0)


def sweep_width(sensor: Any, height_m: float) -> float:
    """The sweep width (m) of a :class:`poc_env.config.SensorConfig` at ``height_m`` above the
    ground: the model ``sensor.model`` names (module docstring)."""
    if sensor.model == "fixed":
        return float(sensor.sweep_width_m)
    if sensor.model == "camera":
        return camera_sweep_width(height_m, sensor.fov_deg, sensor.detection_factor)
    raise ConfigError("sensor.model", sensor.model, "fixed or camera")
