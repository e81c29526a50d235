"""A PPO checkpoint flying through the :class:`poc_env.agents.policies.base.Policy` interface.

``ppo:PATH`` in ``poc-env evaluate --policies`` and the policy registry name
:class:`PPOPolicy`. Model files are pickle-based: load only trusted files.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from poc_env.agents.policies.base import Policy
from poc_env.agents.rl.checkpoint import describe_space, load_policy, model_path
from poc_env.errors import ConfigError
from poc_env.sim.observations import SET_SIZE, SetFeatures, split_observation

if TYPE_CHECKING:
    from stable_baselines3 import PPO

_MODELS: dict[tuple[str, int, int], Any] = {}


def _cached_model(path: Path) -> PPO:
    """The model in ``path``, loaded once per file version (evaluations make many policies)."""
    st = path.stat()
    key = (str(path.resolve()), st.st_mtime_ns, st.st_size)
    if key not in _MODELS:
        if len(_MODELS) >= 8:
            _MODELS.clear()
        _MODELS[key] = load_policy(path)
    return _MODELS[key]


def _flat(obs: Any) -> np.ndarray:
    """One agent's flat observation (raster then vector, as ``obs_type="flat"``)."""
    if isinstance(obs, dict):
        return np.concatenate([np.ravel(obs["raster"]), np.ravel(obs["vector"])]).astype(np.float32)
    return np.asarray(obs, dtype=np.float32)


def _flat_space(space: Any) -> Any:
    """The ``flat`` counterpart of a per-agent ``Dict`` observation space."""
    from gymnasium import spaces

    if isinstance(space, spaces.Dict):
        ras, vec = space["raster"], space["vector"]
        assert isinstance(ras, spaces.Box) and isinstance(vec, spaces.Box)
        low = np.concatenate([ras.low.ravel(), vec.low])
        high = np.concatenate([ras.high.ravel(), vec.high])
        return spaces.Box(low, high, dtype=np.float32)
    return space


def _run_config(model: Path) -> dict[str, Any]:
    """The training config of a model: ``<model>.json`` beside it (a shipped checkpoint's
    card: the run's config.json plus how it was evaluated), else the ``config.json`` of its
    run folder (the model's folder or up to two above it: ``model.zip``,
    ``checkpoints/step_N.zip``), or ``{}``."""
    from poc_env.errors import ConfigError
    from poc_env.io import read_json

    for cfg in [model.with_suffix(".json")] + [f / "config.json" for f in model.parents[:3]]:
        if cfg.is_file():
            try:
                data = read_json(cfg, "config.json")
            except ConfigError:
                return {}
            return data if isinstance(data, dict) else {}
    return {}


def _run_task(model: Path) -> Any:
    """The task a model was trained on, from its run's ``config.json``, or None."""
    from poc_env.tasks import get_task

    task = _run_config(model).get("task")
    return get_task(task) if task else None


def checkpoint_control(spelling: str) -> str | None:
    """The control level a ``ppo:PATH`` or ``rllib:PATH`` policy was trained at (from its
    run's task; ``heading`` for the pilot recipe), or None for other policies and runs
    without a task."""
    kind, sep, path = spelling.partition(":")
    if not sep or kind not in ("ppo", "rllib"):
        return None
    if kind == "rllib":
        from poc_env.agents.rl.rllib import run_control

        try:
            return run_control(path)
        except ConfigError:
            return None
    try:
        task = _run_task(model_path(path))
    except ConfigError:
        return None
    return None if task is None else task.control


def checkpoint_origin(spelling: str) -> tuple[str | None, str | None, tuple[str, ...]]:
    """``(task id, recipe, also-task ids)`` a ``ppo:PATH`` or ``rllib:PATH`` policy was
    trained with (from its run's config or card), ``(None, None, ())`` for other policies and
    models without a config."""
    kind, sep, path = spelling.partition(":")
    if not sep or kind not in ("ppo", "rllib"):
        return None, None, ()
    try:
        if kind == "rllib":
            from poc_env.agents.rl.rllib import run_config

            cfg = run_config(path)
        else:
            cfg = _run_config(model_path(path))
    except ConfigError:
        return None, None, ()
    task = cfg.get("task")
    recipe = cfg.get("recipe") if kind == "ppo" else None  # RLlib runs observe the compass
    also = tuple(str(t) for t in cfg.get("also_task") or ())
    return (str(task) if task else None), (str(recipe) if recipe else None), also


