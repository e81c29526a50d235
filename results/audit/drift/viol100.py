"""A scratch check of the i25 moving-target audit (README.md)."""

import collections

import numpy as np

from poc_env.agents.experiments.evaluate import play
from poc_env.agents.policies.registry import make_policy

for pol in ["spacetime_plan"]:
    for seed in (5000,):
        from poc_env.config import load_scenario
        from poc_env.envs.parallel import UAVSearchParallelEnv

        env = UAVSearchParallelEnv(
            scenario=load_scenario(
                "small",
                {
                    "target.model": "drift",
                    "target.current_kmh": [0.0, -100.0],
                    "target.diffusion_m2_s": 50,
                },
            )
        )
        cnt = collections.Counter()
        orig = env.step

        def step(act, orig=orig, cnt=cnt):
            out = orig(act)
            for _a, inf in out[4].items():
                for k, v in inf.items():
                    if k.startswith("violation_") and bool(v):
                        cnt[k] += 1
            return out

        env.step = step
        play(env, make_policy(pol), seed, None, lambda _: None)
        print(pol, seed, dict(cnt), "drift kmh", np.round(env.sim_state.drift[0] * 3.6, 1))
