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
- **Infos**: exactly what the sync vector env returns for the same seeds and actions: every
  key of the Gymnasium view's info (:mod:`poc_env.envs.gymnasium_env`: ``posc (E,)``, every
  per-agent key ``(E, N)``, ``links (E, N, N)``, ``violations (E, N)``; a finished agent's
  row keeps its last values) with Gymnasium's ``_key`` masks (all True), the same keys at
  reset and at every step. They come from the engine (:func:`poc_env.sim.engine.infos`),
  computed once per step for every env, as arrays.
- Not batched: ``render_mode`` and ``random_airfields`` (the airfields are parameters shared by
  the batch); use ``vectorization_mode="sync"`` for those.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector.utils import batch_space

import poc_env._kernels.adapters as _adapters
from poc_env.envs.gymnasium_env import keep_rows, view_info
from poc_env.envs.parallel import OBS_TYPES, check_seed
from poc_env.errors import ConfigError
from poc_env.sim import core as sim
from poc_env.sim import engine as engine_mod
from poc_env.sim import single as single_mod
from poc_env.theory.probability_map import validate_map

try:  # gymnasium >= 1.1 names the autoreset modes
    from gymnasium.vector import AutoresetMode

    _NEXT_STEP: Any = AutoresetMode.NEXT_STEP
except ImportError:  # pragma: no cover - gymnasium 1.0: next-step autoreset is the only mode
    _NEXT_STEP = "NextStep"


