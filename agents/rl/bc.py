"""Behaviour-cloning (BC) warm start for task training (``poc-env train --task ID --bc-teacher``).

PPO from scratch learns next to nothing at the paper's eq. 19 control level (the
``Increments`` tasks): a random walk of increments seldom reaches the grid, let alone covers
it. The warm start flies a classical teacher of :mod:`poc_env.agents.policies.registry`
(``allocation_plan``, ``greedy_bayes``, ``lawnmower``, ...) for a few episodes, fits the fresh
SB3 ``MlpPolicy`` to what it did, and hands the fitted policy to ordinary PPO fine-tuning:

1. :func:`collect_demos` flies the teacher in
   :class:`poc_env.envs.parallel.UAVSearchParallelEnv` (increments control, dict observations)
   exactly as :func:`poc_env.agents.experiments.evaluate.run_episode` does (``env.reset(seed,
   prior)``, ``policy.reset(env, seed)``, ``predict(obs)`` every step) and records, for every
   step and every UAV still flying, the observation the trained policy sees, a label at the
   task's control level and the UAV's env reward. The observation is the task's: the
   ``compass`` features (:class:`~poc_env.sim.observations.CompassFeatures` over
   :func:`~poc_env.sim.observations.split_observation`, as
   :class:`poc_env.agents.rl.policy.PPOPolicy` computes them; the same values
   :class:`~poc_env.envs.vector.SwarmVecEnv` observes), or for a ``-Set`` task the ``set``
   observation, computed by :func:`poc_env.sim.observations.observe` (the one observation path
   of every env) from the env's engine state, so any network (``--net mlp`` or ``set``) is
   fitted on what it will read.
2. :func:`pretrain` fits the policy's Gaussian mean to the labels and its value head to the
   discounted returns (both mean squared errors, one Adam), then sets the policy's
   ``log_std`` (default -1, std 0.37) so PPO explores near the teacher.
3. :func:`warm_start` does both for a fresh run (:func:`poc_env.agents.rl.train._run`; a resumed run
   loads its checkpoint instead and never repeats BC; one killed before its first checkpoint
   starts again from step 0, BC included, with the same result) and writes ``bc.json`` and
   TensorBoard scalars (``tb/bc``). ``--total-timesteps`` counts PPO transitions only (0:
   the BC policy alone is saved).
4. With ``--bc-dagger N`` (:func:`_dagger`), N DAgger iterations follow the first fit: the
   policy flies (:func:`dagger_rollouts`: its mean, through the path of ``ppo:`` checkpoints,
   :func:`poc_env.agents.rl.policy.compass_actions`, with the run's return autopilot), the
   teacher, planned on the same prior, labels every state it flies into, the rows join all the
   data so far (:func:`concat_demos`) and :func:`pretrain` refits from the current weights. A
   plan-then-fly teacher's label off its route is its follower's way back to the route
   (results/dagger/README.md): with ``--bc-dagger-beta`` the teacher's action flies part of
   the steps, which keeps the states near its routes. ``--bc-dagger 0`` is the warm start as
   before, bit for bit.

Labels (one per UAV and step, ``Box(-1, 1)`` of the control level,
:mod:`poc_env.sim.control`):

=============  ==================================================================================
control        label
=============  ==================================================================================
increments     the teacher's eq. 19 action ``(dv, d alpha, d beta)``, clipped to [-1, 1]
heading        the unit vector of the UAV's displacement over the step (new xy - old xy); steps
               with zero displacement have no label and are left out
waypoint       the UAV's position after the step mapped to [-1, 1] over ``params.bounds`` (eq.
               20's operating area, the inverse of :func:`poc_env.sim.control.waypoint_goal`)
=============  ==================================================================================

Value targets: the discounted return ``G_t = r_t + gamma G_{t+1}`` of each UAV's own trajectory
(its rewards from the scenario's reward config, :mod:`poc_env.sim.rewards`), ending with the
UAV's last step (landing, crash or the horizon: no bootstrap), as PPO's value head estimates
them in :class:`~poc_env.envs.vector.SwarmVecEnv`.

Seeding: every episode seed and random prior comes from one generator of the caller's
``SeedSequence``; :func:`warm_start` uses ``SeedSequence(seed, spawn_key=DEMO_KEY)``, a stream
that neither the training envs (``SeedSequence(seed).spawn(n_envs)``: one-word spawn keys)
nor the evaluation priors (``default_rng([seed, EVAL_PRIOR_STREAM])``: no spawn key) can
produce, so demonstrations never replay a training or held-out episode. Minibatches are
shuffled by a generator of ``SeedSequence(seed, spawn_key=FIT_KEY)`` (DAgger's refits continue
it); DAgger iteration ``i`` draws its episodes and mixture coins from
``SeedSequence(seed, spawn_key=DAGGER_KEY + (i,))``, three-word keys no other stream uses.
BC draws nothing from the global torch, numpy or python generators, so a run with BC is as
reproducible as one without.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from poc_env.agents.rl.args import check_teacher
from poc_env.errors import ConfigError, as_int, as_number

if TYPE_CHECKING:
    from stable_baselines3 import PPO

    from poc_env.agents.rl.args import TrainArgs
    from poc_env.config import Scenario
    from poc_env.tasks import Task

#: Spawn key of the demonstration episodes' SeedSequence (seeds and priors).
DEMO_KEY = (0xBC, 0)
#: Spawn key of the SeedSequence that shuffles BC minibatches.
FIT_KEY = (0xBC, 1)
#: Spawn key prefix of the DAgger rollouts: iteration ``i`` (1, 2, ...) draws its seeds, priors
#: and mixture coins from ``SeedSequence(seed, spawn_key=(*DAGGER_KEY, i))``.
DAGGER_KEY = (0xBC, 2)
#: The warm start's demonstrations in the run folder, kept when ``--bc-coef`` > 0.
DEMOS_FILE = "bc_demos.npz"


@dataclass(frozen=True)
class Demos:
    """Demonstrations of a teacher: one row per (step, flying UAV) that has a label.

    ``obs (M, D)`` the task's observation (the compass features or the set observation),
    ``labels (M, ACTION_DIMS[control])`` the targets of the control level (module docstring),
    ``rewards (M,)`` the UAV's env reward of the step, ``returns (M,)`` its discounted return
    from the step, ``episode (M,)`` and ``uav (M,)`` whose step it is (a UAV's rows are
    consecutive, in step order); ``posc`` and ``seeds``: one per episode."""

    teacher: str
    control: str
    gamma: float
    obs: np.ndarray
    labels: np.ndarray
    rewards: np.ndarray
    returns: np.ndarray
    episode: np.ndarray
    uav: np.ndarray
    posc: tuple[float, ...]
    seeds: tuple[int, ...]

    @property
    def samples(self) -> int:
        return int(self.obs.shape[0])


def _label(control: str, params: Any, action: np.ndarray, xy0: np.ndarray, xy1: np.ndarray):
    """The label of one UAV's step at ``control`` (None: no label)."""
    if control == "increments":
        return np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
    if control == "heading":
        d = xy1 - xy0
        norm = float(np.hypot(d[0], d[1]))
        return None if norm <= 0.0 else d / norm
    from poc_env.sim.control import waypoint_action

    return waypoint_action(params, xy1)[0]


