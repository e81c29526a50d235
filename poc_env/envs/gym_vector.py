"""The Gymnasium vector env over the batched core: ``gymnasium.make_vec(task, num_envs)``.

:class:`SwarmGymVectorEnv` is the ``vector_entry_point`` of every registered task
(:mod:`poc_env.tasks`). It runs ``num_envs`` copies of the centralised Gymnasium view
(:class:`~poc_env.envs.gymnasium_env.UAVSearchGym`: joint observation, joint action, the mean
of the live agents' rewards) in one batched simulator state, one
:func:`poc_env.sim.core.step` call for all of them, and returns exactly what
``gymnasium.make_vec(task, num_envs, vectorization_mode="sync")`` returns for the same seeds and
actions (a test checks it transition for transition, episode ends included), only faster.

- **Seeding.** ``reset(seed=s)`` seeds env ``i`` with ``s + i`` (a list seeds each env), as
  :class:`gymnasium.vector.SyncVectorEnv` does; each env then keeps its own generator.
- **Autoreset.** ``AutoresetMode.NEXT_STEP``, Gymnasium's default: the step after an env's
  episode ended resets it (its action is ignored, reward 0, ``terminated``/``truncated``
  False) and returns the new episode's first observation.
- **Infos** (the same keys at reset and at every step, numeric arrays over the envs):
  ``posc (E,)``, ``pos_team (E,)`` (the step's team POS, 0 at reset), ``landed``, ``crashed``
  ``(E, N)`` bools and ``violations (E, N)`` (cumulative constraint-violation steps).
- Not batched: ``render_mode`` and ``random_airfields`` (the airfields are parameters shared by
  the batch); use ``vectorization_mode="sync"`` for those.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector.utils import batch_space

from poc_env.envs.gymnasium_env import UAVSearchGym
from poc_env.envs.parallel import check_seed
from poc_env.errors import ConfigError
from poc_env.sim import core as sim
from poc_env.sim import observations as obs_mod
from poc_env.sim.control import swarm_increments
from poc_env.sim.rewards import reward_terms, total_reward
from poc_env.theory.probability_map import random_gaussian_mixture, validate_map

try:  # gymnasium >= 1.1 names the autoreset modes
    from gymnasium.vector import AutoresetMode

    _NEXT_STEP: Any = AutoresetMode.NEXT_STEP
except ImportError:  # pragma: no cover - gymnasium 1.0: next-step autoreset is the only mode
    _NEXT_STEP = "NextStep"


class SwarmGymVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` centralised swarm envs in one batched core (module docstring).

    Keyword arguments are those of :class:`~poc_env.envs.gymnasium_env.UAVSearchGym` (and so of
    :class:`~poc_env.envs.parallel.UAVSearchParallelEnv`)."""

    metadata = {"autoreset_mode": _NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 1, render_mode: str | None = None, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer):
            raise ConfigError("num_envs", num_envs, "an integer >= 1")
        if num_envs < 1:
            raise ConfigError("num_envs", num_envs, "an integer >= 1")
        if render_mode is not None:
            raise ConfigError(
                "render_mode", render_mode, "None (use vectorization_mode='sync' to render)"
            )
        if kwargs.get("random_airfields"):
            raise ConfigError(
                "random_airfields",
                kwargs["random_airfields"],
                "False in the batched vector env (use vectorization_mode='sync')",
            )
        self.single_env = UAVSearchGym(**kwargs)  # validates every argument, defines the spaces
        par = self.single_env.par
        self.par = par
        self.params = par.params
        self.scenario = par.scenario
        self.obs_type = self.single_env.obs_type
        self.num_envs = int(num_envs)
        self.n_agents = self.params.n_agents
        self._dim = self.single_env._dim
        self.single_observation_space = self.single_env.observation_space
        self.single_action_space = self.single_env.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None
        self.spec = None
        self._hazard = obs_mod.hazard_mask(self.params)
        self._features = (
            obs_mod.CompassFeatures(self.params) if self.obs_type == "compass" else None
        )
        e, n = self.num_envs, self.n_agents
        self.rngs = [np.random.default_rng() for _ in range(e)]
        self.state: sim.State | None = None
        self._poc_scale = np.ones(e)
        self._live = np.zeros((e, n), dtype=bool)
        self._last: Any = None
        self._autoreset = np.zeros(e, dtype=bool)
        self._pos_team = np.zeros(e)

    # -- reset -------------------------------------------------------------------------------
    def _seeds(self, seed: int | Sequence[int | None] | None) -> list[int | None]:
        if seed is None:
            return [None] * self.num_envs
        if isinstance(seed, int | np.integer) and not isinstance(seed, bool):
            check_seed(int(seed))
            return [int(seed) + i for i in range(self.num_envs)]
        if isinstance(seed, Sequence) and not isinstance(seed, str):
            if len(seed) != self.num_envs:
                raise ConfigError("seed", seed, f"None, an integer or {self.num_envs} seeds")
            for s in seed:
                check_seed(s)
            return list(seed)
        raise ConfigError("seed", seed, f"None, an integer >= 0 or a list of {self.num_envs}")

    def _fresh(self, envs: np.ndarray, prior: Any = None) -> sim.State:
        """New episodes for ``envs`` from their generators (the prior first, as the
        PettingZoo env draws it); sets their POC scale and live agents."""
        grid = self.params.grid
        priors = None
        if prior is not None:
            one = validate_map(prior, grid, "options['prior']")
            priors = np.broadcast_to(one, (len(envs), *one.shape))
        elif self.par.random_prior:
            priors = np.stack([random_gaussian_mixture(grid, self.rngs[k]) for k in envs])
        fresh = sim.initial(self.params, [self.rngs[k] for k in envs], priors)
        p0 = self.params.prior.max() if priors is None else priors.max(axis=(1, 2))
        self._poc_scale[envs] = p0
        self._live[envs] = True
        self._autoreset[envs] = False
        self._pos_team[envs] = 0.0
        return fresh

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ):
        """Start a new episode in every env. ``options={"prior": map}`` gives every env that
        prior (as the PettingZoo env's reset option)."""
        seeds = self._seeds(seed)
        if options is not None and (not isinstance(options, dict) or set(options) - {"prior"}):
            raise ConfigError("options", options, "None or a dict with the key 'prior'")
        for k, s in enumerate(seeds):
            if s is not None:
                self.rngs[k] = np.random.default_rng(s)
        everything = np.arange(self.num_envs)
        self.state = self._fresh(everything, (options or {}).get("prior"))
        self._last = self._observe(self.state)
        return self._joint(self._last), self._infos()

    # -- observations and infos --------------------------------------------------------------
    def _observe(self, state: sim.State) -> Any:
        return obs_mod.observe(
            self.params, state, self._poc_scale, self._hazard, self.obs_type, self._features
        )

    def _joint(self, obs: Any) -> Any:
        if isinstance(obs, dict):
            return {k: v.copy() for k, v in obs.items()}
        return obs.reshape(obs.shape[0], -1).copy()

    def _infos(self) -> dict[str, Any]:
        st = self.state
        assert st is not None
        return {
            "posc": st.posc.astype(float),
            "pos_team": self._pos_team.copy(),
            "landed": st.landed.copy(),
            "crashed": st.crashed.copy(),
            "violations": st.violations.astype(np.int64),
        }

    # -- step --------------------------------------------------------------------------------
    def _actions(self, actions: Any) -> np.ndarray:
        e, n, d = self.num_envs, self.n_agents, self._dim
        allowed = f"shape ({e}, {n * d}): finite real numbers in [-1, 1]"
        try:
            a = np.asarray(actions)
        except (ValueError, TypeError):
            raise ConfigError("actions", actions, allowed) from None
        if a.dtype.kind not in "biuf" or a.size != e * n * d or not np.isfinite(a).all():
            raise ConfigError("actions", getattr(a, "shape", actions), allowed)
        return a.astype(float).reshape(e, n, d)

    def step(self, actions: Any):
        if self.state is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        a = self._actions(actions)
        p = self.params
        e = self.num_envs
        reward = np.zeros(e)
        terminated = np.zeros(e, dtype=bool)
        truncated = np.zeros(e, dtype=bool)
        again = np.flatnonzero(self._autoreset)
        going = np.flatnonzero(~self._autoreset)
        if len(again):  # NEXT_STEP autoreset: these envs start afresh, their actions unused
            fresh = self._fresh(again)
            sim.scatter_envs(self.state, fresh, again)
        if len(going):
            whole = len(going) == e
            st = self.state if whole else sim.take_envs(self.state, going)
            live = self._live[going]
            inc = swarm_increments(p, self.par.control, st, a[going], self.par.auto_return)
            inc = np.where(live[..., None], inc, 0.0)  # finished agents ignore their action
            ev = sim.step(p, st, inc, [self.rngs[k] for k in going])
            r = total_reward(reward_terms(self.scenario.reward, ev))
            for j, k in enumerate(going):  # the mean over the live agents, as UAVSearchGym
                reward[k] = float(np.mean(r[j][live[j]].tolist())) if live[j].any() else 0.0
            self._pos_team[going] = ev.pos_team
            done = sim.episode_over(p, st)
            cut = sim.truncated(p, st)
            truncated[going] = done & cut.any(axis=1)
            terminated[going] = done & ~truncated[going]
            finished = live & (sim.terminal(p, st) | cut)
            if not whole:
                sim.scatter_envs(self.state, st, going)
            self._live[going] = live & ~finished
            self._autoreset[going] = done
            new = obs_mod.observe(
                p, st, self._poc_scale[going], self._hazard, self.obs_type, self._features
            )
            self._keep_last(new, going, live)
        if len(again):
            first = obs_mod.observe(
                p, sim.take_envs(self.state, again), self._poc_scale[again], self._hazard,
                self.obs_type, self._features,
            )  # fmt: skip
            self._keep_last(first, again, np.ones((len(again), self.n_agents), dtype=bool))
        return self._joint(self._last), reward, terminated, truncated, self._infos()

    def _keep_last(self, new: Any, envs: np.ndarray, rows: np.ndarray) -> None:
        """Agents ``rows (len(envs), N)`` of ``envs`` get their observation from ``new``;
        the others keep their last one (finished agents, as in UAVSearchGym)."""
        if isinstance(new, dict):
            for key, v in new.items():
                dst = self._last[key]
                sub = dst[envs]
                sub[rows] = v[rows]
                dst[envs] = sub
        else:
            sub = self._last[envs]
            sub[rows] = new[rows]
            self._last[envs] = sub

    def close_extras(self, **kwargs: Any) -> None:
        if hasattr(self, "single_env"):  # not when __init__ refused its arguments
            self.single_env.close()
