"""i24-smallfix, F1: fly saved plans on a scenario, seeds 0-2 (a script, not a test).

``python flyseeds.py SCENARIO PLAN [PLAN ...]``: each plan flown by the plan policies' waypoint
follower (``agents.testing.flights.fly``), planned and flown POS_C, total flight hours.
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


if __name__ == "__main__":
    sc = load_scenario(sys.argv[1])
    for f in sys.argv[2:]:
        p = json.loads(Path(f).read_text())
        hours = sum(u["flight_time_s"] for u in p["uavs"]) / 3600
        for seed in (0, 1, 2):
            r = fly(sc, Saved(p), seed=seed)
            print(
                f, seed, f"planned={p['posc']:.6f} flown={r.posc:.4f} hours={hours:.2f} "
                f"collision={r.collision_steps}", flush=True,
            )  # fmt: skip