def concat_demos(parts: list[Demos]) -> Demos:
    """One :class:`Demos` of several (same teacher, control level and discount; e.g. one per
    task of a run): rows in order, episode numbers renumbered to follow on."""
    if len(parts) == 1:
        return parts[0]
    first = parts[0]
    want = (first.teacher, first.control, first.gamma)
    for d in parts[1:]:
        if (d.teacher, d.control, d.gamma) != want:
            raise ConfigError("demos", (d.teacher, d.control, d.gamma), f"{want}, as the first")
    offsets = np.cumsum([0, *(len(d.posc) for d in parts[:-1])])
    return Demos(
        teacher=first.teacher,
        control=first.control,
        gamma=first.gamma,
        obs=np.concatenate([d.obs for d in parts]),
        labels=np.concatenate([d.labels for d in parts]),
        rewards=np.concatenate([d.rewards for d in parts]),
        returns=np.concatenate([d.returns for d in parts]),
        episode=np.concatenate([d.episode + o for d, o in zip(parts, offsets, strict=True)]),
        uav=np.concatenate([d.uav for d in parts]),
        posc=tuple(p for d in parts for p in d.posc),
        seeds=tuple(x for d in parts for x in d.seeds),
    )


def discounted_returns(rewards: np.ndarray, gamma: float) -> np.ndarray:
    """``G_t = r_t + gamma G_{t+1}`` over one trajectory (``G`` after its last step: 0)."""
    out = np.zeros(len(rewards))
    g = 0.0
    for t in range(len(rewards) - 1, -1, -1):
        g = float(rewards[t]) + gamma * g
        out[t] = g
    return out


