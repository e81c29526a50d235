"""Fly waypoints with eq. 19 increments only (within their per-step limits), then land.

The follower is how planned routes (the DE plan, lawnmowers, patterns) fly in the
environment: each step it turns towards the current waypoint as far as the turn limit allows,
holds the pattern speed on the pattern and the transit speed on the way to the first waypoint
(by default eq. 17's search speed v_s and cruise speed v_c; a route plan may fly faster), and
levels the pitch to hold the cruise altitude. A waypoint counts as reached when it is within
half a step, or as passed at its closest approach: when the distance to it, having shrunk,
starts to grow while the last step ended within the capture radius ``v dt / 2 + v / omega_max``
(half a step plus the turn radius: the closest the turn-rate bound lets a UAV come to a point
beside it without an orbit). Without that second rule a UAV that comes round at the wrong
phase orbits the waypoint until the return rule sends it home (issue 24). After the last
waypoint -- or as soon as the remaining usable endurance (0.85 T, eq. 18) only just covers the
flight home at cruise speed plus two steps -- the UAV heads for its landing field.
With no-fly zones (eq. 20) the legs to the first waypoint and home follow the shortest path
around them (:class:`poc_env.sim.routing.ZoneRouter`, the planners' router), and the return
rule budgets that path's length. Near a zone every step is also checked before it is flown
(:func:`zone_guard`): a turn whose step would enter a zone, or leave no step after it that
keeps out, is replaced by the admissible turn closest to it that keeps out for two steps.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from poc_env.errors import ConfigError
from poc_env.sim.constraints import NoFlyZones
from poc_env.sim.core import Params
from poc_env.sim.observations import decode_vector, split_observation
from poc_env.sim.routing import ZoneRouter, clearance_m, reach_and_turn_m

#: least bearing difference (degrees) between field-mates flying out: the allocation
#: planner's fan-out (:func:`poc_env.agents.planning.allocation._fan_out`) and the follower's
#: hop out of the field for UAVs given nothing (:func:`_leave_fields`); within
#: ``d_s / sin FAN_DEG`` of an airfield field-mates are together anyway.
FAN_DEG = 20.0


def steer(params: Params, xy, heading, speed, pitch, z, goal, target_speed) -> np.ndarray:
    """Normalised actions (..., 3) that turn towards ``goal`` at ``target_speed``, level."""
    u = params.scenario.uav
    dt = params.dt
    d = np.asarray(goal, dtype=float) - xy
    want = np.arctan2(d[..., 1], d[..., 0])
    turn = (want - heading + np.pi) % (2 * np.pi) - np.pi
    a_turn = np.clip(turn / (u.max_turn_rate_rad_s * dt), -1.0, 1.0)
    a_speed = np.clip((target_speed - speed) / (u.max_accel_mps2 * dt), -1.0, 1.0)
    # pitch towards the cruise altitude, at most the angle that closes the gap in one step
    dz = u.cruise_altitude_m - z
    want_pitch = np.clip(
        np.arctan2(dz, np.maximum(speed * dt, 1.0)), -u.max_pitch_rad, u.max_pitch_rad
    )
    a_pitch = np.clip((want_pitch - pitch) / (u.max_pitch_rate_rad_s * dt), -1.0, 1.0)
    return np.stack([a_speed, a_turn, a_pitch], axis=-1)


def steer_to(params: Params, q: dict, goal, target_speed) -> np.ndarray:
    """:func:`steer` of the UAV (or UAVs) whose state vector entries are ``q`` (``xy``,
    ``heading``, ``speed``, ``pitch``, ``z``), towards ``goal`` at ``target_speed``."""
    return steer(params, q["xy"], q["heading"], q["speed"], q["pitch"], q["z"], goal, target_speed)


def returning(params: Params, xy, usable, k) -> np.ndarray:
    """Vectorised :func:`must_return`: ``xy (..., 2)`` positions, ``usable (...)`` remaining
    usable-endurance shares (observation entry ``usable``), ``k (...)`` UAV indices."""
    u = params.scenario.uav
    d = params.landing[np.asarray(k)] - np.asarray(xy, dtype=float)
    home = np.hypot(d[..., 0], d[..., 1])
    return np.asarray(usable) * u.usable_endurance_s <= home / u.cruise_speed_mps + 2 * params.dt


def homing(params: Params, q: dict, k) -> np.ndarray:
    """Vectorised :func:`go_home` over ``q`` entries shaped (...) and indices ``k (...)``."""
    u = params.scenario.uav
    goal = params.landing[np.asarray(k)]
    d = goal - np.asarray(q["xy"], dtype=float)
    home = np.hypot(d[..., 0], d[..., 1])
    v = np.where(home < 2 * u.cruise_speed_mps * params.dt, u.min_speed_mps, u.cruise_speed_mps)
    return steer_to(params, q, goal, v).astype(np.float32)


def must_return(params: Params, q: dict, k: int) -> bool:
    """True when the usable endurance (0.85 T, eq. 18) only just covers the flight home at
    cruise speed plus two steps (``q`` is :func:`decode_vector` of UAV ``k``'s observation)."""
    return bool(returning(params, q["xy"], q["usable"], k))


def go_home(params: Params, q: dict, k: int) -> np.ndarray:
    """Actions flying UAV ``k`` to its landing field at cruise speed, slowing down to land."""
    return homing(params, q, k)


def capture_radius(params: Params, speed) -> np.ndarray:
    """The follower's capture radius at ``speed`` (m/s): half a step plus the turn radius
    ``v / omega_max`` (eq. 19's turn-rate bound): :func:`poc_env.sim.routing.reach_and_turn_m`,
    which the router's clearance takes at ``v_max``."""
    return np.asarray(reach_and_turn_m(params.scenario, speed))


def zone_guard(
    zones: NoFlyZones, xy, heading: float, step: float, turn: float, max_turn: float, n: int = 15
) -> float:
    """The heading increment to fly instead of ``turn`` so that no-fly ``zones`` (eq. 20) are
    kept: ``turn`` itself when its step (``step`` metres along ``heading + turn``) enters no
    zone and some step after it (any turn within ``max_turn``) enters none either; else the
    admissible turn (``turn`` or one of ``n`` evenly spaced in ``[-max_turn, max_turn]``)
    closest to it with that property, or failing that the closest whose own step keeps out
    (the least bad: the proposal when none does)."""
    p0 = np.asarray(xy, dtype=float)
    t1 = np.concatenate([[float(np.clip(turn, -max_turn, max_turn))],
                         np.linspace(-max_turn, max_turn, n)])  # fmt: skip
    a1 = heading + t1
    p1 = p0 + step * np.stack([np.cos(a1), np.sin(a1)], axis=-1)  # (C, 2)
    bad1 = np.asarray(zones.segment_crosses(np.broadcast_to(p0, p1.shape), p1))
    a2 = a1[:, None] + np.linspace(-max_turn, max_turn, n)[None, :]
    p2 = p1[:, None, :] + step * np.stack([np.cos(a2), np.sin(a2)], axis=-1)  # (C, n, 2)
    hit2 = np.asarray(zones.segment_crosses(np.broadcast_to(p1[:, None, :], p2.shape), p2))
    bad2 = np.all(hit2, axis=1)
    if not (bad1[0] or bad2[0]):
        return float(t1[0])
    cost = 4.0 * bad1 + 2.0 * bad2 + np.abs(t1 - t1[0]) / (2 * max_turn + 1e-12)
    return float(t1[int(np.argmin(cost))])


def _lookahead(p, q, xy, ahead: float) -> np.ndarray:
    """The point ``ahead`` metres beyond the projection of ``xy`` on the leg p -> q (<= q)."""
    d = q - p
    length = float(np.hypot(*d))
    if length == 0:
        return q
    t = float(np.dot(xy - p, d)) / length + ahead
    return p + d * min(max(t, 0.0), length) / length


def _leave_fields(params: Params, waypoints: Sequence[np.ndarray]) -> list[np.ndarray]:
    """``waypoints`` (one ``(m, 2)`` array per UAV) with one point given to every UAV that has
    none and takes off inside its landing field's landing radius: a UAV lands only after
    having left the radius (:func:`poc_env.sim.core.step`), so one given nothing to fly
    circled there until it crashed at T (config-audit). The point lies twice that radius out
    from the field, towards the map's centre; field-mates given nothing all flew that one
    point at the same time, in step, eq. 21 collisions on every step of the hop (i24-flownsep:
    all 20-56 flown collision steps away from the fields on the deconfliction's ``mono2``
    case). So each such UAV, in index order, takes the first bearing of centre, centre +
    ``FAN_DEG``, centre - ``FAN_DEG``, centre + 2 ``FAN_DEG``, ... that is at least
    ``FAN_DEG`` from the outbound bearing of every field-mate (the first waypoint of a routed
    one, the point of one served before it; straight legs ``FAN_DEG`` apart are ``d_s`` apart
    from ``d_s / sin FAN_DEG`` out) and whose point lies in eq. 20's operating area and
    whose leg enters no no-fly zone (the centre bearing is always allowed, as before); failing
    that, the allowed bearing farthest from them. A UAV without field-mates, or whose
    field-mates leave on bearings ``FAN_DEG`` from the centre's, flies the centre's point."""
    out = [np.asarray(w, dtype=float).reshape(-1, 2) for w in waypoints]
    radius = params.scenario.episode.landing_radius_m
    takeoff = np.asarray(params.takeoff, dtype=float).reshape(-1, 2)
    land_all = np.asarray(params.landing, dtype=float).reshape(-1, 2)
    keys = [tuple(np.round(t, 3)) for t in takeoff]
    gap = np.radians(FAN_DEG)
    bx0, by0, bx1, by1 = params.bounds
    offsets = [0] + [s * j for j in range(1, int(np.ceil(np.pi / gap)) + 1) for s in (1, -1)]
    for k in range(len(out)):
        if len(out[k]):
            continue
        land = land_all[k]
        if float(np.hypot(*(takeoff[k] - land))) > radius:
            continue  # it leaves the radius on its way home
        x0, y0, x1, y1 = params.grid.bounds
        d = np.array([0.5 * (x0 + x1), 0.5 * (y0 + y1)]) - land
        norm = float(np.hypot(*d))
        d = d / norm if norm > 0 else np.array([1.0, 0.0])
        taken = [
            float(np.arctan2(*(out[j][0] - takeoff[j])[::-1]))
            for j in range(len(out))
            if j != k and keys[j] == keys[k] and len(out[j])
        ]
        base = float(np.arctan2(d[1], d[0]))
        best, best_gap = d, -1.0
        for i, off in enumerate(offsets):
            ang = base + off * gap
            u = d if off == 0 else np.array([np.cos(ang), np.sin(ang)])
            p = land + 2.0 * radius * u
            if i and not (bx0 <= p[0] <= bx1 and by0 <= p[1] <= by1):
                continue
            if i and len(params.zones) and bool(np.any(params.zones.segment_crosses(land, p))):
                continue
            apart = min(
                (abs((ang - t + np.pi) % (2 * np.pi) - np.pi) for t in taken), default=np.pi
            )
            if apart >= gap - 1e-9:
                best = u
                break
            if apart > best_gap:
                best, best_gap = u, apart
        out[k] = (land + 2.0 * radius * best).reshape(1, 2)
    return out


class WaypointFollower:
    """Policy that flies each agent's waypoint list (metres), then returns to land.

    ``predict(observations)`` takes the env's per-agent observation dict (``dict`` or ``flat``
    observations) and returns an action dict; the interface mirrors SB3's ``predict``.
    """

    def __init__(
        self,
        params: Params,
        waypoints: Sequence[np.ndarray],
        agents: Sequence[str],
        *,
        transit_speed_mps: float | None = None,
        pattern_speed_mps: float | None = None,
        closest_approach: bool = True,
        guard_zones: bool = True,
    ):
        u = params.scenario.uav
        #: the closest-approach rule and the zone guard (module docstring); both off is the
        #: follower before issue 24's fixes (kept to measure them against)
        self.closest_approach = bool(closest_approach)
        self.guard_zones = bool(guard_zones)
        self.params = params
        self.agents = list(agents)
        self.transit_speed = u.cruise_speed_mps if transit_speed_mps is None else transit_speed_mps
        self.pattern_speed = u.search_speed_mps if pattern_speed_mps is None else pattern_speed_mps
        for name, v in (
            ("transit_speed_mps", self.transit_speed),
            ("pattern_speed_mps", self.pattern_speed),
        ):
            if not (u.min_speed_mps <= v <= u.max_speed_mps):
                raise ConfigError(
                    name, v, f"within [{u.min_speed_mps:g}, {u.max_speed_mps:g}] m/s (eq. 19)"
                )
        self.waypoints = _leave_fields(params, waypoints)
        self.index = np.zeros(len(self.agents), dtype=int)
        # the closest-approach rule's memory: the last distance to the current waypoint and
        # whether it has shrunk since the waypoint became current
        self._last = np.full(len(self.agents), np.inf)
        self._closing = np.zeros(len(self.agents), dtype=bool)
        self.router = (
            ZoneRouter(params.zones.polygons, params.bounds, clearance_m(params.scenario))
            if len(params.zones)
            else None
        )

    def _around(self, xy: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, float]:
        """The next point on the way ``xy -> goal`` around the zones, and the way's length."""
        if self.router is None:
            return goal, float(np.hypot(*(goal - xy)))
        path = self.router.path(xy, goal)
        if path is None:
            return goal, float(np.hypot(*(goal - xy)))
        return path[1], float(np.hypot(*np.diff(path, axis=0).T).sum())

    def reset(self) -> None:
        self.index[:] = 0
        self._last[:] = np.inf
        self._closing[:] = False

    def _advance(self, k: int, xy: np.ndarray, speed: float) -> None:
        """Move UAV ``k`` past every waypoint it has reached (within half a step) or passed
        (its closest approach, within :func:`capture_radius`; module docstring)."""
        wps = self.waypoints[k]
        reach = 0.5 * speed * self.params.dt
        capture = float(capture_radius(self.params, speed))
        while self.index[k] < len(wps):
            d = float(np.hypot(*(wps[self.index[k]] - xy)))
            passed = (
                self.closest_approach
                and self._closing[k]
                and d > self._last[k]
                and self._last[k] <= capture
            )
            if d > reach and not passed:
                self._closing[k] |= d < self._last[k]
                self._last[k] = d
                return
            self.index[k] += 1
            self._last[k] = np.inf
            self._closing[k] = False

    def _guarded(self, q: dict, action: np.ndarray) -> np.ndarray:
        """``action`` with its turn replaced by :func:`zone_guard`'s near a zone."""
        zones = self.params.zones
        if not (self.guard_zones and len(zones)):
            return action
        step = float(q["speed"]) * self.params.dt * float(np.cos(q["pitch"]))
        xy = np.asarray(q["xy"], dtype=float)
        if float(zones.distance(xy)) > 2.0 * step + 1.0:
            return action
        m = self.params.scenario.uav.max_turn_rate_rad_s * self.params.dt
        turn = zone_guard(zones, xy, float(q["heading"]), step, float(action[1]) * m, m)
        out = np.array(action, dtype=np.float32)
        out[1] = np.float32(np.clip(turn / m, -1.0, 1.0))
        return out

    def _vector(self, obs) -> np.ndarray:
        """The state vector of one agent's ``dict`` or ``flat`` observation (a ``dict`` may
        hold the vector alone: the follower reads nothing else)."""
        if isinstance(obs, dict):
            return np.asarray(obs["vector"])
        return split_observation(obs, self.params.grid.shape)[1]

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        actions = {}
        for k, agent in enumerate(self.agents):
            if agent not in observations:
                continue
            q = decode_vector(self.params, self._vector(observations[agent]))
            wps = self.waypoints[k]
            reach = 0.5 * q["speed"] * self.params.dt
            xy = np.asarray(q["xy"], dtype=float)
            self._advance(k, xy, float(q["speed"]))
            home_goal, home_len = self._around(xy, self.params.landing[k])
            u = self.params.scenario.uav
            if self.router is None:
                back = must_return(self.params, q, k)
            else:  # eq. 18's rule on the way around the zones
                rule = home_len / u.cruise_speed_mps + 2 * self.params.dt
                back = bool(q["usable"] * u.usable_endurance_s <= rule)
            if back:
                self.index[k] = len(wps)
                self._last[k] = np.inf
                self._closing[k] = False
            on_pattern = 0 < self.index[k] < len(wps)
            if on_pattern:  # pure pursuit along the leg: back onto the line, then along it
                goal = _lookahead(
                    wps[self.index[k] - 1], wps[self.index[k]], q["xy"], float(2 * reach)
                )
            elif self.index[k] < len(wps):
                goal = self._around(xy, wps[self.index[k]])[0]
            else:
                goal = self.params.landing[k]
            if self.index[k] >= len(wps):
                if home_goal is not self.params.landing[k] and np.any(home_goal != goal):
                    act = steer(
                        self.params, xy, q["heading"], q["speed"], q["pitch"], q["z"],
                        home_goal, u.cruise_speed_mps,
                    ).astype(np.float32)  # fmt: skip
                else:
                    act = go_home(self.params, q, k)
                actions[agent] = self._guarded(q, act)
                continue
            v = self.pattern_speed if on_pattern else self.transit_speed
            act = steer_to(self.params, q, goal, v).astype(np.float32)
            actions[agent] = self._guarded(q, act)
        return actions, state
