"""Single-agent (centralised) Gymnasium view of the swarm: joint observation, joint action.

``gymnasium.make("poc_env/UAVSearch-v0", scenario=...)``. The observation is every agent's
flat observation stacked, ``(N * D,)``; the action is every agent's action stacked, ``(N * 3,)``;
the reward is the mean of the agents' rewards (with team credit: the team reward). Agents that
finished keep their last observation and ignore their action. The episode ends when the
swarm's does (:func:`poc_env.sim.core.episode_over`): it is *truncated* if some agent was cut
off by the horizon (:func:`poc_env.sim.core.truncated`), else *terminated* (every agent
terminated, :func:`poc_env.sim.core.terminal`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from poc_env.envs.parallel import UAVSearchParallelEnv, check_seed
from poc_env.errors import ConfigError
from poc_env.sim import core as sim


class UAVSearchGym(gym.Env):
    """Centralised single-agent view of :class:`~poc_env.envs.parallel.UAVSearchParallelEnv`."""

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 8}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        kwargs.setdefault("obs_type", "flat")
        kwargs["obs_type"] = "flat"
        self.par = UAVSearchParallelEnv(render_mode=render_mode, **kwargs)
        self.render_mode = render_mode
        agents = self.par.possible_agents
        one = self.par.observation_space(agents[0])
        assert isinstance(one, spaces.Box)
        n = len(agents)
        self.observation_space = spaces.Box(
            np.tile(one.low, n), np.tile(one.high, n), dtype=np.float32
        )
        self.action_space = spaces.Box(-1.0, 1.0, (3 * n,), np.float32)
        self._last: dict[str, np.ndarray] = {}

    def _joint(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        self._last.update(obs)
        return np.concatenate([self._last[a] for a in self.par.possible_agents])

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        check_seed(seed)
        super().reset(seed=seed)
        self._last = {}
        obs, infos = self.par.reset(seed=seed, options=options)
        return self._joint(obs), {"agents": infos}

    def step(self, action):
        a = self._action_array(action)
        acts = {ag: a[k] for k, ag in enumerate(self.par.possible_agents) if ag in self.par.agents}
        obs, rew, _term, _trunc, infos = self.par.step(acts)
        reward = float(np.mean(list(rew.values()))) if rew else 0.0
        p, st = self.par.params, self.par.sim_state
        done = bool(sim.episode_over(p, st)[0])
        truncated = done and bool(sim.truncated(p, st)[0].any())
        terminated = done and not truncated
        info = {"agents": infos, "posc": float(st.posc[0])}
        return self._joint(obs), reward, terminated, truncated, info

    def _action_array(self, action) -> np.ndarray:
        """The joint action as an (N, 3) float array; ConfigError naming ``action`` otherwise."""
        n = len(self.par.possible_agents)
        allowed = f"{3 * n} finite real numbers in [-1, 1] (shape ({3 * n},))"
        try:
            a = np.asarray(action)
        except (ValueError, TypeError):  # ragged nesting
            raise ConfigError("action", action, allowed) from None
        if a.dtype.kind not in "biuf" or a.size != 3 * n or not np.isfinite(a).all():
            raise ConfigError("action", action, allowed)
        return a.astype(float, copy=False).reshape(n, 3)

    def render(self):
        return self.par.render()

    def close(self):
        self.par.close()
