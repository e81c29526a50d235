import sys
import time

import numpy as np

from poc_env import spec
from poc_env.sim.engine import make_engine

obs_type, control, n_envs = sys.argv[1], sys.argv[2], int(sys.argv[3])
ns = [int(x) for x in sys.argv[4].split(",")]
scen = sys.argv[5] if len(sys.argv) > 5 else "wide_400"
rng = np.random.default_rng(0)
for n in ns:
    eng = make_engine(
        n_envs,
        scenario=scen,
        control=control,
        random_prior=True,
        obs_type=obs_type,
        fleet=spec.fleet_of(n),
        seeds=list(range(n_envs)),
    )
    dim = eng.action_dim
    a = np.zeros((n_envs, n, dim))  # straight on: nobody lands early
    best = 1e9
    for _rep in range(4):
        eng.reset(with_info=False)
        for _ in range(2):
            eng.step(a, with_info=False)
        t = time.perf_counter()
        k = 30
        for _ in range(k):
            eng.step(a, with_info=False)
        best = min(best, (time.perf_counter() - t) / k)
    fly = int(np.asarray(eng.current.flying).sum()) if hasattr(eng.current, "flying") else -1
    print(
        f"{scen} {obs_type} {control} envs={n_envs} N={n}: {best * 1e3:.3f} ms/step  "
        f"{n_envs / best:.0f} env-steps/s  {n * n_envs / best:.0f} agent-steps/s  "
        f"flying_at_end={fly}",
        flush=True,
    )
