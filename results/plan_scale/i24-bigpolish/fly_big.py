"""i24-bigpolish: a plan policy flown on a big scenario's own prior (a script, not a test).

``python fly_big.py SCENARIO.yaml POLICY [POLICY ...]`` (from the checkout)
    Per policy (``allocation_plan``, ``allocation_plan_standard``): the episode of seed 5000
    through results/plan_scale/i24-deconflict/repro.py's ``flown_collisions`` (as
    results/plan_scale/i24-fleet/flown.py flies the default): flown POSC, collision UAV-steps
    (all / away from the fields), one JSON line.
"""

import json
import sys
import time

sys.path.insert(0, "results/plan_scale/i24-deconflict")
from repro import flown_collisions

from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

sc = load_scenario(sys.argv[1])
prior = build_prior(sc.map)
for name in sys.argv[2:]:
    c0 = time.process_time()
    steps, away, posc = flown_collisions(sc, prior, policy=make_policy(name))
    rec = {"scenario": sys.argv[1].rsplit("/", 1)[-1], "policy": name,
           "flown_posc": round(posc, 4), "collision_steps": steps, "away_from_fields": away,
           "cpu_s": round(time.process_time() - c0, 1)}  # fmt: skip
    print(json.dumps(rec), flush=True)
