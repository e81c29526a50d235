"""CPU time and peak allocation of ``gymnasium.make_vec`` steps, by kind of step.

    python agents/benchmarks/vector_steps.py [--scenario Small] [--envs 256] [--steps 800]
                                             [--memory] [--seed 0] [--sb3]

Runs the newest ``UAVSearch-<scenario>-Heading`` task's batched vector env from a seeded reset
under seeded random actions (20 warm-up steps first) and times each step with the process's
CPU clock (``time.process_time``, one thread), sorted by kind: an *autoreset* step (some envs
ended at the step before and start afresh), a step where every agent is live, and a step
where some agents have finished. Prints the count, the median CPU time and, for autoreset
steps, how many envs reset on average; with ``--memory`` a second pass of the same steps under
:mod:`tracemalloc` prints the largest peak allocation per env of each kind (numpy's arrays;
numba's scratch inside kernels is not seen).

``--sb3`` times the SB3 ``VecEnv`` of ``poc-env train --task`` on ``bench peers``' SB3 task
instead (:data:`~poc_env.agents.benchmarks.breakdown.SB3_TASK`, ``TrainArgs``' swarms; a
``step`` is ``step_async`` + ``step_wait`` of every slot, autoresets included): the mean and
median CPU time of a step, the env's share of ``bench peers``' SB3 pair.

It imports ``poc_env`` from ``PYTHONPATH``, so one copy of this file times any tree: run it
alternately over two trees on a loaded machine and compare the medians of the pairs.
"""

from __future__ import annotations

import argparse
import statistics
import time
import tracemalloc

KINDS = ("autoreset", "every agent live", "some finished")


def _env_and_actions(scenario: str, envs: int, steps: int, seed: int):
    from poc_env.agents.benchmarks.breakdown import warm_vec_env

    return warm_vec_env(scenario, envs, steps, seed)


def _kind(env) -> str:
    inner = env.unwrapped
    if inner._autoreset.any():
        return KINDS[0]
    return KINDS[1] if inner._live.all() else KINDS[2]


def time_steps(scenario: str, envs: int, steps: int, seed: int = 0) -> dict[str, dict]:
    """Per kind: ``count``, ``median_ms`` (CPU) and ``envs_reset`` (mean); ``whole`` too."""
    env, acts = _env_and_actions(scenario, envs, steps, seed)
    times: dict[str, list[float]] = {k: [] for k in KINDS}
    resets: list[int] = []
    for a in acts:
        kind = _kind(env)
        if kind == KINDS[0]:
            resets.append(int(env.unwrapped._autoreset.sum()))
        t = time.process_time()
        env.step(a)
        times[kind].append((time.process_time() - t) * 1e3)
    out = {
        k: {"count": len(v), "median_ms": statistics.median(v) if v else float("nan")}
        for k, v in times.items()
    }
    out[KINDS[0]]["envs_reset"] = statistics.mean(resets) if resets else 0.0
    every = [x for v in times.values() for x in v]
    out["whole"] = {"count": len(every), "mean_ms": statistics.mean(every)}
    return out


def peak_per_env(scenario: str, envs: int, steps: int, seed: int = 0) -> dict[str, float]:
    """Per kind: the largest tracemalloc peak of one step, in KiB per env."""
    env, acts = _env_and_actions(scenario, envs, steps, seed)
    peaks: dict[str, list[int]] = {k: [] for k in KINDS}
    for a in acts:
        kind = _kind(env)
        tracemalloc.start()
        tracemalloc.reset_peak()
        base = tracemalloc.get_traced_memory()[0]
        out = env.step(a)
        peaks[kind].append(tracemalloc.get_traced_memory()[1] - base)
        tracemalloc.stop()
        del out
    return {k: max(v) / envs / 1024 for k, v in peaks.items() if v}


def time_sb3_steps(steps: int, seed: int = 0) -> dict[str, float]:
    """``count``, ``mean_ms`` and ``median_ms`` (CPU) of the SB3 task VecEnv's steps under
    seeded random actions, after 50 warm-up steps (``--sb3``)."""
    import numpy as np

    from poc_env.agents.benchmarks.breakdown import SB3_TASK
    from poc_env.agents.rl.args import TrainArgs
    from poc_env.agents.rl.train import make_env
    from poc_env.tasks import get_task

    args = TrainArgs(task=SB3_TASK, seed=seed, progress=False)
    env = make_env(args, get_task(SB3_TASK).load_scenario())
    env.seed(seed)
    env.reset()
    shape = (steps + 50, env.num_envs, *(env.action_space.shape or ()))
    acts = np.random.default_rng(seed).uniform(-1, 1, shape).astype(np.float32)
    for a in acts[:50]:
        env.step(a)
    times = []
    for a in acts[50:]:
        t = time.process_time()
        env.step(a)
        times.append((time.process_time() - t) * 1e3)
    mean, median = statistics.mean(times), statistics.median(times)
    return {"count": steps, "mean_ms": mean, "median_ms": median}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default="Small", help="task scenario part (default: Small)")
    ap.add_argument("--envs", type=int, default=256)
    ap.add_argument("--steps", type=int, default=800)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--memory", action="store_true", help="also the peak allocation per env")
    ap.add_argument("--sb3", action="store_true", help="the SB3 task VecEnv's steps instead")
    args = ap.parse_args(argv)
    if args.sb3:
        r = time_sb3_steps(args.steps, args.seed)
        print(f"SB3 VecEnv step {r['count']:4d} steps, mean {r['mean_ms']:.4f} ms CPU, "
              f"median {r['median_ms']:.4f} ms CPU")  # fmt: skip
        return
    rows = time_steps(args.scenario, args.envs, args.steps, args.seed)
    for k in KINDS:
        r = rows[k]
        extra = f", {r['envs_reset']:.1f} envs reset on average" if k == KINDS[0] else ""
        print(f"{k:17s} {r['count']:4d} steps, median {r['median_ms']:.3f} ms CPU{extra}")
    whole = rows["whole"]
    print(f"{'whole':17s} {whole['count']:4d} steps, mean {whole['mean_ms']:.3f} ms CPU")
    if args.memory:
        for k, v in peak_per_env(args.scenario, args.envs, args.steps // 2, args.seed).items():
            print(f"{k:17s} peak allocation of a step {v:.1f} KiB per env")


if __name__ == "__main__":
    main()
