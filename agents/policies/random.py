"""``random``: the floor every policy must clear."""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.policies.base import Policy
from poc_env.sim.control import to_increments
from poc_env.sim.observations import decode_vector, split_observation


class RandomPolicy(Policy):
    """Uniform random speed and heading increments in level flight (pitch increment 0).

    Level, because with random pitch a UAV at 1000 m hits the ground within a few steps and
    the baseline would only measure crashing; its generator is seeded from the episode seed.
    """

    name = "random"

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.rng = np.random.default_rng([seed, 7])

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        acts = {}
        for a in observations:
            v = self.rng.uniform(-1.0, 1.0, 3)
            v[2] = 0.0
            acts[a] = v.astype(np.float32)
        return acts, state


class RandomHeadingPolicy(RandomPolicy):
    """``random_heading``: a uniform random map-frame heading per UAV and step, flown by the
    ``heading`` control level's autopilot (:mod:`poc_env.sim.control`, with auto-return): the
    floor of the ``-Heading-`` tasks."""

    name = "random_heading"
    control = "heading"

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        if not observations:
            return {}, state
        agents = list(self.env.possible_agents)
        live = [a for a in agents if a in observations]
        shape = self.env.params.grid.shape
        vec = np.stack([split_observation(observations[a], shape)[1] for a in live])
        q = decode_vector(self.env.params, vec)
        act = self.rng.uniform(-1.0, 1.0, (len(live), 2))
        k = np.array([agents.index(a) for a in live])
        inc = to_increments(self.env.params, self.control, q, act, k)
        return {a: inc[j].astype(np.float32) for j, a in enumerate(live)}, state


class RandomWaypointPolicy(RandomHeadingPolicy):
    """``random_waypoint``: a uniform random target point per UAV and step, flown by the
    ``waypoint`` control level's autopilot: the floor of the ``-Waypoint-`` tasks."""

    name = "random_waypoint"
    control = "waypoint"
