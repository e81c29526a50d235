"""One policy interface for everything that flies in poc-env.

A policy is reset at the start of every episode with the environment (its scenario, params and
agent names) and the episode's seed, then maps the per-agent observation dict to an action dict
(``predict`` mirrors SB3's signature: ``(observations, state, episode_start, deterministic) ->
(actions, state)``). The evaluator scores a lawnmower, the DE planner and a PPO checkpoint the
same way through this interface; :mod:`poc_env.agents.policies.registry` makes them by name.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.sim.autopilot import WaypointFollower


class Policy:
    """Base class: ``reset(env, seed)`` then ``predict(observations)`` each step."""

    name = "policy"

    def reset(self, env: Any, seed: int) -> None:
        self.env = env

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        raise NotImplementedError


class PlanPolicy(Policy):
    """A plan made at each episode's start, then flown: ``reset`` plans on the environment's
    prior (the fine belief summed to the grid's cells) with :meth:`make` and flies every UAV's
    ``waypoints_m`` with the waypoint follower, at the plan's ``speeds_mps`` (``out`` in
    transit, ``line`` on the route) when it records them, else at eq. 17's v_c and v_s."""

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        raise NotImplementedError

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        prior = env.params.grid.coarsen(env.sim_state.belief[0], env.params.s)
        self.plan = self.make(env, prior, seed)
        wps = [np.asarray(u["waypoints_m"], dtype=float) for u in self.plan["uavs"]]
        v = self.plan.get("speeds_mps") or {}
        self.follower = WaypointFollower(
            env.params,
            wps,
            env.possible_agents,
            transit_speed_mps=v.get("out"),
            pattern_speed_mps=v.get("line"),
        )

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        return self.follower.predict(observations, state)
