"""The batched episode engine: what every adapter shares between the functional core and its
framework's conventions (the role VMAS's ``Environment`` plays).

:class:`Engine` runs ``n_envs`` episodes of one scenario in one batched :class:`~poc_env.sim.core.
State` and owns everything that belongs to an episode rather than to a framework:

* one generator per env (``engine.rngs``), which draws, at each reset and in this order, the
  env's prior (from the :class:`PriorSource`), its airfields (``random_airfields``), its hidden
  target and detection threshold (:func:`~poc_env.sim.core.initial`), then its link failures
  step after step (:func:`~poc_env.sim.core.step`);
* the prior of each env's episode (``engine.priors``) and its POC scale (``engine.poc_scale``,
  the largest cell POC of that prior: raster channel ``poc`` is POC / scale);
* the hazard mask and the compass features of the observations;
* the control level's autopilot (:func:`~poc_env.sim.control.swarm_increments`), the reward
  (:mod:`poc_env.sim.rewards`), the episode-end rule (:func:`~poc_env.sim.core.terminal`,
  :func:`~poc_env.sim.core.truncated`, :func:`~poc_env.sim.core.episode_over`) and the full info
  set, computed once per step for every env and agent as arrays (:func:`infos`);
* the observation and action spaces of each observation kind and control level
  (:func:`observation_space`, :func:`action_space`, :func:`state_space`, :func:`joint_space`).

``engine.reset(envs)`` starts new episodes in some or all envs and returns their first
observations and infos; ``engine.step(actions)`` advances every env (or ``envs``) by one step
and returns a :class:`Transition`. The adapters (PettingZoo parallel and AEC, the Gymnasium view,
``gymnasium.make_vec``, the SB3 ``VecEnv``, RLlib, TorchRL, the GIF renderer) only convert
these arrays into their framework's layout.

A prior source is the plug for what an episode starts from: :class:`FixedPrior` (the scenario's
prior or a map file) and :class:`RandomPrior` (a seeded Gaussian mixture per episode). A
source's ``draw(grid, rng)`` is called once per reset of each env with that env's generator; a
future source of moving targets plugs in here (and a motion step after
:func:`~poc_env.sim.core.step`).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

import poc_env._kernels.adapters as _adapters
import poc_env.limits as limits
import poc_env.spec as spec
from poc_env.config import Scenario, load_scenario
from poc_env.errors import ConfigError
from poc_env.sim import comms as comms_mod
from poc_env.sim import core as sim
from poc_env.sim import observations as obs_mod
from poc_env.sim.control import ACTION_DIMS, check_control, swarm_increments
from poc_env.sim.rewards import reward_terms, total_reward
from poc_env.theory.probability_map import Grid, load_map, random_gaussian_mixture

#: The reward terms (:data:`poc_env.spec.REWARD_TERMS`), as info keys ``reward_<term>``.
REWARD_TERMS = spec.names(spec.REWARD_TERMS)
#: The constraint flags (eq. 18, 20-24; :data:`poc_env.spec.VIOLATION_FLAGS`), as info keys
#: ``violation_<flag>``.
VIOLATION_FLAGS = tuple(flag for flag, _ in spec.VIOLATION_FLAGS)
#: Per-agent info keys (:func:`poc_env.spec.info_keys`; ``posc`` is per env).
AGENT_INFO_KEYS = tuple(k for k in spec.info_keys() if k != "posc")


def check_seed(seed: Any, field: str = "seed") -> Any:
    """Return ``seed`` if it is None, an integer >= 0 or a ``numpy.random.SeedSequence``."""
    if seed is None or isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ConfigError(field, seed, "None, an integer >= 0 or a numpy SeedSequence")
    return seed


def resolve_overrides(overrides: Mapping[str, Any] | None, kwargs: Mapping[str, Any]):
    """Merge ``overrides`` (dotted YAML keys) and keyword overrides (``sensor__law=...``)."""
    out = dict(overrides or {})
    for key, value in kwargs.items():
        out[key.replace("__", ".")] = value
    return out


# ------------------------------------------------------------------------------- prior sources
class PriorSource(Protocol):
    """Where each episode's prior comes from: ``draw(grid, rng)`` returns a ``(ny, nx)`` prior
    drawn from the env's generator ``rng``, or None for the engine's fixed prior
    (``params.prior``). Called once per reset of each env, before anything else is drawn."""

    def draw(self, grid: Grid, rng: np.random.Generator) -> np.ndarray | None: ...


@dataclass(frozen=True)
class FixedPrior:
    """The scenario's prior (or the map file's) at every reset; draws nothing."""

    def draw(self, grid: Grid, rng: np.random.Generator) -> np.ndarray | None:
        return None


@dataclass(frozen=True)
class RandomPrior:
    """A fresh Gaussian mixture at every reset
    (:func:`~poc_env.theory.probability_map.random_gaussian_mixture`), from the env's generator."""

    def draw(self, grid: Grid, rng: np.random.Generator) -> np.ndarray | None:
        return random_gaussian_mixture(grid, rng)


