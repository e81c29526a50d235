import json, sys, numpy as np
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.deconflict import planned_positions, conflicts
from poc_env.agents.planning.flight_rules import Speeds
sc = load_scenario("/tmp/flownsep_big/big.yaml")
prior = build_prior(sc.map)
p = make_allocation_plan(sc, prior=prior, seed=5000)
json.dump(p, open("/tmp/flownsep_big/plan24.json","w"), default=float)
sp = p["speeds_mps"]; v = Speeds(sp["out"], sp["line"], sp["home"])
routes=[u["waypoints_m"] for u in p["uavs"]]
t,pos,act = planned_positions(sc, routes, v)
c = conflicts(sc,pos,act)
pairs={}
for s,i,j in zip(*np.nonzero(c)):
    if i<j: pairs.setdefault((int(i),int(j)),[]).append(int(s))
print("planned conflicts", c.sum()//2, {k:(len(v),v[:3]) for k,v in pairs.items()})
d = np.hypot(*(pos[:,12]-pos[:,13]).T)
print("12-13 planned dist km", [(s, round(d[s]/1e3,2)) for s in range(100,125)])
print(np.round(np.array(routes[12])/1e3,1).tolist())
print(np.round(np.array(routes[13])/1e3,1).tolist())
print(p["start"], sp)
