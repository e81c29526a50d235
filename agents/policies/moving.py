"""Policies for moving targets: the space-time plan, flown or re-planned every K minutes.

``spacetime_plan`` plans at each episode's start with :func:`poc_env.agents.planning.spacetime.
spacetime_plan` (the allocation planner on the co-moving predicted POC, routes mapped to meet
the mass where it will be) and flies it with the waypoint follower, as ``allocation_plan``
flies its plan. ``spacetime_receding`` does the same and then, every ``replan_min`` minutes,
re-plans from the environment's current belief (the filter's, its detections included) for the
UAVs still searching, each from where it is with the endurance it has left
(:func:`~poc_env.agents.planning.spacetime.replan`), and flies the re-plan only if it scores
more than the routes being flown by ``switch_margin`` (POS), both scored by the planner's model
on the current belief (:func:`~poc_env.agents.planning.spacetime.choose_routes`); otherwise
every UAV keeps its route. Both read the episode's drift velocity from
the environment (the velocity its filter predicts with; zero for a static target, when the
plans are ``allocation_plan``'s).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.planning.allocation import LEVELS, MARGIN, REFINE, SPEED
from poc_env.agents.planning.spacetime import (
    airborne_poc,
    choose_routes,
    replan,
    spacetime_plan,
)
from poc_env.agents.policies.base import PlanPolicy, Policy
from poc_env.errors import ConfigError
from poc_env.sim.autopilot import WaypointFollower, must_return
from poc_env.sim.observations import decode_vector, split_observation

#: how much more POS (the planner's model, :func:`~poc_env.agents.planning.spacetime.
#: choose_routes`) a re-plan must promise over the routes being flown to be taken.
SWITCH_MARGIN = 0.005


def drift_of(env: Any) -> np.ndarray:
    """The episode's uniform drift velocity (m/s) of env 0, zero for a static target."""
    d = getattr(env.sim_state, "drift", None)
    return np.zeros(2) if d is None else np.asarray(d[0], dtype=float)


class SpacetimePlanPolicy(PlanPolicy):
    """``spacetime_plan`` (module docstring)."""

    name = "spacetime_plan"

    def __init__(
        self,
        levels: int | tuple[int, ...] = LEVELS,
        margin: float = MARGIN,
        speed: str = SPEED,
        refine: int = REFINE,
    ) -> None:
        self.alloc: dict[str, Any] = {
            "levels": levels,
            "margin": margin,
            "speed": speed,
            "refine": refine,
        }

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        belief = np.array(env.sim_state.belief[0], dtype=float)
        return spacetime_plan(
            env.scenario, belief, drift_of(env), env.params.s, seed=seed, **self.alloc
        )


class SpacetimeRecedingPolicy(Policy):
    """``spacetime_receding`` (module docstring)."""

    name = "spacetime_receding"

    def __init__(
        self,
        replan_min: float = 20.0,
        switch_margin: float = SWITCH_MARGIN,
        levels: int | tuple[int, ...] = LEVELS,
        margin: float = MARGIN,
        speed: str = SPEED,
        refine: int = REFINE,
    ) -> None:
        if not (isinstance(replan_min, int | float) and 1.0 <= float(replan_min) <= 1e4):
            raise ConfigError("replan_min", replan_min, "minutes between re-plans in [1, 1e4]")
        self.replan_s = float(replan_min) * 60.0
        if not (isinstance(switch_margin, int | float) and 0.0 <= float(switch_margin) <= 1.0):
            raise ConfigError("switch_margin", switch_margin, "a POS margin in [0, 1]")
        self.margin = float(switch_margin)
        self.alloc: dict[str, Any] = {
            "levels": levels,
            "margin": margin,
            "speed": speed,
            "refine": refine,
        }

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.seed = seed
        self.params = env.params
        self.agents = list(env.possible_agents)
        belief = np.array(env.sim_state.belief[0], dtype=float)
        plan = spacetime_plan(
            env.scenario, belief, drift_of(env), env.params.s, seed=seed, **self.alloc
        )
        self._fly([u["waypoints_m"] for u in plan["uavs"]], plan)
        self.last = 0.0
        self.plans = 1
        self.switches = 0
        self.scores: list[list[float]] = []

    def _fly(self, waypoints: list, plan: dict) -> None:
        v = plan.get("speeds_mps") or {}
        self.follower = WaypointFollower(
            self.params,
            [np.asarray(w, dtype=float).reshape(-1, 2) for w in waypoints],
            self.agents,
            transit_speed_mps=v.get("out"),
            pattern_speed_mps=v.get("line"),
        )

    def _replan(self, observations: dict, now: float) -> None:
        p = self.params
        ks, pos = [], []
        for k, agent in enumerate(self.agents):
            if agent not in observations:
                continue
            q = decode_vector(p, split_observation(observations[agent], p.grid.shape)[1])
            if must_return(p, q, k) or self.follower.index[k] >= len(self.follower.waypoints[k]):
                continue  # heading home already: leave it to the follower
            ks.append(k)
            pos.append(np.asarray(q["xy"], dtype=float))
        left = self.env.scenario.uav.endurance_s - now
        if not ks or left < 0.2 * self.env.scenario.uav.endurance_s:
            return
        sc, drift, xy = self.env.scenario, drift_of(self.env), np.array(pos)
        belief = np.array(self.env.sim_state.belief[0], dtype=float)
        poc = airborne_poc(sc, belief, drift, p.s, xy, now, ks)
        plan = replan(
            sc, belief, drift, p.s, xy, now, ks, seed=self.seed + self.plans, poc=poc, **self.alloc
        )
        self.plans += 1
        old = self.follower
        kept, kept_v = [], []
        for k in ks:  # the routes being flown, from where each UAV is, at the follower's speeds
            i = int(old.index[k])
            kept.append(old.waypoints[k][i:])
            kept_v.append(
                [old.transit_speed if i == 0 else old.pattern_speed]
                + [old.pattern_speed] * (len(old.waypoints[k]) - i)
            )
        v = plan.get("speeds_mps") or {}
        new = [
            np.asarray(plan["uavs"][j]["waypoints_m"], dtype=float).reshape(-1, 2)
            for j in range(len(ks))
        ]
        new_v = [
            [v.get("out", old.transit_speed)] + [v.get("line", old.pattern_speed)] * len(w)
            for w in new
        ]
        pick, scores = choose_routes(
            sc,
            belief,
            drift,
            p.s,
            xy,
            now,
            ks,
            [(kept, kept_v), (new, new_v)],
            self.margin,
            poc=poc,
        )
        self.scores.append(scores)
        if pick == 0:
            return  # keep every route: the re-plan does not promise enough more
        self.switches += 1
        wps: list = [np.zeros((0, 2))] * len(self.agents)
        for j, k in enumerate(ks):
            wps[k] = new[j]
        self._fly(wps, plan)
        for k in range(len(self.agents)):  # UAVs not re-planned keep flying their route
            if k not in ks:
                self.follower.waypoints[k] = old.waypoints[k]
                self.follower.index[k] = old.index[k]

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        now = float(self.env.sim_state.step[0]) * self.params.dt
        if now - self.last >= self.replan_s:
            self.last = now
            self._replan(observations, now)
        return self.follower.predict(observations, state)
