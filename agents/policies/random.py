"""``random``: the floor every policy must clear."""

from __future__ import annotations

from typing import Any

import numpy as np

from agents.policies.base import Policy


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
