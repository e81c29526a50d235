"""A scratch check of the i25 moving-target audit (README.md)."""

import numpy as np

from poc_env.tasks import make_parallel

for task, over in [
    ("UAVSearch-Small-Drift-Heading-v1", {}),
    ("UAVSearch-Small-Drift-Heading-v1", {"target__random_current_kmh": 100.0}),
    (
        "UAVSearch-Small-Drift-Heading-v1",
        {"target__current_kmh": [200.0, -150.0], "target__random_current_kmh": 0.0},
    ),
]:
    env = make_parallel(task, **over)
    bad = 0
    mx = -1e9
    mn = 1e9
    for seed in range(3):
        obs, info = env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        done = False
        n = 0
        while env.agents:
            act = {a: env.action_space(a).sample() for a in env.agents}
            obs, rew, term, trunc, info = env.step(act)
            for a, o in obs.items():
                sp = env.observation_space(a)
                if not sp.contains(o):
                    bad += 1
                    if bad < 3:
                        i = np.where((o < sp.low) | (o > sp.high))[0]
                        print(
                            "out",
                            task,
                            over,
                            seed,
                            n,
                            a,
                            i[:5],
                            o[i[:5]],
                            sp.low[i[:5]],
                            sp.high[i[:5]],
                        )
                mx = max(mx, float(np.max(o)))
                mn = min(mn, float(np.min(o)))
            n += 1
    print(task, over, "bad", bad, "range", mn, mx)
