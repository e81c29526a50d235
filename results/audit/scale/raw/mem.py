import sys
import tracemalloc

import numpy as np

from poc_env import limits, spec
from poc_env.sim.engine import make_engine

n, cell, comms, n_envs = (
    int(sys.argv[1]),
    float(sys.argv[2]),
    sys.argv[3] == "comms",
    int(sys.argv[4]),
)
over = {"map.cell_km": cell, "comms.belief_sharing": "comms" if comms else "global"}
tracemalloc.start()
eng = make_engine(
    n_envs,
    scenario="wide_400",
    control="heading",
    random_prior=True,
    obs_type="set",
    fleet=spec.fleet_of(n),
    overrides=over,
    seeds=list(range(n_envs)),
)
eng.reset()
a = np.zeros((n_envs, n, 2))
for _ in range(5):
    eng.step(a)
cur, peak = tracemalloc.get_traced_memory()
g = eng.params.grid if hasattr(eng.params, "grid") else None
cells = int(np.prod(eng.priors.shape[1:]))
s = eng.scenario.sensor.samples_per_cell
est = limits.env_bytes(cells, s, n, n_envs, comms)
print(
    f"N={n} cell={cell} km cells={cells} s={s} comms={comms} envs={n_envs}: "
    f"peak {peak / 2**20:.0f} MiB, held {cur / 2**20:.0f} MiB, "
    f"guard estimate {est / 2**20:.0f} MiB, ratio peak/est {peak / est:.2f}"
)
