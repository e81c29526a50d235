"""Fly saved plan.json files in the environment: python flyplan.py SCENARIO PLAN [PLAN ...]"""
import json, sys
from poc_env.config import load_scenario
from poc_env.agents.policies.base import PlanPolicy
from poc_env.agents.testing.flights import fly

class Saved(PlanPolicy):
    def __init__(self, plan): self._p = plan
    def make(self, env, prior, seed): return self._p

sc0 = load_scenario(sys.argv[1])
for f in sys.argv[2:]:
    p = json.load(open(f))
    sc = sc0.with_uavs(len(p["uavs"])) if len(p["uavs"]) != sc0.n_uavs else sc0
    r = fly(sc, Saved(p), seed=0)
    print(f, f"uavs={len(p['uavs'])} planned={p['posc']:.4f} flown={r.posc:.4f} nofly={r.nofly_steps} oob={r.oob_steps} collision={r.collision_steps} landed={r.landed}", flush=True)
