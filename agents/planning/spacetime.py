"""Space-time allocation for a drifting target: plan where the mass will be, fly to meet it.

For a target drifting with a uniform velocity ``v`` (the registered Drift tasks; the velocity
the environment's filter uses, :mod:`poc_env.theory.motion`), the belief in the frame moving
with the current only diffuses (and loses the mass that leaves the map). The planner

1. predicts the belief without search over the flight (the filter's own predict step,
   :func:`poc_env.theory.motion.predict`, on the fine belief), shifts each step's coarse map
   back by ``v t`` (bilinear) into the co-moving frame, and averages it over the flight: the
   co-moving POC (mass that has drifted out of the map, or diffused away, weighs less);
2. plans on it with the allocation planner (:func:`poc_env.agents.planning.allocation.
   make_allocation_plan`: reach-aware allocation, tracks, routes within the usable endurance);
3. maps every route to the ground: waypoint ``x_k`` of the co-moving frame is met at the time
   ``t_k`` the UAV reaches it and flown to ``x_k + v t_k`` -- each leg's ``t_{k+1} - t_k``
   solves ``|d + v dt| = u dt`` (the intercept of a point drifting with ``v`` at ground speed
   ``u``: transit speed to the first waypoint, search speed along the route).

With ``v = 0`` and no diffusion, step 1 returns the prior and step 3 the static routes.
:func:`replan` makes the same plan mid-flight from the current belief: every UAV takes off
from where it is with the endurance it has left (the receding-horizon policy,
:mod:`poc_env.agents.policies.moving`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
from scipy.ndimage import shift as nd_shift

from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.config import KMH, Airfield, FleetGroup, Scenario
from poc_env.errors import ConfigError
from poc_env.sim.core import operating_area
from poc_env.theory import motion as motion_mod
from poc_env.theory.probability_map import Grid


def comoving_poc(
    scenario: Scenario,
    belief_fine: np.ndarray,
    velocity,
    s: int,
    duration_s: float,
    start_s: float = 0.0,
) -> np.ndarray:
    """Step 1 of the module docstring: the coarse ``(ny, nx)`` POC of ``belief_fine`` predicted
    over ``duration_s`` from ``start_s`` (episode time), in the frame moving with ``velocity``
    (m/s), averaged over the steps."""
    sc = scenario
    grid = Grid.from_config(sc.map)
    dt = sc.episode.dt_s
    motion = motion_mod.check(sc.target, (grid.ny, grid.nx), sc.horizon_steps * dt, sc.map)
    b = np.array(belief_fine, dtype=float)[None]
    vel = np.asarray(velocity, dtype=float).reshape(1, 2)
    n = max(1, round(duration_s / dt))
    acc = np.zeros(grid.shape)
    h = grid.cell_m / s
    for k in range(n):
        t = (k + 1) * dt
        if motion.moves:
            motion_mod.predict(motion, b, vel, start_s + k * dt, dt, h, s)
        coarse = grid.coarsen(b[0], s)
        off = (-vel[0, 1] * t / grid.cell_m, -vel[0, 0] * t / grid.cell_m)  # (rows, cols)
        acc += nd_shift(coarse, off, order=1, mode="constant", cval=0.0, prefilter=False)
    return np.maximum(acc / n, 0.0)


def intercept(start, waypoints, velocity, speeds) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: ground waypoints ``(k, 2)`` and times ``(k,)`` meeting the co-moving
    ``waypoints`` from ``start`` (ground position at time 0), leg ``k`` flown at
    ``speeds[k]`` (m/s) relative to the ground."""
    wps = np.asarray(waypoints, dtype=float).reshape(-1, 2)
    v = np.asarray(velocity, dtype=float)
    vv = float(v @ v)
    out = np.empty_like(wps)
    times = np.empty(len(wps))
    pos, t = np.asarray(start, dtype=float), 0.0
    here = pos.copy()  # co-moving position of the UAV (equals the ground one at t = 0)
    for k, x in enumerate(wps):
        d = x - here
        u = float(speeds[k])
        a = u * u - vv
        if a <= 0:  # a ConfigError (a ValueError): the current given is what to change
            raise ConfigError(
                "target.current_kmh",
                float(np.sqrt(vv)) / KMH,
                f"a drift (km/h: the current plus target.random_current_kmh's draw) below the "
                f"UAVs' ground speed {u / KMH:.1f} km/h: the space-time plan meets the mass",
            )
        dv = float(d @ v)
        dt = (dv + np.sqrt(dv * dv + a * float(d @ d))) / a
        t += dt
        out[k] = x + v * t
        times[k] = t
        here = x
    return out, times


