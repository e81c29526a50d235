"""Env-only throughput of the residual training env against the plain set-task env
(paper_6_2, 4 swarms, zero/ random actions, one thread), measured interleaved in one run.

    PYTHONPATH=. OMP_NUM_THREADS=1 python results/guided/bench_env.py
"""

import time

import numpy as np

from poc_env.agents.rl.residual import ResidualVecEnv
from poc_env.envs.vector import SwarmVecEnv
from poc_env.tasks import get_task

task = get_task("UAVSearch-Paper62-Random-Set-Heading-v1")
sc = task.load_scenario({})


def make(kind):
    if kind == "set task env":
        return SwarmVecEnv(
            sc, n_envs=4, seed=0, obs_type="set", random_priors=True, control=task.kwargs["control"]
        )
    pool = {"residual, pool 4 (plans cached)": 4, "residual, pool 0 (plan every episode)": 0}[kind]
    return ResidualVecEnv(
        sc,
        n_envs=4,
        seed=0,
        obs_type="set",
        random_priors=True,
        teacher="allocation_plan",
        pool=pool,
    )


kinds = ["set task env", "residual, pool 4 (plans cached)", "residual, pool 0 (plan every episode)"]
envs = {k: make(k) for k in kinds}
for env in envs.values():  # warm-up: the kernels' compilation, the pool's plans
    env.reset()
    for _ in range(400):
        env.step(np.zeros((env.num_envs, env.action_space.shape[0])))
rates = {k: [] for k in kinds}
for rep in range(3):
    for k, env in envs.items():
        rng = np.random.default_rng(rep)
        t = time.process_time()
        steps = 360  # two episodes of every swarm (180-step horizon)
        for _ in range(steps):
            a = rng.uniform(-1, 1, (env.num_envs, env.action_space.shape[0])) * 0.1
            env.step(a)
        rates[k].append(steps * env.num_envs / (time.process_time() - t))
for k in kinds:
    print(f"{k:40s} {np.median(rates[k]):9.0f} agent transitions per CPU second (median of 3)")
