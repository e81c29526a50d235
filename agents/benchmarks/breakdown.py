"""Where a step's time goes: ``poc-env bench peers --breakdown KEY``.

Runs one of our contenders of ``poc-env bench peers`` (``make_vec_small``,
``make_vec_paper62``, ``single`` or ``sb3_task``) with the functions of :data:`PARTS` wrapped
by timers of the process's CPU time (``time.process_time``: what other processes on a loaded
machine take is not counted, unlike wall time; one thread), and returns each part's CPU time
per step and its share of the whole (the first part). Parts nest (the core step is inside the
engine's step), so shares do not add up to 100 %. A wrapper costs about a microsecond per
call, which a part of a few microseconds shows: read the large parts.
"""

from __future__ import annotations

import contextlib
import importlib
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from poc_env.errors import ConfigError

#: ``(module, attribute path, label)`` of the timed parts of each contender, the whole first.
#: The batched adapters' step of every env at once: the single env's step (sim.single), nested.
_FAST = [
    ("poc_env.sim.single", "SingleStep.step", "- single step (sim.single.SingleStep.step)"),
    ("poc_env.sim.single", "SingleStep._core_step", "  - core step (SingleStep._core_step)"),
    ("poc_env.sim.single", "SingleStep._observe", "  - observations (SingleStep._observe)"),
    ("poc_env._kernels.observations", "compass", "    - compass kernel"),
    ("poc_env._kernels.observations", "coarse_poc", "    - coarse POC kernel"),
    ("poc_env.sim.single", "swarm_increments", "  - autopilot (control.swarm_increments)"),
    ("poc_env._kernels.observations", "vectors_of", "  - vectors kernel (observation, autopilot)"),
]
PARTS: dict[str, list[tuple[str, str, str]]] = {
    "make_vec_small": [
        ("poc_env.envs.gym_vector", "SwarmGymVectorEnv.step", "make_vec step (whole)"),
        ("poc_env.envs.gym_vector", "SwarmGymVectorEnv._whole_step", "whole-batch step"),
        *_FAST,
        ("poc_env.sim.engine", "Engine.step", "steps of some envs (Engine.step)"),
        ("poc_env.sim.engine", "Engine.reset", "resets (Engine.reset)"),
        ("poc_env.envs.gym_vector", "keep_rows", "finished agents' rows (keep_rows)"),
        ("poc_env.envs.gym_vector", "SwarmGymVectorEnv._infos", "info masks (_infos)"),
        ("poc_env.sim.engine", "mean_over", "reward mean (engine.mean_over)"),
    ],
    "single": [
        ("poc_env.envs.parallel", "UAVSearchParallelEnv.step", "parallel_env step (whole)"),
        ("poc_env.sim.single", "SingleStep.step", "single step (sim.single.SingleStep.step)"),
        (
            "poc_env.sim.single",
            "SingleStep._core_step",
            "- core step and its end (SingleStep._core_step)",
        ),
        (
            "poc_env._kernels.sensing",
            "fly_sense",
            "  - kinematics, sensing and hidden target kernel (eq. 19, 12-14)",
        ),
        (
            "poc_env._kernels.swarm",
            "step_end",
            "  - bookkeeping, topology, rewards, episode end, infos kernel",
        ),
        ("poc_env.sim.single", "SingleStep._observe", "- observations (SingleStep._observe)"),
        ("poc_env._kernels.observations", "rasters_vectors", "  - rasters and vectors kernel"),
        ("poc_env.sim.single", "swarm_increments", "- autopilot (control.swarm_increments)"),
        ("poc_env.envs.parallel", "UAVSearchParallelEnv._actions_array", "action dict to array"),
        ("poc_env.envs.parallel", "UAVSearchParallelEnv._fast_infos", "per-agent info dicts"),
        ("poc_env.envs.parallel", "UAVSearchParallelEnv._agent_obs", "per-agent obs dict"),
    ],
    "sb3_task": [
        ("", "", "SB3 PPO learn (whole)"),
        ("poc_env.envs.vector", "SwarmVecEnv.step_wait", "env step_wait"),
        ("poc_env.envs.vector", "SwarmVecEnv._engine_step", "- engine step (_engine_step)"),
        *_FAST,
        ("poc_env.sim.engine", "Engine.reset", "- resets (Engine.reset)"),
        ("poc_env.envs.vector", "SwarmVecEnv.step_async", "env step_async"),
    ],
}
PARTS["make_vec_paper62"] = PARTS["make_vec_small"]
#: The ``make_vec`` batch of each key when none is given (``bench peers``' default sizes).
ENVS = {"make_vec_small": 256, "make_vec_paper62": 64}
#: The task of the SB3 pair (issue 26: ``poc-env train --task`` on Paper62-Random-Heading).
SB3_TASK = "UAVSearch-Paper62-Random-Heading-v0"


def heading_task(scenario: str) -> str:
    """The newest ``UAVSearch-<scenario>-Heading`` task id."""
    from poc_env import spec, tasks

    return tasks.task_id(scenario, "Heading", False, spec.versions_of("Heading")[-1].version)


@contextlib.contextmanager
def timed(parts: list[tuple[str, str, str]], totals: dict[str, float]) -> Iterator[None]:
    """Wrap each part's function with a CPU timer adding into ``totals[label]``; restore after."""
    saved: list[tuple[Any, str, Any]] = []
    try:
        for module, path, label in parts:
            if not module:
                continue
            owner: Any = importlib.import_module(module)
            *outer, name = path.split(".")
            for attr in outer:
                owner = getattr(owner, attr)
            fn = owner.__dict__[name] if isinstance(owner, type) else getattr(owner, name)
            saved.append((owner, name, fn))
            setattr(owner, name, _timer(fn, label, totals))
        yield
    finally:
        for owner, name, fn in reversed(saved):
            setattr(owner, name, fn)


