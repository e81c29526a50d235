"""Control levels: what a policy commands, turned into eq. 19 increments by one autopilot.

=============  ==================  ==========================================================
control        action per UAV      meaning
=============  ==================  ==========================================================
increments     Box(-1, 1, (3,))    the paper's eq. 19 increments (dv, d alpha, d beta) as
                                   fractions of their per-step limits (the default)
heading        Box(-1, 1, (2,))    a map-frame direction (a_x, a_y); the autopilot turns
                                   towards the point :data:`LOOKAHEAD_M` along it, at the
                                   search speed over the grid and the cruise speed outside it,
                                   level at the cruise altitude; a zero vector keeps the heading
waypoint       Box(-1, 1, (2,))    a target point: (-1, -1) is the operating area's
                                   south-west corner (eq. 20's boundary), (1, 1) its
                                   north-east one; flown like ``heading`` towards that point
=============  ==================  ==========================================================

``heading`` normalises the action as it is, so an action outside the Box still names a
direction (a component of 1e308 flies due east); the variant ``heading_clip``
(:data:`VARIANTS`, the ``...-Heading-v1`` tasks) clips each component to [-1, 1] first, as the
``waypoint`` level clips its point, and is the same level otherwise.

Every level other than ``increments`` is flown by :func:`poc_env.sim.autopilot.steer`, so every
increment stays within its eq. 19 limit (|a| <= 1 before scaling). With ``auto_return`` (the
default) the autopilot takes a UAV home and lands it as soon as eq. 18's usable endurance only
covers the way back (:func:`poc_env.sim.autopilot.returning`, then
:func:`~poc_env.sim.autopilot.homing`); the policy's action is then ignored. The RL
``pilot`` recipe (:mod:`poc_env.agents.rl.pilot`) is the ``heading`` level read from the observation
vector, through :func:`heading_increments`.
"""

from __future__ import annotations

import numpy as np

import poc_env._kernels.autopilot as _autopilot
from poc_env.errors import ConfigError
from poc_env.sim.autopilot import homing, returning, steer
from poc_env.sim.core import Params, State
from poc_env.sim.observations import VECTOR_INDEX, decode_vector, vectors

CONTROLS = ("increments", "heading", "waypoint")
#: Variants of a level with a changed rule (a new task version, :data:`poc_env.spec.TASK_VERSIONS`)
#: -> the level they vary: ``heading_clip`` clips each heading component to [-1, 1] first.
VARIANTS = {"heading_clip": "heading"}
#: Action size per UAV of each control level (and variant).
ACTION_DIMS = {"increments": 3, "heading": 2, "waypoint": 2, "heading_clip": 2}
#: How far ahead along a commanded heading the autopilot aims (m).
LOOKAHEAD_M = 10e3
#: The compiled autopilot's code of each level it flies (:func:`swarm_increments`).
_LEVEL_CODES = {
    "heading": _autopilot.HEADING,
    "heading_clip": _autopilot.HEADING_CLIP,
    "waypoint": _autopilot.WAYPOINT,
}
#: Where the compiled autopilot finds its entries in the state vector.
_VECTOR_ENTRIES = np.array([VECTOR_INDEX[k] for k in _autopilot.VECTOR_ENTRIES], dtype=np.intp)


def check_control(control: object) -> str:
    """``control`` if it names a level of :data:`CONTROLS` or a variant (:data:`VARIANTS`),
    else a ConfigError."""
    if not isinstance(control, str) or control not in (*CONTROLS, *VARIANTS):
        raise ConfigError("control", control, "one of " + ", ".join((*CONTROLS, *VARIANTS)))
    return control


def _fly_to(params: Params, q: dict, goal: np.ndarray, k, auto_return: bool) -> np.ndarray:
    """Increments (B, 3) flying towards ``goal (B, 2)``; home once eq. 18 says so."""
    u = params.scenario.uav
    xy = np.asarray(q["xy"], dtype=float)
    speed = np.where(params.grid.contains(xy), u.search_speed_mps, u.cruise_speed_mps)
    out = steer(params, xy, q["heading"], q["speed"], q["pitch"], q["z"], goal, speed)
    if auto_return:
        out = return_home(params, q, out, k)
    return out.astype(np.float32)


def return_home(params: Params, q: dict, inc: np.ndarray, k) -> np.ndarray:
    """``inc (B, 3)`` with the rows of UAVs that must head home replaced by the autopilot's
    homing increments: once eq. 18's usable endurance only covers the way back
    (:func:`~poc_env.sim.autopilot.returning`), :func:`~poc_env.sim.autopilot.homing` flies the
    UAV to its landing field and lands it. The one return rule of every autopilot level, and of
    the ``increments`` policies trained with a return autopilot (``train --return-autopilot``)."""
    out = np.array(inc, dtype=float, copy=True)
    home = returning(params, np.asarray(q["xy"], dtype=float), q["usable"], k)
    if home.any():
        out[home] = homing(params, {key: v[home] for key, v in q.items()}, np.asarray(k)[home])
    return out


