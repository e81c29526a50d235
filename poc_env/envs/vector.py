"""A stable-baselines3 ``VecEnv`` over the batched core, with parameter sharing.

:class:`SwarmVecEnv` runs ``n_envs`` independent swarms of ``N`` UAVs in one batched simulator
state (arrays ``(n_envs, N, ...)``, one :func:`poc_env.sim.core.step` call per step for all of
them) and shows every *(env, agent)* pair to SB3 as one environment, a **slot**: ``num_envs =
n_envs * N``, slot ``e * N + i`` is agent ``uav_i`` of env ``e``. All slots share one policy
(parameter sharing). Observation and action spaces: the per-agent spaces of
:class:`~poc_env.envs.parallel.UAVSearchParallelEnv` for the same ``obs_type`` (``"dict"``,
``"flat"`` or ``"compass"``) and ``control`` level (``"increments"``: ``Box(-1, 1, (3,))``;
``"heading"``/``"waypoint"``: ``Box(-1, 1, (2,))``, flown by the same autopilot).
Observations, rewards and terminations come from the same functions the PettingZoo env uses
(:mod:`poc_env.sim.observations`, :mod:`poc_env.sim.rewards`, :func:`poc_env.sim.core.terminal` and
:func:`~poc_env.sim.core.truncated`); nothing is re-implemented here. This module needs the ``rl``
extra (stable-baselines3): without it, importing it raises
:class:`~poc_env.errors.MissingExtraError`.

Slots of finished agents
------------------------
SB3 needs a fixed number of slots, but an agent that landed or crashed has no further
transitions while the rest of its swarm flies on. The adapter therefore:

1. emits the agent's **final transition once**: ``done=True``, its real reward, and its last
   real observation in ``infos[slot]["terminal_observation"]`` (``"TimeLimit.truncated":
   False``, it terminated);
2. until its env resets, emits **placeholder transitions** from that slot: a zero observation
   (inside the observation space, and distinct from every live observation, whose ``flying``
   entry is 1), reward 0, ``done=False``, and ``infos[slot]["inactive"] = True``. Its action is
   ignored (the simulator gets 0, as the PettingZoo env does for finished agents);
3. when the env's episode ends, the placeholder run ends too: ``done=True``, a zero
   ``terminal_observation``, ``"inactive": True``, and the slot carries on with the agent's
   first observation of the new episode.

``infos[slot]["inactive"]`` is True exactly for the placeholder transitions, so training code
that wants to can mask them out of its loss. SB3's PPO does not: it stores them in its rollout
buffer. Why that is harmless, and what it costs:

* *No leakage into real returns.* Every placeholder run starts right after a ``done=True``
  and ends with ``done=True`` without ``TimeLimit.truncated``, so GAE never bootstraps a real
  transition from a placeholder value or the other way round; a real agent's advantages are
  exactly those of its own episode.
* *No conflicting targets.* Placeholders have reward 0 and always continue to a zero
  observation or a terminal, so the value target of the zero observation is 0; the zero
  observation never occurs for a live agent, so fitting it constrains nothing the policy uses.
* *Cost.* The placeholders occupy rollout-buffer rows and forward/backward passes (the
  fraction of slot-steps spent inactive, which is small when agents fly to the horizon and
  grows with early landings or crashes), and they dilute each minibatch: they enter the mean
  policy, value and entropy losses and advantage normalisation, so real samples get a
  proportionally smaller effective learning rate and the policy-gradient term nudges the
  action distribution at the (never used) zero observation. A masked rollout buffer would
  remove this cost; the ``inactive`` flag is there for it.

Episode ends and Monitor statistics
-----------------------------------
An env's episode ends (:func:`poc_env.sim.core.episode_over`) when every agent has terminated
(landed, crashed, or the target was detected with ``episode.detection_ends_episode``) or at the
horizon (``step >= horizon``):
all its slots return ``done=True`` with ``terminal_observation`` (the agent's last real
observation, or zeros for an agent that finished earlier), agents cut off by the horizon get
``"TimeLimit.truncated": True`` (others False), and the env resets at once (auto-reset): the
returned observation is the new episode's first. Each of these slots' ``info`` also carries,
as SB3's ``Monitor`` does, ``"episode": {"r": the agent's return (not rounded), "l": its
number of real transitions, "t": seconds since this VecEnv was created, "posc": the env's
POSC}`` and, at the top level, ``"posc"``, ``"landed"``, ``"crashed"`` and ``"violations"``
(the agent's constraint-violation steps). So there is one ``episode`` record per agent and
episode, and ``env_is_wrapped(Monitor)`` answers True: SB3's ``evaluate_policy`` then counts
these records rather than every ``done`` (which would also count placeholder runs).

Seeding
-------
Env ``e`` owns the generator ``np.random.default_rng(np.random.SeedSequence(seed).spawn(
n_envs)[e])`` (:func:`env_seed_sequences`); it draws that env's priors (``random_priors``),
targets and detection thresholds, and link failures, episode after episode, so each env's
episodes are independent of the other envs and reproducible from ``seed``. Because
``UAVSearchParallelEnv.reset(seed=...)`` builds its generator with ``np.random.default_rng``,
which accepts a ``SeedSequence``, ``par_env.reset(seed=env_seed_sequences(seed, n_envs)[e])``
replays env ``e``'s first episode (with the scenario's prior) transition for transition.
:meth:`SwarmVecEnv.seed` re-derives the generators at the next :meth:`reset`.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces

from poc_env.config import Scenario
from poc_env.envs.parallel import OBS_TYPES, EpisodeOverError, UAVSearchParallelEnv
from poc_env.errors import ConfigError, MissingExtraError
from poc_env.sim import core as sim
from poc_env.sim import observations as obs_mod
from poc_env.sim.control import swarm_increments
from poc_env.sim.rewards import reward_terms, total_reward
from poc_env.theory.probability_map import random_gaussian_mixture, validate_map

try:
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env import VecEnv
except ModuleNotFoundError as exc:  # the environment alone does not need the 'rl' extra
    if (exc.name or "").partition(".")[0] not in ("stable_baselines3", "torch"):
        raise
    raise MissingExtraError("rl", "poc_env.envs.vector (the stable-baselines3 VecEnv)") from exc


def env_seed_sequences(seed: int | None, n_envs: int) -> list[np.random.SeedSequence]:
    """The seed sequences of the envs of a :class:`SwarmVecEnv` built with ``seed``."""
    return np.random.SeedSequence(seed).spawn(n_envs)


class SwarmVecEnv(VecEnv):
    """SB3 ``VecEnv`` with one slot per (env, agent) over the batched core (module docstring).

    Parameters
    ----------
    scenario:
        Built-in name, YAML path or :class:`~poc_env.config.Scenario`.
    n_envs:
        Number of independent swarms (``num_envs = n_envs * n_agents`` slots).
    seed:
        Root seed of the per-env generators (``None``: fresh entropy).
    obs_type:
        ``"dict"`` (raster + vector, for ``MultiInputPolicy``), ``"flat"`` or ``"compass"``
        (the size-free features of :class:`~poc_env.sim.observations.CompassFeatures`).
    random_priors:
        Draw a fresh prior (:func:`~poc_env.theory.probability_map.random_gaussian_mixture`) from
        the env's generator at every reset, instead of the scenario's prior.
    overrides:
        Dotted scenario keys, as for the PettingZoo env (``{"episode.horizon_steps": 10}``).
    control, auto_return:
        The control level and its return-home autopilot, as for the PettingZoo env
        (:mod:`poc_env.sim.control`).
    agent_index:
        With ``obs_type="compass"``: ``False`` zeroes the agent-index block of the features
        (the ablation of the credit-and-sharing table; the registered tasks keep it).
    return_autopilot:
        At the ``increments`` level: the autopilot takes over a UAV once eq. 18 says it must
        head home, and lands it (:func:`poc_env.sim.control.return_home`), as at the autopilot
        levels; off in the registered tasks (a training option, recorded in the run).
    """

    def __init__(
        self,
        scenario: str | Scenario = "paper_6_2",
        n_envs: int = 8,
        seed: int | None = 0,
        obs_type: str = "dict",
        random_priors: bool = False,
        overrides: Mapping[str, Any] | None = None,
        control: str = "increments",
        auto_return: bool = True,
        agent_index: bool = True,
        return_autopilot: bool = False,
    ) -> None:
        for name, flag in (("agent_index", agent_index), ("return_autopilot", return_autopilot)):
            if not isinstance(flag, bool):
                raise ConfigError(name, flag, "true or false")
        if isinstance(n_envs, bool) or not isinstance(n_envs, int | np.integer) or n_envs < 1:
            raise ConfigError("n_envs", n_envs, "an integer >= 1")
        if obs_type not in OBS_TYPES:
            raise ConfigError("obs_type", obs_type, "one of " + ", ".join(OBS_TYPES))
        if seed is not None and (
            isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0
        ):
            raise ConfigError("seed", seed, "an integer >= 0 or None")
        # the PettingZoo env resolves the scenario and defines the per-agent spaces: one source
        par = UAVSearchParallelEnv(
            scenario, obs_type=obs_type, overrides=overrides, control=control,
            auto_return=auto_return,
        )  # fmt: skip
        self.control = par.control
        self.auto_return = par.auto_return
        self.scenario = par.scenario
        self.params = par.params
        self.obs_type = obs_type
        self.random_priors = bool(random_priors)
        self.n_envs = int(n_envs)
        self.n_agents = self.params.n_agents
        self.possible_agents = list(par.possible_agents)
        self.render_mode = None
        obs_space = par.observation_space(self.possible_agents[0])
        act_space = par.action_space(self.possible_agents[0])
        super().__init__(self.n_envs * self.n_agents, obs_space, act_space)
        self._hazard = obs_mod.hazard_mask(self.params)
        e, n = self.n_envs, self.n_agents
        self._root_seed = seed
        self.rngs = [np.random.default_rng(s) for s in env_seed_sequences(seed, e)]
        self.state: sim.State | None = None
        self.priors = np.broadcast_to(self.params.prior, (e, *self.params.prior.shape)).copy()
        self._poc_scale = np.ones(e)
        self._active = np.zeros((e, n), dtype=bool)
        self._returns = np.zeros((e, n))
        self._lengths = np.zeros((e, n), dtype=np.int64)
        self._actions = np.zeros((e, n, 3))
        self.agent_index = agent_index
        self.return_autopilot = return_autopilot
        self._features = (
            obs_mod.CompassFeatures(self.params, agent_index) if obs_type == "compass" else None
        )
        self._t_start = time.time()
        self._closed = False

    # -- seeding and reset --------------------------------------------------------------------
    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Re-derive every env's generator from ``seed`` at the next :meth:`reset`
        (``None``: fresh entropy). Returns the root seed once per slot."""
        if seed is None:
            seed = int(np.random.SeedSequence().generate_state(1)[0])
        self._seeds = [int(seed)] * self.num_envs
        return list(self._seeds)

    def _draw_priors(self, envs: np.ndarray) -> np.ndarray | None:
        """Priors (len(envs), ny, nx) for new episodes of ``envs``, or None (scenario prior).

        A ``"prior"`` in the reset options of an env's first slot (``set_options``) wins;
        else, with ``random_priors``, one is drawn from the env's generator."""
        grid = self.params.grid
        given = [self._options[k * self.n_agents].get("prior") for k in envs]
        if not self.random_priors and all(p is None for p in given):
            return None
        out = np.empty((len(envs), grid.ny, grid.nx))
        for j, k in enumerate(envs):
            if given[j] is not None:
                out[j] = validate_map(given[j], grid, f"options[{k * self.n_agents}]['prior']")
            elif self.random_priors:
                out[j] = random_gaussian_mixture(grid, self.rngs[k])
            else:
                out[j] = self.params.prior
        return out

    def _new_episodes(self, envs: np.ndarray) -> sim.State:
        """Fresh states for ``envs`` (episode bookkeeping reset); returns the sub-batch."""
        priors = self._draw_priors(envs)
        fresh = sim.initial(self.params, [self.rngs[k] for k in envs], priors)
        if priors is not None:
            self.priors[envs] = priors
        else:
            self.priors[envs] = self.params.prior
        self._poc_scale[envs] = self.priors[envs].max(axis=(1, 2))
        self._active[envs] = True
        self._returns[envs] = 0.0
        self._lengths[envs] = 0
        return fresh

    def reset(self):
        """Start a new episode in every env; return the first observation of every slot."""
        if self._seeds[0] is not None:
            self._root_seed = self._seeds[0]
            seqs = env_seed_sequences(self._root_seed, self.n_envs)
            self.rngs = [np.random.default_rng(s) for s in seqs]
        everything = np.arange(self.n_envs)
        self.state = self._new_episodes(everything)
        obs = self._observe(self.state, self._poc_scale)
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = [{} for _ in range(self.num_envs)]
        return obs

    # -- observations ---------------------------------------------------------------------------
    def _observe(self, state: sim.State, poc_scale: np.ndarray):
        """Observations of every agent of ``state``'s envs, as (E * N, ...) slot arrays."""
        obs = obs_mod.observe(
            self.params, state, poc_scale, self._hazard, self.obs_type, self._features
        )
        if isinstance(obs, dict):
            return {k: v.reshape(-1, *v.shape[2:]) for k, v in obs.items()}
        return obs.reshape(-1, obs.shape[-1])

    def _slot_obs(self, obs, k: int):
        """Slot ``k``'s observation, copied out of the batch."""
        if isinstance(obs, dict):
            return {key: v[k].copy() for key, v in obs.items()}
        return obs[k].copy()

    @staticmethod
    def _write(obs, slots, value) -> None:
        """``obs[slots] = value`` for a flat array or each key of a dict observation."""
        if isinstance(obs, dict):
            for key, v in obs.items():
                v[slots] = value if np.isscalar(value) else value[key]
        else:
            obs[slots] = value

    # -- stepping --------------------------------------------------------------------------------
    def step_async(self, actions: np.ndarray) -> None:
        a = np.asarray(actions, dtype=float)
        width = int(np.prod(self.action_space.shape or (1,)))
        if a.size != self.num_envs * width:
            raise ConfigError("actions", a.shape, f"shape ({self.num_envs}, {width})")
        a = a.reshape(self.n_envs, self.n_agents, width)
        if not np.isfinite(a).all():
            raise ConfigError("actions", "non-finite values", "finite numbers in [-1, 1]")
        self._actions = self._sim_actions(a)

    # -- hooks for subclasses (poc_env.agents.rl.pilot.PilotVecEnv) -------------------------
    def _sim_actions(self, a: np.ndarray) -> np.ndarray:
        """The simulator's eq. 19 actions (E, N, 3) for the slots' actions ``a (E, N, ...)``
        (the control level's autopilot, :func:`poc_env.sim.control.swarm_increments`, which
        flies home-bound UAVs whatever their slot commands); finished agents get 0."""
        assert self.state is not None
        inc = swarm_increments(
            self.params, self.control, self.state, a, self.auto_return, self.return_autopilot
        )
        if self.control == "increments":
            inc = np.where(self._active[..., None], inc, 0.0)
        return inc

    def _reward(self, ev: sim.Events, state: sim.State) -> np.ndarray:
        """Reward (E, N) of the step that produced ``ev`` and ``state``."""
        return total_reward(reward_terms(self.scenario.reward, ev))

    def _rl_done(self, state: sim.State) -> np.ndarray | bool:
        """Agents whose RL episode ends although they still fly (E, N), or False."""
        return False

    def step_wait(self):
        if self.state is None:
            raise EpisodeOverError("call reset() before step()")
        p, st = self.params, self.state
        n = self.n_agents
        active = self._active
        ev = sim.step(p, st, self._actions, self.rngs)
        reward = np.where(active, self._reward(ev, st), 0.0)
        self._returns += reward
        self._lengths += active
        finished = active & (sim.terminal(p, st) | self._rl_done(st))
        still = active & ~finished
        env_end = sim.episode_over(p, st, ~still)
        done = (finished | env_end[:, None]).ravel()
        truncated = (still & sim.truncated(p, st)).ravel()
        was_active = active.ravel()

        obs = self._observe(st, self._poc_scale)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for k in np.flatnonzero(~was_active):
            infos[k]["inactive"] = True
        for k in np.flatnonzero(done):
            info = infos[k]
            info["terminal_observation"] = (
                self._slot_obs(obs, k) if was_active[k] else self._zero_obs()
            )
            info["TimeLimit.truncated"] = bool(truncated[k])
        self._write(obs, ~still.ravel(), 0.0)  # finished agents show the placeholder
        self._active = still

        ended = np.flatnonzero(env_end)
        if len(ended):
            elapsed = round(time.time() - self._t_start, 6)
            for k in ended:
                posc = float(st.posc[k])
                for i in range(n):
                    info = infos[k * n + i]
                    info["episode"] = {
                        "r": float(self._returns[k, i]),  # unrounded, unlike Monitor's
                        "l": int(self._lengths[k, i]),
                        "t": elapsed,
                        "posc": posc,
                    }
                    info["posc"] = posc
                    info["landed"] = bool(st.landed[k, i])
                    info["crashed"] = bool(st.crashed[k, i])
                    info["violations"] = int(st.violations[k, i])
            fresh = self._new_episodes(ended)
            sim.scatter_envs(st, fresh, ended)
            first = self._observe(fresh, self._poc_scale[ended])
            slots = (ended[:, None] * n + np.arange(n)).ravel()
            self._write(obs, slots, first)
        return obs, reward.ravel().astype(np.float32), done, infos

    def _zero_obs(self):
        space = self.observation_space
        if isinstance(space, spaces.Dict):
            return {key: np.zeros(s.shape, s.dtype) for key, s in space.spaces.items()}
        return np.zeros(space.shape, space.dtype)

    # -- the rest of the VecEnv API ------------------------------------------------------------
    def close(self) -> None:
        self._closed = True

    def _indices(self, indices) -> list[int]:
        out = list(self._get_indices(indices))
        for k in out:
            if not 0 <= int(k) < self.num_envs:
                raise ConfigError("indices", k, f"slot numbers in [0, {self.num_envs})")
        return out

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        """The adapter's attribute ``attr_name``, once per slot (all slots share the core)."""
        value = getattr(self, attr_name)
        return [value for _ in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        """Set an attribute of the adapter; it is shared by every slot, so ``indices`` must
        name all of them (or be None)."""
        if sorted(set(self._indices(indices))) != list(range(self.num_envs)):
            raise ConfigError("indices", indices, "None or every slot: slots share attributes")
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs):
        """Call the adapter's method once; its result is returned once per requested slot."""
        slots = self._indices(indices)
        result = getattr(self, method_name)(*method_args, **method_kwargs)
        return [result for _ in slots]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        """True for ``Monitor`` only: infos follow its conventions (module docstring)."""
        return [wrapper_class is Monitor for _ in self._indices(indices)]
