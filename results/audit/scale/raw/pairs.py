import collections
import sys

import numpy as np

import poc_env
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario

sc = load_scenario(sys.argv[1])
env = poc_env.parallel_env(sc)
obs, infos = env.reset(seed=5000)
p = make_policy("allocation_plan")
p.reset(env, 5000)
d_s = sc.uav.safe_distance_m if hasattr(sc.uav, "safe_distance_m") else None
print(
    "d_s",
    d_s,
    [f for f in dir(sc.uav) if "safe" in f or "sep" in f],
    [f for f in dir(sc.episode) if "safe" in f],
)
pairs = collections.Counter()
t = 0
while env.agents:
    act, _ = p.predict(obs)
    obs, r, te, tr, infos = env.step(act)
    t += 1
    st = env.sim_state
    xy = st.pos[0, :, :2]
    fl = st.flying[0]
    d = np.hypot(*(xy[:, None] - xy[None]).transpose(2, 0, 1))
    for i in range(len(xy)):
        for j in range(i + 1, len(xy)):
            if fl[i] and fl[j] and d[i, j] < 1000 * float(sys.argv[2]):
                pairs[(i + 1, j + 1)] += 1
print(sorted(pairs.items(), key=lambda x: -x[1])[:15])
