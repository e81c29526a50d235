"""One policy interface for everything that flies in poc-env.

A policy is reset at the start of every episode with the environment (its scenario, params and
agent names) and the episode's seed, then maps the per-agent observation dict to an action dict
(``predict`` mirrors SB3's signature: ``(observations, state, episode_start, deterministic) ->
(actions, state)``). The evaluator scores a lawnmower, the DE planner and a PPO checkpoint the
same way through this interface.
"""

from __future__ import annotations

from typing import Any

import numpy as np


class Policy:
    """Base class: ``reset(env, seed)`` then ``predict(observations)`` each step."""

    name = "policy"

    def reset(self, env: Any, seed: int) -> None:
        self.env = env

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        raise NotImplementedError


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


class LawnmowerPolicy(Policy):
    """The lawnmower baseline (:mod:`agents.policies.baselines`) through the waypoint follower."""

    name = "lawnmower"

    def reset(self, env: Any, seed: int) -> None:
        from agents.policies.baselines import lawnmower_policy

        super().reset(env, seed)
        self.follower = lawnmower_policy(env.params, env.possible_agents)

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        return self.follower.predict(observations, state)
