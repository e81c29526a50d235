"""The ground waypoints of ``spacetime_plan``'s take-off plan on one Paper61-Drift seed, hashed:
run from two checkouts to see that a change leaves the flown routes as they were.

    PYTHONPATH=. python results/moving/recede/waypoints_hash.py LABEL [SEED]
"""

from __future__ import annotations

import hashlib
import sys

import numpy as np

from poc_env.agents.planning.spacetime import spacetime_plan
from poc_env.agents.policies.moving import drift_of
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.tasks import get_task

seed = int(sys.argv[2]) if len(sys.argv) > 2 else 8000
sc = get_task("UAVSearch-Paper61-Drift-Heading-v1").load_scenario({})
env = UAVSearchParallelEnv(scenario=sc)
env.reset(seed=seed)
belief = np.array(env.sim_state.belief[0], dtype=float)
plan = spacetime_plan(sc, belief, drift_of(env), env.params.s, seed=seed)
h = hashlib.sha256()
for u in plan["uavs"]:
    h.update(np.asarray(u["waypoints_m"], dtype=float).tobytes())
last = [round(u["meet_times_s"][-1]) for u in plan["uavs"] if u["meet_times_s"]]
print(sys.argv[1], "seed", seed, "cut", plan.get("cut_outside_area", 0))
print("ground waypoints sha256", h.hexdigest()[:16], "last meet time per UAV (s)", last)
