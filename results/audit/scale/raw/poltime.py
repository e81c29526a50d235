import sys
import time

import poc_env
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario

pol = sys.argv[1]
for n in [int(x) for x in sys.argv[2].split(",")]:
    sc = load_scenario("wide_400", {"episode.horizon_steps": 20}).with_uavs(n)
    env = poc_env.parallel_env(sc, random_prior=True)
    obs, _ = env.reset(seed=5000)
    p = make_policy(pol)
    t0 = time.perf_counter()
    p.reset(env, 5000)
    t1 = time.perf_counter()
    k = 0
    while env.agents:
        a, _ = p.predict(obs)
        obs, *_ = env.step(a)
        k += 1
    t2 = time.perf_counter()
    print(
        f"{pol} N={n}: reset {t1 - t0:.2f} s, {1e3 * (t2 - t1) / k:.1f} ms/step over {k} steps",
        flush=True,
    )
