"""Each flying UAV's marginal planned POS (the plan's sampled eq. 14 total less the total
without it) beside its credit in plan order, for UAVs crediting below 1e-3 (probe 8):
``python marginal.py SCENARIO PLAN``."""

import json
import sys
from pathlib import Path

from poc_env.agents.planning.allocation import sampled_sweep
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior

p = json.loads(Path(sys.argv[2]).read_text())
sc = load_scenario(sys.argv[1]).with_uavs(len(p["uavs"]))
grid = Grid.from_config(sc.map)
prior = build_prior(sc.map)
paths = [
    [u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else []
    for u in p["uavs"]
]
pos, _ = sampled_sweep(sc, grid, prior, paths)
tot = sum(pos)
print(f"plan posc {p['posc']:.6f} resampled {tot:.6f} mass {prior.sum():.6f}")
for k, u in enumerate(p["uavs"]):
    if u["waypoints_m"] and pos[k] < 1e-3:
        rest = [q if j != k else [] for j, q in enumerate(paths)]
        without = sum(sampled_sweep(sc, grid, prior, rest)[0])
        hours = u["flight_time_s"] / 3600
        print(f"UAV {u['id']}: {hours:.2f} h, credit {pos[k]:.2e}, marginal {tot - without:.2e}")
