"""A residual policy on top of a planner (``poc-env train --task ID --residual-teacher NAME``).

The teacher (a plan-then-fly policy of :mod:`poc_env.agents.policies.registry`, e.g.
``allocation_plan``) plans at every episode's start and flies its routes with the waypoint
follower, exactly as it does when it is evaluated alone. Each step the learned policy sees the
task's observation plus the teacher's eq. 19 action of the UAV (3 values in [-1, 1]) and
outputs a residual ``(dv, d turn)`` in [-1, 1]; the UAV flies

    ``(dv, d turn)`` = clip(teacher's + residual, -1, 1),  ``d pitch`` = the teacher's

(:func:`combine`, the one rule of training and evaluation). Once the teacher's follower heads
a UAV home (its route is done, or eq. 18 says so), the residual is ignored and the follower
lands it: the learned part cannot break the return rule. The policy's mean starts at zero
(:func:`init_policy`: the action layer's weights and bias are zeroed), so the deterministic
policy starts *at* the teacher's score and PPO only has to improve it; the std starts at
``--residual-log-std`` (default -3.0, std 0.05: the residual is a fraction of eq. 19's per-step
limits, up to 180 degrees of turn per step on ``paper_6_2``, and with std 0.37 the first
training episodes scored 0.31-0.35 against the teacher's 0.69).

New action semantics on an existing task id: the task gives the scenario, the prior kind and the
observation; the run's ``config.json`` records ``residual_teacher`` and
:class:`poc_env.agents.rl.policy.PPOPolicy` flies the checkpoint as a residual of the same
teacher (the registered task ids keep their meaning).

Training env: :class:`ResidualVecEnv`, a :class:`~poc_env.envs.vector.SwarmVecEnv` at the
increments level. Planning costs about 30 times an episode's simulation on ``paper_6_2``
(``results/guided/bench_env.py``), so with ``residual_pool > 0`` the training priors come
from a pool of ``residual_pool`` random priors (drawn once from stream :data:`POOL_KEY` of the
run's seed; each env draws its next pool index from its own generator) whose plans are made
once and reused; ``residual_pool=0`` draws a fresh prior and plans every episode. Evaluation
always plans on the evaluation prior. A resumed run starts new episodes (the followers in
flight are not checkpointed).

Moving targets (the ``-Drift-`` tasks): the teacher may be a moving-target planner,
``spacetime_plan`` (a plan) or ``spacetime_receding`` (a plan re-made every 20 min from the
current belief: :data:`ROUTE_TEACHERS`). Each env's teacher reads that env's live state through
:class:`EnvView` (its belief, step and drift velocity), as it reads the environment's when it
flies alone. A plan depends on the episode's drift, so on a moving target (and with a re-planning
teacher) no plan is pooled: the teacher plans every episode.
"""

from __future__ import annotations

import copy
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import numpy as np
from gymnasium import spaces

from poc_env.agents.rl.args import ROUTE_TEACHERS, check_residual_teacher
from poc_env.envs.vector import SwarmVecEnv
from poc_env.errors import ConfigError

if TYPE_CHECKING:
    from stable_baselines3 import PPO


#: Residual action per UAV: (dv, d turn), added to the teacher's eq. 19 action.
RESIDUAL_DIMS = 2
#: The teacher's eq. 19 action appended to the observation.
TEACHER_DIMS = 3
#: Spawn key of the SeedSequence of the training prior pool.
POOL_KEY = (0xAE, 0)


def combine(teacher: np.ndarray, residual: np.ndarray, homing: np.ndarray) -> np.ndarray:
    """Eq. 19 actions (B, 3): the teacher's ``(B, 3)`` with ``residual (B, 2)`` added to its
    speed and turn components (clipped to [-1, 1]), except for the ``homing (B,)`` UAVs."""
    out = np.array(teacher, dtype=float, copy=True).reshape(-1, TEACHER_DIMS)
    r = np.asarray(residual, dtype=float).reshape(-1, RESIDUAL_DIMS)
    moved = np.clip(out[:, :RESIDUAL_DIMS] + r, -1.0, 1.0)
    keep = np.asarray(homing, dtype=bool).reshape(-1, 1)
    out[:, :RESIDUAL_DIMS] = np.where(keep, out[:, :RESIDUAL_DIMS], moved)
    return out


