"""Single-agent (centralised) Gymnasium view of the swarm: joint observation, joint action.

``gymnasium.make("poc_env/UAVSearch-v0", scenario=...)``; keyword arguments as
:class:`~poc_env.envs.parallel.UAVSearchParallelEnv` (``random_prior=True``, ``max_cycles``,
overrides ...). The observation is every agent's observation stacked: with ``obs_type="flat"``
(the default) a Box ``(N * D,)``, with ``obs_type="dict"`` a Dict of ``raster`` ``(N, 4, ny,
nx)`` and ``vector`` ``(N, 14)``. The action is every agent's action stacked, ``(N * 3,)``; the
reward is the mean of the agents' rewards (with team credit: the team reward). Agents that
finished keep their last observation and info and ignore their action. The episode ends when
the swarm's does (:func:`poc_env.sim.core.episode_over`): it is *truncated* if some agent was
cut off by the horizon (:func:`poc_env.sim.core.truncated`), else *terminated* (every agent
terminated, :func:`poc_env.sim.core.terminal`).

The info has the same keys at reset and at every step: ``posc`` (float) and every key of the
parallel env's per-agent infos as a numpy array over the agents, ``(N,)`` (``links``: ``(N,
N)``), of a fixed dtype.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from poc_env.envs.parallel import OBS_TYPES, UAVSearchParallelEnv, check_seed
from poc_env.errors import ConfigError
from poc_env.sim import core as sim


class UAVSearchGym(gym.Env):
    """Centralised single-agent view of :class:`~poc_env.envs.parallel.UAVSearchParallelEnv`."""

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 8}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        obs_type = kwargs.setdefault("obs_type", "flat")
        if obs_type not in OBS_TYPES:
            raise ConfigError("obs_type", obs_type, "'flat' (default), 'dict' or 'compass'")
        self.par = UAVSearchParallelEnv(render_mode=render_mode, **kwargs)
        self.render_mode = render_mode
        self.obs_type = obs_type
        agents = self.par.possible_agents
        one = self.par.observation_space(agents[0])
        n = len(agents)

        def stacked(box: spaces.Space) -> spaces.Box:
            assert isinstance(box, spaces.Box)
            low, high = np.stack([box.low] * n), np.stack([box.high] * n)
            return spaces.Box(low, high, dtype=np.float32)

        if obs_type == "dict":
            assert isinstance(one, spaces.Dict)
            self.observation_space: spaces.Space = spaces.Dict(
                {k: stacked(one[k]) for k in ("raster", "vector")}
            )
        else:
            assert isinstance(one, spaces.Box)
            self.observation_space = spaces.Box(
                np.tile(one.low, n), np.tile(one.high, n), dtype=np.float32
            )
        self._dim = self.par._dim  # the control level's action size per UAV
        self.action_space = spaces.Box(-1.0, 1.0, (self._dim * n,), np.float32)
        self._last: dict[str, Any] = {}
        self._last_info: dict[str, dict[str, Any]] = {}

    def _joint(self, obs: dict[str, Any]) -> Any:
        self._last.update(obs)
        rows = [self._last[a] for a in self.par.possible_agents]
        if self.obs_type == "dict":
            return {k: np.stack([r[k] for r in rows]) for k in ("raster", "vector")}
        return np.concatenate(rows)

    def _joint_info(self, infos: dict[str, dict[str, Any]]) -> dict[str, Any]:
        self._last_info.update(infos)
        rows = [self._last_info[a] for a in self.par.possible_agents]
        out: dict[str, Any] = {"posc": float(self.par.sim_state.posc[0])}
        for key, value in rows[0].items():
            if key == "posc":
                continue
            if isinstance(value, np.ndarray):
                dtype: Any = value.dtype
            elif isinstance(value, bool | np.bool_):
                dtype = np.bool_
            elif isinstance(value, int | np.integer):
                dtype = np.int64
            else:
                dtype = np.float64
            out[key] = np.asarray([r[key] for r in rows], dtype=dtype)
        return out

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        check_seed(seed)
        super().reset(seed=seed)
        self._last = {}
        self._last_info = {}
        obs, infos = self.par.reset(seed=seed, options=options)
        return self._joint(obs), self._joint_info(infos)

    def step(self, action):
        a = self._action_array(action)
        acts = {ag: a[k] for k, ag in enumerate(self.par.possible_agents) if ag in self.par.agents}
        obs, rew, _term, _trunc, infos = self.par.step(acts)
        reward = float(np.mean(list(rew.values()))) if rew else 0.0
        p, st = self.par.params, self.par.sim_state
        done = bool(sim.episode_over(p, st)[0])
        truncated = done and bool(sim.truncated(p, st)[0].any())
        terminated = done and not truncated
        return self._joint(obs), reward, terminated, truncated, self._joint_info(infos)

    def _action_array(self, action) -> np.ndarray:
        """The joint action as an (N, dim) float array; ConfigError naming ``action`` otherwise."""
        n, d = len(self.par.possible_agents), self._dim
        allowed = f"{d * n} finite real numbers in [-1, 1] (shape ({d * n},))"
        try:
            a = np.asarray(action)
        except (ValueError, TypeError):  # ragged nesting
            raise ConfigError("action", action, allowed) from None
        if a.dtype.kind not in "biuf" or a.size != d * n or not np.isfinite(a).all():
            raise ConfigError("action", action, allowed)
        return a.astype(float, copy=False).reshape(n, d)

    def render(self):
        return self.par.render()

    def close(self):
        self.par.close()
