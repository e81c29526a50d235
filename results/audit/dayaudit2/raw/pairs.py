"""Print each UAV's take-off and landing airfield (by name) of plan.json files."""
import json, sys
for f in sys.argv[1:]:
    d = json.load(open(f))
    names = {tuple(round(c) for c in a["position_m"]): a["name"] for a in d["airfields"]} if isinstance(d["airfields"], list) else {}
    def nm(p):
        return names.get(tuple(round(c) for c in p), p)
    print(f, "POS_C %.4f" % d["posc"], [f"{u['id']}:{nm(u['takeoff_m'])}->{nm(u['landing_m'])}{'' if u['waypoints_m'] else '(idle)'}" for u in d["uavs"]])
