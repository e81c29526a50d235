import numpy as np

import poc_env
from poc_env import spec

for obs in ("compass", "set"):
    for n in (1, 2, 64):
        env = poc_env.parallel_env(
            scenario="wide_400",
            control="heading",
            random_prior=True,
            obs_type=obs,
            fleet=spec.fleet_of(n),
        )
        o, _ = env.reset(seed=1)
        rng = np.random.default_rng(0)
        bad = 0
        nan = 0
        while env.agents:
            o, r, te, tr, inf = env.step({a: rng.uniform(-1, 1, 2) for a in env.agents})
            for a, x in o.items():
                nan += int(~np.isfinite(x).all())
                bad += int(not env.observation_space(a).contains(x))
            nan += sum(int(not np.isfinite(v)) for v in r.values())
        print(obs, n, "nan", nan, "outside", bad, "posc", round(float(env.sim_state.posc[0]), 4))
