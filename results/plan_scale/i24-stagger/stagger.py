"""i24-stagger: the default allocation plan of a fleet, planned once, its idle UAVs, the
reachable mass it leaves, its planned eq. 21 conflicts, and the plan flown on episode seeds
(a script, not a test; run it with each tree's interpreter, from the checkout).

``python stagger.py SCENARIO N SEED [SEED ...]``
    SCENARIO as in results/plan_scale/i24-fleet/fleet.py (a scenario file, ``mono2`` or
    ``mini:SIDE_KM:CELL_KM``). One JSON line: fleet.py's record (planned POS_C, start, UAVs
    without a route, the split of the unfound mass), the planned conflict pair-steps
    (:func:`poc_env.agents.planning.deconflict.conflicts`: d_s, 120 s slack, away from the
    fields) and per seed the flown POSC and collision UAV-steps (all / away from the fields,
    results/plan_scale/i24-deconflict/repro.py's ``flown_collisions``), the same plan flown
    on every seed (the planner is deterministic; the seed drives the episode).
"""

import json
import sys
import time

sys.path.insert(0, "results/plan_scale/i24-deconflict")
sys.path.insert(0, "results/plan_scale/i24-fleet")
from fleet import scenario, split
from repro import flown_collisions

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.deconflict import conflicts, planned_positions
from poc_env.agents.planning.flight_rules import SPEED, plan_speeds
from poc_env.agents.policies.registry import make_policy

name, n, seeds = sys.argv[1], int(sys.argv[2]), [int(s) for s in sys.argv[3:]]
sc, prior = scenario(name, n)
t0 = time.process_time()
plan = make_allocation_plan(sc, prior=prior)
cpu = time.process_time() - t0
routes = [u["waypoints_m"] for u in plan["uavs"]]
_, pos, act = planned_positions(sc, routes, plan_speeds(sc, SPEED))
rec = {
    "case": name,
    "uavs": n,
    "posc": round(float(plan["posc"]), 4),
    "start": plan["start"],
    "no_route": sum(1 for r in routes if not r),
    **split(sc, prior, plan),
    "planned_conflict_pair_steps": int(conflicts(sc, pos, act).sum()) // 2,
    "plan_cpu_s": round(cpu, 1),
}
for seed in seeds:
    pol = make_policy("allocation_plan")
    pol.make = lambda env, prior, seed, plan=plan: plan  # type: ignore[method-assign]
    steps, away, posc = flown_collisions(sc, prior, seed=seed, policy=pol)
    rec[f"flown_{seed}"] = {"posc": round(posc, 4), "collision_steps": steps, "away": away}
print(json.dumps(rec), flush=True)