class _Rows:
    """The labelled rows of demonstration episodes, gathered per UAV trajectory: each step's
    ``(features, label or None, reward)``; a step's value target is the discounted return of
    the UAV's trajectory from it (:func:`discounted_returns`), and steps without a label are
    left out. The one assembly of :func:`collect_demos` and :func:`dagger_rollouts`."""

    def __init__(self) -> None:
        self.obs: list[np.ndarray] = []
        self.lab: list[np.ndarray] = []
        self.rew: list[float] = []
        self.ret: list[float] = []
        self.who: list[tuple[int, int]] = []

    def add(self, ep: int, traj: dict[int, list[Any]], gamma: float) -> None:
        """Episode ``ep``'s trajectories, UAV index -> its steps in order."""
        for i, steps in traj.items():
            if not steps:
                continue
            g = discounted_returns(np.array([r for *_, r in steps]), gamma)
            for (f, lab, r), gt in zip(steps, g, strict=True):
                if lab is not None:
                    self.obs.append(f)
                    self.lab.append(lab)
                    self.rew.append(r)
                    self.ret.append(float(gt))
                    self.who.append((ep, i))

    def demos(self, teacher: str, control: str, gamma: float, width: int,
              posc: list[float], seeds: list[int]) -> Demos:  # fmt: skip
        from poc_env.sim.control import ACTION_DIMS

        return Demos(
            teacher=teacher,
            control=control,
            gamma=float(gamma),
            obs=np.array(self.obs, dtype=np.float32).reshape(-1, width),
            labels=np.array(self.lab, dtype=np.float32).reshape(-1, ACTION_DIMS[control]),
            rewards=np.array(self.rew, dtype=np.float32),
            returns=np.array(self.ret, dtype=np.float32),
            episode=np.array([e for e, _ in self.who], dtype=np.int64),
            uav=np.array([i for _, i in self.who], dtype=np.int64),
            posc=tuple(posc),
            seeds=tuple(seeds),
        )


def collect_demos(
    scenario: str | Scenario,
    task: str | Task,
    teacher: str,
    episodes: int,
    seed_seq: np.random.SeedSequence,
    gamma: float = 0.99,
    agent_index: bool = True,
) -> Demos:
    """Fly ``teacher`` for ``episodes`` episodes of ``scenario`` and record demonstrations at
    ``task``'s control level (module docstring).

    ``scenario``: the run's scenario (overrides applied); ``task``: a task id or
    :class:`~poc_env.tasks.Task` (its ``random_prior`` and ``control``); ``seed_seq``: the
    stream of the episodes' seeds and (with random priors) priors, drawn in turn from one
    generator, so episode ``i`` is the same whatever ``episodes`` is; ``gamma``: the discount of
    the value targets; ``agent_index``: as the run's ``SwarmVecEnv`` (the compass index block).
    """
    from poc_env.agents.policies.registry import make_policy
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.sim.engine import RandomPrior
    from poc_env.sim.observations import (
        FEATURES,
        SET_SIZE,
        CompassFeatures,
        SetFeatures,
        observe,
        split_observation,
    )
    from poc_env.tasks import get_task

    check_teacher(teacher, "teacher")
    episodes = as_int("episodes", episodes, 1, None)
    t = get_task(task) if isinstance(task, str) else task
    control = t.control
    env = UAVSearchParallelEnv(scenario=scenario)  # increments, dict observations
    params = env.params
    shape = params.grid.shape
    features = CompassFeatures(params, agent_index)
    set_features = SetFeatures(params) if t.obs == "set" else None
    width = SET_SIZE if t.obs == "set" else FEATURES
    index = {a: i for i, a in enumerate(env.possible_agents)}
    rng = np.random.default_rng(seed_seq)
    rows = _Rows()
    poscs: list[float] = []
    seeds: list[int] = []
    for ep in range(episodes):
        seed = int(rng.integers(0, 2**31))
        prior = RandomPrior().draw(params.grid, rng) if t.random_prior else None
        obs, _ = env.reset(seed=seed, options=None if prior is None else {"prior": prior})
        policy = make_policy(teacher)
        policy.reset(env, seed)
        # per UAV: (features, label or None, reward) of each of its steps
        traj: dict[int, list[tuple[np.ndarray, np.ndarray | None, float]]] = {
            i: [] for i in index.values()
        }
        while env.agents:
            live = list(env.agents)
            k = np.array([index[a] for a in live])
            if set_features is not None:  # the set tasks' observation, as their envs compute it
                eng = env.engine
                feats = observe(params, eng.current, eng.poc_scale, eng.hazard, "set",
                                set_features)[0, k]  # fmt: skip
            else:
                ras, vec = zip(*(split_observation(obs[a], shape) for a in live), strict=True)
                feats = features(np.stack(ras), np.stack(vec), k)
            actions, _ = policy.predict(obs)
            xy0 = np.array(env.sim_state.pos[0, :, :2], dtype=float)
            obs, rewards, *_ = env.step(actions)
            xy1 = np.array(env.sim_state.pos[0, :, :2], dtype=float)
            for j, a in enumerate(live):
                i = int(k[j])
                lab = _label(control, params, actions[a], xy0[i], xy1[i])
                traj[i].append((feats[j], lab, float(rewards[a])))
        rows.add(ep, traj, gamma)
        poscs.append(float(env.sim_state.posc[0]))
        seeds.append(seed)
    env.close()
    return rows.demos(teacher, control, gamma, width, poscs, seeds)


