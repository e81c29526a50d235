"""Per-agent observations and the global state, batched over envs and agents.

Raster (``RASTER_CHANNELS`` x ny x nx, float32 in [0, 1], one pixel per grid cell):

===  ================  ========================================================================
ch   name              meaning
===  ================  ========================================================================
0    ``poc``           current POC of the cell / the largest cell POC of the episode's prior
1    ``self``          1 in the cell holding this UAV (all 0 while it is outside the grid)
2    ``others``        1 in cells holding another flying UAV
3    ``hazard``        1 where the cell centre is in a no-fly zone or above the threat threshold
===  ================  ========================================================================

Vector (``VECTOR_SIZE`` float32 values, bounds in ``VECTOR_LOW`` / ``VECTOR_HIGH``):

===  =====================  ==================================================  ===========
idx  name                   meaning                                             bounds
===  =====================  ==================================================  ===========
0-1  ``x``, ``y``           position in the operating area, 0 .. 1 per axis     [-1, 2]
2    ``z``                  altitude / ceiling                                  [0, 1]
3    ``speed``              (v - v_min) / (v_max - v_min)                       [0, 1]
4-5  ``sin``, ``cos``       heading alpha                                       [-1, 1]
6    ``pitch``              beta / beta_max                                     [-1, 1]
7    ``endurance``          remaining endurance 1 - t / T                       [0, 1]
8    ``usable``             remaining usable time 1 - t / (0.85 T), clipped     [-1, 1]
9-10 ``to_landing``         vector to the landing field / area diagonal         [-1, 1]
11   ``neighbours``         UAVs in communication range / (N - 1)               [0, 1]
12   ``flying``             1 while the UAV flies, 0 after landing or a crash   [0, 1]
13   ``time``               step / horizon                                      [0, 1]
===  =====================  ==================================================  ===========
"""

from __future__ import annotations

import numpy as np

from poc_env import comms as comms_mod
from poc_env import constraints as cons
from poc_env.simulator import Params, State

RASTER_CHANNELS = 4
VECTOR_NAMES = (
    "x", "y", "z", "speed", "sin", "cos", "pitch", "endurance", "usable",
    "to_landing_x", "to_landing_y", "neighbours", "flying", "time",
)  # fmt: skip
VECTOR_SIZE = len(VECTOR_NAMES)
VECTOR_LOW = np.array([-1, -1, 0, 0, -1, -1, -1, 0, -1, -1, -1, 0, 0, 0], dtype=np.float32)
VECTOR_HIGH = np.array([2, 2, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1], dtype=np.float32)


def hazard_mask(params: Params) -> np.ndarray:
    """(ny, nx) float32: 1 where a cell centre is in a no-fly zone or above the threat limit."""
    c = params.grid.centers
    mask = np.zeros(params.grid.shape, dtype=bool)
    if len(params.zones):
        mask |= params.zones.inside(c)
    if len(params.threat_lambdas):
        mask |= cons.threat_violation(
            c, params.threat_centers, params.threat_lambdas, params.scenario.map.threat_threshold
        )
    return mask.astype(np.float32)


def cell_pixels(params: Params, xy: np.ndarray):
    """Row, column and inside-grid mask of positions (..., 2)."""
    g = params.grid
    inside = g.contains(xy)
    j, i = g.cell_of(xy)
    return j, i, inside


def rasters(params: Params, state: State, poc_scale: np.ndarray, hazard: np.ndarray):
    """(E, N, C, ny, nx) float32 raster observations of every agent."""
    e, n = state.flying.shape
    g = params.grid
    poc = g.coarsen(state.belief, params.s) / poc_scale[:, None, None]
    out = np.zeros((e, n, RASTER_CHANNELS, g.ny, g.nx), dtype=np.float32)
    out[:, :, 0] = np.clip(poc, 0.0, 1.0)[:, None]
    out[:, :, 3] = hazard
    j, i, inside = cell_pixels(params, state.pos[..., :2])
    present = inside & state.flying
    ee, nn = np.nonzero(present)
    occupancy = np.zeros((e, g.ny, g.nx), dtype=np.float32)
    occupancy[ee, j[ee, nn], i[ee, nn]] = 1.0
    own = np.zeros((e, n, g.ny, g.nx), dtype=np.float32)
    own[ee, nn, j[ee, nn], i[ee, nn]] = 1.0
    out[:, :, 1] = own
    # others = occupancy without oneself (another UAV in the same cell keeps it at 1)
    counts = np.zeros((e, g.ny, g.nx), dtype=np.float32)
    np.add.at(counts, (ee, j[ee, nn], i[ee, nn]), 1.0)
    out[:, :, 2] = np.clip(counts[:, None] - own, 0.0, 1.0)
    del occupancy
    return out


def vectors(params: Params, state: State) -> np.ndarray:
    """(E, N, VECTOR_SIZE) float32 state vectors of every agent."""
    sc = params.scenario
    u = sc.uav
    bx0, by0, bx1, by1 = params.bounds
    w, h = bx1 - bx0, by1 - by0
    diag = float(np.hypot(w, h))
    xy = state.pos[..., :2]
    to_land = (params.landing[None] - xy) / diag
    adj = comms_mod.in_range(xy, sc.comms.range_m, state.flying)
    n = state.flying.shape[1]
    v = np.empty((*state.flying.shape, VECTOR_SIZE), dtype=np.float64)
    v[..., 0] = (xy[..., 0] - bx0) / w
    v[..., 1] = (xy[..., 1] - by0) / h
    v[..., 2] = state.pos[..., 2] / u.max_altitude_m
    v[..., 3] = (state.speed - u.min_speed_mps) / (u.max_speed_mps - u.min_speed_mps)
    v[..., 4] = np.sin(state.heading)
    v[..., 5] = np.cos(state.heading)
    v[..., 6] = state.pitch / u.max_pitch_rad
    v[..., 7] = 1.0 - state.elapsed / u.endurance_s
    v[..., 8] = 1.0 - state.elapsed / u.usable_endurance_s
    v[..., 9:11] = to_land
    v[..., 11] = adj.sum(axis=2) / max(n - 1, 1)
    v[..., 12] = state.flying
    v[..., 13] = (state.step / params.horizon)[:, None]
    return np.clip(v, VECTOR_LOW, VECTOR_HIGH).astype(np.float32)


def decode_vector(params: Params, vec: np.ndarray) -> dict[str, np.ndarray]:
    """Physical quantities back from state vectors (..., VECTOR_SIZE): the inverse of
    :func:`vectors` for position (m), altitude (m), speed (m/s), heading and pitch (rad)."""
    u = params.scenario.uav
    bx0, by0, bx1, by1 = params.bounds
    v = np.asarray(vec, dtype=float)
    return {
        "xy": np.stack([bx0 + v[..., 0] * (bx1 - bx0), by0 + v[..., 1] * (by1 - by0)], -1),
        "z": v[..., 2] * u.max_altitude_m,
        "speed": u.min_speed_mps + v[..., 3] * (u.max_speed_mps - u.min_speed_mps),
        "heading": np.arctan2(v[..., 4], v[..., 5]),
        "pitch": v[..., 6] * u.max_pitch_rad,
        "flying": v[..., 12] > 0.5,
        "usable": v[..., 8],
    }
