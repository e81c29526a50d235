"""Each flying UAV's marginal planned POS (the plan's sampled eq. 14 total less the total
without it) and its credit in plan order, for UAVs whose credit is below 1e-4 of the mass."""
import json, sys
import numpy as np
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.agents.planning.allocation import sampled_sweep

sc = load_scenario(sys.argv[1]); p = json.load(open(sys.argv[2]))
sc = sc.with_uavs(len(p["uavs"]))
grid = Grid.from_config(sc.map); prior = build_prior(sc.map)
paths = [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else [] for u in p["uavs"]]
pos, _ = sampled_sweep(sc, grid, prior, paths); tot = sum(pos)
print(f"plan posc {p['posc']:.6f} resampled {tot:.6f} mass {prior.sum():.6f}")
for k, u in enumerate(p["uavs"]):
    if u["waypoints_m"] and pos[k] < 1e-3:
        without = sum(sampled_sweep(sc, grid, prior, [q if j != k else [] for j, q in enumerate(paths)])[0])
        print(f"UAV {u['id']}: {u['flight_time_s']/3600:.2f} h, credit {pos[k]:.2e}, marginal {tot-without:.2e}")
