"""i24-gainhour: every flying UAV of saved plans against its floor per flight hour (a script).

``python floorcheck.py SCENARIO PLAN [PLAN ...]``: per plan (``with_uavs`` its size), each
flying UAV's marginal planned POS (the sampled eq. 14 total less the total without it), its
eq. 17 hours and POS per hour, the least POS per hour, and the UAVs below the plan's
``gain_per_hour`` (its options' or the default). The rule tries only the UAVs whose credit
swept first or last is below their floor (an upper bound of the marginal): this checks the
ones it did not try as well.
"""

import json
import sys
from pathlib import Path

from poc_env.agents.planning.allocation import sampled_sweep
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior

sc0 = load_scenario(sys.argv[1])
for f in sys.argv[2:]:
    p = json.loads(Path(f).read_text())
    sc = sc0.with_uavs(len(p["uavs"]))
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map)
    g = p["optimizer"]["settings"].get("options", {}).get("gain_per_hour",
                                                          PlanOptions.gain_per_hour)  # fmt: skip
    paths = [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else []
             for u in p["uavs"]]  # fmt: skip
    total = sum(sampled_sweep(sc, grid, prior, paths)[0])
    rows = []
    for k, u in enumerate(p["uavs"]):
        if u["waypoints_m"]:
            rest = [q if j != k else [] for j, q in enumerate(paths)]
            m = total - sum(sampled_sweep(sc, grid, prior, rest)[0])
            h = u["flight_time_s"] / 3600
            rows.append((m / h, u["id"], h, m))
    rows.sort()
    below = [r[1] for r in rows if r[3] < g * r[2] * float(prior.sum())]
    print(f"{f}: {len(rows)} flying, posc {p['posc']:.6f}, gain_per_hour {g:g}; least POS per "
          "hour: " + ", ".join(f"UAV {i} {m:.2e} in {h:.2f} h ({r:.2e}/h)"
                               for r, i, h, m in rows[:4])
          + f"; below the floor: {below}", flush=True)  # fmt: skip
