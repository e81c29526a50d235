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

The info has the same keys at reset and at every step: ``posc`` (float), every key of the
parallel env's per-agent infos as a numpy array over the agents, ``(N,)`` (``links``: ``(N,
N)``), of a fixed dtype, and ``violations`` ``(N,)`` (each UAV's cumulative
constraint-violation steps). It is the engine's info set (:func:`poc_env.sim.engine.infos`),
row ``i`` frozen once agent ``i`` has finished; ``gymnasium.make_vec`` returns the same,
batched.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from poc_env.envs.parallel import OBS_TYPES, UAVSearchParallelEnv, check_seed
from poc_env.errors import ConfigError
from poc_env.sim import engine as engine_mod


def joint_observation(obs: Any) -> Any:
    """Every agent's observation of one env stacked (the view's layout) from the engine's
    ``(N, ...)`` rows: a dict of ``(N, ...)`` arrays, or the ``N`` rows concatenated."""
    if isinstance(obs, dict):
        return {k: v.copy() for k, v in obs.items()}
    return obs.reshape(-1).copy()


def view_info(info: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The view's info arrays of one or more envs from the engine's (:func:`~poc_env.sim.
    engine.infos`): ``posc`` and every per-agent key with ``violations``, copied."""
    return {k: np.array(v) for k, v in info.items()}


def keep_rows(last: Any, new: Any, envs: np.ndarray, rows: np.ndarray) -> Any:
    """``last`` (batched over every env) with agents ``rows (len(envs), N)`` of ``envs`` taking
    their entry of ``new`` (batched over ``envs``); the others keep theirs (finished agents keep
    their last observation and info). ``last``/``new``: arrays or dicts of arrays.

    Copy on write: ``last`` is never modified, the result is a new array (or ``new`` itself when
    it replaces every row), so arrays handed out earlier stay as they were."""
    envs = np.asarray(envs)
    rows = np.asarray(rows, dtype=bool)
    whole = len(envs) == len(rows) and bool(rows.all())
    if isinstance(last, dict):
        every = len(envs) == _rows_of(last) and bool((envs == np.arange(len(envs))).all())
        if every and whole:  # the common step: every row of every env is new
            return dict(new)
        if every:  # some agents finished: one mask per rank, shared by the keys
            masks: dict[int, np.ndarray] = {}
            out = {}
            for k, v in last.items():
                if v.ndim == 1:  # a per-env entry (posc) is never frozen
                    out[k] = new[k]
                    continue
                m = masks.get(v.ndim)
                if m is None:
                    m = masks[v.ndim] = rows.reshape(rows.shape + (1,) * (v.ndim - 2))
                out[k] = np.where(m, new[k], v)
            return out
        return {k: _keep(v, new[k], envs, rows, every, whole) for k, v in last.items()}
    every = len(envs) == len(last) and bool((envs == np.arange(len(envs))).all())
    return _keep(last, new, envs, rows, every, whole)


def _rows_of(last: dict[str, np.ndarray]) -> int:
    return len(next(iter(last.values()))) if last else 0


def _keep(last, new, envs, rows, every: bool, whole: bool) -> np.ndarray:
    """:func:`keep_rows` of one array; ``every``: ``envs`` is every env in order; ``whole``:
    every row of ``envs`` is replaced."""
    new = np.asarray(new)
    if every and (whole or last.ndim == 1):  # a per-env entry (posc) is never frozen
        return new
    if last.ndim == 1:
        out = last.copy()
        out[envs] = new
        return out
    mask = rows.reshape(rows.shape + (1,) * (new.ndim - 2))
    if every:
        return np.where(mask, new, last)
    out = last.copy()
    out[envs] = new if whole else np.where(mask, new, last[envs])
    return out


class UAVSearchGym(gym.Env):
    """Centralised single-agent view of :class:`~poc_env.envs.parallel.UAVSearchParallelEnv`."""

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 8}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        obs_type = kwargs.setdefault("obs_type", "flat")
        if obs_type not in OBS_TYPES:
            raise ConfigError(
                "obs_type", obs_type, "'flat' (default) or one of " + ", ".join(OBS_TYPES)
            )
        self.par = UAVSearchParallelEnv(render_mode=render_mode, **kwargs)
        self.render_mode = render_mode
        self.obs_type = obs_type
        eng = self.par.engine
        n = eng.n_agents
        self.observation_space: spaces.Space = engine_mod.joint_space(eng.observation_space, n)
        self._dim = eng.action_dim  # the control level's action size per UAV
        self.action_space = spaces.Box(-1.0, 1.0, (self._dim * n,), np.float32)
        self._last: Any = None
        self._last_info: dict[str, np.ndarray] = {}

    def _joint_info(self) -> dict[str, Any]:
        out: dict[str, Any] = {"posc": float(self._last_info["posc"][0])}
        out.update({k: v[0].copy() for k, v in self._last_info.items() if k != "posc"})
        return out

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        check_seed(seed)
        super().reset(seed=seed)
        self.par.reset(seed=seed, options=options)
        self._last = self.par.engine.observe()  # (1, N, ...): the engine's batch of one env
        self._last_info = view_info(self.par.info_arrays)
        return self._observation(), self._joint_info()

    def _observation(self) -> Any:
        if isinstance(self._last, dict):
            return joint_observation({k: v[0] for k, v in self._last.items()})
        return joint_observation(self._last[0])

    def step(self, action):
        a = self._action_array(action)
        par = self.par
        live = np.array([ag in par.agents for ag in par.possible_agents])[None]
        par.step({ag: a[k] for k, ag in enumerate(par.possible_agents) if ag in par.agents})
        tr = par.transition
        reward = float(engine_mod.mean_over(tr.reward, live)[0])
        done = bool(tr.over[0])
        truncated = done and bool(tr.truncated[0].any())
        terminated = done and not truncated
        everything = np.zeros(1, dtype=np.intp)
        self._last = keep_rows(self._last, tr.obs, everything, live)
        self._last_info = keep_rows(self._last_info, tr.info, everything, live)
        return self._observation(), reward, terminated, truncated, self._joint_info()

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
