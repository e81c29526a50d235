"""The PettingZoo parallel environment of the UAV swarm (the n_envs == 1 case of the core)."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from poc_env import limits, spec
from poc_env.config import Scenario, load_scenario
from poc_env.errors import ConfigError, PocEnvError
from poc_env.sim import comms as comms_mod
from poc_env.sim import core as sim
from poc_env.sim import observations as obs_mod
from poc_env.sim.control import ACTION_DIMS, check_control, swarm_increments
from poc_env.sim.rewards import reward_terms, total_reward
from poc_env.theory.probability_map import (
    Grid,
    load_map,
    random_gaussian_mixture,
    validate_map,
)

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


def check_seed(seed: Any, field: str = "seed") -> Any:
    """Return ``seed`` if it is None, an integer >= 0 or a ``numpy.random.SeedSequence``."""
    if seed is None or isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ConfigError(field, seed, "None, an integer >= 0 or a numpy SeedSequence")
    return seed


class EpisodeOverError(PocEnvError, RuntimeError):
    """``step()`` was called after every agent finished; call ``reset()``."""


def resolve_overrides(overrides: Mapping[str, Any] | None, kwargs: Mapping[str, Any]):
    """Merge ``overrides`` (dotted YAML keys) and keyword overrides (``sensor__law=...``)."""
    out = dict(overrides or {})
    for key, value in kwargs.items():
        out[key.replace("__", ".")] = value
    return out


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
    ``COMPASS``), rendered in ``docs/ENVIRONMENT.md``.

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
    ``docs/ENVIRONMENT.md``); a key missing from either side raises at ``reset``.

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
        if obs_type not in OBS_TYPES:
            raise ConfigError("obs_type", obs_type, "'dict', 'flat' or 'compass'")
        if map_file is not None and not isinstance(map_file, str | os.PathLike):
            raise ConfigError("map_file", map_file, "None or a path to a .npy or .csv prior map")
        for name, flag in (("random_prior", random_prior), ("random_airfields", random_airfields)):
            if not isinstance(flag, bool | np.bool_):
                raise ConfigError(name, flag, "True or False")
        if random_prior and map_file is not None:
            raise ConfigError(
                "random_prior", random_prior, "False when a map_file prior is given (one prior)"
            )
        self.control = check_control(control)
        if not isinstance(auto_return, bool | np.bool_):
            raise ConfigError("auto_return", auto_return, "True or False")
        self.auto_return = bool(auto_return)
        self._dim = ACTION_DIMS[self.control]
        merged = resolve_overrides(overrides, kwargs)
        if max_cycles is not None:
            allowed = f"None or an integer in [1, {limits.MAX_STEPS}] (the episode's steps)"
            if (
                isinstance(max_cycles, bool)
                or not isinstance(max_cycles, int | np.integer)
                or not 1 <= max_cycles <= limits.MAX_STEPS
            ):
                raise ConfigError("max_cycles", max_cycles, allowed)
            given = merged.get("episode.horizon_steps")
            if given is not None and given != max_cycles:
                raise ConfigError(
                    "max_cycles", max_cycles, f"None or equal to episode.horizon_steps ({given})"
                )
            merged["episode.horizon_steps"] = int(max_cycles)
        self.scenario = load_scenario(scenario, merged)
        self.random_prior = bool(random_prior)
        self.max_cycles = self.scenario.horizon_steps
        grid = Grid.from_config(self.scenario.map)
        prior = load_map(map_file, grid) if map_file is not None else None
        self.params = sim.make_params(self.scenario, prior)
        self._base_params = self.params
        self.random_airfields = bool(random_airfields)
        names = [a.name for a in self.scenario.airfields]
        fleet = [g for g in self.scenario.fleet for _ in range(g.count)]
        self._takeoff_field = np.array([names.index(g.takeoff) for g in fleet], dtype=np.intp)
        landing = [g.landing or g.takeoff for g in fleet]  # None only before __post_init__
        self._landing_field = np.array([names.index(a) for a in landing], dtype=np.intp)
        self.render_mode = render_mode
        self.obs_type = obs_type
        n = self.params.n_agents
        self.possible_agents = [f"uav_{i}" for i in range(n)]
        self.agents: list[str] = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self._upper = np.triu(np.ones((n, n), dtype=bool))  # links (i, j) with i <= j
        self._hazard = obs_mod.hazard_mask(self.params)
        g = self.params.grid
        raster = spaces.Box(0.0, 1.0, (obs_mod.RASTER_CHANNELS, g.ny, g.nx), np.float32)
        vector = spaces.Box(obs_mod.VECTOR_LOW, obs_mod.VECTOR_HIGH, dtype=np.float32)
        if obs_type == "dict":
            space: spaces.Space = spaces.Dict({"raster": raster, "vector": vector})
        elif obs_type == "compass":
            space = spaces.Box(obs_mod.FEATURE_LOW, obs_mod.FEATURE_HIGH, dtype=np.float32)
        else:
            low = np.concatenate([raster.low.ravel(), vector.low])
            high = np.concatenate([raster.high.ravel(), vector.high])
            space = spaces.Box(low, high, dtype=np.float32)
        self._obs_space = space
        self._act_space = spaces.Box(-1.0, 1.0, (self._dim,), np.float32)
        slow = np.concatenate([np.zeros(g.ny * g.nx), np.tile(obs_mod.VECTOR_LOW, n)])
        shigh = np.concatenate([np.ones(g.ny * g.nx), np.tile(obs_mod.VECTOR_HIGH, n)])
        self.state_space = spaces.Box(
            slow.astype(np.float32), shigh.astype(np.float32), dtype=np.float32
        )
        self._rng = np.random.default_rng()
        self._state: sim.State | None = None
        self._renderer = None
        self._poc_scale = np.ones(1)
        self._features = obs_mod.CompassFeatures(self.params) if obs_type == "compass" else None

    # -- spaces ------------------------------------------------------------------------
    def observation_space(self, agent: str) -> spaces.Space:
        self._check_agent(agent)
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
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
        if self._state is None:
            raise EpisodeOverError("call reset() first")
        return self._state

    def reset(self, seed: int | None = None, options: dict | None = None):
        check_seed(seed)
        if options is not None and not isinstance(options, Mapping):
            raise ConfigError("options", options, "None or a dict (key 'prior': a map)")
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        prior = None
        if options and "prior" in options:
            prior = validate_map(options["prior"], self.params.grid, "options['prior']")[None]
        elif self.random_prior:
            prior = random_gaussian_mixture(self.params.grid, self._rng)[None]
        if self.random_airfields:
            fields = self._draw_airfields()
            self.params = dataclasses.replace(
                self._base_params,
                takeoff=fields[self._takeoff_field],
                landing=fields[self._landing_field],
            )
            if self._features is not None:
                self._features = obs_mod.CompassFeatures(self.params)
            if self._renderer is not None:  # its background shows the airfields: draw afresh
                self._renderer.close()
                self._renderer = None
        self._state = sim.initial(self.params, [self._rng], prior)
        p0 = self.params.prior if prior is None else prior[0]
        self._poc_scale = np.array([float(p0.max())])
        self.agents = list(self.possible_agents)
        self._detect_time = None
        if self._renderer is not None:
            self._renderer.reset_history()
            self._renderer.record(self._state)
        observations = self._observations()
        return observations, self._infos(self.agents)

    def _draw_airfields(self) -> np.ndarray:
        """One position ``(n_airfields, 2)`` per scenario airfield, uniform over the search grid,
        outside the no-fly zones by at least the landing radius, from the env's generator."""
        x0, y0, x1, y1 = self.params.grid.bounds
        zones = self.params.zones
        clearance = self.scenario.episode.landing_radius_m
        out = np.empty((len(self.scenario.airfields), 2))
        for k in range(len(out)):
            for _ in range(1000):
                xy = np.array([self._rng.uniform(x0, x1), self._rng.uniform(y0, y1)])
                if zones.n_zones == 0 or float(zones.distance(xy)) >= clearance:
                    break
            else:
                raise ConfigError(
                    "random_airfields",
                    True,
                    "a search grid with room for an airfield outside the no-fly zones",
                )
            out[k] = xy
        return out

    def _observations(self) -> dict[str, Any]:
        obs = obs_mod.observe(
            self.params, self.sim_state, self._poc_scale, self._hazard, self.obs_type,
            self._features,
        )  # fmt: skip
        index = self._index
        if self.obs_type == "dict":
            ras, vec = obs["raster"][0], obs["vector"][0]
            return {a: {"raster": ras[index[a]], "vector": vec[index[a]]} for a in self.agents}
        return {a: obs[0, index[a]] for a in self.agents}

    def _actions_array(self, actions: Mapping[str, Any]) -> np.ndarray:
        if not isinstance(actions, Mapping):
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
                and np.isfinite(arr).all()
            ):
                if len(agents) == self.params.n_agents:
                    return arr.astype(float, copy=False)[None]
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
        st = self.sim_state
        # the control level's autopilot (poc_env.sim.control); increments pass through
        arr = swarm_increments(self.params, self.control, st, arr, self.auto_return)
        ev = sim.step(self.params, st, arr, [self._rng])
        terms = reward_terms(self.scenario.reward, ev)
        reward = np.asarray(total_reward(terms)[0], dtype=float).tolist()
        live = list(self.agents)
        rewards, terminations, truncations = {}, {}, {}
        terminal = sim.terminal(self.params, st)[0].tolist()
        truncated = sim.truncated(self.params, st)[0].tolist()
        for a in live:
            i = self._index[a]
            rewards[a] = reward[i]
            terminations[a] = terminal[i]
            truncations[a] = truncated[i]
        infos = self._infos(live, ev, terms)
        observations = self._observations_for(live)  # agents finishing now get a last obs
        self.agents = [a for a in live if not (terminations[a] or truncations[a])]
        if self._renderer is not None:
            self._renderer.record(st)
        if self.render_mode == "human":
            self.render()
        return observations, rewards, terminations, truncations, infos

    def _observations_for(self, agents: list[str]) -> dict[str, Any]:
        keep = self.agents
        self.agents = agents
        try:
            return self._observations()
        finally:
            self.agents = keep

    def _infos(
        self,
        agents: list[str],
        ev: sim.Events | None = None,
        terms: Mapping[str, np.ndarray] | None = None,
    ) -> dict[str, dict[str, Any]]:
        """Per-agent infos: the same keys at reset (``ev`` None: nothing happened yet) and at
        every step, every value a Python float/int/bool or a fixed-shape numpy array."""
        st = self.sim_state
        n = self.params.n_agents
        zeros, no = [0.0] * n, [False] * n
        if ev is None:
            pos, pos_team, shielded = zeros, 0.0, no
            flags = {f: no for f in VIOLATION_FLAGS}
            flying = st.flying[0]
            reach = comms_mod.reachable(st.links)[0]
            connected = bool(reach[np.ix_(flying, flying)].all())
        else:
            pos, pos_team = ev.pos_agent[0].tolist(), float(ev.pos_team[0])
            shielded = ev.shielded[0].tolist()
            flags = {
                "out_of_bounds": ev.out_of_bounds[0].tolist(),
                "no_fly": ev.no_fly[0].tolist(),
                "collision": ev.collision[0].tolist(),
                "threat": ev.threat[0].tolist(),
                "comms": (~ev.comms_ok[0]).tolist(),
                "overtime": ev.overtime[0].tolist(),
            }
            connected = bool(ev.connected[0])
        term_cols = {
            t: (np.asarray(terms[t][0], dtype=float).tolist() if terms is not None else zeros)
            for t in REWARD_TERMS
        }
        landed = st.landed[0].tolist()
        crashed = st.crashed[0].tolist()
        elapsed = st.elapsed[0].tolist()
        detected = bool(st.detected[0])
        detect_time = float(st.detect_step[0] * self.params.dt) if detected else -1.0
        posc = float(st.posc[0])
        topology = int(st.topology[0])
        links = st.links[0]
        out = {}
        for a in agents:
            i = self._index[a]
            info: dict[str, Any] = {
                "pos": float(pos[i]),
                "pos_team": pos_team,
                "posc": posc,
            }
            for t in REWARD_TERMS:
                info[f"reward_{t}"] = float(term_cols[t][i])
            for f in VIOLATION_FLAGS:
                info[f"violation_{f}"] = bool(flags[f][i])
            info.update(
                shielded=bool(shielded[i]),
                landed=bool(landed[i]),
                crashed=bool(crashed[i]),
                flight_time_s=float(elapsed[i]),
                target_detected=detected,
                time_to_detection_s=detect_time,
                topology=topology,
                links=links[i].copy(),
                connected=connected,
            )
            out[a] = info
        if ev is None and agents and tuple(out[agents[0]]) != INFO_KEYS:  # once per reset
            raise RuntimeError(f"infos {tuple(out[agents[0]])} differ from spec {INFO_KEYS}")
        return out

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
        poc = np.clip(g.coarsen(st.belief[0], self.params.s) / self._poc_scale[0], 0, 1)
        vec = obs_mod.vectors(self.params, st)[0]
        return np.concatenate([poc.ravel(), vec.ravel()]).astype(np.float32)

    # -- rendering -----------------------------------------------------------------------
    def render(self):
        if self.render_mode is None:
            import warnings

            warnings.warn("render() called with render_mode=None", stacklevel=2)
            return None
        if self._renderer is None:
            from poc_env.viz.rendering import Renderer

            self._renderer = Renderer(self.params, self.render_mode)
            self._renderer.record(self.sim_state)
        frame = self._renderer.frame(self.sim_state)
        return frame if self.render_mode == "rgb_array" else None

    def __getstate__(self) -> dict[str, Any]:
        """Pickle without the renderer (a matplotlib figure); a copy draws afresh."""
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
