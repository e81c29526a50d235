"""bound-zones: the bounds printed beside plans on maps WITHOUT zones, to the last digit (run
with each tree's PYTHONPATH and compare the two files; they must be equal).

    OMP_NUM_THREADS=1 python results/bounds/bound_zones/nozones_check.py OUT.json
"""

import json
import os
import sys
import warnings

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario
from poc_env.theory.bound import honest_optimum, reach_bound, rule_bound

warnings.simplefilter("ignore")
out = {}
for name, seed in (("paper_6_2", None), ("paper_6_2", 1), ("small", None)):
    sc = load_scenario(name)
    prior = None if seed is None else episode_prior(sc, seed)
    key = f"{name}:{'scenario' if seed is None else seed}"
    a = make_allocation_plan(sc, prior=prior)
    d = make_plan(sc, prior=prior, planner="de", popsize=8, maxiter=4, seed=0)
    out[key] = {
        "allocation": {k: repr(a[k]) for k in ("posc", "upper_bound", "bound_reach", "bound_rule")}
        | {"bounds": repr(a.get("bounds"))},
        "de": {k: repr(d[k]) for k in ("posc", "upper_bound", "bound_rule")}
        | {"bounds": repr(d.get("bounds"))},
    }
    if prior is None:
        from poc_env.theory.probability_map import build_prior

        prior = build_prior(sc.map)
    out[key]["theory"] = {
        "honest": repr(honest_optimum(sc, prior).pos),
        "reach": repr(reach_bound(sc, prior).upper),
        "rule": repr(rule_bound(sc, prior).upper),
    }
    print(key, json.dumps(out[key]), flush=True)
with open(sys.argv[1] + ".tmp", "w") as f:
    json.dump(out, f, indent=1)
os.replace(sys.argv[1] + ".tmp", sys.argv[1])