def dagger_rollouts(
    scenario: str | Scenario,
    task: str | Task,
    teacher: str,
    model: PPO,
    episodes: int,
    seed_seq: np.random.SeedSequence,
    gamma: float = 0.99,
    agent_index: bool = True,
    return_autopilot: bool = False,
    beta: float = 0.0,
) -> tuple[Demos, dict[str, Any]]:
    """One DAgger iteration's data: fly ``model`` (its deterministic mean, as
    :class:`~poc_env.agents.rl.policy.PPOPolicy` flies a compass checkpoint, through
    :func:`~poc_env.agents.rl.policy.compass_actions`, with the run's ``return_autopilot``) for
    ``episodes`` episodes of ``scenario`` and label each state with ``teacher``'s action there.

    The teacher is made and reset on the same env and seed as each episode starts (so a
    planner plans on the episode's prior) and is asked every step, on the observations the
    learner's flight produced, for its eq. 19 action: a plan-then-fly teacher's waypoint
    follower steers back to its route from wherever the UAV is and advances its waypoints only
    when the UAV reaches or passes them (:class:`~poc_env.sim.autopilot.WaypointFollower`).
    The label of the row is that action clipped to [-1, 1]; rows of UAVs the return autopilot
    has taken home are left out (the autopilot, not the policy, flies them). With ``beta`` > 0
    each UAV flies the teacher's action instead of the policy's with probability ``beta`` at
    every step (coins from the ``seed_seq`` generator); the labels are the teacher's either way.
    Value targets: the discounted returns of the trajectories as flown (:func:`collect_demos`).
    Seeds and priors are drawn as in :func:`collect_demos` from a generator of ``seed_seq``.

    Returns the labelled rows (``posc``: the episodes' POSC as flown, i.e. DAgger's own
    on-policy score when ``beta`` is 0) and counts: ``rows`` (UAV-steps flown), ``labelled``,
    ``autopilot`` (rows the autopilot owned), ``teacher_flown`` (rows flown by the teacher's
    action), ``teacher_homing`` (labelled rows where the teacher's follower had finished its
    route and was taking the UAV home)."""
    from poc_env.agents.policies.registry import make_policy
    from poc_env.agents.rl.policy import compass_actions
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.sim.engine import RandomPrior
    from poc_env.sim.observations import FEATURES, CompassFeatures
    from poc_env.tasks import get_task

    check_teacher(teacher, "teacher")
    episodes = as_int("bc_dagger_episodes", episodes, 1, None)
    beta = as_number("bc_dagger_beta", beta, 0.0, 1.0)
    t = get_task(task) if isinstance(task, str) else task
    if (t.control, t.obs) != ("increments", "compass"):
        raise ConfigError(
            "task", t.id, "an increments task with the compass observation (DAgger's labels)"
        )
    env = UAVSearchParallelEnv(scenario=scenario)
    params = env.params
    features = CompassFeatures(params, agent_index)
    index = {a: i for i, a in enumerate(env.possible_agents)}
    rng = np.random.default_rng(seed_seq)
    rows = _Rows()
    poscs: list[float] = []
    seeds: list[int] = []
    counts = dict.fromkeys(("rows", "labelled", "autopilot", "teacher_flown", "teacher_homing"), 0)
    for ep in range(episodes):
        seed = int(rng.integers(0, 2**31))
        prior = RandomPrior().draw(params.grid, rng) if t.random_prior else None
        obs, _ = env.reset(seed=seed, options=None if prior is None else {"prior": prior})
        expert = make_policy(teacher)
        expert.reset(env, seed)
        follower = getattr(expert, "follower", None)
        traj: dict[int, list[tuple[np.ndarray, np.ndarray | None, float]]] = {
            i: [] for i in index.values()
        }
        while env.agents:
            live = list(env.agents)
            k = np.array([index[a] for a in live])
            labels, _ = expert.predict(obs)  # the teacher at the learner's states
            feats, inc, home = compass_actions(
                params, features, model, "increments", return_autopilot,
                [obs[a] for a in live], k, True,
            )  # fmt: skip
            lab = np.clip(np.stack([np.asarray(labels[a], dtype=float) for a in live]), -1, 1)
            if beta > 0.0:
                coin = rng.random(len(live)) < beta
                fly = coin & ~home
                inc = np.where(fly[:, None], lab, inc)
                counts["teacher_flown"] += int(fly.sum())
            actions = {a: np.asarray(inc[j], dtype=np.float32) for j, a in enumerate(live)}
            obs, rewards, *_ = env.step(actions)
            for j, a in enumerate(live):
                i = int(k[j])
                keep = not bool(home[j])
                if keep and follower is not None:
                    counts["teacher_homing"] += int(follower.index[i] >= len(follower.waypoints[i]))
                traj[i].append((feats[j], lab[j] if keep else None, float(rewards[a])))
            counts["rows"] += len(live)
            counts["autopilot"] += int(home.sum())
        rows.add(ep, traj, gamma)
        poscs.append(float(env.sim_state.posc[0]))
        seeds.append(seed)
    env.close()
    counts["labelled"] = len(rows.obs)
    return rows.demos(teacher, "increments", gamma, FEATURES, poscs, seeds), counts


