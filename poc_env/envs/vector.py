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

import math
import time
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np
from gymnasium import spaces

import poc_env._kernels.adapters as _adapters
from poc_env.config import Scenario
from poc_env.envs.parallel import OBS_TYPES, EpisodeOverError
from poc_env.errors import ConfigError, MissingExtraError
from poc_env.sim import core as sim
from poc_env.sim import engine as engine_mod
from poc_env.sim import single as single_mod
from poc_env.theory.probability_map import validate_map

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


class _Outcome(NamedTuple):
    """What :meth:`SwarmVecEnv.step_wait` reads of the engine's step: the fields of its
    :class:`~poc_env.sim.engine.Transition` but the reward terms, events and infos."""

    obs: Any
    reward: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    over: np.ndarray


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
        #: The episode engine this adapter converts (:class:`poc_env.sim.engine.Engine`).
        self.engine = engine_mod.make_engine(
            int(n_envs),
            scenario=scenario,
            obs_type=obs_type,
            overrides=overrides,
            random_prior=bool(random_priors),
            control=control,
            auto_return=auto_return,
            return_increments=return_autopilot,
            agent_index=agent_index,
            seeds=env_seed_sequences(seed, int(n_envs)),
        )
        eng = self.engine
        self.control = eng.control
        self.auto_return = eng.auto_return
        self.scenario = eng.scenario
        self.obs_type = obs_type
        self.random_priors = bool(random_priors)
        self.n_envs = int(n_envs)
        self.n_agents = eng.n_agents
        self.possible_agents = [f"uav_{i}" for i in range(self.n_agents)]
        self.render_mode = None
        super().__init__(self.n_envs * self.n_agents, eng.observation_space, eng.action_space)
        e, n = self.n_envs, self.n_agents
        self._root_seed = seed
        self._active = np.zeros((e, n), dtype=bool)
        self._returns = np.zeros((e, n))
        self._lengths = np.zeros((e, n), dtype=np.int64)
        self._actions = np.zeros((e, n, eng.action_dim))
        self.agent_index = agent_index
        self.return_autopilot = return_autopilot
        self._t_start = time.time()
        self._closed = False
        #: The engine's step with its glue formed once (:class:`poc_env.sim.single.SingleStep`,
        #: the PettingZoo env's; every env is stepped at once here too), or None (per-UAV
        #: beliefs: :meth:`Engine.step <poc_env.sim.engine.Engine.step>`).
        self._fast = single_mod.SingleStep(eng) if single_mod.SingleStep.supports(eng) else None

    @property
    def params(self) -> sim.Params:
        return self.engine.params

    @property
    def state(self) -> sim.State | None:
        """The batched simulator state (None before :meth:`reset`)."""
        return self.engine.state

    @state.setter
    def state(self, value: sim.State | None) -> None:
        self.engine.state = value

    @property
    def rngs(self) -> list[np.random.Generator]:
        """Each env's generator (priors, targets, thresholds, link failures)."""
        return self.engine.rngs

    @property
    def priors(self) -> np.ndarray:
        """(n_envs, ny, nx) the prior of each env's current episode."""
        return self.engine.priors

    # -- seeding and reset --------------------------------------------------------------------
    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Re-derive every env's generator from ``seed`` at the next :meth:`reset`
        (``None``: fresh entropy). Returns the root seed once per slot."""
        if seed is None:
            seed = int(np.random.SeedSequence().generate_state(1)[0])
        self._seeds = [int(seed)] * self.num_envs
        return list(self._seeds)

    def _new_episodes(self, envs: np.ndarray):
        """New episodes for ``envs`` (a ``"prior"`` in the reset options of an env's first slot,
        ``set_options``, wins over the prior source); slot bookkeeping reset. Returns their
        first observations as ``(len(envs) * N, ...)`` slot arrays."""
        grid = self.params.grid
        given = []
        for k in envs:
            p = self._options[k * self.n_agents].get("prior")
            field = f"options[{k * self.n_agents}]['prior']"
            given.append(None if p is None else validate_map(p, grid, field))
        obs, _ = self.engine.reset(envs, given, with_info=False)
        self._active[envs] = True
        self._returns[envs] = 0.0
        self._lengths[envs] = 0
        return self._slots(obs)

    def reset(self):
        """Start a new episode in every env; return the first observation of every slot."""
        if self._seeds[0] is not None:
            self._root_seed = self._seeds[0]
            self.engine.seed(env_seed_sequences(self._root_seed, self.n_envs))
        obs = self._new_episodes(np.arange(self.n_envs))
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = [{} for _ in range(self.num_envs)]
        return obs

    # -- observations ---------------------------------------------------------------------------
    @staticmethod
    def _slots(obs):
        """The engine's observations ``(E, N, ...)`` as ``(E * N, ...)`` slot arrays."""
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
        width = math.prod(self.action_space.shape or (1,))  # a subclass may set its own
        if a.size != self.num_envs * width:
            raise ConfigError("actions", a.shape, f"shape ({self.num_envs}, {width})")
        a = a.reshape(self.n_envs, self.n_agents, width)
        if not np.logical_and.reduce(np.isfinite(a), axis=None):
            raise ConfigError("actions", "non-finite values", "finite numbers in [-1, 1]")
        self._actions = self._sim_actions(a)

    # -- hooks for subclasses (poc_env.agents.rl.pilot.PilotVecEnv) -------------------------
    def _sim_actions(self, a: np.ndarray) -> np.ndarray:
        """The control-level actions ``(E, N, ...)`` the engine gets for the slots' actions
        ``a``; the engine's autopilot (:func:`poc_env.sim.control.swarm_increments`) flies
        them, home-bound UAVs whatever their slot commands; finished agents' are ignored."""
        return a

    def _reward(self, reward: np.ndarray, state: sim.State) -> np.ndarray:
        """Reward (E, N) of the step whose engine reward was ``reward`` and that produced
        ``state``."""
        return reward

    def _rl_done(self, state: sim.State) -> np.ndarray | bool:
        """Agents whose RL episode ends although they still fly (E, N), or False."""
        return False

    def step_wait(self):
        if self.state is None:
            raise EpisodeOverError("call reset() before step()")
        n = self.n_agents
        active = self._active
        tr = self._engine_step()  # the few infos: from the state
        st = self.engine.current
        rl_done = self._rl_done(st)
        finished = tr.terminated if rl_done is False else tr.terminated | rl_done
        # the slots' bookkeeping in one compiled pass (_kernels.adapters): as numpy would,
        #   reward = np.where(active, reward, 0.0); returns += reward; lengths += active
        #   finished = active & finished; still = active & ~finished
        #   env_end = over | all(~still, axis=1)   (sim.episode_over(p, st, ~still): the
        #       engine's over is the horizon or every agent terminal, and a terminal agent
        #       is not still going, so or-ing in the rows where none is gives the same)
        #   done = finished | env_end[:, None]; truncated = still & truncated
        e = self.n_envs
        reward = np.empty(e * n, dtype=np.float32)  # new arrays: SB3 keeps and writes them
        done = np.empty(e * n, dtype=bool)
        truncated = np.empty(e * n, dtype=bool)
        still = np.empty((e, n), dtype=bool)
        env_end = np.empty(e, dtype=bool)
        flags = _adapters.slot_step(
            active, self._reward(tr.reward, st), finished, tr.truncated, tr.over,
            self._returns, self._lengths, reward, done, truncated, still, env_end,
        )  # fmt: skip
        was_active = active.ravel()

        obs = self._slots(tr.obs)
        infos = [{} for _ in range(self.num_envs)]  # list[dict[str, Any]]
        # (each loop and write below runs only when some slot needs it: usually none does)
        if flags & _adapters.SOME_INACTIVE:
            for k in np.flatnonzero(~was_active).tolist():
                infos[k]["inactive"] = True
        if flags & _adapters.SOME_DONE:
            for k in np.flatnonzero(done).tolist():
                info = infos[k]
                info["terminal_observation"] = (
                    self._slot_obs(obs, k) if was_active[k] else self._zero_obs()
                )
                info["TimeLimit.truncated"] = bool(truncated[k])
        if flags & _adapters.SOME_STOPPED:
            self._write(obs, ~still.ravel(), 0.0)  # finished agents show the placeholder
        self._active = still

        if not flags & _adapters.SOME_ENV_ENDS:
            return obs, reward, done, infos
        ended = np.flatnonzero(env_end)
        elapsed = round(time.time() - self._t_start, 6)
        posc_all = st.posc.tolist()
        landed, crashed = st.landed.tolist(), st.crashed.tolist()
        violations = st.violations.tolist()
        for k in ended.tolist():
            posc = posc_all[k]
            for i in range(n):
                info = infos[k * n + i]
                info["episode"] = {
                    "r": float(self._returns[k, i]),  # unrounded, unlike Monitor's
                    "l": int(self._lengths[k, i]),
                    "t": elapsed,
                    "posc": posc,
                }
                info["posc"] = posc
                info["landed"] = landed[k][i]
                info["crashed"] = crashed[k][i]
                info["violations"] = violations[k][i]
        first = self._new_episodes(ended)
        slots = (ended[:, None] * n + np.arange(n)).ravel()
        self._write(obs, slots, first)
        return obs, reward, done, infos

    def _engine_step(self) -> _Outcome:
        """The engine's step of every env under the last actions, without infos:
        :meth:`Engine.step <poc_env.sim.engine.Engine.step>`'s transition (``with_info=False``)
        but its reward terms and events, through :class:`~poc_env.sim.single.SingleStep` when
        it runs the engine (the same arrays bit for bit, ``tests/sim/test_single.py``;
        ``tests/rl/test_vector.py`` runs both here)."""
        fast = self._fast
        if fast is None:
            t = self.engine.step(self._actions, with_info=False)
            return _Outcome(t.obs, t.reward, t.terminated, t.truncated, t.over)
        s = fast.step(self._actions)
        return _Outcome(s.obs, s.reward, s.terminated, s.truncated, s.over)

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
