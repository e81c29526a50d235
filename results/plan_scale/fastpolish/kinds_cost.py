"""i24-fastpolish: the CPU time of one polish pass by the kinds of move it tries (a script, not a
test): the default plan of ``paper_6_2``'s prior SEED polished one pass from the same routes
with the waypoint moves only, with the grade moves too, and with the block moves too (the
second polish's kinds, at the polish's radii and at ``thorough``'s W/8-2W), in turn after a
warm-up. ``python results/plan_scale/fastpolish/kinds_cost.py SEED``."""

import sys
import time

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.polish import KINDS, MOVES, polish_for
from poc_env.config import load_scenario

sc = load_scenario("paper_6_2")
prior = episode_prior(sc, int(sys.argv[1]))
routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
polish_for(sc, routes, prior, 1, moves=(*KINDS, "block"))  # warm-up
for name, kinds, radii in (
    ("waypoint moves", MOVES, (0.25, 0.5, 1.0, 2.0)),
    ("+ grade", KINDS, (0.25, 0.5, 1.0, 2.0)),
    ("+ grade + block", (*KINDS, "block"), (0.25, 0.5, 1.0, 2.0)),
    ("+ grade + block, W/8-2W", (*KINDS, "block"), (0.125, 0.25, 0.5, 1.0, 2.0)),
):
    for _ in range(2):
        c0 = time.process_time()
        _, value, stats = polish_for(sc, routes, prior, 1, moves=kinds, radii=radii)
        print(f"{name}: {time.process_time() - c0:.2f} s CPU, {stats}", flush=True)
