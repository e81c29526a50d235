"""RLlib multi-agent PPO on the registered tasks: ``poc-env train --engine rllib``.

The environment is the task's PettingZoo parallel env (:func:`poc_env.tasks.make_parallel`)
behind RLlib's own ``ParallelPettingZooEnv`` wrapper, so what RLlib trains on is exactly what
every other framework sees; the compass observation is a Box, which RLlib's default MLP
encoder takes without configuration. Two policy layouts (``--rllib-policies``):

- ``shared``: one RLModule flies every UAV (parameter sharing, as the SB3 recipes);
- ``per_uav``: one RLModule per UAV (``uav_0`` ... ``uav_{N-1}``).

Training runs inside :func:`poc_env.agents.rl.cluster.ray_session`: a local Ray instance by
default, an existing cluster with ``--address``; ``--num-env-runners K`` samples on K Ray actors
(0: in the driver). The run folder gets ``config.json`` (the
:class:`~poc_env.agents.rl.args.TrainArgs`), ``metrics.csv`` (one row per training iteration;
``agent_steps`` is env steps x UAVs, an upper bound once UAVs land) and ``checkpoint/`` (RLlib's
``save_to_path``, written into a temporary folder and renamed when complete); both are
rewritten every ``--checkpoint-every`` env steps and at the end, so a stopped run keeps its
newest checkpoint and curve. ``tb/rllib_K/`` holds TensorBoard scalars under the tags SB3 runs
log, so ``poc-env curve`` reads either (:func:`_log_iteration`; flushed every iteration).
``--total-timesteps`` counts env steps here (each holds one transition of every UAV still
flying).
:class:`RLlibPolicy` (``rllib:PATH`` in ``poc-env evaluate``) flies such a checkpoint.
Needs the ``rllib`` extra (``ray[rllib]``).
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from poc_env.agents.policies.base import Policy
from poc_env.agents.rl.checkpoint import read_json, write_json
from poc_env.errors import ConfigError, MissingExtraError
from poc_env.io import csv_text, write_text_atomic

if TYPE_CHECKING:
    from poc_env.agents.rl.args import TrainArgs

ENV_NAME = "poc_env_task"
POLICY_LAYOUTS = ("shared", "per_uav")


def _require() -> None:
    for m in ("ray", "torch", "tensorboardX"):  # tensorboardX comes with ray[rllib]
        try:
            __import__(m)
        except ModuleNotFoundError as exc:
            if (exc.name or "").partition(".")[0] != m:
                raise
            raise MissingExtraError("rllib", "poc-env train --engine rllib") from exc


def env_kwargs(args: TrainArgs) -> dict[str, Any]:
    """The PettingZoo env's keyword arguments of a run: its task's, with the run's overrides
    (without a task: the scenario at the heading level with the compass observation)."""
    from poc_env import tasks
    from poc_env.config import parse_overrides

    if args.task is not None:
        kw = tasks.task_kwargs(args.task)
    else:
        kw = {
            "scenario": args.scenario,
            "control": "heading",
            "obs_type": "compass",
            "random_prior": args.random_priors,
        }
    if args.overrides:
        kw["overrides"] = parse_overrides(args.overrides)
    return kw


def make_env(config: dict[str, Any]):
    """RLlib's env creator: ``config`` holds the PettingZoo env's keyword arguments."""
    from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv

    from poc_env.envs.parallel import UAVSearchParallelEnv

    return ParallelPettingZooEnv(UAVSearchParallelEnv(**dict(config)))


def _shared_policy(agent_id: Any, *args: Any, **kwargs: Any) -> str:
    return "shared"


def _own_policy(agent_id: Any, *args: Any, **kwargs: Any) -> str:
    return str(agent_id)


def ppo_config(args: TrainArgs, kw: dict[str, Any], n_agents: int):
    """The PPOConfig of a run (RLlib's new API stack, torch, CPU)."""
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
    from ray.rllib.core.rl_module.rl_module import RLModuleSpec

    if args.rllib_policies == "shared":
        ids = ["shared"]
        mapping = _shared_policy
    else:
        ids = [f"uav_{i}" for i in range(n_agents)]
        mapping = _own_policy
    model = {"fcnet_hiddens": list(args.net_arch), "fcnet_activation": "tanh"}
    specs = {i: RLModuleSpec(model_config=model) for i in ids}
    fragment = max(1, args.n_steps)
    return (
        PPOConfig()
        .environment(ENV_NAME, env_config=kw)
        .framework("torch")
        .env_runners(
            num_env_runners=args.num_env_runners,
            num_envs_per_env_runner=1,
            rollout_fragment_length=fragment,
            num_cpus_per_env_runner=1,
        )
        .multi_agent(policies=set(ids), policy_mapping_fn=mapping)
        .rl_module(rl_module_spec=MultiRLModuleSpec(rl_module_specs=specs))
        .training(
            # RLlib counts a multi-agent batch in env steps (each holds every live UAV's step)
            train_batch_size_per_learner=fragment * max(1, args.num_env_runners),
            minibatch_size=min(args.batch_size, fragment * max(1, args.num_env_runners)),
            num_epochs=args.n_epochs,
            lr=args.learning_rate,
            gamma=args.gamma,
            lambda_=args.gae_lambda,
            entropy_coeff=args.ent_coef,
        )
        .callbacks(on_episode_end=record_posc)
        .debugging(seed=args.seed)
    )


def record_posc(*, episode: Any, metrics_logger: Any = None, **kwargs: Any) -> None:
    """RLlib's ``on_episode_end`` callback: logs the episode's final POSC (the team's value,
    which every UAV's last info carries; the largest of them, since POSC never decreases
    within an episode) as the metric ``posc`` (``result["env_runners"]["posc"]``)."""
    values = []
    for agent_episode in episode.agent_episodes.values():
        try:
            info = agent_episode.get_infos(-1)
        except IndexError:  # an agent without any step
            continue
        v = info.get("posc") if isinstance(info, dict) else None
        if isinstance(v, int | float | np.floating) and np.isfinite(v):
            values.append(float(v))
    if values and metrics_logger is not None:
        metrics_logger.log_value("posc", max(values), reduce="mean")


def _metric(result: dict[str, Any], *keys: str) -> float:
    node: Any = result
    for k in keys:
        if not isinstance(node, dict) or k not in node:
            return float("nan")
        node = node[k]
    try:
        return float(node)
    except (TypeError, ValueError):
        return float("nan")


def _tb_dir(run_dir: Path) -> Path:
    """``run_dir/tb/rllib_K``, K one more than any earlier run's in the folder (a run restarted
    in its folder after a kill logs beside the killed attempt, as SB3's ``ppo_K`` do)."""
    ks = [
        int(d.name.removeprefix("rllib_"))
        for d in (run_dir / "tb").glob("rllib_*")
        if d.name.removeprefix("rllib_").isdigit()
    ]
    return run_dir / "tb" / f"rllib_{max(ks, default=0) + 1}"


def _log_iteration(writer: Any, result: dict[str, Any], agent_steps: int) -> None:
    """One training iteration's TensorBoard scalars, at step ``agent_steps`` (env steps x UAVs,
    the x axis of SB3's curves): ``rollout/posc_mean``, the mean final POSC of the episodes
    RLlib reports for the iteration (:func:`record_posc`), and ``rollout/ep_rew_mean``, the
    mean episode return per UAV (SB3's is per slot, i.e. per UAV); an iteration that finished
    no episode logs neither, as SB3 logs nothing without one."""
    runners = result.get("env_runners", {})
    posc = _metric(result, "env_runners", "posc")
    per_uav = runners.get("agent_episode_returns_mean") if isinstance(runners, dict) else None
    returns = [_metric(per_uav, k) for k in per_uav] if isinstance(per_uav, dict) else []
    ret = float(np.mean(returns)) if returns else float("nan")
    for tag, value in (("rollout/posc_mean", posc), ("rollout/ep_rew_mean", ret)):
        if np.isfinite(value):
            writer.add_scalar(tag, value, agent_steps)
    writer.flush()  # a killed run keeps its curve up to its last iteration


def train_rllib(args: TrainArgs, run_dir: Path) -> Path:
    """Train ``args`` with RLlib into ``run_dir`` (module docstring); returns the run folder."""
    _require()
    import torch as th

    from poc_env.agents.rl.cluster import ray_session
    from poc_env.sim.engine import make_engine

    kw = env_kwargs(args)
    n_agents = make_engine(1, **kw).n_agents  # validates the env's arguments
    cpus = max(2, args.num_env_runners + 1)
    # Ray first: a bad --address is refused before the run folder is written
    with ray_session(args.address, num_cpus=cpus, what="poc-env train --engine rllib"):
        run_dir.mkdir(parents=True, exist_ok=True)
        write_json(run_dir / "config.json", dataclasses.asdict(args))
        from tensorboardX import SummaryWriter

        threads = th.get_num_threads()
        th.set_num_threads(args.torch_threads)
        writer = SummaryWriter(str(_tb_dir(run_dir)))
        try:
            rows = _train_loop(args, kw, n_agents, run_dir, writer)
        finally:
            writer.close()
            th.set_num_threads(threads)
    write_text_atomic(run_dir / "metrics.csv", csv_text(rows))
    return run_dir


def _train_loop(
    args: TrainArgs, kw: dict[str, Any], n_agents: int, run_dir: Path, writer: Any
) -> list[dict[str, float]]:
    """Build the algorithm, train it up to ``args.total_timesteps`` env steps (checkpoints,
    metrics rows, TensorBoard scalars) and save it; returns the metrics rows."""
    from ray.tune.registry import register_env

    register_env(ENV_NAME, make_env)
    algo = ppo_config(args, kw, n_agents).build_algo()
    rows: list[dict[str, float]] = []
    try:
        t0 = time.perf_counter()
        steps = 0
        next_save = args.checkpoint_every
        while steps < args.total_timesteps:
            result = algo.train()
            steps = int(_metric(result, "num_env_steps_sampled_lifetime"))
            agent_steps = steps * n_agents  # upper bound: UAVs that landed act no more
            _log_iteration(writer, result, agent_steps)
            rows.append(
                {
                    "iteration": len(rows) + 1,
                    "env_steps": steps,
                    "agent_steps": agent_steps,
                    "seconds": round(time.perf_counter() - t0, 3),
                    "episode_return_mean": _metric(result, "env_runners", "episode_return_mean"),
                }
            )
            if args.progress:
                r = rows[-1]
                print(
                    f"iteration {r['iteration']}: {steps} env steps, "
                    f"return {r['episode_return_mean']:.4f}",
                    flush=True,
                )
            if steps >= next_save and steps < args.total_timesteps:
                # a long run keeps its newest checkpoint and curve (a kill loses at most
                # checkpoint_every env steps)
                _save(algo, run_dir / "checkpoint")
                write_text_atomic(run_dir / "metrics.csv", csv_text(rows))
                next_save = (steps // args.checkpoint_every + 1) * args.checkpoint_every
        _save(algo, run_dir / "checkpoint")
    finally:
        algo.stop()
    return rows


def _save(algo: Any, dest: Path) -> None:
    """RLlib's checkpoint into ``dest``, complete or absent (a temporary folder, renamed)."""
    # RLlib writes through pyarrow's file systems, which take absolute paths (URIs) only
    tmp = Path(tempfile.mkdtemp(prefix=".checkpoint-", dir=dest.parent)).resolve()
    try:
        algo.save_to_path(str(tmp))
        if dest.exists():
            shutil.rmtree(dest)
        os.replace(tmp, dest)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


# -- flying a checkpoint -----------------------------------------------------------------------
def shipped_rllib() -> list[str]:
    """Names of the RLlib checkpoints shipped in the package (``agents/checkpoints/<name>/``:
    the run's ``config.json`` and the RLModule states of ``checkpoint/``, what flying needs)."""
    import importlib.resources

    folder = importlib.resources.files("poc_env.agents").joinpath("checkpoints")
    return sorted(
        f.name for f in folder.iterdir() if f.is_dir() and f.joinpath("config.json").is_file()
    )


def _checkpoint_dir(path: str | os.PathLike[str]) -> Path:
    p = Path(path)
    if not p.exists() and str(path) in shipped_rllib():
        import importlib.resources

        p = Path(
            str(importlib.resources.files("poc_env.agents").joinpath("checkpoints", str(path)))
        )
    if (p / "checkpoint").is_dir():
        p = p / "checkpoint"
    if not (p / "learner_group").is_dir():
        raise ConfigError(
            "checkpoint", str(path), "a run folder of poc-env train --engine rllib or its "
            "checkpoint/ folder (holding learner_group/), or a shipped one: "
            + ", ".join(shipped_rllib()),
        )  # fmt: skip
    return p


def run_config(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The ``config.json`` of an RLlib run (its folder or ``checkpoint/``), as a dict."""
    cfg = _checkpoint_dir(path).parent / "config.json"
    if not cfg.is_file():
        raise ConfigError("checkpoint", str(path), "a checkpoint beside its config.json")
    data = read_json(cfg, "config.json")
    if not isinstance(data, dict):
        raise ConfigError("config.json", data, "a JSON object of TrainArgs fields")
    return data


def run_control(path: str | os.PathLike[str]) -> str:
    """The control level an RLlib run (its folder or ``checkpoint/``) was trained at, from its
    ``config.json`` through :func:`env_kwargs` (the rule the run itself used): the level, not
    a task version's variant of it (``heading`` for ``...-Heading-v1``'s ``heading_clip``,
    :data:`poc_env.sim.control.VARIANTS`), as ``evaluate --task`` compares it with a task's."""
    from poc_env.agents.rl.args import TrainArgs
    from poc_env.sim.control import VARIANTS

    args = TrainArgs.from_dict(run_config(path), "config.json")
    control = str(env_kwargs(args).get("control", "increments"))
    return VARIANTS.get(control, control)


class RLlibPolicy(Policy):
    """An RLlib checkpoint of ``poc-env train --engine rllib`` as a poc-env policy.

    ``RLlibPolicy(path)``: a run folder or its ``checkpoint/``. The run's ``config.json`` names
    the task, so the policy knows its control level and observation; :meth:`reset` refuses an
    env of another number of UAVs. Actions are the mean of the Gaussian (deterministic)."""

    def __init__(self, path: str | os.PathLike[str], name: str | None = None) -> None:
        _require()
        from ray.rllib.core.rl_module.rl_module import RLModule

        from poc_env.agents.rl.args import TrainArgs

        self.dir = _checkpoint_dir(path).resolve()  # RLlib reads URIs: absolute paths only
        self.name = name or f"rllib:{path}"
        self.args = TrainArgs.from_dict(run_config(path), "config.json")
        kw = env_kwargs(self.args)
        self.control = kw.get("control", "increments")
        modules = self.dir / "learner_group" / "learner" / "rl_module"
        allowed = (
            "a complete RLlib checkpoint (learner_group/learner/rl_module/<policy>/ as "
            "poc-env train --engine rllib writes it)"
        )
        folders = sorted(d for d in modules.iterdir() if d.is_dir()) if modules.is_dir() else []
        if not folders:
            raise ConfigError("checkpoint", str(path), f"{allowed}; it has no RLModule folder")
        self.modules = {}
        for d in folders:
            try:
                self.modules[d.name] = RLModule.from_checkpoint(str(d))
            except Exception as err:  # a damaged file: RLlib fails deep inside (pickle, torch)
                shown = f"{type(err).__name__}: {err}"[:200]
                raise ConfigError(
                    "checkpoint", str(path), f"{allowed}; {d.name} cannot be read ({shown})"
                ) from None
        self._n = None
        self._set: Any = None  # SetFeatures of a -Set task's run (set at reset)

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        from poc_env.sim.observations import CompassFeatures, SetFeatures
        from poc_env.tasks import get_task

        n = env.params.n_agents
        if self.args.rllib_policies == "per_uav" and len(self.modules) != n:
            raise ConfigError(
                "checkpoint", str(self.dir), f"one policy per UAV for {n} UAVs "
                f"(this run has {len(self.modules)})",
            )  # fmt: skip
        self._n = n
        # the observation the run trained on: its task's (a -Set task's set observation,
        # computed from the swarm's state as PPOPolicy's set mode does), else the compass
        obs = get_task(self.args.task).obs if self.args.task is not None else "compass"
        self._set = SetFeatures(env.params) if obs == "set" else None
        self._features = CompassFeatures(env.params)
        self._agents = list(env.possible_agents)

    def predict(self, observations: dict, state=None, episode_start=None, deterministic=True):
        import torch as th

        from poc_env.sim.control import ACTION_DIMS, to_increments
        from poc_env.sim.observations import VECTOR_SIZE, decode_vector, split_observation

        if not observations:
            return {}, state
        live = [a for a in self._agents if a in observations]
        k = np.array([self._agents.index(a) for a in live])
        if self._set is not None:  # a -Set task's run: the set observation of the swarm
            eng = self.env.engine
            feats = self._set.of_state(eng.current, eng.poc_scale)[0, k]
            vectors = feats[:, :VECTOR_SIZE]
        else:
            shape = self.env.params.grid.shape
            pairs = (split_observation(observations[a], shape) for a in live)
            ras, vec = zip(*pairs, strict=True)
            feats = self._features(np.stack(ras), np.stack(vec), k)
            vectors = np.stack(vec)
        acts = np.zeros((len(live), ACTION_DIMS[self.control]))
        groups = (
            {"shared": list(range(len(live)))}
            if "shared" in self.modules
            else {a: [j] for j, a in enumerate(live)}
        )  # one forward pass per module: every live UAV at once for a shared policy
        for name, rows in groups.items():
            with th.no_grad():
                out = self.modules[name].forward_inference({"obs": th.as_tensor(feats[rows])})
            dist = out["action_dist_inputs"].numpy()
            acts[rows] = np.clip(dist[:, : acts.shape[1]], -1.0, 1.0)  # the Gaussian's mean
        q = decode_vector(self.env.params, vectors)
        inc = to_increments(self.env.params, self.control, q, acts, k)
        return {a: inc[j] for j, a in enumerate(live)}, state
