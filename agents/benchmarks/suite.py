"""Speed of the benchmark suite: env-steps/s per control level, PPO transitions/s per framework.

    poc-env bench suite [--scenario Small] [--envs 1 64] [--runs 5] [--iterations 3]
                        [--skip-rllib] [--skip-sb3]

On one core (``OMP_NUM_THREADS=1``, set before numpy is imported), in one run, so the figures
compare:

- **env**: joint env-steps per second of ``gymnasium.make_vec(task, num_envs)`` (the batched
  :class:`~poc_env.envs.gym_vector.SwarmGymVectorEnv`) for the ``Increments``, ``Heading`` and
  ``Waypoint`` tasks of ``--scenario``, with seeded uniform random actions (autoresets
  included), and of the PettingZoo parallel env (1 env); median of ``--runs`` timed stretches
  after a warm-up one. Multiply by the number of UAVs for agent-steps.
- **ppo**: agent transitions per second of PPO on the ``Random-Heading`` task: SB3 on
  :class:`~poc_env.envs.vector.SwarmVecEnv` (the ``pilot`` recipe's env and network, 4 envs)
  and RLlib's multi-agent PPO (shared policy) on RLlib's ``ParallelPettingZooEnv`` with 0
  (sampling in the driver), 1 and 2 env runners on a local Ray instance with 2 CPUs; one
  warm-up iteration, then ``--iterations`` timed ones (sampling and updates together). RLlib
  reports env steps; agent transitions are env steps x UAVs (SB3 counts its slots the same
  way, finished UAVs' placeholder slots included).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from poc_env.helptext import HelpFormatter, examples  # noqa: E402

STEPS = 200  # joint steps per timed stretch


def bench_vector(task: str, num_envs: int, runs: int, seed: int = 0, steps: int = STEPS) -> float:
    """Env-steps/s (joint steps x num_envs) of ``gymnasium.make_vec(task, num_envs)``: the
    median of ``runs`` stretches of ``steps`` joint steps after a warm-up one."""
    import gymnasium

    import poc_env  # noqa: F401  (registers the tasks)

    env = gymnasium.make_vec(task, num_envs=num_envs, vectorization_mode="vector_entry_point")
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    acts = rng.uniform(-1, 1, (steps, *(env.action_space.shape or ()))).astype(np.float32)
    rates = []
    for r in range(runs + 1):
        t0 = time.perf_counter()
        for a in acts:
            env.step(a)
        if r:  # the first stretch is the warm-up
            rates.append(steps * num_envs / (time.perf_counter() - t0))
    env.close()
    return statistics.median(rates)


def bench_parallel(task: str, runs: int, seed: int = 0) -> float:
    """Env-steps/s of the task's PettingZoo parallel env (dict actions, resets included)."""
    from poc_env import tasks

    env = tasks.make_parallel(task)
    rng = np.random.default_rng(seed)
    dim = env.action_space(env.possible_agents[0]).shape[0]
    env.reset(seed=seed)
    rates = []
    for r in range(runs + 1):
        t0 = time.perf_counter()
        for _ in range(STEPS):
            if not env.agents:
                env.reset()
            env.step({a: rng.uniform(-1, 1, dim).astype(np.float32) for a in env.agents})
        if r:
            rates.append(STEPS / (time.perf_counter() - t0))
    return statistics.median(rates)


def bench_sb3(scenario: str, iterations: int) -> float:
    """SB3 PPO agent transitions/s on the pilot recipe (SwarmVecEnv at the heading level)."""
    from poc_env.agents.benchmarks.train import bench_train

    return bench_train(scenario, "pilot", iterations=iterations)["transitions_per_s"]


def bench_rllib(task: str, runners: int, iterations: int) -> float:
    """RLlib PPO agent transitions/s with ``runners`` env runners (shared policy)."""
    from poc_env.agents.rl.cluster import require_ray

    require_ray("poc-env bench suite (the RLlib figures; --skip-rllib leaves them out)")
    import torch as th
    from ray.tune.registry import register_env

    from poc_env.agents.rl.args import TrainArgs
    from poc_env.agents.rl.cluster import ray_session
    from poc_env.agents.rl.rllib import ENV_NAME, env_kwargs, make_env, ppo_config
    from poc_env.envs.parallel import UAVSearchParallelEnv

    th.set_num_threads(1)
    args = TrainArgs(engine="rllib", task=task, num_env_runners=runners, progress=False)
    kw = env_kwargs(args)
    n = UAVSearchParallelEnv(**kw).params.n_agents
    with ray_session(None, num_cpus=2):
        register_env(ENV_NAME, make_env)
        algo = ppo_config(args, kw, n).build_algo()
        try:
            done0 = _env_steps(algo.train())  # the warm-up iteration
            t0 = time.perf_counter()
            last: dict[str, Any] = {}
            for _ in range(iterations):
                last = algo.train()
            wall = time.perf_counter() - t0
            done = _env_steps(last)
        finally:
            algo.stop()
    return (done - done0) * n / wall


def _env_steps(result: dict[str, Any]) -> float:
    """Env steps sampled so far, from an RLlib training result."""
    return float(result["num_env_steps_sampled_lifetime"])


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    p = argparse.ArgumentParser(
        prog="poc-env bench suite",
        description=__doc__.split("\n")[0],
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench suite --scenario Small --envs 1 64 --runs 3 --skip-rllib",
        ),
    )
    p.add_argument("--scenario", default="Small", choices=["Small", "Paper62", "Paper61"])
    p.add_argument("--envs", type=int, nargs="+", default=[1, 64])
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--iterations", type=int, default=3)
    p.add_argument("--skip-rllib", action="store_true")
    p.add_argument("--skip-sb3", action="store_true")
    return p


def main(argv: list[str] | None = None) -> dict[str, float]:
    from poc_env.agents.benchmarks import check_counts

    args = build_parser().parse_args(argv)
    check_counts(args, envs=1, runs=1, iterations=1)
    from poc_env import tasks

    out: dict[str, float] = {}
    for control in ("Increments", "Heading", "Waypoint"):
        tid = tasks.task_id(args.scenario, control, False)
        out[f"pettingzoo {control} 1 env"] = bench_parallel(tid, args.runs)
        for e in args.envs:
            out[f"make_vec {control} {e} envs"] = bench_vector(tid, e, args.runs)
    for k, v in out.items():
        print(f"{k:<32} {v:>10.0f} env-steps/s", flush=True)
    task = tasks.task_id(args.scenario, "Heading", True)
    scenario = tasks.get_task(task).scenario
    if not args.skip_sb3:
        out["ppo sb3 (4 envs)"] = bench_sb3(scenario, args.iterations)
        print(f"{'ppo sb3 (4 envs)':<32} {out['ppo sb3 (4 envs)']:>10.0f} agent transitions/s")
    if not args.skip_rllib:
        for runners in (0, 1, 2):
            key = f"ppo rllib ({runners} env runners)"
            out[key] = bench_rllib(task, runners, args.iterations)
            print(f"{key:<32} {out[key]:>10.0f} agent transitions/s", flush=True)
    return out


if __name__ == "__main__":
    from poc_env.agents.benchmarks import run_main

    run_main(main)