def _timer(fn: Callable, label: str, totals: dict[str, float]) -> Callable:
    clock = time.process_time

    def wrapped(*args: Any, **kwargs: Any) -> Any:
        t = clock()
        try:
            return fn(*args, **kwargs)
        finally:
            totals[label] += clock() - t

    return wrapped


def warm_vec_env(scenario: str, envs: int, steps: int, seed: int):
    """``make_vec`` of ``scenario``'s Heading task, reset with ``seed`` and stepped 20 times
    (compilation, caches), and ``steps`` seeded random actions for it to time."""
    import gymnasium

    import poc_env  # noqa: F401  (registers the tasks)

    env = gymnasium.make_vec(
        heading_task(scenario), num_envs=envs, vectorization_mode="vector_entry_point"
    )
    env.reset(seed=seed)
    shape = (steps + 20, *(env.action_space.shape or ()))
    acts = np.random.default_rng(seed).uniform(-1, 1, shape).astype(np.float32)
    for a in acts[:20]:  # warm-up: compilation, caches
        env.step(a)
    return env, acts[20:]


def _make_vec(scenario: str, envs: int, steps: int, seed: int) -> Callable[[], int]:
    env, acts = warm_vec_env(scenario, envs, steps, seed)

    def run() -> int:
        for a in acts:
            env.step(a)
        return steps

    return run


def _single(steps: int, seed: int) -> Callable[[], int]:
    import poc_env

    env = poc_env.parallel_env("paper_6_2")
    rng = np.random.default_rng(seed)
    n = len(env.possible_agents)
    acts = rng.uniform(-1.0, 1.0, (steps + 50, n, 3))
    acts[..., 2] = 0.0
    plan = [dict(zip(env.possible_agents, row, strict=True)) for row in acts]

    def go(rows: list[dict]) -> int:
        count = 0
        for actions in rows:
            if not env.agents:  # a new episode with the UAVs over the area, as bench peers
                env.reset(seed=int(rng.integers(2**31)))
                st = env.sim_state
                x0, y0, x1, y1 = env.params.grid.bounds
                st.pos[..., 0] = rng.uniform(x0, x1, st.pos.shape[:2])
                st.pos[..., 1] = rng.uniform(y0, y1, st.pos.shape[:2])
            env.step({a: actions[a] for a in env.agents})
            count += 1
        return count

    go(plan[:50])
    return lambda: go(plan[50:])


def breakdown(key: str, steps: int = 400, seed: int = 0, envs: int | None = None) -> list[dict]:
    """The parts of contender ``key``'s step (:data:`PARTS`): rows ``{"part", "ms_per_step",
    "share"}``, CPU milliseconds per env step (per joint step of the batch; per environment
    step of SB3's VecEnv) and the share of the first part, over ``steps`` steps after a
    warm-up (SB3: one PPO iteration, then two). ``envs``: the batch of ``make_vec`` (default
    ``bench peers``' sizes)."""
    if key not in PARTS:
        raise ConfigError("breakdown", key, "one of " + ", ".join(PARTS))
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ConfigError("steps", steps, "an integer >= 1")
    parts = PARTS[key]
    totals: dict[str, float] = defaultdict(float)
    if key == "sb3_task":
        run = _sb3(seed)
        with timed(parts, totals):
            t0 = time.process_time()
            n = run()
            totals[parts[0][2]] = time.process_time() - t0
    else:
        run = (
            _single(steps, seed)
            if key == "single"
            else _make_vec(
                "Small" if key == "make_vec_small" else "Paper62", envs or ENVS[key], steps, seed
            )
        )
        with timed(parts, totals):
            n = run()
    whole = totals[parts[0][2]] or 1.0
    return [
        {
            "part": label,
            "ms_per_step": round(1e3 * totals[label] / n, 4),
            "share": round(100.0 * totals[label] / whole, 1),
        }
        for _m, _p, label in parts
    ]


def _sb3(seed: int) -> Callable[[], int]:
    """Two timed PPO iterations of ``bench peers``' ``sb3_task`` contender (``poc-env train
    --task SB3_TASK``'s env and model, the shipped settings) after a warm-up one."""
    import torch as th

    from poc_env.agents.rl.args import TrainArgs
    from poc_env.agents.rl.train import make_env, make_model, seed_everything
    from poc_env.tasks import get_task

    th.set_num_threads(1)
    args = TrainArgs(task=SB3_TASK, seed=seed, progress=False)
    env = make_env(args, get_task(SB3_TASK).load_scenario())
    seed_everything(seed)
    model = make_model(args, env, None)
    model.learn(args.n_steps * env.num_envs)

    def run() -> int:
        model.learn(2 * args.n_steps * env.num_envs, reset_num_timesteps=False)
        return 2 * args.n_steps

    return run


def markdown(key: str, rows: list[dict], load: tuple[float, float]) -> str:
    head = (
        f"`poc-env bench peers --breakdown {key}`: CPU time per step (time.process_time, one "
        f"thread); load average (1 min) {load[0]:.2f} before, {load[1]:.2f} after.\n\n"
        "| part | ms per step (CPU) | share |\n|---|---|---|\n"
    )
    return head + "".join(
        f"| {r['part']} | {r['ms_per_step']:.4f} | {r['share']} % |\n" for r in rows
    )


if __name__ == "__main__":  # python agents/benchmarks/breakdown.py KEY: any tree's package
    import os
    import sys

    _key = sys.argv[1] if len(sys.argv) > 1 else "make_vec_small"
    _load0 = os.getloadavg()[0]
    _rows = breakdown(_key)
    print(markdown(_key, _rows, (_load0, os.getloadavg()[0])), end="")
