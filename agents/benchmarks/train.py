"""PPO training speed: agent transitions per second and where the wall time goes.

    poc-env bench train [--scenario paper_6_2] [--recipe shared] [--n-envs N] [--iterations 2]

(or ``python -m poc_env.agents.benchmarks.train ...``). Trains PPO with the default
:class:`~poc_env.agents.rl.args.TrainArgs` (the shipped network and hyper-parameters) on one torch
thread: one warm-up iteration (allocations, first-call overheads), then ``--iterations`` timed
ones. Prints the agent transitions per second (a central joint step counts once per UAV) and
the shares of wall time spent in the environment (``VecEnv.step_wait``: simulator,
observations, rewards, resets), in the network during rollouts (the rest of
``collect_rollouts``: action sampling, values, buffer) and in the PPO updates (``PPO.train``).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections.abc import Callable, Sequence
from typing import Any

from poc_env.agents.rl.args import RECIPES, TrainArgs
from poc_env.agents.rl.train import make_env, make_model, seed_everything
from poc_env.helptext import HelpFormatter, examples


def bench_train(
    scenario: str = "paper_6_2",
    recipe: str = "shared",
    n_envs: int | None = None,
    iterations: int = 2,
    seed: int = 0,
) -> dict[str, float]:
    """Time ``iterations`` PPO iterations after a warm-up one (module docstring).

    Returns ``{"transitions_per_s", "env_share", "rollout_net_share", "update_share",
    "wall_s", "transitions"}``."""
    import torch as th

    from poc_env.config import load_scenario

    threads = th.get_num_threads()
    th.set_num_threads(1)
    try:
        base = TrainArgs(scenario=scenario, recipe=recipe, seed=seed, progress=False)
        if n_envs is not None:
            base = dataclasses.replace(base, n_envs=n_envs)
        seed_everything(seed)
        env = make_env(base, load_scenario(scenario))
        model = make_model(base, env, None)
        clock = {"env": 0.0, "collect": 0.0, "train": 0.0}

        def timed(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
            def wrapper(*a: Any, **kw: Any) -> Any:
                t0 = time.perf_counter()
                try:
                    return fn(*a, **kw)
                finally:
                    clock[name] += time.perf_counter() - t0

            return wrapper

        env.step_wait = timed("env", env.step_wait)  # type: ignore[method-assign]
        model.collect_rollouts = timed("collect", model.collect_rollouts)  # type: ignore[method-assign]
        model.train = timed("train", model.train)  # type: ignore[method-assign]
        rollout = base.n_steps * env.num_envs
        model.learn(rollout)  # warm-up: allocations, first-call overheads
        for k in clock:
            clock[k] = 0.0
        t0 = time.perf_counter()
        model.learn(iterations * rollout, reset_num_timesteps=False)
        wall = time.perf_counter() - t0
    finally:
        th.set_num_threads(threads)
    n = iterations * rollout
    per_step = 1 if recipe in ("shared", "pilot") else load_scenario(scenario).n_uavs
    return {
        "transitions_per_s": n * per_step / wall,
        "env_share": clock["env"] / wall,
        "rollout_net_share": (clock["collect"] - clock["env"]) / wall,
        "update_share": clock["train"] / wall,
        "wall_s": wall,
        "transitions": float(n * per_step),
    }


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    ap = argparse.ArgumentParser(
        prog="poc-env bench train",
        description="PPO training speed: agent transitions/s and env vs network time shares",
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench train --scenario small --recipe pilot --iterations 1",
            "poc-env bench train --n-envs 8",
        ),
    )
    ap.add_argument("--scenario", default="paper_6_2")
    ap.add_argument("--recipe", default="shared", choices=RECIPES)
    ap.add_argument("--n-envs", type=int, default=None, help="default: TrainArgs.n_envs")
    ap.add_argument("--iterations", type=int, default=2, help="timed PPO iterations")
    return ap


def main(argv: Sequence[str] | None = None) -> dict[str, float]:
    """``poc-env bench train``: print the figures of :func:`bench_train`."""
    from poc_env.agents.benchmarks import check_counts

    ns = build_parser().parse_args(argv)
    check_counts(ns, n_envs=1, iterations=1)
    r = bench_train(ns.scenario, ns.recipe, ns.n_envs, ns.iterations)
    d = TrainArgs()
    print(
        f"PPO {ns.recipe} on {ns.scenario}: {r['transitions_per_s']:,.0f} agent transitions/s "
        f"({int(r['transitions'])} in {r['wall_s']:.1f} s; n_steps={d.n_steps}, "
        f"batch_size={d.batch_size}, n_epochs={d.n_epochs}, 1 torch thread)"
    )
    print(
        f"time shares: env {r['env_share']:.0%}, network in rollouts "
        f"{r['rollout_net_share']:.0%}, PPO updates {r['update_share']:.0%} "
        f"(network total {r['rollout_net_share'] + r['update_share']:.0%})",
        flush=True,
    )
    return r


if __name__ == "__main__":  # pragma: no cover
    from poc_env.agents.benchmarks import run_main

    run_main(main)