def flight_times(start, waypoints, speeds) -> np.ndarray:
    """The times ``(k,)`` at which the ground ``waypoints`` are reached flown in turn from
    ``start`` (time 0), leg ``k`` at ground speed ``speeds[k]`` (m/s): the sums of leg
    lengths over speeds."""
    g = np.asarray(waypoints, dtype=float).reshape(-1, 2)
    legs = np.diff(np.vstack([np.asarray(start, dtype=float).reshape(1, 2), g]), axis=0)
    return np.cumsum(np.hypot(legs[:, 0], legs[:, 1]) / np.asarray(speeds, dtype=float)[: len(g)])


def comoving_route(start, waypoints, velocity, speeds) -> np.ndarray:
    """The inverse of :func:`intercept`: the co-moving waypoints ``(k, 2)`` of the ground
    ``waypoints`` flown from ``start`` (ground position at time 0), leg ``k`` at ground speed
    ``speeds[k]`` (m/s): ``x_k = g_k - v t_k`` with ``t_k`` their :func:`flight_times`."""
    g = np.asarray(waypoints, dtype=float).reshape(-1, 2)
    v = np.asarray(velocity, dtype=float)
    if not len(g):
        return g.copy()
    return g - flight_times(start, g, speeds)[:, None] * v


def ground_plan(plan: dict, starts, velocity, area=None) -> dict:
    """The plan with every UAV's ``waypoints_m`` mapped to the ground (step 3); each UAV's
    ``meet_times_s`` records when it meets them (from the plan's start). ``area``: eq. 20's
    operating area ``(x0, y0, x1, y1)`` (:func:`poc_env.sim.core.operating_area`): a ground
    waypoint outside it (where the mass has drifted off the map) is dropped, the route flying
    on to its next waypoint inside (chosen over ending the route there: +0.0044 and -0.0003
    POSC on the two ``UAVSearch-Paper61-Drift-Heading-v1`` seeds of 5000-5002 that differ);
    the plan records how many were dropped in ``cut_outside_area`` (absent when none). After a
    dropped waypoint the route is shorter, so the later ones are reached before their co-moving
    points pass there: ``meet_times_s`` are then the times they are reached
    (:func:`flight_times` at the plan's speeds, the follower's; what :func:`choose_routes`
    scores), not the intercept's. The plan's POS figures (``posc``, per-UAV ``pos``) stay those
    of the co-moving POC it was made on."""
    v = plan.get("speeds_mps") or {}
    out = dict(plan)
    uavs = []
    cut = 0
    for k, u in enumerate(plan["uavs"]):
        wps = np.asarray(u["waypoints_m"], dtype=float).reshape(-1, 2)
        u2 = dict(u)
        if len(wps):
            speeds = [v.get("out", 0.0)] + [v.get("line", 0.0)] * (len(wps) - 1)
            g, times = intercept(starts[k], wps, velocity, speeds)
            if area is not None:
                x0, y0, x1, y1 = area
                inside = (g[:, 0] >= x0) & (g[:, 0] <= x1) & (g[:, 1] >= y0) & (g[:, 1] <= y1)
                cut += int((~inside).sum())
                if not inside.all():  # reached early after a drop (docstring)
                    g = g[inside]
                    times = flight_times(starts[k], g, speeds)
            u2["waypoints_m"] = g.tolist()
            u2["meet_times_s"] = times.tolist()
        uavs.append(u2)
    out["uavs"] = uavs
    if cut:
        out["cut_outside_area"] = cut
    out["planner"] = "spacetime"
    out["drift_mps"] = [float(x) for x in np.asarray(velocity, dtype=float)]
    return out


def spacetime_plan(
    scenario: Scenario,
    belief_fine: np.ndarray,
    velocity,
    s: int,
    seed: int = 0,
    start_s: float = 0.0,
    **allocation: Any,
) -> dict:
    """The space-time plan (module docstring) of ``scenario`` from the fine belief at episode
    time ``start_s``, from the scenario's airfields (use :func:`replan` mid-flight)."""
    sc = scenario
    window = sc.uav.usable_endurance_s
    poc = comoving_poc(sc, belief_fine, velocity, s, window, start_s)
    if poc.sum() <= 0:  # nothing left to find in the map: plan on the belief as it is
        poc = Grid.from_config(sc.map).coarsen(np.asarray(belief_fine, dtype=float), s)
    plan = make_allocation_plan(sc, prior=poc, seed=seed, **allocation)
    area = operating_area(sc)
    return ground_plan(plan, np.asarray(sc.takeoff_m, dtype=float), velocity, area)