def bc_losses(model: PPO, demos: Demos) -> dict[str, float]:
    """Mean squared errors of ``model``'s policy on ``demos``: ``actor_mse`` (Gaussian mean
    vs labels), ``action_mse`` (deterministic actions, i.e. the mean clipped to the action
    space, vs labels) and ``value_mse`` (value head vs discounted returns)."""
    import torch as th

    policy = model.policy
    with th.no_grad():
        obs = th.as_tensor(demos.obs)
        mean = policy.get_distribution(obs).mode()  # the Gaussian mean
        value = policy.predict_values(obs).squeeze(-1)
    lab = th.as_tensor(demos.labels)
    ret = th.as_tensor(demos.returns)
    return {
        "actor_mse": float(((mean - lab) ** 2).mean()),
        "action_mse": float(((mean.clamp(-1.0, 1.0) - lab) ** 2).mean()),
        "value_mse": float(((value - ret) ** 2).mean()),
    }


def actor_loss(policy: Any, obs: Any, labels: Any, weights: Any = None) -> Any:
    """The BC actor loss: the mean squared error of ``policy``'s Gaussian mean at ``obs`` to
    the teacher's ``labels`` (torch tensors; differentiable). The one implementation of the
    warm start's fit (:func:`pretrain`) and of the BC term during PPO
    (:mod:`poc_env.agents.rl.bcppo`). With ``weights`` (one per row, >= 0): the weighted
    mean over the rows (0 when every weight is 0), e.g. the filtered BC term's 0/1 mask."""
    sq = (policy.get_distribution(obs).mode() - labels) ** 2
    if weights is None:
        return sq.mean()
    return (weights * sq.mean(dim=-1)).sum() / weights.sum().clamp(min=1e-12)


