"""i24-fleet: planned eq. 21 conflicts of the default allocation plan (a script, not a test;
run it with each tree's interpreter).

``python conflicts.py SCENARIO N``: planned POS_C, the start, the conflict pair-steps
(:func:`poc_env.agents.planning.deconflict.conflicts`: d_s, 120 s slack, away from the
fields) and the UAVs without a route.
"""

import sys

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.deconflict import conflicts, planned_positions
from poc_env.agents.planning.flight_rules import SPEED, plan_speeds
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

sc = load_scenario(sys.argv[1]).with_uavs(int(sys.argv[2]))
pr = build_prior(sc.map)
p = make_allocation_plan(sc, prior=pr)
_, pos, act = planned_positions(sc, [u["waypoints_m"] for u in p["uavs"]], plan_speeds(sc, SPEED))
c = int(conflicts(sc, pos, act).sum()) // 2
idle = sum(1 for u in p["uavs"] if not u["waypoints_m"])
print(sys.argv[2], "posc", round(p["posc"], 4), p["start"], "planned conflict pair-steps", c,
      "idle", idle)  # fmt: skip