# ------------------------------------------------------------------------------------ spaces
def observation_space(params: sim.Params, obs_type: str):
    """One agent's observation space of kind ``obs_type`` (``gymnasium.spaces``, float32):
    ``dict`` (raster + vector), ``flat`` (the two raveled, raster first), ``compass`` or
    ``set``."""
    from gymnasium import spaces

    g = params.grid
    raster = spaces.Box(0.0, 1.0, (obs_mod.RASTER_CHANNELS, g.ny, g.nx), np.float32)
    vector = spaces.Box(obs_mod.VECTOR_LOW, obs_mod.VECTOR_HIGH, dtype=np.float32)
    if obs_type == "dict":
        return spaces.Dict({"raster": raster, "vector": vector})
    if obs_type == "compass":
        return spaces.Box(obs_mod.FEATURE_LOW, obs_mod.FEATURE_HIGH, dtype=np.float32)
    if obs_type == "set":
        return spaces.Box(obs_mod.SET_LOW, obs_mod.SET_HIGH, dtype=np.float32)
    if obs_type == "flat":
        low = np.concatenate([raster.low.ravel(), vector.low])
        high = np.concatenate([raster.high.ravel(), vector.high])
        return spaces.Box(low, high, dtype=np.float32)
    raise ConfigError("obs_type", obs_type, "one of " + ", ".join(obs_mod.OBS_TYPES))


def action_space(control: str):
    """One agent's action space at the ``control`` level: ``Box(-1, 1, (ACTION_DIMS,))``."""
    from gymnasium import spaces

    return spaces.Box(-1.0, 1.0, (ACTION_DIMS[check_control(control)],), np.float32)


def state_space(params: sim.Params):
    """The global state's space (centralised critics): the POC raster, then every vector."""
    from gymnasium import spaces

    g, n = params.grid, params.n_agents
    low = np.concatenate([np.zeros(g.ny * g.nx), np.tile(obs_mod.VECTOR_LOW, n)])
    high = np.concatenate([np.ones(g.ny * g.nx), np.tile(obs_mod.VECTOR_HIGH, n)])
    return spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)


def joint_space(space: Any, n: int):
    """``n`` agents' observations (or actions) stacked: a Dict of Boxes ``(n, ...)`` for a Dict,
    else one Box of the ``n`` Boxes concatenated (the centralised Gymnasium view's spaces)."""
    from gymnasium import spaces

    def stacked(box: Any):
        assert isinstance(box, spaces.Box)
        return spaces.Box(np.stack([box.low] * n), np.stack([box.high] * n), dtype=np.float32)

    if isinstance(space, spaces.Dict):
        return spaces.Dict({k: stacked(b) for k, b in space.spaces.items()})
    assert isinstance(space, spaces.Box)
    return spaces.Box(np.tile(space.low, n), np.tile(space.high, n), dtype=np.float32)


