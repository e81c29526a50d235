"""i24-fleetcli: fly saved plan files with the waypoint follower and
print per plan and seed its flown POSC, UAVs landed, eq. 20 no-fly steps and eq. 21 collision
UAV-steps. Usage: python fly.py SCENARIO.yaml SEED[,SEED...] PLAN.json... (episode seeds; each
plan flown on the scenario
with the plan's number of UAVs, ``Scenario.with_uavs``, as ``plan --fleet-sizes`` and
``plan --uavs`` plan them)."""

import json
import sys
import time

from poc_env.agents.mission.plan import load_plan
from poc_env.agents.policies.base import PlanPolicy
from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario


class FilePlan(PlanPolicy):
    """Flies a saved plan (planned before the episode, not on its prior)."""

    def __init__(self, plan) -> None:
        super().__init__()
        self.saved = plan

    def make(self, env, prior, seed):
        return self.saved


sc = load_scenario(sys.argv[1])
seeds = [int(s) for s in sys.argv[2].split(",")]
for path in sys.argv[3:]:
    plan = load_plan(path)
    n = len(plan["uavs"])
    for seed in seeds:
        t0 = time.process_time()
        f = fly(sc.with_uavs(n), FilePlan(plan), seed=seed)
        rec = {"plan": path, "seed": seed, "uavs": n, "planned_posc": round(plan["posc"], 4),
               "flown_posc": round(f.posc, 4), "landed": f.landed, "nofly_steps": f.nofly_steps,
               "collision_steps": f.collision_steps,
               "cpu_s": round(time.process_time() - t0, 1)}  # fmt: skip
        print(json.dumps(rec), flush=True)
