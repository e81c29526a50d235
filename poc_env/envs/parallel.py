"""The PettingZoo parallel environment of the UAV swarm (the n_envs == 1 case of the core)."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from itertools import repeat
from typing import Any

import numpy as np
from pettingzoo import ParallelEnv

import poc_env._kernels.swarm as _swarm
from poc_env import spec
from poc_env.config import Scenario
from poc_env.errors import ConfigError, PocEnvError
from poc_env.sim import core as sim
from poc_env.sim import engine as engine_mod
from poc_env.sim import observations as obs_mod
from poc_env.sim import single as single_mod
from poc_env.sim.engine import check_seed, resolve_overrides
from poc_env.theory.probability_map import validate_map

OBS_TYPES = obs_mod.OBS_TYPES
#: Array kinds an action may have: bool, signed and unsigned integer, real float.
_NUMERIC_KINDS = "biuf"
_ACTION_ALLOWED = "3 finite real numbers in [-1, 1] (a list or array, not strings or complex)"
#: The reward terms (:data:`poc_env.spec.REWARD_TERMS`), as info keys ``reward_<term>``.
REWARD_TERMS = spec.names(spec.REWARD_TERMS)
#: The constraint flags (:data:`poc_env.spec.VIOLATION_FLAGS`), as info keys ``violation_<flag>``.
VIOLATION_FLAGS = tuple(flag for flag, _ in spec.VIOLATION_FLAGS)
#: Every per-agent info key, in order (:func:`poc_env.spec.info_keys`).
INFO_KEYS = spec.info_keys()
#: How an info row's value is made from :func:`poc_env.sim.engine.info_parts`: the agent's entry,
#: its env's value, its row of ``links``.
_COLUMN, _PER_ENV, _ROWS = 0, 1, 2
#: The info keys of a :class:`poc_env.sim.single.Step`: its float, bool and int groups, then
#: the adjacency row.
_GROUPED_KEYS = (*single_mod.FLOAT_INFOS, *single_mod.BOOL_INFOS, *single_mod.INT_INFOS, "links")

__all__ = [
    "OBS_TYPES",
    "REWARD_TERMS",
    "VIOLATION_FLAGS",
    "EpisodeOverError",
    "UAVSearchParallelEnv",
    "check_seed",
    "resolve_overrides",
]


@functools.lru_cache(maxsize=16)
def _row_builder(keys: tuple[str, ...]) -> tuple[Any, Any]:
    """Functions ``(env_row, row)`` making the per-agent info dicts with ``keys`` in order from
    the :class:`~poc_env.sim.single.Step` values of one env: ``env_row(f, b, i)`` a dict of
    every key whose value is the env's (:data:`poc_env.sim.engine.PER_ENV_INFOS`, from any
    agent's rows: the same for all), the others None; ``row(d, f, b, i, links)`` a copy of
    that dict with one agent's values stored (``f``, ``b``, ``i`` its rows of the float, bool
    and int groups, lists; ``links`` its adjacency row). Written as code (as
    :mod:`dataclasses` writes its methods): a dict copy and a store per agent key is about
    0.4 the time of ``dict(zip(keys, values))`` for the two dozen keys of a step, 0.7 that of
    one dict display."""
    groups = {
        **{k: f"f[{j}]" for j, k in enumerate(single_mod.FLOAT_INFOS)},
        **{k: f"b[{j}]" for j, k in enumerate(single_mod.BOOL_INFOS)},
        **{k: f"i[{j}]" for j, k in enumerate(single_mod.INT_INFOS)},
        "links": "links",
    }
    shared = [k for k in keys if k in engine_mod.PER_ENV_INFOS]
    own = [k for k in keys if k not in engine_mod.PER_ENV_INFOS]
    env_body = "".join(f"    d[{k!r}] = {groups[k]}\n" for k in shared)
    body = "".join(f"    d[{k!r}] = {groups[k]}\n" for k in own)
    scope: dict[str, Any] = {"_keys": dict.fromkeys(keys)}
    exec(
        f"def env_row(f, b, i):\n    d = _keys.copy()\n{env_body}    return d\n"
        f"def row(d, f, b, i, links):\n    d = d.copy()\n{body}    return d\n",
        scope,
    )
    return scope["env_row"], scope["row"]


class EpisodeOverError(PocEnvError, RuntimeError):
    """``step()`` was called after every agent finished; call ``reset()``."""


class UAVSearchParallelEnv(ParallelEnv):
    """UAV-swarm search over a probability-of-containment map (Fan et al., Drones 2024).

    ## Description

    ``N`` fixed-wing UAVs take off from their airfields, search a gridded area whose prior POC
    map says where a lost target probably is, and must land at their landing fields before
    their endurance ``T`` runs out. Every step each UAV flies the eq. 19 point-mass kinematics
    and its sensor sweeps the segment it flew with Koopman's inverse-cube law, integrated
    along the segment and averaged over ``s x s`` sample points per cell, so a lawnmower flown
    step by step reproduces eq. 10. The belief is updated by eq. 14; the reward is the POS
    found (eq. 12). A hidden target drawn from the prior is detected with the same
    probability. Safety (eq. 20-23) and communication (eq. 24, §3.2.5 topologies)
    constraints are flagged, penalised, terminal or shielded (``constraints.violation``).
    Beliefs are ``global`` (the paper's assumption: one shared map) or, with
    ``comms.belief_sharing: comms``, one per UAV, merged only with the UAVs the active topology
    connects it to (through relays); rewards always use the true (global) belief.

    ## Action Space

    ``Box(-1, 1, (3,), float32)`` per agent: the increments (dv, d alpha, d beta) of eq. 19
    as fractions of their per-step limits ``max_accel * dt``, ``max_turn_rate * dt`` and
    ``max_pitch_rate * dt``. Speed stays in ``[v_min, v_max]``, pitch in ``[-beta_max,
    beta_max]``. Actions of finished agents are not expected; NaN/inf or wrong shapes raise.

    ``control="heading"`` (``Box(-1, 1, (2,))``: a map-frame direction) and
    ``control="waypoint"`` (``Box(-1, 1, (2,))``: a point of the operating area, (-1, -1) its
    south-west corner) are flown by the autopilot of :mod:`poc_env.sim.control`, which turns
    them into the increments above within their limits; with ``auto_return=True`` (default)
    it takes a UAV home and lands it once eq. 18's usable endurance only covers the way back.

    ## Observation Space

    ``obs_type="dict"``: ``Dict(raster=Box(0, 1, (4, ny, nx)), vector=Box(low, high, (14,)))``;
    ``obs_type="flat"``: their concatenation (raster first); ``obs_type="compass"``: a
    size-free ``Box((63,))`` (:class:`poc_env.sim.observations.CompassFeatures`: the vector,
    the remaining POC per 8 sectors x 4 distance rings, nearby UAVs per sector, the mean POC
    and the agent index). float32. The raster channels, vector entries and compass blocks
    (names, bounds, meanings) are the tables of :mod:`poc_env.spec` (``RASTER``, ``VECTOR``,
    ``COMPASS``), rendered in ``docs/environment.md``.

    ``state()`` (centralised critics): the POC raster (ny x nx) then every agent's vector.

    ## Rewards

    ``alpha * POS`` of the step (team-shared by default, ``reward.credit: individual`` for
    own credit) ``- beta *`` the eq. 25 time term ``-`` penalties for constraint violations,
    overtime beyond 0.85 T and crashes (:mod:`poc_env.sim.rewards`; the terms are
    :data:`poc_env.spec.REWARD_TERMS`). Every term is in ``infos[agent]["reward_<term>"]``.
    With team credit and ``beta = 0`` and no penalties, an episode's return is its POSC (eq. 13).

    ## Starting State

    UAVs start over their take-off fields at cruise altitude and cruise speed, level, heading
    for the centre of the grid; the belief is the prior (the scenario's, a ``--map`` file, or
    ``options={"prior": array}``); the hidden target is drawn from it by the env's generator.

    With ``random_prior=True`` every reset without an ``options["prior"]`` draws a fresh prior,
    a Gaussian mixture of 1-6 components of random position, spread, orientation and weight over
    a small uniform background (:func:`~poc_env.theory.probability_map.random_gaussian_mixture`,
    the same family as the RL training's), from the env's generator, which ``reset(seed=s)``
    reseeds: the seed changes the episode (prior and target), the same seed and actions give a
    bit-identical episode. Without it only the hidden target depends on the seed.
    ``random_airfields=True`` moves every scenario airfield at each reset (after the prior, from
    the same generator) to a uniform point of the search grid at least ``landing_radius_km``
    outside the no-fly zones; UAVs keep their fleet's take-off and landing fields, the operating
    area (eq. 20) stays the scenario's. ``env.params.takeoff``/``landing`` are the current ones.

    ## Infos

    ``infos[agent]`` has the same keys at ``reset`` and at every ``step``, each a Python number
    or a fixed-shape numpy array (for TorchRL-style specs; at reset nothing has happened yet:
    step quantities are 0/False). The keys, types, shapes and meanings are the table
    :data:`poc_env.spec.INFOS` (:func:`poc_env.spec.info_keys`, rendered in
    ``docs/environment.md``); a key missing from either side raises at ``reset``.

    The topology's name and the link list are attributes: ``env.unwrapped.topology``
    (``"auto"`` or a Table 2 letter) and ``env.unwrapped.links`` (pairs ``(i, j)``, ``i < j``).

    ## Episode End

    The rule is the core's (:func:`poc_env.sim.core.terminal`, :func:`~poc_env.sim.core.truncated`).
    An agent *terminates* when it lands (it has left the landing radius once and is back
    within ``episode.landing_radius_km`` of its landing field at or below
    ``episode.landing_max_altitude_m`` and ``episode.landing_max_speed_kmh``: an approach),
    crashes (altitude <= 0, endurance T exhausted, or a safety violation in ``terminate``
    mode), or, with ``episode.detection_ends_episode``, when the target is detected. All
    remaining agents are *truncated* after ``episode.horizon_steps`` (default ``ceil(T / dt)``).

    ## Arguments

    ``scenario`` (name, YAML path or :class:`Scenario`, default ``"paper_6_2"``),
    ``render_mode`` (``None``, ``"rgb_array"``, ``"human"``), ``obs_type`` (``"dict"`` or
    ``"flat"``), ``map_file`` (a prior ``.npy``/``.csv``), ``overrides`` (dotted YAML keys,
    e.g. ``{"sensor.sweep_width_km": 4}``) and keyword overrides with ``__`` for the dot
    (``uav__endurance_h=2``), ``random_prior`` (bool, default False: a random prior at every
    reset, see Starting State; not with ``map_file``), ``random_airfields`` (bool, default
    False) and ``max_cycles`` (PettingZoo's
    convention: every agent still flying is truncated after that many steps; it sets
    ``episode.horizon_steps``, so both given must agree). The default time step is 60 s: at
    180 km/h a UAV flies 3 km, below the 5 km cell and the 5 km sweep width, and an episode of
    T = 3 h is 180 steps.

    ## Version History

    * v0: first release. Infos became flat and numeric (``reward_terms`` and ``violations``
      dicts became ``reward_<term>`` and ``violation_<flag>`` keys; ``topology`` an int code,
      ``links`` an adjacency row; names and pairs moved to attributes); ``random_prior``,
      ``random_airfields`` and ``max_cycles`` added (defaults keep the first release's episodes).
    """

    metadata = {
        "name": "uav_search_v0",
        "render_modes": ["rgb_array", "human"],
        "is_parallelizable": True,
        "render_fps": 8,
    }

    def __init__(
        self,
        scenario: str | Scenario = "paper_6_2",
        render_mode: str | None = None,
        obs_type: str = "dict",
        map_file: str | None = None,
        overrides: Mapping[str, Any] | None = None,
        random_prior: bool = False,
        max_cycles: int | None = None,
        random_airfields: bool = False,
        control: str = "increments",
        auto_return: bool = True,
        **kwargs: Any,
    ) -> None:
        if render_mode not in (None, "rgb_array", "human"):
            raise ConfigError("render_mode", render_mode, "None, 'rgb_array' or 'human'")
        if render_mode is not None:  # checked before the work, not at the first render()
            from poc_env.errors import EXTRA_MODULES, require_extra

            require_extra("plot", f"render_mode={render_mode!r}", *EXTRA_MODULES["plot"])
        #: The episode engine (one env) this adapter converts: :class:`poc_env.sim.engine.Engine`.
        self.engine = engine_mod.make_engine(
            1,
            scenario=scenario,
            obs_type=obs_type,
            map_file=map_file,
            overrides=overrides,
            random_prior=random_prior,
            max_cycles=max_cycles,
            random_airfields=random_airfields,
            control=control,
            auto_return=auto_return,
            **kwargs,
        )
        eng = self.engine
        self.control = eng.control
        self.auto_return = eng.auto_return
        self._dim = eng.action_dim
        self.scenario = eng.scenario
        self.random_prior = bool(random_prior)
        self.max_cycles = self.scenario.horizon_steps
        self.random_airfields = eng.random_airfields
        self.render_mode = render_mode
        self.obs_type = obs_type
        n = eng.n_agents
        self.possible_agents = [f"uav_{i}" for i in range(n)]
        self.agents: list[str] = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self._upper = np.triu(np.ones((n, n), dtype=bool))  # links (i, j) with i <= j
        self._obs_space = eng.observation_space
        self._act_space = eng.action_space
        self.state_space = engine_mod.state_space(eng.params)
        self._renderer = None
        self._info: dict[str, np.ndarray] | None = {}
        self._transition: engine_mod.Transition | None = None
        #: ``(params, state, events, terms)`` of the last step: its info arrays, made when asked.
        self._step_of: tuple[Any, ...] = ()
        #: The per-agent info keys in order and how each is made (set at reset).
        self._info_keys: tuple[str, ...] = ()
        self._info_kinds: tuple[int, ...] = ()
        #: The step with its end compiled (:mod:`poc_env.sim.single`), or None: the engine's.
        self._single = single_mod.SingleStep(eng) if single_mod.SingleStep.supports(eng) else None
        self._last: single_mod.Step | None = None
        #: Whether :func:`_row_builder` makes the infos of a :class:`~poc_env.sim.single.Step`
        #: (set at reset): not when the keys differ (moving targets' ``mass_out``).
        self._grouped_infos = False
        #: The info row functions of ``_info_keys`` (:func:`_row_builder`; made by exec, so not
        #: pickled: ``__getstate__`` drops them, :meth:`_fast_infos` makes them again).
        self._row: Any = None

    @property
    def info_arrays(self) -> dict[str, np.ndarray]:
        """The engine's info arrays of the last reset or step (:func:`poc_env.sim.engine.infos`,
        batched over one env): what :meth:`step` and :meth:`reset` turn into per-agent infos."""
        if self._info is None:  # a step's: made when first asked for
            self._info = self.transition.info
        return self._info

    @property
    def transition(self) -> engine_mod.Transition:
        """The engine's :class:`~poc_env.sim.engine.Transition` of the last step (arrays), its
        ``info`` that step's info arrays. AttributeError before the first step."""
        tr = self._transition
        if tr is None and self._last is not None:  # the fast step's, made when asked for
            last = self._last.copy()  # its arrays are the fast step's scratch: kept
            tr = engine_mod.Transition(
                last.obs, last.reward, last.terms_dict(), last.events, last.terminated,
                last.truncated, last.over, {},
            )  # fmt: skip
            self._transition = tr
            self._step_of = (self.engine.params, self.engine.current, tr.events, tr.terms)
        if tr is None:
            raise AttributeError("transition: no step yet")
        if not tr.info:  # the step's state is untouched until the next step (a reset replaces it)
            tr.info = engine_mod.infos(*self._step_of)
        return tr

    @property
    def params(self) -> sim.Params:
        """The current episode's parameters (``random_airfields`` moves them at each reset)."""
        return self.engine.params

    # -- spaces ------------------------------------------------------------------------
    def observation_space(self, agent: str) -> Any:
        self._check_agent(agent)
        return self._obs_space

    def action_space(self, agent: str) -> Any:
        self._check_agent(agent)
        return self._act_space

    def _check_agent(self, agent: str) -> int:
        if agent not in self._index:
            raise ConfigError("agent", agent, f"one of {self.possible_agents}")
        return self._index[agent]

    # -- core --------------------------------------------------------------------------
    @property
    def sim_state(self) -> sim.State:
        """The simulator state (batched arrays with n_envs = 1); None before reset()."""
        if self.engine.state is None:
            raise EpisodeOverError("call reset() first")
        return self.engine.state

    def reset(self, seed: int | None = None, options: dict | None = None):
        check_seed(seed)
        if options is not None and not isinstance(options, Mapping):
            raise ConfigError("options", options, "None or a dict (key 'prior': a map)")
        if seed is not None:
            self.engine.seed([seed])
        if self._last is not None and self._transition is None:
            self.transition  # noqa: B018 (the last step's, of the state the reset replaces)
        prior = None
        if options and "prior" in options:
            prior = validate_map(options["prior"], self.params.grid, "options['prior']")
        obs, self._info = self.engine.reset(priors=[prior])
        parts = engine_mod.info_parts(self.params, self.sim_state)
        missing = [k for k in INFO_KEYS if k not in parts]
        if missing:  # a key of the spec that the engine does not produce: never dropped silently
            raise RuntimeError(f"infos lack {missing} of the spec's keys {INFO_KEYS}")
        keys = INFO_KEYS + tuple(e.name for e in spec.MOTION_INFOS if e.name in parts)
        self._info_keys = keys
        self._info_kinds = tuple(
            _PER_ENV if k in engine_mod.PER_ENV_INFOS else _ROWS if k == "links" else _COLUMN
            for k in keys
        )
        self._grouped_infos = sorted(keys) == sorted(_GROUPED_KEYS)
        self._row = None
        if self.random_airfields and self._renderer is not None:
            # its background shows the airfields: draw afresh
            self._renderer.close()
            self._renderer = None
        self.agents = list(self.possible_agents)
        if self._renderer is not None:
            self._renderer.reset_history()
            self._renderer.record(self.sim_state)
        return self._agent_obs(obs, self.agents), self._agent_infos(parts, self.agents)

    def _observations(self) -> dict[str, Any]:
        """The current observations of the live agents."""
        return self._agent_obs(self.engine.observe(), self.agents)

    def _agent_obs(self, obs: Any, agents: list[str]) -> dict[str, Any]:
        """The engine's batched observations ``obs`` as a dict over ``agents``."""
        index = self._index
        if self.obs_type == "dict":
            ras, vec = obs["raster"][0], obs["vector"][0]
            if len(agents) == len(ras):  # every agent, in index order: views by iteration
                return {a: {"raster": r, "vector": v} for a, r, v in zip(agents, ras, vec)}
            return {a: {"raster": ras[index[a]], "vector": vec[index[a]]} for a in agents}
        if len(agents) == obs.shape[1]:
            return dict(zip(agents, obs[0]))
        return {a: obs[0, index[a]] for a in agents}

    def _actions_array(self, actions: Mapping[str, Any]) -> np.ndarray:
        if type(actions) is not dict and not isinstance(actions, Mapping):
            raise ConfigError(
                "actions", actions, f"a dict {{agent: action}} of the live agents {self.agents}"
            )
        agents = self.agents
        if len(actions) == len(agents):  # fast path: one well-formed action per live agent
            try:
                arr = np.array([actions[a] for a in agents])
            except (KeyError, ValueError, TypeError):
                arr = None
            if (
                arr is not None
                and arr.dtype.kind in _NUMERIC_KINDS
                and arr.shape == (len(agents), self._dim)
                and _swarm.all_finite(arr := arr.astype(float, copy=False))
            ):
                if len(agents) == len(self.possible_agents):
                    return arr[None]
                out = np.zeros((1, self.params.n_agents, self._dim))
                out[0, [self._index[a] for a in agents]] = arr
                return out
        return self._actions_array_checked(actions)

    def _actions_array_checked(self, actions: Mapping[str, Any]) -> np.ndarray:
        """Agent by agent, raising a precise error for the first bad entry."""
        n = self.params.n_agents
        arr = np.zeros((1, n, self._dim))
        allowed = _ACTION_ALLOWED.replace("3 finite", f"{self._dim} finite")
        for agent, act in actions.items():
            i = self._check_agent(agent)
            if agent not in self.agents:
                continue  # an action for a finished agent is ignored
            field = f"actions[{agent}]"
            try:
                a = np.asarray(act)
            except (ValueError, TypeError):  # ragged nesting
                raise ConfigError(field, act, allowed) from None
            if a.dtype.kind not in _NUMERIC_KINDS:
                raise ConfigError(field, act, allowed)
            if a.shape != (self._dim,):
                raise ConfigError(field, act, f"shape ({self._dim},): {allowed}")
            if not np.all(np.isfinite(a)):
                raise ConfigError(field, a.tolist(), allowed)
            arr[0, i] = a
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ConfigError(
                "actions", sorted(actions), f"an action for every live agent {missing}"
            )
        return arr

    def step(self, actions: Mapping[str, Any]):
        if not self.agents:
            raise EpisodeOverError("every agent has finished; call reset() before step()")
        arr = self._actions_array(actions)
        if self._single is None:
            return self._step_engine(arr)
        last = self._single.step(arr)
        self._last = last
        self._transition = None
        self._info = None
        live = self.agents
        reward = last.reward.tolist()[0]  # (the env's row of the lists: no array view)
        terminal = last.terminated.tolist()[0]
        truncated = last.truncated.tolist()[0]
        infos = self._fast_infos(last, live)
        if len(live) == len(reward):  # every agent: in index order
            rewards = dict(zip(live, reward))
            terminations = dict(zip(live, terminal))
            truncations = dict(zip(live, truncated))
        else:
            idx = list(map(self._index.__getitem__, live))
            rewards = {a: reward[i] for a, i in zip(live, idx)}
            terminations = {a: terminal[i] for a, i in zip(live, idx)}
            truncations = {a: truncated[i] for a, i in zip(live, idx)}
        observations = self._agent_obs(last.obs, live)  # agents finishing now get a last obs
        done = True in terminal or True in truncated  # (the lists of every agent's flag)
        return self._end_step(live, observations, rewards, terminations, truncations, infos, done)

    def _end_step(self, live, observations, rewards, terminations, truncations, infos, done=True):
        """The end of both step paths: the agents still flying (``live``, a new list, when
        ``done`` is False: none finished), the renderer, the return."""
        if done:
            self.agents = [a for a in live if not (terminations[a] or truncations[a])]
        else:
            self.agents = live.copy()
        if self._renderer is not None:
            self._renderer.record(self.sim_state)
        if self.render_mode == "human":
            self.render()
        return observations, rewards, terminations, truncations, infos

    def _fast_infos(self, last: single_mod.Step, live: list[str]) -> dict[str, dict[str, Any]]:
        """Per-agent infos of a :class:`~poc_env.sim.single.Step`: its grouped values, one
        ``tolist()`` per group, joined and put in ``_info_keys``' order (the values and types of
        :meth:`_agent_infos`, which builds them when keys beyond the groups exist)."""
        if not self._grouped_infos:  # keys beyond the grouped ones: the engine's info values
            self.transition  # noqa: B018 (sets _step_of)
            return self._agent_infos(engine_mod.info_parts(*self._step_of), live)
        fl, bl, il = last.finfo.tolist()[0], last.binfo.tolist()[0], last.iinfo.tolist()[0]
        links = list(self.engine.current.links[0].copy())  # each agent's row, its own
        rows = self._row
        if rows is None:
            rows = self._row = _row_builder(self._info_keys)
        env_row, row = rows
        d = env_row(fl[0], bl[0], il[0])
        if len(live) == len(fl):  # every agent: in index order
            return dict(zip(live, map(row, repeat(d), fl, bl, il, links)))
        idx = map(self._index.__getitem__, live)
        return {a: row(d, fl[i], bl[i], il[i], links[i]) for a, i in zip(live, idx)}

    def _step_engine(self, arr: np.ndarray):
        """:meth:`step` through the engine's step (per-UAV beliefs)."""
        eng = self.engine
        tr = eng.step(arr, with_info=False)  # the info arrays only when asked for (info_arrays)
        self._transition = tr
        self._last = None
        self._step_of = (eng.params, eng.current, tr.events, tr.terms)
        self._info = None
        reward = tr.reward[0].tolist()
        terminal = tr.terminated[0].tolist()
        truncated = tr.truncated[0].tolist()
        live = list(self.agents)
        rewards, terminations, truncations = {}, {}, {}
        for a in live:
            i = self._index[a]
            rewards[a] = reward[i]
            terminations[a] = terminal[i]
            truncations[a] = truncated[i]
        infos = self._agent_infos(engine_mod.info_parts(*self._step_of), live)
        observations = self._agent_obs(tr.obs, live)  # agents finishing now get a last obs
        return self._end_step(live, observations, rewards, terminations, truncations, infos)

    def _agent_infos(
        self, parts: dict[str, np.ndarray], agents: list[str]
    ) -> dict[str, dict[str, Any]]:
        """Per-agent infos from the engine's :func:`~poc_env.sim.engine.info_parts` (the values
        of :func:`poc_env.sim.engine.infos`): the same keys at reset and at every step, in the
        spec's order (:func:`poc_env.spec.info_keys`, then ``MOTION_INFOS``), every value a
        Python float/int/bool or a fixed-shape numpy array."""
        n = self.engine.n_agents
        cols: list[list[Any]] = []
        for k, kind in zip(self._info_keys, self._info_kinds):
            if kind == _COLUMN:  # (1, N): the env's row as Python numbers
                cols.append(parts[k].tolist()[0])
            elif kind == _PER_ENV:  # (1,): the env's value, for every agent
                cols.append([parts[k].tolist()[0]] * n)
            else:  # links: each agent's row of the adjacency, its own (one copy, split)
                cols.append(list(parts[k][0].copy()))
        keys = self._info_keys
        rows = list(map(dict, map(zip, repeat(keys), zip(*cols))))
        index = self._index
        return {a: rows[index[a]] for a in agents}

    @property
    def topology(self) -> str:
        """Name of the active §3.2.5 topology (Table 2 letter), or ``"auto"``."""
        name = None
        if self.params.switcher is not None:
            name = self.params.switcher.name(int(self.sim_state.topology[0]))
        return name or "auto"

    @property
    def links(self) -> list[tuple[int, int]]:
        """Active communication links as agent-index pairs ``(i, j)``, ``i < j``."""
        rows, cols = np.nonzero(self.sim_state.links[0] & self._upper)
        return list(zip(rows.tolist(), cols.tolist()))

    def state(self) -> np.ndarray:
        st = self.sim_state
        g = self.params.grid
        scale = self.engine.poc_scale[0]
        poc = np.clip(g.coarsen(st.belief[0], self.params.s) / scale, 0, 1)
        vec = obs_mod.vectors(self.params, st)[0]
        return np.concatenate([poc.ravel(), vec.ravel()]).astype(np.float32)

    # -- rendering -----------------------------------------------------------------------
    def render(self):
        if self.render_mode is None:
            import warnings

            warnings.warn(
                "render() called with render_mode=None: pass render_mode='rgb_array' or "
                "'human' when making the env",
                stacklevel=2,
            )
            return None
        if self._renderer is None:
            from poc_env.viz.rendering import Renderer

            self._renderer = Renderer(self.params, self.render_mode)
            self._renderer.record(self.sim_state)
        frame = self._renderer.frame(self.sim_state)
        return frame if self.render_mode == "rgb_array" else None

    def __getstate__(self) -> dict[str, Any]:
        """Pickle without the renderer (a matplotlib figure; a copy draws afresh) and the info
        row function (made by exec; a copy makes it again)."""
        state = self.__dict__.copy()
        state["_renderer"] = None
        state["_row"] = None
        return state

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