def augment(obs: np.ndarray, teacher: np.ndarray) -> np.ndarray:
    """The residual policy's observation: ``obs (B, D)`` then the teacher's action (B, 3)."""
    t = np.clip(np.asarray(teacher, dtype=np.float32).reshape(-1, TEACHER_DIMS), -1.0, 1.0)
    return np.concatenate([np.asarray(obs, dtype=np.float32).reshape(len(t), -1), t], axis=1)


def observation_space(space: spaces.Box) -> spaces.Box:
    """The residual observation space of a task's per-agent ``space``."""
    low = np.concatenate([space.low, -np.ones(TEACHER_DIMS, np.float32)])
    high = np.concatenate([space.high, np.ones(TEACHER_DIMS, np.float32)])
    return spaces.Box(low, high, dtype=np.float32)


ACTION_SPACE = spaces.Box(-1.0, 1.0, (RESIDUAL_DIMS,), np.float32)


def teacher_actions(
    teacher: Any, observations: dict, agents: list[str]
) -> tuple[np.ndarray, np.ndarray]:
    """The ``teacher``'s (a PlanPolicy or a :data:`ROUTE_TEACHERS` policy, reset: both fly
    with a ``follower``) eq. 19 actions ``(len(agents), 3)`` for the live ``agents`` (those in
    ``observations``) and whether its follower is taking each home (``(len(agents),)``)."""
    acts, _ = teacher.predict(observations)
    follower = teacher.follower
    index = {a: i for i, a in enumerate(follower.agents)}
    inc = np.stack([np.asarray(acts[a], dtype=float) for a in agents]).reshape(-1, TEACHER_DIMS)
    homing = np.array(
        [follower.index[index[a]] >= len(follower.waypoints[index[a]]) for a in agents], bool
    )
    return inc, homing


def init_policy(model: PPO, log_std: float) -> None:
    """Zero the action layer of ``model`` (the residual's mean is 0 for every observation: the
    deterministic policy flies the teacher) and set its log std."""
    import torch as th

    net = model.policy.action_net
    with th.no_grad():
        net.weight.zero_()  # type: ignore[operator]
        net.bias.zero_()  # type: ignore[operator]
        model.policy.log_std.fill_(float(log_std))  # type: ignore[operator]


class EnvView:
    """What a teacher reads of env ``k`` of a vectorised ``engine`` (the attributes a policy's
    ``reset`` and a re-planning teacher's ``predict`` read of a parallel env): ``sim_state``
    holds that env's rows (``belief``, ``step``, ``drift``) at the time it is read."""

    def __init__(self, venv: SwarmVecEnv, k: int) -> None:
        self.params = venv.params
        self.scenario = venv.scenario
        self.possible_agents = venv.possible_agents
        self._engine = venv.engine
        self._k = k

    @property
    def sim_state(self) -> SimpleNamespace:
        cur, k = self._engine.current, self._k
        drift = getattr(cur, "drift", None)
        return SimpleNamespace(
            belief=cur.belief[k : k + 1],
            step=cur.step[k : k + 1],
            drift=None if drift is None else drift[k : k + 1],
        )