def compass_actions(
    params: Any,
    features: Any,
    model: Any,
    control: str,
    return_autopilot: bool,
    observations: Sequence[Any],
    k: np.ndarray,
    deterministic: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How a compass-observation checkpoint flies (:class:`PPOPolicy`'s ``compass`` mode): the
    UAVs ``k (B,)`` with env ``observations`` (B of them) read the compass ``features``
    (:class:`~poc_env.sim.observations.CompassFeatures`), ``model`` acts at ``control``, its
    actions become eq. 19 increments (:func:`poc_env.sim.control.to_increments`) and, with
    ``return_autopilot`` (an increments run trained with ``--return-autopilot``), the UAVs that
    must head home fly the autopilot's homing increments
    (:func:`poc_env.sim.control.return_home`). Returns the features ``(B, FEATURES)``, the
    increments ``(B, 3)`` and which UAVs the autopilot took home ``(B,)`` (all False without
    it). The one path of :class:`PPOPolicy` and of the DAgger rollouts
    (:func:`poc_env.agents.rl.bc.dagger_rollouts`)."""
    from poc_env.sim.observations import decode_vector

    shape = params.grid.shape
    ras, vec = zip(*(split_observation(o, shape) for o in observations), strict=True)
    feats = features(np.stack(ras), np.stack(vec), k)
    act, _ = model.predict(feats, deterministic=deterministic)
    q = decode_vector(params, np.stack(vec))
    inc, home = model_increments(params, control, return_autopilot, q, act, k)
    return feats, inc, home


def model_increments(
    params: Any, control: str, return_autopilot: bool, q: Any, act: Any, k: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """A task checkpoint's actions ``act`` at ``control`` for the UAVs ``k`` in states ``q``
    as eq. 19 increments (:func:`poc_env.sim.control.to_increments`); with
    ``return_autopilot`` (an increments run trained with ``--return-autopilot``) the UAVs that
    must head home (eq. 18, :func:`poc_env.sim.autopilot.returning`) fly the autopilot's homing
    increments (:func:`poc_env.sim.control.return_home`), as in training. Returns the
    increments ``(B, 3)`` and which UAVs the autopilot took home ``(B,)``. The one rule of the
    compass and the set observation."""
    from poc_env.sim.autopilot import returning
    from poc_env.sim.control import return_home, to_increments

    inc = to_increments(params, control, q, np.asarray(act), k)
    home = np.zeros(len(k), dtype=bool)
    if return_autopilot:  # trained with the return autopilot
        home = np.asarray(returning(params, np.asarray(q["xy"], dtype=float), q["usable"], k))
        inc = return_home(params, q, inc, k).astype(np.float32)
    return inc, home


class PPOPolicy(Policy):
    """A PPO checkpoint flying through the :class:`poc_env.agents.policies.base.Policy` interface.

    ``PPOPolicy(path)`` loads ``path`` (a ``.zip``, or a run folder: its ``model.zip`` or latest
    checkpoint) on the CPU; :meth:`reset` checks it against the env and picks the recipe from
    the model's spaces: ``compass`` (the compass features; actions at the control level of the
    task the run was trained on, from its ``config.json``, or ``heading`` for the ``pilot``
    recipe, flown by :mod:`poc_env.sim.control`), ``set`` (a ``-Set`` task's policy: the set
    observation of the env's swarm, :class:`~poc_env.sim.observations.SetFeatures`, so one
    checkpoint flies any fleet size),
    ``shared`` (the per-agent space: the live agents' observations go through
    ``model.predict`` as one batch), ``shared_flat``, or ``central`` (the joint flat space:
    finished agents keep their last observation, as in ``UAVSearch-v0``). Actions are
    deterministic by default::

        from poc_env.agents.rl.policy import PPOPolicy
        policy = PPOPolicy("runs/.../model.zip"); policy.reset(env, seed=0)
        actions, _ = policy.predict(observations)

    Model files are pickle-based: load only trusted files.
    """

    def __init__(self, path: str | os.PathLike[str], name: str | None = None) -> None:
        self.path = model_path(path)
        self.name = name or f"ppo:{path}"
        self.model = _cached_model(self.path)
        self.mode = ""
        self._return = False  # increments checkpoints trained with --return-autopilot
        self._last: dict[str, np.ndarray] = {}

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        from gymnasium import spaces

        from poc_env.agents.rl import pilot

        agents = list(env.possible_agents)
        agent_space = env.observation_space(agents[0])
        joint = _flat_space(agent_space)
        assert isinstance(joint, spaces.Box)
        joint = spaces.Box(
            np.tile(joint.low, len(agents)), np.tile(joint.high, len(agents)), dtype=np.float32
        )
        m_obs, m_act = self.model.observation_space, self.model.action_space
        one_act = spaces.Box(-1.0, 1.0, (3,), np.float32)
        joint_act = spaces.Box(-1.0, 1.0, (3 * len(agents),), np.float32)
        task = _run_task(self.path)
        cfg = _run_config(self.path) if task is not None else {}
        if task is not None and cfg.get("residual_teacher"):
            # a residual on a planner (poc_env.agents.rl.residual): the teacher flies, the
            # model adds (dv, d turn) from the task's observation plus the teacher's action
            from poc_env.agents.policies.registry import make_policy
            from poc_env.agents.rl.args import check_residual_teacher

            self.mode, self.control = "residual", "increments"
            teacher = make_policy(check_residual_teacher(cfg["residual_teacher"]))
            self._teacher = teacher  # a PlanPolicy or a re-planner with a follower
            self._teacher.reset(env, seed)
            if task.obs == "set":
                self._set = SetFeatures(env.params)
            else:
                index = cfg.get("agent_index", True) is not False
                self._features = pilot.PilotFeatures(env.params, agent_index=index)
            self._obs = task.obs
        elif task is not None and m_obs == pilot.OBSERVATION_SPACE:
            # trained on a task: its control level flies the compass-observation policy
            self.mode, self.control = "compass", task.control
            cfg = _run_config(self.path)
            index = cfg.get("agent_index", True) is not False
            self._features = pilot.PilotFeatures(env.params, agent_index=index)
            self._return = self.control == "increments" and cfg.get("return_autopilot") is True
        elif task is not None and task.obs == "set" and m_obs.shape == (SET_SIZE,):
            # a -Set task's policy: the set observation of this env's swarm, any fleet size
            self.mode, self.control = "set", task.control
            self._set = SetFeatures(env.params)
            self._return = self.control == "increments" and cfg.get("return_autopilot") is True
        elif m_obs == pilot.OBSERVATION_SPACE and m_act == pilot.ACTION_SPACE:
            self.mode, self.control = "compass", "heading"  # the pilot recipe
            self._features = pilot.PilotFeatures(env.params)
        elif m_obs == agent_space and m_act == one_act:
            self.mode = "shared"
        elif m_obs == _flat_space(agent_space) and m_act == one_act:
            self.mode = "shared_flat"
        elif m_obs == joint and m_act == joint_act:
            self.mode = "central"
        else:
            raise ConfigError(
                "checkpoint",
                str(self.path),
                f"a model for this env ({len(agents)} UAVs; per-agent observation "
                f"{describe_space(agent_space)}, joint {describe_space(joint)}), but the file "
                f"was trained for observation {describe_space(m_obs)} and action "
                f"{describe_space(m_act)} (another grid, number of UAVs or recipe?)",
            )
        self._agents = agents
        self._last = {}

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        if not observations:
            return {}, state
        live = [a for a in self._agents if a in observations]
        if self.mode == "central":
            self._last.update({a: _flat(observations[a]) for a in live})
            joint = np.concatenate([self._last[a] for a in self._agents])
            act, _ = self.model.predict(joint, deterministic=deterministic)
            act = np.asarray(act, dtype=np.float32).reshape(len(self._agents), 3)
            return {a: act[self._agents.index(a)] for a in live}, state
        batch: Any
        if self.mode == "compass":
            k = np.array([self._agents.index(a) for a in live])
            _, inc, _ = compass_actions(
                self.env.params, self._features, self.model, self.control, self._return,
                [observations[a] for a in live], k, deterministic,
            )  # fmt: skip
            return {a: inc[j] for j, a in enumerate(live)}, state
        if self.mode == "set":  # computed from the swarm's state as the -Set tasks observe it
            from poc_env.sim.observations import VECTOR_SIZE, decode_vector

            eng = self.env.engine
            k = np.array([self._agents.index(a) for a in live])
            feats = self._set.of_state(eng.current, eng.poc_scale)[0, k]
            act, _ = self.model.predict(feats, deterministic=deterministic)
            q = decode_vector(self.env.params, feats[:, :VECTOR_SIZE])
            inc, _ = model_increments(self.env.params, self.control, self._return, q, act, k)
            return {a: inc[j] for j, a in enumerate(live)}, state
        if self.mode == "residual":
            from poc_env.agents.rl.residual import augment, combine, teacher_actions

            k = np.array([self._agents.index(a) for a in live])
            t_inc, homing = teacher_actions(self._teacher, observations, live)
            if self._obs == "set":
                eng = self.env.engine
                feats = self._set.of_state(eng.current, eng.poc_scale)[0, k]
            else:
                shape = self.env.params.grid.shape
                pairs = (split_observation(observations[a], shape) for a in live)
                ras, vec = zip(*pairs, strict=True)
                feats = self._features(np.stack(ras), np.stack(vec), k)
            act, _ = self.model.predict(augment(feats, t_inc), deterministic=deterministic)
            inc = combine(t_inc, np.asarray(act), homing).astype(np.float32)
            return {a: inc[j] for j, a in enumerate(live)}, state
        if self.mode == "shared":
            batch = {
                k: np.stack([np.asarray(observations[a][k]) for a in live])
                for k in ("raster", "vector")
            }
        else:
            batch = np.stack([_flat(observations[a]) for a in live])
        act, _ = self.model.predict(batch, deterministic=deterministic)
        act = np.asarray(act, dtype=np.float32).reshape(len(live), 3)
        return {a: act[k] for k, a in enumerate(live)}, state
