"""Would sortie 2 find more if the planner saw the belief on half cells? (an experiment; replan
unchanged)

Usage: python results/audit/replan/half_cells.py SCENARIO SEED0 SEED1 OUT.json
On the random priors SEED0..SEED1-1 (validation priors: 5000-...), sortie 1 by the allocation
planner, then sortie 2 two ways: ``next_sortie`` as replan plans it (the planner on the cells'
belief), and the planner on a scenario with cells half as wide and half the sample points per
cell side (the same sample lattice), given the sample points' belief summed onto those half
cells. Both sortie-2 plans are scored the same way: their routes swept over the sample points'
belief sortie 1 left (``sortie_posc``). Records rewritten after every seed.
"""

import json
import sys
import time
from pathlib import Path

import numpy as np

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.planning.replan import next_sortie, plan_paths, sweep_points
from poc_env.config import load_scenario, parse_overrides
from poc_env.theory.probability_map import Grid

name, s0, s1, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), Path(sys.argv[4])
sc = load_scenario(name)
s = sc.sensor.samples_per_cell
assert s % 2 == 0, "half cells need an even number of sample points per cell side"
half = load_scenario(
    name,
    parse_overrides([f"map.cell_km={sc.map.cell_m / 2000}", f"sensor.samples_per_cell={s // 2}"]),
)
grid, hgrid = Grid.from_config(sc.map), Grid.from_config(half.map)
records = []
for seed in range(s0, s1):
    prior = episode_prior(name, seed)
    p1 = make_plan(sc, prior=prior, planner="allocation", seed=seed)
    t0 = time.perf_counter()
    cells = next_sortie(sc, prior, [p1], seed=seed)
    t1 = time.perf_counter()
    fine = np.ascontiguousarray(grid.refine(prior, s))
    searched = sweep_points(sc, fine, plan_paths(p1))
    p2 = make_plan(half, prior=hgrid.coarsen(fine, s // 2), planner="allocation", seed=seed)
    t2 = time.perf_counter()
    gain = sweep_points(sc, fine.copy(), plan_paths(p2))
    rec = {
        "seed": seed,
        "searched": searched,
        "cells": cells["sortie_posc"],
        "cells_planner": cells["posc"],
        "half": gain,
        "half_planner": p2["posc"],
        "cells_s": t1 - t0,
        "half_s": t2 - t1,
    }
    records.append(rec)
    print(json.dumps(rec), flush=True)
    out.write_text(json.dumps(records, indent=1))
d = np.array([r["half"] - r["cells"] for r in records])
n = len(d)
if n > 1:
    from scipy import stats

    half_ci = stats.t.ppf(0.975, n - 1) * d.std(ddof=1) / np.sqrt(n)
    wins = (d > 1e-9).sum(), (abs(d) <= 1e-9).sum(), (d < -1e-9).sum()
    print(f"half - cells: mean {d.mean():+.4f} +- {half_ci:.4f} (t 95 %), w/t/l {wins}")
