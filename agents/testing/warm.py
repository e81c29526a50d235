"""Compile the numba kernels once, in one process, before the suite's workers start.

Every kernel is compiled with ``cache=True`` (:mod:`poc_env._kernels`): the first process that
calls it with a new signature compiles it and writes the machine code beside its source; a
later process loads it. Under ``pytest -n 2`` both workers start cold and each compiles the same
kernels at the same time (about 100 s of CPU in one process on a fresh clone, 4.5 s once
cached). :func:`warm` flies a workload that calls most of them -- every registered task's
first steps and a deep copy's, the batched cores, the allocation planner with and without its
polish, the DE planner, the objective's rectangle masses -- so that ``tests/conftest.py`` can
run it once in the controlling process, on a fresh checkout only (:func:`cold`), and the
workers load what it wrote. What it misses is compiled by the workers as before: it changes
when code is compiled, never what a test checks.

``python -m poc_env.agents.testing.warm`` runs it alone and prints the time.
"""

from __future__ import annotations

import time
from pathlib import Path


def step_index() -> Path | None:
    """Where numba keeps the cache index of the eq. 19-24 step kernel, or None if numba no longer
    records it where this reads (a private attribute)."""
    from poc_env._kernels import swarm

    try:
        return Path(swarm.step._cache._cache_file._index_path)  # type: ignore[attr-defined]
    except AttributeError:
        return None


def cold() -> bool:
    """True if the step kernel has no cache index yet: nothing was compiled here. False if
    :func:`step_index` cannot tell (the suite then compiles in its workers, as before)."""
    index = step_index()
    return index is not None and not index.exists()


def warm() -> None:
    """Call the compiled kernels the suite uses most, each once (a few seconds once cached)."""
    import copy
    import warnings

    import gymnasium
    import numpy as np

    import poc_env
    from poc_env.agents.planning.allocation import make_allocation_plan
    from poc_env.agents.planning.options import PlanOptions
    from poc_env.agents.planning.planner import make_plan
    from poc_env.config import load_scenario
    from poc_env.envs.vector import SwarmVecEnv
    from poc_env.theory.probability_map import Grid
    from poc_env.theory.regions import area_fractions, boundary_mass, exclusive_fractions

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for tid in sorted(k for k in gymnasium.registry if k.startswith("poc_env/")):
            env = gymnasium.make(tid)
            env.action_space.seed(0)
            env.reset(seed=0)
            for _ in range(10 if "Drift" in tid else 3):
                env.step(env.action_space.sample())
            # a copy (as the suite's copies and pickled workers make) holds writeable arrays
            # where the original's are read-only: numba compiles that signature apart
            twin = copy.deepcopy(env)
            twin.step(env.action_space.sample())
            env.close()
        vec = gymnasium.make_vec(
            "poc_env/UAVSearch-Small-Heading-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
        )
        vec.action_space.seed(0)
        vec.reset(seed=0)
        for _ in range(3):
            vec.step(vec.action_space.sample())
        vec.close()
        par = poc_env.parallel_env("small")
        par.reset(seed=0)
        for i, a in enumerate(par.agents):
            par.action_space(a).seed(i)
        for _ in range(3):
            par.step({a: par.action_space(a).sample() for a in par.agents})
        sb3 = SwarmVecEnv("small", n_envs=2, seed=0)
        sb3.action_space.seed(0)
        sb3.reset()
        for _ in range(3):
            sb3.step(np.stack([sb3.action_space.sample() for _ in range(sb3.num_envs)]))
        make_allocation_plan("small")
        make_allocation_plan("small", options=PlanOptions.preset("standard"))
        make_plan("small", popsize=8, maxiter=2)
        grid = Grid.from_config(load_scenario("paper_6_2").map)
        rng = np.random.default_rng(0)
        center = rng.uniform(0.0, grid.bounds[2], (4, 3, 2))
        ln, wd, th = (rng.uniform(1.0, 3.0, (4, 3)) * grid.cell_m for _ in range(3))
        weights = rng.random(grid.shape)
        area_fractions(grid, center, ln, wd, th)
        exclusive_fractions(grid, center, ln, wd, th)
        for exclusive in (False, True):
            boundary_mass(grid, center, ln, wd, th, weights, exclusive=exclusive)


def main() -> None:
    start = time.perf_counter()
    warm()
    print(f"warm: {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
