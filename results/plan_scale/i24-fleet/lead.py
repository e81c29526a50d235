"""i24-fleet: the flown lead of ``allocation_plan`` over ``greedy_rectangles`` with no-fly
zones, where the greedy rectangles changed (a script, not a test; run it in each tree).

``python lead.py CASE SEED [SEED ...]``
    CASE ``paper_6_2`` or ``large_400``: the scenario with 4 random no-fly zones
    (:func:`poc_env.agents.benchmarks.plan_scale.random_zones`, ``default_rng(1000 + SEED)``,
    as ``bench plan --scale-parts zones`` draws them) on the random prior of SEED
    (``episode_prior``), both policies flown (episode seed SEED); one JSON line per seed:
    POSC over the rule-aware bound of each and the lead.
"""

import json
import sys

import numpy as np

from poc_env.agents.benchmarks.plan_scale import random_zones
from poc_env.agents.experiments.evaluate import episode_prior, play
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.theory.bound import rule_bound

case = sys.argv[1]
for seed in map(int, sys.argv[2:]):
    plain = load_scenario(case)
    m = plain.map
    ox, oy = (v / 1000 for v in m.origin_m)
    drawn = random_zones(m.width_m / 1000, m.height_m / 1000, 4, np.random.default_rng(1000 + seed))
    zones = [[[x + ox, y + oy] for x, y in z] for z in drawn]
    sc = load_scenario(case, {"map.no_fly_zones_km": zones})
    prior = episode_prior(sc, seed)
    bound = float(rule_bound(sc, prior).upper)
    rec: dict = {"case": case, "seed": seed, "rule_bound": round(bound, 4)}
    for pol in ("allocation_plan", "greedy_rectangles"):
        env = UAVSearchParallelEnv(scenario=sc)
        play(env, make_policy(pol), seed, prior)
        rec[pol] = round(float(env.sim_state.posc[0]) / bound, 4)
    rec["lead"] = round(rec["allocation_plan"] - rec["greedy_rectangles"], 4)
    print(json.dumps(rec), flush=True)
