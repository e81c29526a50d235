"""One policy interface for everything that flies in poc-env.

A policy is reset at the start of every episode with the environment (its scenario, params and
agent names) and the episode's seed, then maps the per-agent observation dict to an action dict
(``predict`` mirrors SB3's signature: ``(observations, state, episode_start, deterministic) ->
(actions, state)``). The evaluator scores a lawnmower, the DE planner and a PPO checkpoint the
same way through this interface; :mod:`poc_env.agents.policies.registry` makes them by name.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from poc_env.sim.autopilot import WaypointFollower, go_home, must_return
from poc_env.sim.observations import RASTER_INDEX, decode_vector, split_observation


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


@dataclass(frozen=True)
class Reading:
    """What a belief-driven policy reads from one live UAV's observation.

    Attributes
    ----------
    k:
        The UAV's index.
    agent:
        Its agent name.
    poc:
        ``(ny, nx)`` its POC raster (the belief it holds, kept up to date by eq. 14).
    q:
        Its state decoded from the observation vector
        (:func:`poc_env.sim.observations.decode_vector`).
    """

    k: int
    agent: str
    poc: np.ndarray
    q: dict


class BeliefPolicy(Policy):
    """An online policy that re-decides every step from the observations alone: it reads every
    live UAV's belief and state (:meth:`read`), flies home and lands the UAVs whose usable
    endurance (eq. 18) only covers the way back (:func:`poc_env.sim.autopilot.must_return`,
    :func:`~poc_env.sim.autopilot.go_home`, the waypoint follower's rule), and leaves the rest
    to :meth:`search`, which subclasses write (``greedy_bayes``, ``potential_game``,
    ``de_receding``)."""

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.params = env.params
        self.agents = env.possible_agents

    def read(self, observations: dict) -> list[Reading]:
        """One :class:`Reading` per live UAV, in agent order."""
        p = self.params
        out = []
        for k, agent in enumerate(self.agents):
            if agent not in observations:
                continue
            ras, vec = split_observation(observations[agent], p.grid.shape)
            poc = np.asarray(ras[RASTER_INDEX["poc"]], dtype=float)
            out.append(Reading(k, agent, poc, decode_vector(p, vec)))
        return out

    def search(self, searching: list[Reading], readings: list[Reading]) -> dict[str, Any]:
        """Actions ``{agent: eq. 19 action}`` of the ``searching`` UAVs (those not heading
        home), given every live UAV's ``readings``."""
        raise NotImplementedError

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        p = self.params
        readings = self.read(observations)
        home = {r.agent: go_home(p, r.q, r.k) for r in readings if must_return(p, r.q, r.k)}
        moves = self.search([r for r in readings if r.agent not in home], readings)
        actions = {}
        for r in readings:  # in agent order
            if r.agent in home:
                actions[r.agent] = home[r.agent]
            elif r.agent in moves:
                actions[r.agent] = moves[r.agent]
        return actions, state
