"""One policy interface for everything that flies in poc-env.

A policy is reset at the start of every episode with the environment (its scenario, params and
agent names) and the episode's seed, then maps the per-agent observation dict to an action dict
(``predict`` mirrors SB3's signature: ``(observations, state, episode_start, deterministic) ->
(actions, state)``). The evaluator scores a lawnmower, the DE planner and a PPO checkpoint the
same way through this interface; :mod:`agents.policies.registry` makes them by name.
"""

from __future__ import annotations

from typing import Any


class Policy:
    """Base class: ``reset(env, seed)`` then ``predict(observations)`` each step."""

    name = "policy"

    def reset(self, env: Any, seed: int) -> None:
        self.env = env

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        raise NotImplementedError