# ------------------------------------------------------------------------------------- infos
#: Info keys with one value per env (every agent of the env gets its env's value).
PER_ENV_INFOS = frozenset(
    ("posc", "pos_team", "target_detected", "time_to_detection_s", "topology", "connected")
).union(e.name for e in spec.MOTION_INFOS)
#: Keys whose :func:`info_parts` array is the state's own array (:func:`infos` copies it).
_STATE_ARRAYS = frozenset(("landed", "crashed", "links"))


def info_parts(
    params: sim.Params,
    state: sim.State,
    events: sim.Events | None = None,
    terms: Mapping[str, np.ndarray] | None = None,
) -> dict[str, np.ndarray]:
    """Every info of every env, in :func:`infos`' order, before the per-env values are repeated
    for each agent: ``(E,)`` for the keys of :data:`PER_ENV_INFOS`, ``(E, N)`` for the others
    (``links (E, N, N)``). ``landed``, ``crashed`` and ``links`` are the state's own arrays (not
    copies). The one place the info values are computed: :func:`infos` batches them, the single
    PettingZoo env turns one env's into per-agent rows."""
    e, n = state.flying.shape
    if events is None or terms is None:
        zeros = np.zeros((e, n))
    if events is None:
        no = np.zeros((e, n), dtype=bool)
        pos, pos_team, shielded = zeros, np.zeros(e), no
        flags = {f: no for f in VIOLATION_FLAGS}
        both = state.flying[:, :, None] & state.flying[:, None, :]
        connected = np.all(comms_mod.reachable(state.links) | ~both, axis=(1, 2))
    else:
        pos = events.pos_agent
        pos_team = np.asarray(events.pos_team, dtype=float)
        shielded = events.shielded
        flags = {
            "out_of_bounds": events.out_of_bounds,
            "no_fly": events.no_fly,
            "collision": events.collision,
            "threat": events.threat,
            "comms": ~events.comms_ok,
            "overtime": events.overtime,
        }
        connected = np.asarray(events.connected, dtype=bool)
    out: dict[str, np.ndarray] = {
        "posc": state.posc.astype(float),
        "pos": np.asarray(pos, dtype=float),
        "pos_team": pos_team,
    }
    for t in REWARD_TERMS:
        term = zeros if terms is None else terms[t]
        out[f"reward_{t}"] = np.asarray(term, dtype=float)  # (E, N) already
    for f in VIOLATION_FLAGS:
        out[f"violation_{f}"] = flags[f]
    detected = state.detected
    out.update(
        shielded=shielded,
        landed=state.landed,
        crashed=state.crashed,
        flight_time_s=state.elapsed.astype(float),
        target_detected=detected,
        time_to_detection_s=np.where(detected, state.detect_step * params.dt, -1.0),
        topology=state.topology.astype(np.int64),
        links=state.links,
        connected=connected,
        violations=state.violations.astype(np.int64),
    )
    if state.mass_out is not None:  # moving targets (spec.MOTION_INFOS)
        out["mass_out"] = state.mass_out.astype(float)
    return out


def infos(
    params: sim.Params,
    state: sim.State,
    events: sim.Events | None = None,
    terms: Mapping[str, np.ndarray] | None = None,
) -> dict[str, np.ndarray]:
    """Every info of every env and agent, as arrays: ``posc (E,)`` and each key of
    :data:`AGENT_INFO_KEYS` ``(E, N)`` (``links (E, N, N)``). ``events`` None: a reset
    (nothing happened yet, step quantities are 0/False). The values of :func:`info_parts`."""
    n = state.flying.shape[1]
    out: dict[str, np.ndarray] = {}
    for k, v in info_parts(params, state, events, terms).items():
        if k in PER_ENV_INFOS and k != "posc":
            v = _per_agent(v, n)
        elif k in _STATE_ARRAYS:
            v = v.copy()
        out[k] = v
    return out


