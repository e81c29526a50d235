"""A terrain case the mission tests and scripts share: an Alps-like valley with a wall.

:func:`wall_scenario` is the scenario of tests/mission/test_altitude_layers.py and
results/mission/i24-layers/zero_ab.py (tests/mission/test_terrain.py and
results/audit/terrainleft/probes.py build the same one their own way).
:func:`hill_across_first_leg` raises a plan's recorded ground across a UAV's take-off climb,
:func:`ring_around` in a ring round a point (tests/mission/test_final_glide.py,
tests/mission/test_vertical_rates.py); :func:`cell_centres` gives a recorded grid's cell
centres.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: The valley floor and the wall's top, metres AMSL; the wall runs north-south at x = 30 km.
VALLEY_M, WALL_M, WALL_X_KM = 600.0, 4000.0, 30.0


def wall_scenario(**over: Any) -> dict[str, Any]:
    """A 60 x 40 km search area near 46.5 N 7.9 E, one airfield ``valley`` at (-10, 20) km with
    two UAVs (ceiling 6,000 m), over an elevation grid of 1 km cells from (-40, -30) km: the
    valley floor, and a wall 4 km wide at x = 30 km. ``over``: top-level sections replaced."""
    x = -40 + np.arange(120) + 0.5
    row = np.where(np.abs(x - WALL_X_KM) < 2.0, WALL_M, VALLEY_M)
    data: dict[str, Any] = {
        "name": "alps",
        "map": {"width_km": 60, "height_km": 40, "cell_km": 5, "origin_deg": [46.5, 7.9],
                "prior": {"components": [{"mean_km": [32, 20], "sigma_km": [10, 8]}]}},
        "airfields": [{"name": "valley", "position_km": [-10, 20]}],
        "fleet": [{"takeoff": "valley", "count": 2}],
        "uav": {"max_altitude_m": 6000},
        "terrain": {"elevation_m": np.tile(row, (100, 1)).tolist(), "cell_km": 1.0,
                    "origin_km": [-40, -30]},
    }  # fmt: skip
    return {**data, **over}


#: The two fields of :func:`valley_to_bowl` (km): ``valley`` and ``bowl``.
VALLEY_KM, BOWL_KM = (-10.0, 20.0), (70.0, 20.0)


def valley_to_bowl(ring_m: float | None = None, count: int = 2) -> dict[str, Any]:
    """:func:`wall_scenario` flown from ``valley`` to ``bowl`` by ``count`` UAVs over a flat
    valley (an elevation grid of 1 km cells from (-40, -30) km); with ``ring_m``, ground of
    that height in a ring 6-8 km round ``bowl`` (tests/mission/test_orbit_fit.py,
    test_vertical_rates.py, test_missionfix.py)."""
    x = -40 + np.arange(140) + 0.5
    gx, gy = np.meshgrid(x, -30 + np.arange(100) + 0.5)
    elev = np.full(gx.shape, VALLEY_M)
    if ring_m is not None:
        d = np.hypot(gx - BOWL_KM[0], gy - BOWL_KM[1])
        elev = np.where((d >= 6.0) & (d <= 8.0), ring_m, elev)
    return wall_scenario(
        airfields=[{"name": "valley", "position_km": list(VALLEY_KM)},
                   {"name": "bowl", "position_km": list(BOWL_KM)}],
        fleet=[{"takeoff": "valley", "landing": "bowl", "count": count}],
        terrain={"elevation_m": elev.tolist(), "cell_km": 1.0, "origin_km": [-40, -30]},
    )  # fmt: skip


def hill_across_first_leg(
    plan: dict[str, Any], k: int, start_m: float, end_m: float, half_width_m: float, height_m: float
) -> dict[str, Any]:
    """The terrain record of ``plan`` with ground ``height_m`` (both layers) in every cell whose
    centre lies within ``half_width_m`` of UAV ``k``'s first leg between ``start_m`` and
    ``end_m`` from its take-off field: a hill across its take-off climb
    (tests/mission/test_terrain.py, tests/mission/test_climb_spiral.py)."""
    u = plan["uavs"][k]
    field, first = np.asarray(u["takeoff_m"], float), np.asarray(u["waypoints_m"][0], float)
    step = max(1, int(np.ceil((end_m - start_m) / 250.0)))
    along = (
        field
        + (first - field)
        / np.hypot(*(first - field))
        * np.linspace(start_m, end_m, step + 1)[:, None]
    )
    rec = dict(plan["terrain"])
    gx, gy = cell_centres(rec)
    near = np.min(np.hypot(gx[..., None] - along[:, 0], gy[..., None] - along[:, 1]), axis=-1)
    for key in ("ground_m", "ground_max_m"):
        rec[key] = np.where(near < half_width_m, height_m, np.asarray(rec[key])).tolist()
    return rec


def ring_around(
    plan: dict[str, Any], centre_km: Any, r0_km: float, r1_km: float, height_m: float
) -> dict[str, Any]:
    """``plan`` with ground ``height_m`` (both layers of its terrain record) in every cell
    whose centre lies ``r0_km``-``r1_km`` from ``centre_km``."""
    rec = dict(plan["terrain"])
    gx, gy = cell_centres(rec)
    d = np.hypot(gx - centre_km[0] * 1e3, gy - centre_km[1] * 1e3)
    on = (d >= r0_km * 1e3) & (d <= r1_km * 1e3)
    for key in ("ground_m", "ground_max_m"):
        rec[key] = np.where(on, height_m, np.asarray(rec[key])).tolist()
    return {**plan, "terrain": rec}


def cell_centres(rec: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """``(x, y)`` of every cell centre of a plan's terrain record (local metres, each of the
    grid's shape, rows from the south)."""
    ny, nx = np.asarray(rec["ground_m"]).shape
    cell = float(rec["cell_m"])
    gx, gy = np.meshgrid(
        rec["origin_m"][0] + (np.arange(nx) + 0.5) * cell,
        rec["origin_m"][1] + (np.arange(ny) + 0.5) * cell,
    )
    return gx, gy
