"""CPU time of one call of the compass and coarse POC kernels on realistic batched states.

    python agents/benchmarks/compass_kernel.py [--calls 2000] [--seed 0]

Captures the arguments of ``poc_env._kernels.observations.compass`` and ``coarse_poc`` from
three batched envs after 50 seeded random steps (then four more states, ten steps apart):
``make_vec`` Small-Heading at 256 envs, the SB3 task's ``VecEnv`` (4 swarms x 6 UAVs,
:data:`~poc_env.agents.benchmarks.breakdown.SB3_TASK`) and ``make_vec`` Paper62-Heading at 64
envs. Then calls each kernel on those states in turn and prints the median CPU time of a call
(``time.process_time_ns``, one thread). It imports ``poc_env`` from ``PYTHONPATH`` and captures
whatever arguments that tree's kernels take, so one copy of this file times any tree: run it
alternately over two trees on a loaded machine and compare the medians of the pairs.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np

KERNELS = ("compass", "coarse_poc")


def _states(which: str, seed: int, envs: int | None = None) -> dict[str, list[tuple]]:
    """The captured arguments of each kernel at five steps of ``which``'s env (``envs``: the
    ``make_vec`` batch instead of the default)."""
    from poc_env._kernels import observations as kernels
    from poc_env.agents.benchmarks.breakdown import SB3_TASK, heading_task

    captured: dict[str, tuple] = {}
    originals = {name: getattr(kernels, name) for name in KERNELS}

    def spy(name):
        def call(*args):
            captured[name] = tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args)
            return originals[name](*args)

        return call

    for name in KERNELS:
        setattr(kernels, name, spy(name))
    try:
        env: Any
        if which == "sb3_task":
            from poc_env.agents.rl.args import TrainArgs
            from poc_env.agents.rl.train import make_env
            from poc_env.tasks import get_task

            env = make_env(
                TrainArgs(task=SB3_TASK, seed=seed, progress=False),
                get_task(SB3_TASK).load_scenario(),
            )
            env.seed(seed)
            env.reset()
            shape = (env.num_envs, *(env.action_space.shape or ()))
        else:
            import gymnasium

            import poc_env  # noqa: F401  (registers the tasks)

            sizes = {"make_vec_small": ("Small", 256), "make_vec_paper62": ("Paper62", 64)}
            scenario, default = sizes[which]
            mode = "vector_entry_point"
            env = gymnasium.make_vec(
                heading_task(scenario), num_envs=envs or default, vectorization_mode=mode
            )
            env.reset(seed=seed)
            shape = env.action_space.shape or ()
        rng = np.random.default_rng(seed)
        states: dict[str, list[tuple]] = {name: [] for name in KERNELS}
        for t in range(90):
            env.step(rng.uniform(-1, 1, shape).astype(np.float32))
            if t >= 49 and t % 10 == 9:
                for name in KERNELS:
                    states[name].append(captured[name])
        return states
    finally:
        for name in KERNELS:
            setattr(kernels, name, originals[name])


def time_kernels(
    which: str, calls: int, seed: int = 0, envs: int | None = None
) -> dict[str, float]:
    """Median CPU ms of one call of each kernel on ``which``'s captured states."""
    from poc_env._kernels import observations as kernels

    states = _states(which, seed, envs)
    out = {}
    for name in KERNELS:
        fn = getattr(kernels, name)
        times = []
        for k in range(calls):
            args = states[name][k % len(states[name])]
            t = time.process_time_ns()
            fn(*args)
            times.append((time.process_time_ns() - t) / 1e6)
        out[name] = statistics.median(times)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--calls", type=int, default=2000, help="calls per kernel and env")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    for which in ("make_vec_small", "sb3_task", "make_vec_paper62"):
        r = time_kernels(which, args.calls, args.seed)
        parts = (f"{name} {ms:.4f} ms CPU (median of {args.calls})" for name, ms in r.items())
        print(f"{which:17s} " + ", ".join(parts))


if __name__ == "__main__":
    main()
