"""Policies for moving targets: the space-time plan, flown or re-planned every K minutes.

``spacetime_plan`` plans at each episode's start with :func:`poc_env.agents.planning.spacetime.
spacetime_plan` (the allocation planner on the co-moving predicted POC, routes mapped to meet
the mass where it will be) and flies it with the waypoint follower, as ``allocation_plan``
flies its plan. ``spacetime_receding`` does the same and then, every ``replan_min`` minutes,
re-plans from the environment's current belief (the filter's, its detections included) for the
UAVs still searching, each from where it is with the endurance it has left
(:func:`~poc_env.agents.planning.spacetime.replan`). Both read the episode's drift velocity from
the environment (the velocity its filter predicts with; zero for a static target, when the
plans are ``allocation_plan``'s).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.planning.allocation import LEVELS, MARGIN, REFINE, SPEED
from poc_env.agents.planning.spacetime import replan, spacetime_plan
from poc_env.agents.policies.base import PlanPolicy, Policy
from poc_env.errors import ConfigError
from poc_env.sim.autopilot import WaypointFollower, must_return
from poc_env.sim.observations import decode_vector, split_observation


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
        levels: int | tuple[int, ...] = LEVELS,
        margin: float = MARGIN,
        speed: str = SPEED,
        refine: int = REFINE,
    ) -> None:
        if not (isinstance(replan_min, int | float) and 1.0 <= float(replan_min) <= 1e4):
            raise ConfigError("replan_min", replan_min, "minutes between re-plans in [1, 1e4]")
        self.replan_s = float(replan_min) * 60.0
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
        belief = np.array(self.env.sim_state.belief[0], dtype=float)
        plan = replan(
            self.env.scenario, belief, drift_of(self.env), p.s, np.array(pos), now, ks,
            seed=self.seed + self.plans, **self.alloc,
        )  # fmt: skip
        wps: list = [np.zeros((0, 2))] * len(self.agents)
        for j, k in enumerate(ks):
            wps[k] = plan["uavs"][j]["waypoints_m"]
        old = self.follower
        self._fly(wps, plan)
        for k in range(len(self.agents)):  # UAVs not re-planned keep flying their route
            if k not in ks:
                self.follower.waypoints[k] = old.waypoints[k]
                self.follower.index[k] = old.index[k]
        self.plans += 1

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        now = float(self.env.sim_state.step[0]) * self.params.dt
        if now - self.last >= self.replan_s:
            self.last = now
            self._replan(observations, now)
        return self.follower.predict(observations, state)
