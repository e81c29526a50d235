"""Sorties in a row, checked: does the belief only fall, and where it was searched? Is each
plan's cumulative_posc eq. 14 over every flight so far, 1 - prod(1 - conditional POS_i), and
below the honest bound for k sorties?

Usage: python results/audit/replan/chain_check.py SCENARIO [--overrides K=V ...] -- P1.json ...
(the plans of sorties 1..n in order: P1 from `poc-env plan`, the others from `poc-env replan`).
"""

import itertools
import json
import sys
from pathlib import Path

import numpy as np

from poc_env.agents.planning.replan import plan_paths, searched_belief
from poc_env.config import load_scenario, parse_overrides
from poc_env.theory.bound import honest_optimum
from poc_env.theory.probability_map import Grid, build_prior

args = sys.argv[1:]
cut = args.index("--")
name, over = args[0], [a for a in args[1:cut] if a != "--overrides"]
sc = load_scenario(name, parse_overrides(over))
prior = build_prior(sc.map)
grid = Grid.from_config(sc.map)
plans = [json.loads(Path(p).read_text()) for p in args[cut + 1 :]]
print(f"{sc.name}: {len(plans)} sorties, prior mass {prior.sum():.6f}")
prev, paths, cond = prior, [], []
for k, plan in enumerate(plans, start=1):
    mine = plan_paths(plan)
    paths += mine
    belief, cum = searched_belief(sc, prior, paths)
    drop = prev - belief
    # where sortie k searched: cells within half a sweep width of its routes' sample points
    fine = np.zeros((grid.ny, grid.nx), dtype=bool)
    for path in mine:
        for a, b in itertools.pairwise(path):
            for t in np.linspace(0, 1, 50):
                x, y = a + t * (b - a)
                i, j = (
                    int((y - grid.origin_m[1]) // grid.cell_m),
                    int((x - grid.origin_m[0]) // grid.cell_m),
                )
                if 0 <= i < grid.ny and 0 <= j < grid.nx:
                    fine[i, j] = True
    share = drop[fine].sum() / drop.sum() if drop.sum() > 0 else float("nan")
    own = cum - (1 - prev.sum() / prior.sum()) * prior.sum() if k > 1 else cum
    cond.append(own / prev.sum())
    one_minus_prod = 1 - np.prod([1 - c for c in cond])
    bound = honest_optimum(sc, prior, sorties=k).pos
    rec = plan.get("cumulative_posc", plan["posc"])
    print(
        f"sortie {k}: belief min drop {drop.min():+.2e} (>= 0: only falls), "
        f"{share:.3f} of the drop in cells its routes cross; eq.14 over all flights {cum:.6f}, "
        f"plan's cumulative_posc {rec:.6f} (diff {rec - cum:+.1e}); 1-prod(1-cond POS) "
        f"{one_minus_prod:.6f}; bound({k}) {bound:.4f} {'OK' if cum <= bound + 1e-12 else 'ABOVE'}"
    )
    prev = belief