#: Arrays of a :class:`Demos` kept in ``bc_demos.npz`` (:func:`save_demos`).
_DEMO_ARRAYS = ("obs", "labels", "rewards", "returns", "episode", "uav")


def save_demos(demos: Demos, path: Path) -> Path:
    """``demos`` written atomically to ``path`` (``.npz``, no pickles; :func:`load_demos`)."""
    from poc_env.io import atomic_path

    with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh:
        np.savez(
            fh,
            allow_pickle=False,
            **{k: getattr(demos, k) for k in _DEMO_ARRAYS},
            teacher=np.array(demos.teacher),
            control=np.array(demos.control),
            gamma=np.array(demos.gamma),
            posc=np.array(demos.posc, dtype=float),
            seeds=np.array(demos.seeds, dtype=np.int64),
        )
    return path


def load_demos(path: Path) -> Demos:
    """The :class:`Demos` :func:`save_demos` wrote to ``path`` (ConfigError if it is missing
    or unreadable)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: np.array(z[k]) for k in _DEMO_ARRAYS}
            return Demos(
                teacher=str(z["teacher"]),
                control=str(z["control"]),
                gamma=float(z["gamma"]),
                posc=tuple(float(p) for p in z["posc"]),
                seeds=tuple(int(x) for x in z["seeds"]),
                **arrays,
            )
    except (OSError, KeyError, ValueError) as err:
        raise ConfigError(
            "bc_coef", str(path), f"the run's demonstrations saved by its warm start, readable "
            f"({type(err).__name__}: {err})",
        ) from None  # fmt: skip


def pretrain(
    model: PPO,
    demos: Demos,
    epochs: int = 10,
    batch_size: int = 64,
    seed: int | np.random.Generator = 0,
    log_std: float = -1.0,
    learning_rate: float = 1e-3,
    writer: Any = None,
) -> dict[str, Any]:
    """Fit ``model``'s SB3 actor-critic policy to ``demos`` (behaviour cloning), in place.

    Loss per minibatch: MSE of the Gaussian mean to the labels plus MSE of the value head to
    the discounted returns (the actor and value MLPs of ``MlpPolicy`` share no weights, so the
    two fits do not trade off), minimised by Adam (``learning_rate``) for ``epochs`` passes in
    minibatches of ``batch_size`` shuffled by ``seed`` (an int or a numpy Generator). The
    mean, not the likelihood, is fitted: NLL would also shrink the std towards the demo
    noise, which the warm start sets explicitly instead: ``policy.log_std`` becomes
    ``log_std`` at the end. PPO's own optimiser (and its state) is left alone.

    Returns the losses (:func:`bc_losses`) ``before`` and ``after``, the mean minibatch losses
    of each epoch (``epochs_actor_mse``, ``epochs_value_mse``) and the sizes; with a
    TensorBoard ``writer`` (``SummaryWriter``) the per-epoch losses are logged as
    ``bc/actor_mse`` and ``bc/value_mse``.
    """
    import torch as th

    epochs = as_int("bc_epochs", epochs, 0, None)
    batch_size = as_int("bc_batch_size", batch_size, 1, None)
    log_std = as_number("bc_log_std", log_std, -20.0, 2.0)
    if demos.samples == 0:
        raise ConfigError("bc_episodes", demos.samples, "demonstrations with labelled samples")
    policy = model.policy
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    before = bc_losses(model, demos)
    obs = th.as_tensor(demos.obs)
    lab = th.as_tensor(demos.labels)
    ret = th.as_tensor(demos.returns)
    opt = th.optim.Adam(policy.parameters(), lr=learning_rate)
    policy.set_training_mode(True)
    hist_a: list[float] = []
    hist_v: list[float] = []
    m = demos.samples
    for epoch in range(epochs):
        perm = th.as_tensor(rng.permutation(m))
        sum_a = sum_v = 0.0
        for lo in range(0, m, batch_size):
            b = perm[lo : lo + batch_size]
            la = actor_loss(policy, obs[b], lab[b])
            value = policy.predict_values(obs[b]).squeeze(-1)
            lv = ((value - ret[b]) ** 2).mean()
            opt.zero_grad()
            (la + lv).backward()
            opt.step()
            sum_a += float(la.detach()) * len(b)
            sum_v += float(lv.detach()) * len(b)
        hist_a.append(sum_a / m)
        hist_v.append(sum_v / m)
        if writer is not None:
            writer.add_scalar("bc/actor_mse", hist_a[-1], epoch + 1)
            writer.add_scalar("bc/value_mse", hist_v[-1], epoch + 1)
    policy.set_training_mode(False)
    with th.no_grad():
        policy.log_std.fill_(log_std)  # type: ignore[operator]
    return {
        "epochs": epochs,
        "batch_size": batch_size,
        "learning_rate": learning_rate,
        "log_std": log_std,
        "before": before,
        "after": bc_losses(model, demos),
        "epochs_actor_mse": hist_a,
        "epochs_value_mse": hist_v,
    }


def warm_start(args: TrainArgs, scenario: Scenario, model: PPO, run_dir: Path) -> dict[str, Any]:
    """The BC warm start of a fresh task run: demonstrations of ``args.bc_teacher``
    (``args.bc_episodes`` episodes of the run's ``scenario``, stream :data:`DEMO_KEY` of
    ``args.seed``), :func:`pretrain` (``args.bc_epochs``, minibatches of
    ``args.bc_batch_size``, ``args.bc_log_std``), ``bc.json`` in ``run_dir`` (teacher POSC,
    samples, losses, times) and TensorBoard scalars in ``run_dir/tb/bc``. Returns what
    ``bc.json`` holds."""
    from poc_env.agents.rl.checkpoint import write_json

    assert args.task is not None and args.bc_teacher is not None
    t0 = time.perf_counter()
    tasks = [args.task, *(args.also_task if args.bc_all_tasks else [])]
    parts = []
    for k, tid in enumerate(tasks):  # the k-th task's stream: DEMO_KEY, then (*DEMO_KEY, k)
        key: tuple[int, ...] = DEMO_KEY
        if k == 0:
            sc = scenario
        else:
            from poc_env.agents.rl.args import parse_overrides
            from poc_env.tasks import get_task

            sc = get_task(tid).load_scenario(parse_overrides(args.overrides))
            key = (*DEMO_KEY, k)
        seq = np.random.SeedSequence(args.seed, spawn_key=key)
        parts.append(collect_demos(sc, tid, args.bc_teacher, args.bc_episodes, seq,
                                   gamma=args.gamma, agent_index=args.agent_index))  # fmt: skip
    demos = concat_demos(parts)
    if args.bc_coef > 0:  # the BC term during PPO imitates these (poc_env.agents.rl.bcppo)
        save_demos(demos, run_dir / DEMOS_FILE)
    t1 = time.perf_counter()
    fit_rng = np.random.default_rng(np.random.SeedSequence(args.seed, spawn_key=FIT_KEY))
    writer = _tb_writer(run_dir / "tb" / "bc")
    try:
        fit = pretrain(
            model,
            demos,
            epochs=args.bc_epochs,
            batch_size=args.bc_batch_size,
            seed=fit_rng,
            log_std=args.bc_log_std,
            writer=writer,
        )
    finally:
        if writer is not None:
            writer.close()
    t2 = time.perf_counter()
    posc = np.array(demos.posc)
    dagger = _dagger(args, scenario, model, run_dir, demos, fit_rng) if args.bc_dagger else None
    out: dict[str, Any] = {
        "teacher": demos.teacher,
        "control": demos.control,
        "episodes": len(demos.posc),
        "teacher_posc_mean": float(posc.mean()),
        "teacher_posc": [float(p) for p in posc],
        "seeds": list(demos.seeds),
        "samples": demos.samples,
        "gamma": demos.gamma,
        **(
            {
                "tasks": [
                    {
                        "task": t,
                        "episodes": len(d.posc),
                        "samples": d.samples,
                        "teacher_posc_mean": float(np.mean(d.posc)),
                    }
                    for t, d in zip(tasks, parts, strict=True)
                ]
            }
            if len(tasks) > 1
            else {}
        ),
        **fit,
        "collect_seconds": round(t1 - t0, 3),
        "fit_seconds": round(t2 - t1, 3),
    }
    if dagger is not None:
        out["dagger"] = dagger
    write_json(run_dir / "bc.json", out)
    return out


def _dagger(
    args: TrainArgs,
    scenario: Scenario,
    model: PPO,
    run_dir: Path,
    demos: Demos,
    fit_rng: np.random.Generator,
) -> list[dict[str, Any]]:
    """``args.bc_dagger`` DAgger iterations after the initial fit (:func:`warm_start`): each
    flies the current policy (:func:`dagger_rollouts`, ``args.bc_dagger_episodes`` episodes,
    stream ``DAGGER_KEY + (i,)`` of ``args.seed``, mixture ``args.bc_dagger_beta ** i``), adds
    its labelled rows to all the data so far and refits from the current weights
    (:func:`pretrain`, ``args.bc_dagger_epochs``; the minibatch generator continues the first
    fit's). The policy after iteration ``i`` is saved as ``bc_dagger/iter_<i>.zip``
    (``iter_0``: the first fit's; flown with ``ppo:RUN/bc_dagger/iter_<i>.zip``). Returns one
    record per iteration for ``bc.json``."""
    assert args.task is not None and args.bc_teacher is not None
    data = demos
    records: list[dict[str, Any]] = []
    _save(model, run_dir / "bc_dagger" / "iter_0.zip")  # the first fit's policy
    for i in range(1, args.bc_dagger + 1):
        t0 = time.perf_counter()
        beta = float(args.bc_dagger_beta) ** i
        new, counts = dagger_rollouts(
            scenario,
            args.task,
            args.bc_teacher,
            model,
            args.bc_dagger_episodes,
            np.random.SeedSequence(args.seed, spawn_key=(*DAGGER_KEY, i)),
            gamma=args.gamma,
            agent_index=args.agent_index,
            return_autopilot=args.return_autopilot,
            beta=beta,
        )
        t1 = time.perf_counter()
        on_new = bc_losses(model, new) if new.samples else None
        data = concat_demos([data, new])
        fit = pretrain(
            model,
            data,
            epochs=args.bc_dagger_epochs,
            batch_size=args.bc_batch_size,
            seed=fit_rng,
            log_std=args.bc_log_std,
        )
        t2 = time.perf_counter()
        path = _save(model, run_dir / "bc_dagger" / f"iter_{i}.zip")
        posc = np.array(new.posc)
        records.append(
            {
                "iteration": i,
                "beta": beta,
                "episodes": len(new.posc),
                "rollout_posc_mean": float(posc.mean()),
                "rollout_posc": [float(p) for p in posc],
                "seeds": list(new.seeds),
                **counts,
                "samples_new": new.samples,
                "samples_total": data.samples,
                "new_before_fit": on_new,
                "before": fit["before"],
                "after": fit["after"],
                "epochs": fit["epochs"],
                "epochs_actor_mse": fit["epochs_actor_mse"],
                "epochs_value_mse": fit["epochs_value_mse"],
                "model": path.relative_to(run_dir).as_posix(),
                "rollout_seconds": round(t1 - t0, 3),
                "fit_seconds": round(t2 - t1, 3),
            }
        )
        print(
            f"DAgger {i}/{args.bc_dagger}: rollout POSC {posc.mean():.4f} ({len(posc)} episodes),"
            f" +{new.samples} rows -> {data.samples}; action MSE on the new rows "
            f"{(on_new or {}).get('action_mse', float('nan')):.4f} -> "
            f"{bc_losses(model, new)['action_mse'] if new.samples else float('nan'):.4f}",
            flush=True,
        )
    return records


def _save(model: PPO, path: Path) -> Path:
    """``model`` saved atomically as ``path`` (its folder made)."""
    from poc_env.io import atomic_path

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path, suffix=".zip") as tmp:
        model.save(tmp)
    return path


def _tb_writer(folder: Path) -> Any:
    """A TensorBoard ``SummaryWriter`` on ``folder``, or None if torch's writer is missing."""
    try:
        from torch.utils.tensorboard import SummaryWriter
    except ImportError:  # pragma: no cover - tensorboard is part of the rl extra
        return None
    return SummaryWriter(str(folder))
