"""Several parameter-shared swarms of different sizes in one SB3 ``VecEnv``
(``poc-env train --also-task``): :class:`MixedVecEnv`."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from poc_env.errors import ConfigError


class MixedVecEnv(VecEnv):
    """Several :class:`~poc_env.envs.vector.SwarmVecEnv` of one observation and action space
    side by side as one SB3 ``VecEnv`` (``poc-env train --also-task``): their slots are
    concatenated in order, so a rollout holds transitions of every part (e.g. fleets of 6, 12
    and 24 UAVs) and the parameter-shared policy is trained on all of them at once. Each part
    keeps its own envs, generators and auto-resets; this class only splits the actions and
    joins what comes back. Checkpoints keep every part's generators (not the episodes in
    flight: a resumed run starts new episodes)."""

    def __init__(self, parts: list[Any]) -> None:
        first = parts[0]
        for p in parts[1:]:
            if p.observation_space != first.observation_space:
                raise ConfigError(
                    "also_task", p.scenario.name, f"an observation space equal to the first "
                    f"task's ({first.observation_space}); got {p.observation_space}",
                )  # fmt: skip
            if p.action_space != first.action_space:
                raise ConfigError("also_task", p.scenario.name, "the first task's action space")
        self.parts = list(parts)
        self._bounds = np.cumsum([0, *(p.num_envs for p in parts)])
        super().__init__(int(self._bounds[-1]), first.observation_space, first.action_space)

    @property
    def rngs(self) -> list[np.random.Generator]:
        """Every part's env generators, in order."""
        return [g for p in self.parts for g in p.rngs]

    def _split(self, x: Any) -> list[Any]:
        return [x[a:b] for a, b in itertools.pairwise(self._bounds)]

    def reset(self):
        return np.concatenate([p.reset() for p in self.parts])

    def seed(self, seed: int | None = None):
        out: list[int | None] = []
        for k, p in enumerate(self.parts):
            s = (
                None
                if seed is None
                else int(np.random.SeedSequence([seed, k]).generate_state(1)[0])
            )
            out += list(p.seed(s))
        return out

    def set_options(self, options: list[dict] | dict | None = None) -> None:
        """Each slot's reset options go to its part (a ``"prior"`` for a part's env)."""
        opts = list(options) if isinstance(options, list) else [options or {}] * self.num_envs
        for p, o in zip(self.parts, self._split(opts), strict=True):
            p.set_options(o)

    def step_async(self, actions: np.ndarray) -> None:
        for p, a in zip(self.parts, self._split(np.asarray(actions)), strict=True):
            p.step_async(a)

    def step_wait(self):
        outs = [p.step_wait() for p in self.parts]
        obs = np.concatenate([o[0] for o in outs])
        rew = np.concatenate([o[1] for o in outs])
        done = np.concatenate([o[2] for o in outs])
        infos = [i for o in outs for i in o[3]]
        return obs, rew, done, infos

    def close(self) -> None:
        for p in self.parts:
            p.close()

    def _parts_of(self, indices) -> list[tuple[Any, list[int]]]:
        idx = range(self.num_envs) if indices is None else indices
        idx = [idx] if isinstance(idx, int) else list(idx)
        out = []
        for k, p in enumerate(self.parts):
            a, b = int(self._bounds[k]), int(self._bounds[k + 1])
            mine = [i - a for i in idx if a <= i < b]
            if mine:
                out.append((p, mine))
        return out

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [v for p, i in self._parts_of(indices) for v in p.get_attr(attr_name, i)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        for p, i in self._parts_of(indices):
            p.set_attr(attr_name, value, i)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs):
        return [
            v
            for p, i in self._parts_of(indices)
            for v in p.env_method(method_name, *method_args, indices=i, **method_kwargs)
        ]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [v for p, i in self._parts_of(indices) for v in p.env_is_wrapped(wrapper_class, i)]
