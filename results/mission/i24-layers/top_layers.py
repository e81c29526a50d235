"""i24-layers: the highest layer each ordering needs (every UAV given a route; an upper bound:
UAVs without one get none), in layers of S above the plan's altitude.

``python top_layers.py [DIR/big.yaml]``: per case, UAVs, fields, and the top layer index
``field`` (the most UAVs on one field, less one) and ``fleet`` (UAVs less one).
"""

import collections
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "plan_scale" / "i24-deconflict"))
from repro import case  # noqa: E402

from poc_env.config import load_scenario  # noqa: E402

cases = [("paper_6_2", load_scenario("paper_6_2"))]
cases += [(f"{k} {n}", case(k, n)[0]) for k in ("mono2", "lanes") for n in (6, 12, 24)]
if len(sys.argv) > 1:
    cases += [(f"big {n}", load_scenario(sys.argv[1]).with_uavs(n)) for n in (24, 32, 48)]
for name, sc in cases:
    per = collections.Counter(tuple(p) for p in sc.takeoff_m)
    n = sum(per.values())
    rec = {"case": name, "uavs": n, "fields": len(per), "top_field": max(per.values()) - 1}
    print(json.dumps({**rec, "top_fleet": n - 1}))