def heading_increments(
    params: Params, q: dict, action: np.ndarray, k, auto_return: bool = True
) -> np.ndarray:
    """The ``heading`` level: increments (B, 3) for directions ``action (B, 2)`` of UAVs
    ``k (B,)`` whose state is ``q`` (:func:`poc_env.sim.observations.decode_vector`)."""
    xy = np.asarray(q["xy"], dtype=float)
    a = np.asarray(action, dtype=float).reshape(-1, 2)
    norm = np.hypot(a[:, 0], a[:, 1])
    keep = norm < 1e-6
    ux = np.where(keep, np.cos(q["heading"]), a[:, 0] / np.where(keep, 1.0, norm))
    uy = np.where(keep, np.sin(q["heading"]), a[:, 1] / np.where(keep, 1.0, norm))
    goal = xy + LOOKAHEAD_M * np.stack([ux, uy], axis=-1)
    return _fly_to(params, q, goal, k, auto_return)


def waypoint_goal(params: Params, action: np.ndarray) -> np.ndarray:
    """The point (B, 2) in metres a ``waypoint`` action (B, 2) in [-1, 1] names."""
    x0, y0, x1, y1 = params.bounds
    a = np.clip(np.asarray(action, dtype=float).reshape(-1, 2), -1.0, 1.0)
    return np.stack([x0 + (a[:, 0] + 1) / 2 * (x1 - x0), y0 + (a[:, 1] + 1) / 2 * (y1 - y0)], -1)


def waypoint_action(params: Params, xy: np.ndarray) -> np.ndarray:
    """The ``waypoint`` action (B, 2) naming the points ``xy (B, 2)`` in metres: the inverse of
    :func:`waypoint_goal`, clipped to [-1, 1] (points outside the operating area name its edge)."""
    x0, y0, x1, y1 = params.bounds
    p = np.asarray(xy, dtype=float).reshape(-1, 2)
    a = np.stack([2 * (p[:, 0] - x0) / (x1 - x0) - 1, 2 * (p[:, 1] - y0) / (y1 - y0) - 1], -1)
    return np.clip(a, -1.0, 1.0)


def to_increments(
    params: Params, control: str, q: dict, action: np.ndarray, k, auto_return: bool = True
) -> np.ndarray:
    """Eq. 19 increments (B, 3) for the ``control`` level's actions (B, ACTION_DIMS[control])."""
    if control == "increments":
        return np.asarray(action, dtype=float).reshape(-1, 3)
    if control == "heading":
        return heading_increments(params, q, action, k, auto_return)
    if control == "heading_clip":
        a = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)  # nan stays nan: as heading
        return heading_increments(params, q, a, k, auto_return)
    return _fly_to(params, q, waypoint_goal(params, action), k, auto_return)


def swarm_increments(
    params: Params,
    control: str,
    state: State,
    action: np.ndarray,
    auto_return: bool = True,
    return_increments: bool = False,
) -> np.ndarray:
    """Eq. 19 increments (E, N, 3) for every UAV of the batched ``state`` commanded by the
    ``control`` level's actions ``action (E, N, ACTION_DIMS[control])``: the one conversion the
    PettingZoo env and the batched VecEnvs share. ``increments`` pass through unchanged; the
    autopilot levels read each UAV's state from its observation vector and give 0 to UAVs that
    no longer fly, in one compiled pass (:func:`poc_env._kernels.autopilot.fly`: this module's
    and :mod:`~poc_env.sim.autopilot`'s rules, to which the tests pin it).
    ``return_increments`` applies :func:`return_home` to the ``increments`` level too (off in
    every registered task: their increments pass through; a training option)."""
    e, n = state.flying.shape
    a = np.asarray(action, dtype=float).reshape(e, n, ACTION_DIMS[control])
    if control == "increments" and not return_increments:
        return a
    if control == "increments":
        q = decode_vector(params, vectors(params, state).reshape(e * n, -1))
        inc = return_home(params, q, a.reshape(e * n, 3), np.tile(np.arange(n), e))
        return np.where(state.flying[..., None], inc.reshape(e, n, 3), a)
    out = np.empty((e, n, 3), dtype=np.float32)  # as the numpy autopilot rounds them
    _autopilot.fly(
        _LEVEL_CODES[control], vectors(params, state), a, state.flying, params.landing,
        _VECTOR_ENTRIES, params.autopilot_constants, LOOKAHEAD_M, auto_return, out,
    )  # fmt: skip
    return out
