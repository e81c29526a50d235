"""Print each UAV's take-off and landing airfield (by name) of plan.json files (probe 10)."""

import json
import sys
from pathlib import Path


def field(names: dict, p: list) -> str:
    """The airfield's name at position ``p`` (metres, rounded), else the position."""
    return names.get(tuple(round(c) for c in p), str(p))


for f in sys.argv[1:]:
    d = json.loads(Path(f).read_text())
    names = {tuple(round(c) for c in a["position_m"]): a["name"] for a in d["airfields"]}
    pairs = [
        f"{u['id']}:{field(names, u['takeoff_m'])}->{field(names, u['landing_m'])}"
        + ("" if u["waypoints_m"] else "(idle)")
        for u in d["uavs"]
    ]
    print(f, f"POS_C {d['posc']:.4f}", pairs)
