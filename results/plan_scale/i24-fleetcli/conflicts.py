"""i24-fleetcli: planned eq. 21 conflict pair-steps of saved plan files (``deconflict.conflicts``
at the planned positions, as results/plan_scale/i24-stagger counts them), each on SCENARIO
with the plan's number of UAVs. Prints: file, speed rule, pair-steps, CPU s.
Usage: python conflicts.py SCENARIO.yaml PLAN.json..."""

import json
import sys
import time
from pathlib import Path

from poc_env.agents.planning.deconflict import conflicts, planned_positions
from poc_env.agents.planning.flight_rules import plan_speeds
from poc_env.config import load_scenario

sc = load_scenario(sys.argv[1])
for f in sys.argv[2:]:
    plan = json.loads(Path(f).read_text())
    s = sc.with_uavs(len(plan["uavs"]))
    t = time.process_time()
    routes = [u["waypoints_m"] for u in plan["uavs"]]
    _, pos, act = planned_positions(s, routes, plan_speeds(s, plan.get("speed_rule", "max")))
    pairs = int(conflicts(s, pos, act).sum()) // 2
    print(f, plan.get("speed_rule"), pairs, round(time.process_time() - t, 2), flush=True)