class _Outcome(NamedTuple):
    """What :meth:`SwarmGymVectorEnv._advance` reads of a step: the fields of the engine's
    :class:`~poc_env.sim.engine.Transition` but its reward terms and events."""

    obs: Any
    reward: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    over: np.ndarray
    info: dict[str, np.ndarray]


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
        obs_type = kwargs.setdefault("obs_type", "flat")
        if obs_type not in OBS_TYPES:
            raise ConfigError("obs_type", obs_type, "'flat' (default), 'dict' or 'compass'")
        #: The episode engine this adapter converts (:class:`poc_env.sim.engine.Engine`).
        self.engine = engine_mod.make_engine(int(num_envs), **kwargs)
        eng = self.engine
        self.obs_type = obs_type
        self.num_envs = int(num_envs)
        self.n_agents = eng.n_agents
        self._dim = eng.action_dim
        self.single_observation_space = engine_mod.joint_space(eng.observation_space, self.n_agents)
        self.single_action_space = spaces.Box(-1.0, 1.0, (self._dim * self.n_agents,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None
        self.spec = None
        e, n = self.num_envs, self.n_agents
        self._live = np.zeros((e, n), dtype=bool)
        self._last: Any = None
        self._last_info: dict[str, np.ndarray] = {}
        self._autoreset = np.zeros(e, dtype=bool)
        self._mask_keys: list[str] = []
        self._all = np.arange(e)
        #: The whole batch's step with its glue formed once (:class:`poc_env.sim.single.
        #: SingleStep`, the PettingZoo env's: the engine's transition bit for bit), or None
        #: (per-UAV beliefs). Steps of some envs (an autoreset that resets first) keep
        #: :meth:`Engine.step <poc_env.sim.engine.Engine.step>`.
        self._fast = single_mod.SingleStep(eng) if single_mod.SingleStep.supports(eng) else None
        self._info_keys: tuple[str, ...] = ()

    @property
    def params(self) -> sim.Params:
        return self.engine.params

    @property
    def scenario(self):
        return self.engine.scenario

    @property
    def state(self) -> sim.State | None:
        """The batched simulator state (None before :meth:`reset`)."""
        return self.engine.state

    @property
    def rngs(self) -> list[np.random.Generator]:
        """Each env's generator."""
        return self.engine.rngs

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
        self.engine.seed(seeds)
        prior = (options or {}).get("prior")
        priors = None
        if prior is not None:
            priors = [validate_map(prior, self.params.grid, "options['prior']")] * self.num_envs
        self._last, info = self.engine.reset(priors=priors)
        self._last_info = view_info(info)
        self._info_keys = tuple(info)  # the engine's keys, in its order (the same at a step)
        self._live[:] = True
        self._autoreset[:] = False
        return self._joint(), self._infos()

    # -- observations and infos --------------------------------------------------------------
    def _joint(self) -> Any:
        # no copies: keep_rows never writes into arrays handed out (copy on write)
        obs = self._last
        if isinstance(obs, dict):
            return dict(obs)
        return obs.reshape(obs.shape[0], -1)

    def _infos(self) -> dict[str, Any]:
        """The sync vector env's infos: every key batched, with its ``_key`` mask (the arrays
        themselves, which :func:`keep_rows` never writes into; one allocation for the masks)."""
        out: dict[str, Any] = dict(self._last_info)
        if len(self._mask_keys) != len(out):  # the info keys are fixed by the first reset
            self._mask_keys = [f"_{key}" for key in out]
        out.update(zip(self._mask_keys, np.ones((len(out), self.num_envs), dtype=bool)))
        return out

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
        if self.engine.state is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        a = self._actions(actions)
        if not self._autoreset.any():  # the common step: every env goes on (no index arrays)
            reward, terminated, truncated = self._advance(a, None)
            return self._joint(), reward, terminated, truncated, self._infos()
        again = np.flatnonzero(self._autoreset)
        if not sim.step_is_per_env(self.params):  # the ended envs would draw or weigh in
            return self._step_around(a, again)
        # NEXT_STEP autoreset: every env is stepped (the ended ones to no effect: their step
        # touches only their own state, which is replaced with their observations and infos),
        # then the ended envs start afresh, drawing what the sync env's reset draws
        self._live[again] = True
        reward, terminated, truncated = self._advance(a, None)
        first, fresh_info = self.engine.reset(again)
        # the arrays _advance left are this step's own (not handed out yet): rows written in
        if isinstance(self._last, dict):
            for key, v in self._last.items():
                v[again] = first[key]
        else:
            self._last[again] = first
        for key, v in self._last_info.items():
            v[again] = fresh_info[key]
        reward[again] = 0.0
        terminated[again] = False
        truncated[again] = False
        self._live[again] = True
        self._autoreset[again] = False
        return self._joint(), reward, terminated, truncated, self._infos()

    def _step_around(self, a: np.ndarray, again: np.ndarray):
        """The autoreset step that resets ``again`` first and steps only the other envs (when
        stepping them could change the others or their streams,
        :func:`~poc_env.sim.core.step_is_per_env`)."""
        e = self.num_envs
        reward = np.zeros(e)
        terminated = np.zeros(e, dtype=bool)
        truncated = np.zeros(e, dtype=bool)
        going = np.flatnonzero(~self._autoreset)
        # NEXT_STEP autoreset: these envs start afresh, their actions unused
        first, fresh_info = self.engine.reset(again)
        every = np.ones((len(again), self.n_agents), dtype=bool)
        self._last = keep_rows(self._last, first, again, every)
        self._last_info = keep_rows(self._last_info, fresh_info, again, every)
        self._live[again] = True
        self._autoreset[again] = False
        if len(going):
            reward[going], terminated[going], truncated[going] = self._advance(a[going], going)
        return self._joint(), reward, terminated, truncated, self._infos()

    def _advance(self, a: np.ndarray, going: np.ndarray | None):
        """Step the envs ``going`` (None: every env) under ``a``; update which agents are live,
        which envs reset next, the last observations and infos; return their (reward,
        terminated, truncated), each ``(len(going),)``, as arrays over those envs."""
        whole = going is None
        live = self._live.copy() if whole else self._live[going]
        # finished agents' actions: ignored
        if whole and self._fast is not None:
            tr = self._whole_step(a)
        else:
            t = self.engine.step(a, going)
            tr = _Outcome(t.obs, t.reward, t.terminated, t.truncated, t.over, t.info)
        done = tr.over
        if whole and self._fast is not None and live.shape[1] < 8:  # one compiled pass:
            e = len(live)  # mean_over's reward, the ends, the live agents as below
            reward = np.empty(e)
            terminated = np.empty(e, dtype=bool)
            truncated = np.empty(e, dtype=bool)
            every = _adapters.live_step(
                live, tr.reward, tr.terminated, tr.truncated, done, reward, terminated,
                truncated, self._live,
            )  # fmt: skip
        else:
            reward = engine_mod.mean_over(tr.reward, live)
            truncated = done & tr.truncated.any(axis=1)
            terminated = done & ~truncated
            finished = live & (tr.terminated | tr.truncated)
            every = bool(live.all())
            if whole:
                self._live[:] = live & ~finished
        if whole:
            self._autoreset[:] = done
            if every:  # every row is new (keep_rows would return the new arrays)
                self._last, self._last_info = tr.obs, tr.info
                return reward, terminated, truncated
            # the engine's observations are fresh arrays of this step, not handed out yet: the
            # finished agents' rows are written into them (keep_rows' values, no full copy)
            dead = ~live
            obs = tr.obs
            if isinstance(obs, dict):
                for key, v in obs.items():
                    v[dead] = self._last[key][dead]
            else:
                obs[dead] = self._last[dead]
            self._last = obs
            if self._fast is None:
                self._last_info = keep_rows(self._last_info, tr.info, self._all, live)
                return reward, terminated, truncated
            # so are the infos of the whole batch's step (_whole_step): keep_rows' values too
            # (a per-env entry, posc, is never frozen; links (E, N, N) by the agent's row)
            for key, v in tr.info.items():
                if v.ndim > 1:
                    where = dead.reshape(dead.shape + (1,) * (v.ndim - 2))
                    np.copyto(v, self._last_info[key], where=where)
            self._last_info = tr.info
            return reward, terminated, truncated
        envs = self.engine.envs(going)
        if not whole:
            self._live[envs] = live & ~finished
            self._autoreset[envs] = done
        self._last = keep_rows(self._last, tr.obs, envs, live)
        self._last_info = keep_rows(self._last_info, tr.info, envs, live)
        return reward, terminated, truncated

    def _whole_step(self, a: np.ndarray) -> _Outcome:
        """:meth:`Engine.step <poc_env.sim.engine.Engine.step>` of every env under ``a``
        through :class:`~poc_env.sim.single.SingleStep`: the same transition bit for bit (but
        the reward terms and events, which the adapter does not read), its infos
        (:func:`~poc_env.sim.engine.infos`) taken from the step's per-agent values grouped by
        type (one copy per group, each key a column of it) and the state's."""
        assert self._fast is not None
        s = self._fast.step(a)
        st = self.engine.current
        groups: dict[str, np.ndarray] = {}
        for names, values in (
            (single_mod.FLOAT_INFOS, s.finfo),
            (single_mod.BOOL_INFOS, s.binfo),
            (single_mod.INT_INFOS, s.iinfo),
        ):
            own = values.copy()  # the step's own values; each key a column (E, N) of them
            groups.update((name, own[..., j]) for j, name in enumerate(names))
        info: dict[str, np.ndarray] = {}
        for key in self._info_keys:
            if key == "posc":  # per env, as the engine's
                info[key] = st.posc.astype(float)
            elif key == "links":
                info[key] = st.links.copy()
            elif key in groups:
                info[key] = groups[key]
            else:  # a key the kernel does not group (moving targets' mass_out): the engine's,
                # copied (this step's own array, as the others: _advance writes rows into them)
                info[key] = np.array(
                    engine_mod.infos(self.params, st, s.events, s.terms_dict())[key]
                )
        return _Outcome(s.obs, s.reward, s.terminated, s.truncated, s.over, info)
