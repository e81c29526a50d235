"""Peak memory (tracemalloc) of a DE plan against limits.plan_bytes, from the checkout root
with big.yaml (make_inputs.py) in the folder: python demem2.py > demem2.log"""

import tracemalloc
import warnings

from poc_env import limits
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario

warnings.simplefilter("ignore")
limits.set_memory_limit_gb(1000)
cases = [
    ("small", {}, 3, 10000),
    ("small", {}, 3, 1000),
    ("paper_6_2", {}, 6, 1000),
    ("paper_6_2", {}, 6, 4000),
    ("paper_6_2", {}, 24, 1000),
    ("paper_6_2", {"map.cell_km": 1}, 6, 400),
    ("big.yaml", {}, 24, 100),
    ("big.yaml", {}, 64, 400),
    ("big.yaml", {}, 64, 2000),
]
for name, over, n, pop in cases:
    sc = load_scenario(name, over)
    make_plan(sc, uavs=n, popsize=pop, maxiter=1)
    tracemalloc.start()
    make_plan(sc, uavs=n, popsize=pop, maxiter=2)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    cells = sc.map.nx * sc.map.ny
    est = limits.plan_bytes(pop, n, cells)
    print(
        f"{name} {over} N={n} P={pop} cells={cells}: peak {peak / 2**20:.1f} MiB, "
        f"est {est / 2**20:.0f} MiB",
        flush=True,
    )
