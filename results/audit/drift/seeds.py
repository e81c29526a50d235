"""A scratch check of the i25 moving-target audit (README.md)."""

import numpy as np

from poc_env.tasks import make_parallel


def run(env, seed, steps=30):
    obs, _ = env.reset(seed=seed)
    out = []
    for _t in range(steps):
        act = {a: np.full(env.action_space(a).shape, 0.3, dtype=np.float32) for a in env.agents}
        obs, _r, *_ = env.step(act)
        out.append(np.concatenate([obs[a] for a in sorted(obs)]))
    return np.array(out)


e1 = make_parallel("UAVSearch-Small-Drift-Heading-v1")
a = run(e1, 7)
b = run(e1, 7)
c = run(e1, 8)
e2 = make_parallel("UAVSearch-Small-Drift-Heading-v1")
d = run(e2, 7)
print(
    "same seed same env",
    np.array_equal(a, b),
    "fresh env",
    np.array_equal(a, d),
    "other seed differs",
    not np.array_equal(a, c),
)
u = e1
while hasattr(u, "env") and not hasattr(u, "sim_state"):
    u = u.env
print(type(u), getattr(getattr(u, "sim_state", None), "drift", None))
