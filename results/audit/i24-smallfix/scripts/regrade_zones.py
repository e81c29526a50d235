"""i24-smallfix: does the regrade enter no-fly zones? (a script, not a test).

``python regrade_zones.py`` (from the worktree): the default plan of ``paper_6_2`` with two
30 x 40 km zones regraded twice without and with the router; routes meeting a zone and legs
across the router's clearance ring (tests/planning/test_zonepolish.py's ``_entering``).
"""

import sys

sys.path.insert(0, "tests/planning")

from test_zonepolish import TWO_ZONES, _entering

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.polish import polish_for
from poc_env.agents.planning.regrade import regrade_routes
from poc_env.config import load_scenario
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import build_prior

sc = load_scenario("paper_6_2", TWO_ZONES)
prior = build_prior(sc.map)
routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
print("start", _entering(sc, routes))
for router in (None, ZoneRouter.for_scenario(sc)):
    kw = {} if router is None else {"router": router}
    out, val, st = polish_for(sc, routes, prior, 2, routine=regrade_routes, **kw)
    print("guarded" if router else "blind", _entering(sc, out), st, round(val, 4))
