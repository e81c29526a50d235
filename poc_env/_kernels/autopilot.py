"""The compiled autopilot of the ``heading``, ``heading_clip`` and ``waypoint`` control levels.

The kernel behind :func:`poc_env.sim.control.swarm_increments` for the levels that fly a goal:
each flying UAV's state is decoded from its float32 observation vector (as
:func:`poc_env.sim.observations.decode_vector`), its goal made from the action
(:func:`~poc_env.sim.control.heading_increments`, :func:`~poc_env.sim.control.waypoint_goal`),
flown towards by :func:`poc_env.sim.autopilot.steer`'s rule, and replaced by the homing
increments once eq. 18 says so (:func:`~poc_env.sim.control.return_home`); the increments are
rounded to float32 as the numpy path rounds them. The numpy functions stay the definition
(the waypoint follower and the RL pilot call them); ``tests/sim/test_kernels.py`` pins this
copy to them: bit for bit with numpy's baseline (X86_V2/V3) dispatch, whose ``arctan2`` is
the C library's as here; numpy's AVX-512 ``arctan2`` may round the last bit otherwise.

A kernel module: imports nothing of the project (the cache rule, :mod:`poc_env._kernels`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy")

_TWO_PI = 2 * np.pi

#: Control levels the kernel flies, by code.
HEADING, HEADING_CLIP, WAYPOINT = 0, 1, 2

#: The scalar constants of :func:`fly`, in the order of its ``constants`` array.
CONSTANTS = (
    "dt_s",
    "bx0", "by0", "bx1", "by1",  # the operating area (eq. 20): the vector's position scale
    "gx0", "gy0", "gx1", "gy1",  # the search grid (``Grid.contains``): search or cruise speed
    "max_altitude_m",
    "min_speed_mps",
    "max_speed_mps",
    "max_pitch_rad",
    "max_turn_rate_rad_s",
    "max_accel_mps2",
    "max_pitch_rate_rad_s",
    "cruise_altitude_m",
    "cruise_speed_mps",
    "search_speed_mps",
    "usable_endurance_s",
)  # fmt: skip

#: The state vector entries the kernel reads, in the order of its ``index`` array.
VECTOR_ENTRIES = ("x", "y", "z", "speed", "sin", "cos", "pitch", "usable")


def constants(**values: float) -> np.ndarray:
    """The float64 array of :func:`fly`'s constants from their names (:data:`CONSTANTS`)."""
    if set(values) != set(CONSTANTS):
        raise TypeError(f"autopilot constants need exactly {CONSTANTS}, got {sorted(values)}")
    out = np.array([float(values[name]) for name in CONSTANTS], dtype=np.float64)
    out.flags.writeable = False
    return out


@_jit
def _clip(q, lo, hi):
    """``q`` clipped to [lo, hi] (NaN stays NaN, as ``np.clip``)."""
    if q < lo:
        return lo
    if q > hi:
        return hi
    return q


@_jit
def _steer(c, x, y, heading, speed, pitch, z, gx, gy, target_speed, out):
    """:func:`poc_env.sim.autopilot.steer` of one UAV into ``out (3,)`` (float32)."""
    dt = c[0]
    want = math.atan2(gy - y, gx - x)
    m = want - heading + np.pi
    if not (m > 0.0 and m < _TWO_PI):  # inside (0, 2 pi) the remainder is m itself, exactly
        m = m % _TWO_PI
    turn = m - np.pi  # (want - heading + pi) % (2 pi) - pi
    a_turn = _clip(turn / (c[13] * dt), -1.0, 1.0)
    a_speed = _clip((target_speed - speed) / (c[14] * dt), -1.0, 1.0)
    dz = c[16] - z
    run = speed * dt
    if run < 1.0:  # np.maximum(run, 1.0): NaN stays NaN
        run = 1.0
    want_pitch = _clip(math.atan2(dz, run), -c[12], c[12])
    a_pitch = _clip((want_pitch - pitch) / (c[15] * dt), -1.0, 1.0)
    out[0] = a_speed
    out[1] = a_turn
    out[2] = a_pitch


@_jit
def fly(level, vec, action, flying, landing, index, c, lookahead, auto_return, out):
    """Increments ``out (E, N, 3)`` (float32) for the ``level`` (:data:`HEADING`,
    :data:`HEADING_CLIP`, :data:`WAYPOINT`) actions ``action (E, N, 2)`` of UAVs whose
    observation vectors are ``vec (E, N, V)`` float32 (entries at ``index``,
    :data:`VECTOR_ENTRIES`); 0 for UAVs not ``flying``. ``landing (N, 2)``: each UAV's landing
    field; ``c``: :func:`constants`; ``lookahead``: how far along a heading the goal lies (m);
    ``auto_return``: eq. 18's return rule on."""
    dt = c[0]
    bx0, by0, bw, bh = c[1], c[2], c[3] - c[1], c[4] - c[2]
    gx0, gy0, gx1, gy1 = c[5], c[6], c[7], c[8]
    n_env, n = flying.shape
    for e in range(n_env):
        for k in range(n):
            o = out[e, k]
            if not flying[e, k]:
                o[0] = 0.0
                o[1] = 0.0
                o[2] = 0.0
                continue
            v = vec[e, k]
            x = bx0 + np.float64(v[index[0]]) * bw
            y = by0 + np.float64(v[index[1]]) * bh
            z = np.float64(v[index[2]]) * c[9]
            speed = c[10] + np.float64(v[index[3]]) * (c[11] - c[10])
            heading = math.atan2(np.float64(v[index[4]]), np.float64(v[index[5]]))
            pitch = np.float64(v[index[6]]) * c[12]
            usable = np.float64(v[index[7]])
            a0 = action[e, k, 0]
            a1 = action[e, k, 1]
            if level == WAYPOINT:
                a0 = _clip(a0, -1.0, 1.0)
                a1 = _clip(a1, -1.0, 1.0)
                gx = c[1] + (a0 + 1) / 2 * (c[3] - c[1])
                gy = c[2] + (a1 + 1) / 2 * (c[4] - c[2])
            else:
                if level == HEADING_CLIP:
                    a0 = _clip(a0, -1.0, 1.0)
                    a1 = _clip(a1, -1.0, 1.0)
                norm = math.hypot(a0, a1)
                if norm < 1e-6:  # a zero vector keeps the heading
                    ux = math.cos(heading)
                    uy = math.sin(heading)
                else:
                    ux = a0 / norm
                    uy = a1 / norm
                gx = x + lookahead * ux
                gy = y + lookahead * uy
            inside = x >= gx0 and x <= gx1 and y >= gy0 and y <= gy1
            target = c[18] if inside else c[17]
            _steer(c, x, y, heading, speed, pitch, z, gx, gy, target, o)
            if auto_return:  # eq. 18: home once the usable endurance only covers the way back
                hx, hy = landing[k, 0], landing[k, 1]
                home = math.hypot(hx - x, hy - y)
                if usable * c[19] <= home / c[17] + 2 * dt:
                    v_home = c[10] if home < 2 * c[17] * dt else c[17]
                    _steer(c, x, y, heading, speed, pitch, z, hx, hy, v_home, o)
