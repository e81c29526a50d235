import collections
import sys

import poc_env
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario

scen = sys.argv[1]
pol = sys.argv[2] if len(sys.argv) > 2 else "allocation_plan"
uavs = int(sys.argv[3]) if len(sys.argv) > 3 else None
sc = load_scenario(scen)
if uavs:
    sc = sc.with_uavs(uavs)
env = poc_env.parallel_env(sc)
obs, infos = env.reset(seed=5000)
p = make_policy(pol)
p.reset(env, 5000)
cnt = collections.Counter()
first = {}
t = 0
while env.agents:
    act, _ = p.predict(obs)
    obs, r, te, tr, infos = env.step(act)
    t += 1
    for a, inf in infos.items():
        for k, v in inf.items():
            if k.startswith("violation_") and v:
                cnt[k] += 1
                first.setdefault((k, a), t)
print(pol, "posc", round(float(env.sim_state.posc[0]), 4), "steps", t, dict(cnt))
byk = collections.defaultdict(list)
for (k, a), tt in first.items():
    byk[k].append((a, tt))
for k, v in byk.items():
    print(k, len(v), "agents; first steps", sorted(v, key=lambda x: x[1])[:6])