def airborne_scenario(
    scenario: Scenario, positions, elapsed_s: float, agents: list[int]
) -> Scenario:
    """``scenario`` with the UAVs ``agents`` taking off from ``positions (len(agents), 2)``
        (metres) with ``elapsed_s`` of their endurance spent (the usable endurance left is eq. 18's
    ``0.85 T - elapsed``), each still landing where it would."""
    sc = scenario
    land_names = []
    for g in sc.fleet:
        land_names += [g.landing] * g.count
    fields = list(sc.airfields)
    fleet = []
    for j, k in enumerate(agents):
        name = f"_uav{k}"
        x, y = (float(c) for c in positions[j])
        fields.append(Airfield(name=name, position_m=(x, y)))
        fleet.append(FleetGroup(takeoff=name, count=1, landing=land_names[k]))
    # the usable endurance left is 0.85 T - elapsed (eq. 18), so T' = T - elapsed / 0.85
    left = sc.uav.endurance_s - elapsed_s / sc.uav.usable_fraction
    uav = replace(sc.uav, endurance_s=max(left, 60.0))
    return replace(sc, airfields=tuple(fields), fleet=tuple(fleet), uav=uav)


def airborne_poc(
    scenario: Scenario, belief_fine: np.ndarray, velocity, s: int, positions, elapsed_s, agents
) -> np.ndarray:
    """The co-moving POC (:func:`comoving_poc`) of the current belief over the usable endurance
    the UAVs ``agents`` have left at ``elapsed_s``: what :func:`replan` plans on and
    :func:`choose_routes` scores with."""
    sc = airborne_scenario(scenario, positions, elapsed_s, agents)
    return comoving_poc(sc, belief_fine, velocity, s, sc.uav.usable_endurance_s, elapsed_s)


def replan(
    scenario: Scenario,
    belief_fine: np.ndarray,
    velocity,
    s: int,
    positions,
    elapsed_s: float,
    agents: list[int],
    seed: int = 0,
    poc: np.ndarray | None = None,
    **allocation: Any,
) -> dict:
    """The space-time plan of the UAVs ``agents`` (indices into the fleet) from where they are
    (``positions``, metres) at episode time ``elapsed_s``, on the current fine belief; the
    plan's ``uavs`` follow ``agents``' order. ``poc``: the co-moving POC if already computed
    (:func:`airborne_poc`)."""
    sc = airborne_scenario(scenario, positions, elapsed_s, agents)
    if poc is None:
        poc = airborne_poc(scenario, belief_fine, velocity, s, positions, elapsed_s, agents)
    if poc.sum() <= 0:
        poc = Grid.from_config(sc.map).coarsen(np.asarray(belief_fine, dtype=float), s)
    plan = make_allocation_plan(sc, prior=poc, seed=seed, **allocation)
    area = operating_area(scenario)  # the scenario's: the UAVs' positions are no airfields
    return ground_plan(plan, np.asarray(positions, dtype=float), velocity, area)


def choose_routes(
    scenario: Scenario,
    belief_fine: np.ndarray,
    velocity,
    s: int,
    positions,
    elapsed_s: float,
    agents: list[int],
    candidates: list[tuple[list, list]],
    margin: float,
    poc: np.ndarray | None = None,
) -> tuple[int, list[float]]:
    """The switch rule (module docstring). ``candidates[i]`` is ``(routes, speeds)``: per UAV of
    ``agents`` (at ``positions``) its remaining ground waypoints and the ground speed of each leg;
    candidate 0 is the set being flown. Each is scored by the predicted POS of its routes over
    the endurance left (:func:`sampled_sweep` on :func:`comoving_poc` of the current belief, each
    route from the UAV's position in the co-moving frame). Returns the index to fly -- the best
    candidate if it scores more than candidate 0 by ``margin``, else 0 -- and the scores.
    ``poc``: :func:`airborne_poc` if already computed."""
    if not candidates:
        raise ValueError("choose_routes needs at least the routes being flown")
    sc = airborne_scenario(scenario, positions, elapsed_s, agents)
    grid = Grid.from_config(sc.map)
    if poc is None:
        poc = airborne_poc(scenario, belief_fine, velocity, s, positions, elapsed_s, agents)
    pos = np.asarray(positions, dtype=float).reshape(-1, 2)
    scores = []
    for routes, speeds in candidates:
        paths = [
            np.vstack([pos[j], comoving_route(pos[j], routes[j], velocity, speeds[j])])
            for j in range(len(pos))
        ]
        scores.append(float(sum(sampled_sweep(sc, grid, poc, paths)[0])))
    best = int(np.argmax(scores))
    return (best if scores[best] > scores[0] + margin else 0), scores
