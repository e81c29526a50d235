"""A scratch check of the i25 moving-target audit (README.md): the violation flags (per UAV
and step) each policy flies on ``small`` with a drifting target.

``python viol.py`` (the Drift task's current, seeds 8000, 8001, allocation_plan and
spacetime_plan); ``python viol.py 100`` (a 100 km/h current south, seed 5000,
spacetime_plan).
"""

import collections
import sys

import numpy as np

from poc_env.agents.experiments.evaluate import play
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario
from poc_env.envs.parallel import UAVSearchParallelEnv

FAST = len(sys.argv) > 1
OVER = {"target.model": "drift", "target.diffusion_m2_s": 50}
if FAST:
    OVER["target.current_kmh"] = [0.0, -float(sys.argv[1])]
else:
    OVER["target.random_current_kmh"] = 25
POLICIES = ["spacetime_plan"] if FAST else ["allocation_plan", "spacetime_plan"]
SEEDS = (5000,) if FAST else (8000, 8001)

for pol in POLICIES:
    for seed in SEEDS:
        env = UAVSearchParallelEnv(scenario=load_scenario("small", OVER))
        cnt: collections.Counter = collections.Counter()
        orig = env.step

        def step(act, orig=orig, cnt=cnt):
            out = orig(act)
            for inf in out[4].values():
                for k, v in inf.items():
                    if k.startswith("violation_") and bool(v):
                        cnt[k] += 1
            return out

        env.step = step
        play(env, make_policy(pol), seed, None, lambda _: None)
        print(pol, seed, dict(cnt), "drift kmh", np.round(env.sim_state.drift[0] * 3.6, 1))
