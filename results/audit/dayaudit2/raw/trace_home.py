"""Log every sampled_sweep call of the 48-UAV big plan whose paths include one crediting < 1e-4."""

import sys

import poc_env.agents.planning.allocation as A
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario

orig = A.sampled_sweep
calls = []


def wrapped(sc, grid, prior, paths):
    r = orig(sc, grid, prior, paths)
    small = [(k, f"{p:.1e}") for k, p in enumerate(r[0]) if len(paths[k]) and p < 1e-4]
    calls.append((len(paths), sum(1 for p in paths if len(p)), round(sum(r[0]), 6), small))
    return r


A.sampled_sweep = wrapped
sc = load_scenario(sys.argv[1])
plan = make_plan(sc, uavs=48, planner="allocation")
print("posc", plan["posc"])
for c in calls:
    print(c)
