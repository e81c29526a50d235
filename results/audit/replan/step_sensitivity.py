"""How the POS a path finds depends on how finely it is cut into steps (the sensor's cut-off).

Usage: python results/audit/replan/step_sensitivity.py PLAN.json
The plan's routes swept over its scenario's prior with legs cut into steps of at most
``step_m`` (None: whole legs; the cell: what the planner and ``replan --plan`` use; 2 km: the
environment's step on ``small``; 67 m and 10 m: a 1 Hz GPS log), with the scenario's cut-off
and without one.
"""

import json
import sys
from pathlib import Path

import numpy as np

from poc_env.agents.planning.replan import plan_paths
from poc_env.config import load_scenario
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import sweep_track

plan = json.loads(Path(sys.argv[1]).read_text())
sc = load_scenario(plan["scenario"])
prior = build_prior(sc.map)
grid = Grid.from_config(sc.map)
s, w = sc.sensor.samples_per_cell, sc.sensor.sweep_width_m
cut = sc.sensor.cutoff_sweep_widths * w
print(f"W {w:g} m, cut-off {cut:g} m, cell {grid.cell_m:g} m, s {s}, law {sc.sensor.law}")


def found(paths, step, cutoff):
    b = np.ascontiguousarray(grid.refine(prior, s))
    return sum(sweep_track(b, grid, s, p, w, sc.sensor.law, cutoff, step) for p in paths)


paths = plan_paths(plan)
for step in [None, 20000, grid.cell_m, 2000, 500, 67, 10]:
    print(
        f"step {step!s:>7}: found {found(paths, step, cut):.6f}, "
        f"no cut-off {found(paths, step, np.inf):.6f}"
    )
dup = [np.repeat(p, 3, axis=0) for p in paths]
print(f"every vertex repeated 3 times, steps of a cell: {found(dup, grid.cell_m, cut):.6f}")
