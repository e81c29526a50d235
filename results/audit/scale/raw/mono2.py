import sys

import numpy as np

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid

cell = float(sys.argv[1])
zone = [[100, 150], [175, 150], [175, 225], [100, 225]]
sc0 = load_scenario("large_400", {"map.cell_km": cell, "map.no_fly_zones_km": [zone]})
g = Grid.from_config(sc0.map)
prior = np.zeros(g.shape)
for x, y, w in [
    (160.9, 151.6, 0.1),
    (139.1, 226.6, 0.1),
    (301.6, 45.3, 0.06),
    (123.4, 98.4, 0.12),
    (373.4, 126.6, 0.1),
    (251.6, 273.4, 0.06),
    (26.6, 380, 0.15),
    (160.9, 380, 0.09),
    (307.8, 380, 0.04),
]:
    prior[int(y // cell), int(x // cell)] += w
prior /= prior.sum()
for n in [int(v) for v in sys.argv[2].split(",")]:
    p = make_allocation_plan(sc0.with_uavs(n), prior=prior)
    u = p["uavs"]
    print(
        cell,
        n,
        "posc",
        round(p["posc"], 4),
        "upper",
        round(p["upper_bound"], 4),
        "no route",
        sum(1 for x in u if not x["waypoints_m"]),
        flush=True,
    )