def _per_agent(x: np.ndarray, n: int) -> np.ndarray:
    """(E, N): each env's value ``x (E,)`` repeated for its ``n`` agents."""
    return np.repeat(x[:, None], n, axis=1)


def mean_over(values: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(E,) the mean of ``values (E, N)`` over the True entries of ``mask (E, N)`` in each row
    (0 for a row without any): the centralised view's reward, the mean of the live agents'.

    Each mean is numpy's mean of exactly the row's live values (the same floating-point sums).
    Rows of fewer than 8 entries, which numpy sums one after the other, are summed in one
    compiled pass (:func:`poc_env._kernels.adapters.live_mean`); longer rows, which numpy sums
    pairwise, are grouped by how many entries they average."""
    values = np.asarray(values, dtype=float)
    mask = np.asarray(mask, dtype=bool)
    if values.ndim == 2 and 0 < values.shape[1] < 8 and mask.shape == values.shape:
        out = np.empty(values.shape[0])
        _adapters.live_mean(values, mask, out)
        return out
    if mask.all():  # every agent live: the same rows, the same sums
        return values.mean(axis=1)
    count = mask.sum(axis=1)
    c0 = int(count[0])
    if c0 and bool((count == c0).all()):  # one group (always so with one env)
        return values[mask].reshape(-1, c0).mean(axis=1)
    out = np.zeros(values.shape[0])
    for c in np.unique(count[count > 0]).tolist():
        rows = count == c
        out[rows] = values[rows][mask[rows]].reshape(-1, c).mean(axis=1)
    return out


# ------------------------------------------------------------------------------ the engine
@dataclass
class Transition:
    """What one :meth:`Engine.step` did to the envs it stepped (``E'`` of them).

    Attributes
    ----------
    obs:
        Every agent's observation after the step (:func:`~poc_env.sim.observations.observe`'s
        layout: ``(E', N, D)`` or a dict of ``raster``/``vector``).
    reward:
        ``(E', N)`` each agent's reward (:func:`~poc_env.sim.rewards.total_reward`).
    terms:
        Each reward term ``(E', N)`` (:func:`~poc_env.sim.rewards.reward_terms`).
    events:
        The core's :class:`~poc_env.sim.core.Events` of the step.
    terminated, truncated:
        ``(E', N)`` :func:`~poc_env.sim.core.terminal` and :func:`~poc_env.sim.core.truncated`.
    over:
        ``(E',)`` :func:`~poc_env.sim.core.episode_over`.
    info:
        The full info set, :func:`infos`.
    """

    obs: Any
    reward: np.ndarray
    terms: dict[str, np.ndarray]
    events: sim.Events
    terminated: np.ndarray
    truncated: np.ndarray
    over: np.ndarray
    info: dict[str, np.ndarray]


class Engine:
    """``n_envs`` episodes of one scenario in one batched state (module docstring).

    Parameters
    ----------
    scenario:
        The resolved :class:`~poc_env.config.Scenario` (or anything
        :func:`~poc_env.config.load_scenario` takes).
    n_envs:
        Number of envs in the batch.
    prior:
        A fixed ``(ny, nx)`` prior replacing the scenario's (a map file's), or None.
    prior_source:
        Where each episode's prior comes from (default :class:`FixedPrior`).
    obs_type:
        ``"dict"``, ``"flat"``, ``"compass"`` or ``"set"``
        (:func:`~poc_env.sim.observations.observe`).
    control, auto_return, return_increments:
        The control level and its autopilot (:func:`~poc_env.sim.control.swarm_increments`).
    random_airfields:
        Move every airfield at each reset (one env only: the airfields are parameters).
    agent_index:
        With ``compass``: False zeroes the agent-index block of the features.
    seeds:
        One seed per env for its first generator (``np.random.default_rng(seed)``: an int, a
        ``SeedSequence`` or None for fresh entropy); default fresh entropy.
    """

    def __init__(
        self,
        scenario: Scenario | str,
        n_envs: int = 1,
        *,
        prior: np.ndarray | None = None,
        prior_source: PriorSource | None = None,
        obs_type: str = "dict",
        control: str = "increments",
        auto_return: bool = True,
        return_increments: bool = False,
        random_airfields: bool = False,
        agent_index: bool = True,
        seeds: Sequence[Any] | None = None,
    ) -> None:
        if isinstance(n_envs, bool) or not isinstance(n_envs, int | np.integer) or n_envs < 1:
            raise ConfigError("n_envs", n_envs, "an integer >= 1")
        if obs_type not in obs_mod.OBS_TYPES:
            raise ConfigError("obs_type", obs_type, "one of " + ", ".join(obs_mod.OBS_TYPES))
        for name, flag in (
            ("auto_return", auto_return),
            ("return_increments", return_increments),
            ("random_airfields", random_airfields),
            ("agent_index", agent_index),
        ):
            if not isinstance(flag, bool | np.bool_):
                raise ConfigError(name, flag, "True or False")
        if random_airfields and n_envs != 1:
            raise ConfigError(
                "random_airfields", random_airfields, "False with more than one env (the "
                "airfields are parameters shared by the batch)",
            )  # fmt: skip
        self.scenario = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
        self.n_envs = int(n_envs)
        self.control = check_control(control)
        self.auto_return = bool(auto_return)
        self.return_increments = bool(return_increments)
        self.random_airfields = bool(random_airfields)
        self.agent_index = bool(agent_index)
        self.obs_type = obs_type
        self.prior_source: PriorSource = prior_source or FixedPrior()
        self.base_params = sim.make_params(self.scenario, prior)
        self.params = self.base_params
        self.n_agents = self.params.n_agents
        self.action_dim = ACTION_DIMS[self.control]
        self.hazard = obs_mod.hazard_mask(self.params)
        self.features = self._features()
        if seeds is None:
            seeds = [None] * self.n_envs
        if len(seeds) != self.n_envs:
            raise ConfigError("seeds", seeds, f"{self.n_envs} seeds (one per env)")
        self.rngs = [np.random.default_rng(s) for s in seeds]
        self._all_envs = np.arange(self.n_envs)
        self.state: sim.State | None = None
        prior0 = self.params.prior
        self.priors = np.broadcast_to(prior0, (self.n_envs, *prior0.shape)).copy()
        self.poc_scale = np.ones(self.n_envs)
        sc = self.scenario
        names = [a.name for a in sc.airfields]
        fleet = [g for g in sc.fleet for _ in range(g.count)]
        self._takeoff_field = np.array([names.index(g.takeoff) for g in fleet], dtype=np.intp)
        landing = [g.landing or g.takeoff for g in fleet]  # None only before __post_init__
        self._landing_field = np.array([names.index(a) for a in landing], dtype=np.intp)

    def _features(self) -> obs_mod.CompassFeatures | obs_mod.SetFeatures | None:
        if self.obs_type == "set":
            return obs_mod.SetFeatures(self.params)
        if self.obs_type != "compass":
            return None
        return obs_mod.CompassFeatures(self.params, self.agent_index)

    # -- spaces --------------------------------------------------------------------------------
    @property
    def observation_space(self):
        """One agent's observation space (:func:`observation_space`)."""
        return observation_space(self.params, self.obs_type)

    @property
    def action_space(self):
        """One agent's action space (:func:`action_space`)."""
        return action_space(self.control)

    # -- seeding and reset -----------------------------------------------------------------------
    def envs(self, envs: Sequence[int] | np.ndarray | None = None) -> np.ndarray:
        """``envs`` as an index array (None: every env)."""
        if envs is None:
            return np.arange(self.n_envs)
        return np.asarray(envs, dtype=np.intp).reshape(-1)

    def _everything(self, idx: np.ndarray) -> bool:
        if len(idx) != self.n_envs:
            return False
        if self.n_envs == 1:
            return int(idx[0]) == 0
        return bool((idx == self._all_envs).all())

    def seed(self, seeds: Sequence[Any], envs: Sequence[int] | np.ndarray | None = None) -> None:
        """New generators ``np.random.default_rng(seed)`` for ``envs`` (a None seed keeps the
        env's generator, which continues its stream)."""
        idx = self.envs(envs)
        if len(seeds) != len(idx):
            raise ConfigError("seeds", seeds, f"{len(idx)} seeds (one per env)")
        for k, s in zip(idx.tolist(), seeds, strict=True):
            if s is not None:
                self.rngs[k] = np.random.default_rng(s)

    def draw_airfields(self, rng: np.random.Generator) -> np.ndarray:
        """One position ``(n_airfields, 2)`` per scenario airfield, uniform over the search
        grid, outside the no-fly zones by at least the landing radius, from ``rng``."""
        x0, y0, x1, y1 = self.base_params.grid.bounds
        zones = self.base_params.zones
        clearance = self.scenario.episode.landing_radius_m
        out = np.empty((len(self.scenario.airfields), 2))
        for k in range(len(out)):
            for _ in range(1000):
                xy = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
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

    def reset(
        self,
        envs: Sequence[int] | np.ndarray | None = None,
        priors: Sequence[np.ndarray | None] | None = None,
        with_info: bool = True,
    ) -> Any:
        """Start new episodes in ``envs`` (default all); return their first observations and
        infos (:func:`infos` at a reset: step quantities 0/False), batched over ``envs``
        (``with_info=False``: an empty dict, for an adapter that reads no reset infos).

        ``priors``: one per env of ``envs``, a ``(ny, nx)`` map or None (then the
        :class:`PriorSource` draws it from the env's generator); maps are taken as given
        (validate them first, :func:`~poc_env.theory.probability_map.validate_map`)."""
        idx = self.envs(envs)
        given: Sequence[np.ndarray | None] = [None] * len(idx) if priors is None else priors
        grid = self.base_params.grid
        drawn = [
            p if p is not None else self.prior_source.draw(grid, self.rngs[k])
            for k, p in zip(idx.tolist(), given, strict=True)
        ]
        if self.random_airfields:
            fields = self.draw_airfields(self.rngs[int(idx[0])])
            self.params = dataclasses.replace(
                self.base_params,
                takeoff=fields[self._takeoff_field],
                landing=fields[self._landing_field],
            )
            self.features = self._features()
        p = self.params
        stack = None
        if any(d is not None for d in drawn):
            stack = np.stack([p.prior if d is None else np.asarray(d, dtype=float) for d in drawn])
        fresh = sim.initial(p, [self.rngs[k] for k in idx.tolist()], stack)
        self.priors[idx] = p.prior if stack is None else stack
        if stack is None:
            self.poc_scale[idx] = float(p.prior.max())
        else:
            self.poc_scale[idx] = stack.max(axis=(1, 2))
        if self.state is None or self._everything(idx):
            self.state = fresh
        else:
            sim.scatter_envs(self.state, fresh, idx)
        return self.observe_state(fresh, idx), (infos(p, fresh) if with_info else {})

    # -- observations ------------------------------------------------------------------------------
    def observe_state(self, state: sim.State, envs: Sequence[int] | np.ndarray | None = None):
        """Every agent's observation of ``state``, a batch of the engine's envs ``envs``
        (default all: then ``state`` is the whole batch), with their POC scales."""
        scale = self.poc_scale if envs is None else self.poc_scale[self.envs(envs)]
        return obs_mod.observe(self.params, state, scale, self.hazard, self.obs_type, self.features)

    def observe(self):
        """Every agent's observation of every env."""
        return self.observe_state(self.current)

    @property
    def current(self) -> sim.State:
        """The batched state (a RuntimeError before the first :meth:`reset`)."""
        if self.state is None:
            raise RuntimeError("call reset() first")
        return self.state

    # -- step ----------------------------------------------------------------------------------
    def step(
        self,
        actions: np.ndarray,
        envs: Sequence[int] | np.ndarray | None = None,
        with_info: bool = True,
    ) -> Transition:
        """Advance ``envs`` (default all) by one step under the control level's ``actions
        (E', N, ACTION_DIMS[control])`` (finished UAVs' actions are ignored by the core).
        ``with_info=False`` leaves ``Transition.info`` empty (an adapter that reads the few
        infos it needs from the state saves computing the full set)."""
        if envs is None:  # every env (the common case: no index arrays)
            idx, whole = None, True
        else:
            idx = self.envs(envs)
            whole = self._everything(idx)
        p = self.params
        st = self.current if idx is None or whole else sim.take_envs(self.current, idx)
        rngs = self.rngs if idx is None else [self.rngs[k] for k in idx.tolist()]
        inc = swarm_increments(
            p, self.control, st, actions, self.auto_return, self.return_increments
        )
        ev = sim.step(p, st, inc, rngs)
        terms = reward_terms(self.scenario.reward, ev)
        reward = total_reward(terms)
        terminated = sim.terminal(p, st)
        truncated = sim.truncated(p, st)
        over = sim.episode_over(p, st, terminated)
        if idx is not None and not whole:
            sim.scatter_envs(self.current, st, idx)
        obs = self.observe_state(st, idx)
        info = infos(p, st, ev, terms) if with_info else {}
        return Transition(obs, reward, terms, ev, terminated, truncated, over, info)


def make_engine(
    n_envs: int = 1,
    *,
    scenario: str | Scenario = "paper_6_2",
    obs_type: str = "dict",
    map_file: str | os.PathLike[str] | None = None,
    overrides: Mapping[str, Any] | None = None,
    random_prior: bool = False,
    max_cycles: int | None = None,
    random_airfields: bool = False,
    control: str = "increments",
    auto_return: bool = True,
    return_increments: bool = False,
    agent_index: bool = True,
    seeds: Sequence[Any] | None = None,
    **kwargs: Any,
) -> Engine:
    """An :class:`Engine` from the environments' keyword arguments (those of
    :class:`~poc_env.envs.parallel.UAVSearchParallelEnv` but ``render_mode``), validated:
    ``overrides`` and keyword overrides (``uav__endurance_h=2``) resolve the scenario,
    ``max_cycles`` sets ``episode.horizon_steps``, ``map_file`` gives a fixed prior and
    ``random_prior`` a :class:`RandomPrior` source; ``return_increments``, ``agent_index`` and
    ``seeds`` are the :class:`Engine`'s."""
    if obs_type not in obs_mod.OBS_TYPES:
        raise ConfigError("obs_type", obs_type, "one of " + ", ".join(obs_mod.OBS_TYPES))
    if map_file is not None and not isinstance(map_file, str | os.PathLike):
        raise ConfigError("map_file", map_file, "None or a path to a .npy or .csv prior map")
    for name, flag in (("random_prior", random_prior), ("random_airfields", random_airfields)):
        if not isinstance(flag, bool | np.bool_):
            raise ConfigError(name, flag, "True or False")
    if random_prior and map_file is not None:
        raise ConfigError(
            "random_prior", random_prior, "False when a map_file prior is given (one prior)"
        )
    check_control(control)
    if not isinstance(auto_return, bool | np.bool_):
        raise ConfigError("auto_return", auto_return, "True or False")
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
    sc = load_scenario(scenario, merged)
    prior = load_map(map_file, Grid.from_config(sc.map)) if map_file is not None else None
    return Engine(
        sc,
        n_envs,
        prior=prior,
        prior_source=RandomPrior() if random_prior else FixedPrior(),
        obs_type=obs_type,
        control=control,
        auto_return=bool(auto_return),
        return_increments=return_increments,
        random_airfields=bool(random_airfields),
        agent_index=agent_index,
        seeds=seeds,
    )
