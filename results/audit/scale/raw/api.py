import resource
import sys
import time

import numpy as np
from pettingzoo.test import api_test, parallel_api_test

import poc_env
from poc_env import spec

n = int(sys.argv[1])
kw = dict(
    scenario="wide_400",
    control="heading",
    random_prior=True,
    obs_type="set",
    fleet=spec.fleet_of(n),
)
env = poc_env.parallel_env(**kw)
t = time.perf_counter()
parallel_api_test(env, num_cycles=50)
print(n, "parallel_api_test ok", round(time.perf_counter() - t, 1), "s")
aec = poc_env.env(**kw)
api_test(aec, num_cycles=20)
print(n, "aec api_test ok")
# random rollout to end, observations in spaces
env = poc_env.parallel_env(**kw)
obs, info = env.reset(seed=5)
rng = np.random.default_rng(1)
steps = 0
bad = 0
while env.agents:
    acts = {
        a: env.action_space(a).sample()
        if False
        else rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32)
        for a in env.agents
    }
    obs, r, te, tr, info = env.step(acts)
    steps += 1
    for a, o in obs.items():
        if not env.observation_space(a).contains(o):
            bad += 1
print(n, "rollout steps", steps, "obs outside space", bad, "posc", float(env.sim_state.posc[0]))
print("maxrss MB", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