class ResidualVecEnv(SwarmVecEnv):
    """:class:`~poc_env.envs.vector.SwarmVecEnv` (increments level) flown by ``teacher``'s
    plan plus each slot's residual (module docstring). Observation: the task's plus the
    teacher's action; action: the residual."""

    snapshots = False  # checkpoints keep the generators, not the followers in flight

    def __init__(
        self,
        scenario: Any,
        n_envs: int,
        seed: int,
        obs_type: str,
        random_priors: bool,
        teacher: str,
        pool: int = 64,
        agent_index: bool = True,
    ) -> None:
        from poc_env.sim.engine import RandomPrior

        super().__init__(
            scenario,
            n_envs=n_envs,
            seed=seed,
            obs_type=obs_type,
            random_priors=random_priors,
            control="increments",
            agent_index=agent_index,
        )
        if obs_type not in ("compass", "set"):
            raise ConfigError("obs_type", obs_type, "compass or set (a task's observation)")
        self.teacher = check_residual_teacher(teacher)
        self.pool = int(pool)
        assert isinstance(self.observation_space, spaces.Box)
        self.observation_space = observation_space(self.observation_space)
        self.action_space = ACTION_SPACE
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=POOL_KEY))
        grid = self.params.grid
        self._pool = [RandomPrior().draw(grid, rng) for _ in range(self.pool)]
        self._plans: dict[int, Any] = {}  # pool index (or -1: the fixed prior) -> teacher
        self._key = [-1] * self.n_envs
        self._teachers: list[Any] = [None] * self.n_envs
        e, n = self.n_envs, self.n_agents
        self._teacher_inc = np.zeros((e, n, TEACHER_DIMS))
        self._homing = np.ones((e, n), dtype=bool)
        self.plans_made = 0

    @property
    def pooled(self) -> bool:
        """Whether plans are reused (a plan-once teacher on a static target)."""
        return self.teacher not in ROUTE_TEACHERS and self.params.motion is None

    def _plan(self, k: int, key: int) -> Any:
        """A teacher reset on env ``k``'s new episode (its prior); pooled plans reused."""
        from poc_env.agents.policies.registry import make_policy

        if key in self._plans:
            t = copy.copy(self._plans[key])
            t.follower = copy.copy(t.follower)
            t.follower.index = np.zeros_like(t.follower.index)
            return t
        t = make_policy(self.teacher)
        # pooled: the pool index seeds the plan (as before); else one seed per plan made
        t.reset(EnvView(self, k), int(max(key, 0)) if self.pooled else self.plans_made)
        self.plans_made += 1
        if self.pooled and (key >= 0 or not self.random_priors):
            self._plans[key] = t
            return self._plan(k, key)
        return t

    def _new_episodes(self, envs: np.ndarray):
        n = self.n_agents
        keys = []
        for k in np.asarray(envs).tolist():
            key = -1
            if self.random_priors and self.pool > 0 and self.pooled:
                key = int(self.rngs[k].integers(self.pool))
                self._options[k * n] = {**self._options[k * n], "prior": self._pool[key]}
            keys.append(key)
        obs = super()._new_episodes(envs)
        for k, key in zip(np.asarray(envs).tolist(), keys, strict=True):
            self._teachers[k] = self._plan(k, key)
            if self.random_priors and self.pool > 0 and self.pooled:
                self._options[k * n] = {}
        return obs

    def _teach(self) -> None:
        """The teacher's actions for every live slot at the current state."""
        from poc_env.sim.observations import vectors

        vec = vectors(self.params, self.engine.current)
        self._teacher_inc[:] = 0.0
        self._homing[:] = True
        for e in range(self.n_envs):
            live = np.flatnonzero(self._active[e])
            if not len(live):
                continue
            agents = [self.possible_agents[i] for i in live]
            obs = {  # the vector alone: the follower and the re-planner read nothing else
                a: {"raster": None, "vector": vec[e, i]} for a, i in zip(agents, live, strict=True)
            }
            inc, hom = teacher_actions(self._teachers[e], obs, agents)
            self._teacher_inc[e, live] = inc
            self._homing[e, live] = hom

    def _augmented(self, obs: np.ndarray) -> np.ndarray:
        self._teach()
        return augment(obs, self._teacher_inc.reshape(-1, TEACHER_DIMS))

    def reset(self):
        return self._augmented(super().reset())

    def _sim_actions(self, a: np.ndarray) -> np.ndarray:
        e, n = self.n_envs, self.n_agents
        inc = combine(
            self._teacher_inc.reshape(-1, TEACHER_DIMS),
            a.reshape(-1, RESIDUAL_DIMS),
            self._homing.ravel(),
        )
        return inc.reshape(e, n, TEACHER_DIMS)

    def step_wait(self):
        obs, reward, done, infos = super().step_wait()
        pad = np.zeros(TEACHER_DIMS, np.float32)
        for info in infos:
            term = info.get("terminal_observation")
            if term is not None and term.shape[-1] != self.observation_space.shape[-1]:
                info["terminal_observation"] = np.concatenate([term, pad])
        return self._augmented(obs), reward, done, infos
