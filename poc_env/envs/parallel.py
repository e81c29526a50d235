"""The PettingZoo parallel environment of the UAV swarm (the n_envs == 1 case of the core)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from poc_env.config import Scenario, load_scenario
from poc_env.errors import ConfigError, PocEnvError
from poc_env.sim import core as sim
from poc_env.sim import observations as obs_mod
from poc_env.sim.rewards import reward_terms, total_reward
from poc_env.theory.probability_map import Grid, load_map, validate_map

OBS_TYPES = ("dict", "flat")
#: Array kinds an action may have: bool, signed and unsigned integer, real float.
_NUMERIC_KINDS = "biuf"
_ACTION_ALLOWED = "3 finite real numbers in [-1, 1] (a list or array, not strings or complex)"


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

    ## Observation Space

    ``obs_type="dict"``: ``Dict(raster=Box(0, 1, (4, ny, nx)), vector=Box(low, high, (14,)))``;
    ``obs_type="flat"``: their concatenation (raster first). float32. Raster channels:

    ==  =======  =====================================================================
    0   poc      current cell POC / largest prior cell POC, in [0, 1]
    1   self     1 in this UAV's cell
    2   others   1 in cells with another flying UAV
    3   hazard   1 in no-fly or threat cells
    ==  =======  =====================================================================

    Vector (units normalised as shown; see :mod:`poc_env.sim.observations`):

    =====  ==============  =====================================================  ========
    idx    name            meaning                                                 bounds
    =====  ==============  =====================================================  ========
    0-1    x, y            position in the operating area (0..1 across it)        [-1, 2]
    2      z               altitude / ceiling                                      [0, 1]
    3      speed           (v - v_min) / (v_max - v_min)                           [0, 1]
    4-5    sin, cos        heading alpha                                           [-1, 1]
    6      pitch           beta / beta_max                                         [-1, 1]
    7      endurance       1 - t / T                                               [0, 1]
    8      usable          1 - t / (0.85 T)                                        [-1, 1]
    9-10   to_landing      (landing field - position) / operating-area diagonal   [-1, 1]
    11     neighbours      UAVs within RC_max / (N - 1)                            [0, 1]
    12     flying          1 while flying                                          [0, 1]
    13     time            step / horizon                                          [0, 1]
    =====  ==============  =====================================================  ========

    ``state()`` (centralised critics): the POC raster (ny x nx) then every agent's vector.

    ## Rewards

    ``alpha * POS`` of the step (team-shared by default, ``reward.credit: individual`` for
    own credit) ``- beta *`` the eq. 25 time term ``-`` penalties for constraint violations,
    overtime beyond 0.85 T and crashes (:mod:`poc_env.sim.rewards`). Every term is in
    ``infos[agent]["reward_terms"]``. With team credit and ``beta = 0`` and no penalties, an
    episode's return is its POSC (eq. 13).

    ## Starting State

    UAVs start over their take-off fields at cruise altitude and cruise speed, level, heading
    for the centre of the grid; the belief is the prior (the scenario's, a ``--map`` file, or
    ``options={"prior": array}``); the hidden target is drawn from it by the env's generator.

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
    (``uav__endurance_h=2``). The default time step is 60 s: at 180 km/h a UAV flies 3 km,
    below the 5 km cell and the 5 km sweep width, and an episode of T = 3 h is 180 steps.

    ## Version History

    * v0: first release.
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
        **kwargs: Any,
    ) -> None:
        if render_mode not in (None, "rgb_array", "human"):
            raise ConfigError("render_mode", render_mode, "None, 'rgb_array' or 'human'")
        if obs_type not in OBS_TYPES:
            raise ConfigError("obs_type", obs_type, "'dict' or 'flat'")
        if map_file is not None and not isinstance(map_file, str | os.PathLike):
            raise ConfigError("map_file", map_file, "None or a path to a .npy or .csv prior map")
        self.scenario = load_scenario(scenario, resolve_overrides(overrides, kwargs))
        grid = Grid.from_config(self.scenario.map)
        prior = load_map(map_file, grid) if map_file is not None else None
        self.params = sim.make_params(self.scenario, prior)
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
        else:
            low = np.concatenate([raster.low.ravel(), vector.low])
            high = np.concatenate([raster.high.ravel(), vector.high])
            space = spaces.Box(low, high, dtype=np.float32)
        self._obs_space = space
        self._act_space = spaces.Box(-1.0, 1.0, (3,), np.float32)
        slow = np.concatenate([np.zeros(g.ny * g.nx), np.tile(obs_mod.VECTOR_LOW, n)])
        shigh = np.concatenate([np.ones(g.ny * g.nx), np.tile(obs_mod.VECTOR_HIGH, n)])
        self.state_space = spaces.Box(
            slow.astype(np.float32), shigh.astype(np.float32), dtype=np.float32
        )
        self._rng = np.random.default_rng()
        self._state: sim.State | None = None
        self._renderer = None
        self._poc_scale = np.ones(1)

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
        self._state = sim.initial(self.params, [self._rng], prior)
        p0 = self.params.prior if prior is None else prior[0]
        self._poc_scale = np.array([float(p0.max())])
        self.agents = list(self.possible_agents)
        self._detect_time = None
        if self._renderer is not None:
            self._renderer.reset_history()
            self._renderer.record(self._state)
        observations = self._observations()
        infos = {a: {"posc": 0.0} for a in self.agents}
        return observations, infos

    def _observations(self) -> dict[str, Any]:
        st = self.sim_state
        vec = obs_mod.vectors(self.params, st)[0]
        ras = obs_mod.rasters(self.params, st, self._poc_scale, self._hazard)[0]
        index = self._index
        if self.obs_type == "dict":
            return {a: {"raster": ras[index[a]], "vector": vec[index[a]]} for a in self.agents}
        n = len(vec)
        flat = np.empty((n, ras[0].size + vec.shape[1]), dtype=np.float32)
        flat[:, : ras[0].size] = ras.reshape(n, -1)
        flat[:, ras[0].size :] = vec
        return {a: flat[index[a]] for a in self.agents}

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
                and arr.shape == (len(agents), 3)
                and np.isfinite(arr).all()
            ):
                if len(agents) == self.params.n_agents:
                    return arr.astype(float, copy=False)[None]
                out = np.zeros((1, self.params.n_agents, 3))
                out[0, [self._index[a] for a in agents]] = arr
                return out
        return self._actions_array_checked(actions)

    def _actions_array_checked(self, actions: Mapping[str, Any]) -> np.ndarray:
        """Agent by agent, raising a precise error for the first bad entry."""
        n = self.params.n_agents
        arr = np.zeros((1, n, 3))
        for agent, act in actions.items():
            i = self._check_agent(agent)
            if agent not in self.agents:
                continue  # an action for a finished agent is ignored
            field = f"actions[{agent}]"
            try:
                a = np.asarray(act)
            except (ValueError, TypeError):  # ragged nesting
                raise ConfigError(field, act, _ACTION_ALLOWED) from None
            if a.dtype.kind not in _NUMERIC_KINDS:
                raise ConfigError(field, act, _ACTION_ALLOWED)
            if a.shape != (3,):
                raise ConfigError(field, act, f"shape (3,): {_ACTION_ALLOWED}")
            if not np.all(np.isfinite(a)):
                raise ConfigError(field, a.tolist(), _ACTION_ALLOWED)
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
        ev = sim.step(self.params, st, arr, [self._rng])
        terms = reward_terms(self.scenario.reward, ev)
        reward = np.asarray(total_reward(terms)[0], dtype=float).tolist()
        live = list(self.agents)
        detected = bool(st.detected[0])
        rewards, terminations, truncations, infos = {}, {}, {}, {}
        topo = self._topology_info(bool(ev.connected[0]))
        # per-agent values as Python lists, converted once per step
        term_names = list(terms)
        term_rows = list(zip(*(np.asarray(v[0], dtype=float).tolist() for v in terms.values())))
        pos = ev.pos_agent[0].tolist()
        oob = ev.out_of_bounds[0].tolist()
        no_fly = ev.no_fly[0].tolist()
        collision = ev.collision[0].tolist()
        threat = ev.threat[0].tolist()
        comms = (~ev.comms_ok[0]).tolist()
        overtime = ev.overtime[0].tolist()
        shielded = ev.shielded[0].tolist()
        landed = st.landed[0].tolist()
        crashed = st.crashed[0].tolist()
        elapsed = st.elapsed[0].tolist()
        terminal = sim.terminal(self.params, st)[0].tolist()
        truncated = sim.truncated(self.params, st)[0].tolist()
        pos_team = float(ev.pos_team[0])
        posc = float(st.posc[0])
        detect_time = float(st.detect_step[0] * self.params.dt) if detected else None
        for a in live:
            i = self._index[a]
            rewards[a] = reward[i]
            terminations[a] = terminal[i]
            truncations[a] = truncated[i]
            infos[a] = {
                "pos": float(pos[i]),
                "pos_team": pos_team,
                "posc": posc,
                "reward_terms": dict(zip(term_names, term_rows[i])),
                "violations": {
                    "out_of_bounds": oob[i],
                    "no_fly": no_fly[i],
                    "collision": collision[i],
                    "threat": threat[i],
                    "comms": comms[i],
                    "overtime": overtime[i],
                },
                "shielded": shielded[i],
                "landed": landed[i],
                "crashed": crashed[i],
                "flight_time_s": float(elapsed[i]),
                "target_detected": detected,
                "time_to_detection_s": detect_time,
                **topo,
            }
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

    def _topology_info(self, connected: bool) -> dict[str, Any]:
        st = self.sim_state
        rows, cols = np.nonzero(st.links[0] & self._upper)
        name = None
        if self.params.switcher is not None:
            name = self.params.switcher.name(int(st.topology[0]))
        return {
            "topology": name or "auto",
            "links": list(zip(rows.tolist(), cols.tolist())),
            "connected": connected,
        }

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
