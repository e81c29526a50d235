"""i24-dayaudit: fly saved plan.json files in the environment (a script, not a test).

``python flyplan.py SCENARIO PLAN [PLAN ...]``: each plan flown once (seed 0) by the plan
policies' waypoint follower on SCENARIO with the plan's number of UAVs
(``Scenario.with_uavs``, as ``plan --uavs``), its eq. 20 / 21 steps counted
(``agents.testing.flights.fly``).
"""

import json
import sys
from pathlib import Path

from poc_env.agents.policies.base import PlanPolicy
from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario


class Saved(PlanPolicy):
    """A plan policy that flies a plan made before."""

    def __init__(self, plan):
        self._plan = plan

    def make(self, env, prior, seed):
        return self._plan


sc0 = load_scenario(sys.argv[1])
for f in sys.argv[2:]:
    p = json.loads(Path(f).read_text())
    n = len(p["uavs"])
    sc = sc0.with_uavs(n) if n != sc0.n_uavs else sc0
    r = fly(sc, Saved(p), seed=0)
    print(
        f, f"uavs={n} planned={p['posc']:.4f} flown={r.posc:.4f} nofly={r.nofly_steps} "
        f"oob={r.oob_steps} collision={r.collision_steps} landed={r.landed}", flush=True,
    )  # fmt: skip
