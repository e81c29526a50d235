"""i24-smallfix, F1: planning CPU at 64 UAVs on the 500 km scenario (a script, not a test).

``python time64.py OUT.json``: ``/tmp/dayaudit/big_3.125.yaml`` with ``with_uavs(64)``
planned three times in one process (``nothing=0``, the default, ``nothing=0`` again): wall
and CPU seconds, load, planned POS_C, UAVs flying.
"""

import json
import os
import sys
import time
from pathlib import Path

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario

sc = load_scenario("/tmp/dayaudit/big_3.125.yaml").with_uavs(64)
runs = (
    ("nothing=0", PlanOptions(nothing=0.0)),
    ("default", PlanOptions()),
    ("nothing=0 again", PlanOptions(nothing=0.0)),
)
out = {}
for name, opt in runs:
    t, c = time.perf_counter(), time.process_time()
    p = make_allocation_plan(sc, options=opt)
    out[name] = {
        "wall_s": time.perf_counter() - t,
        "cpu_s": time.process_time() - c,
        "load": os.getloadavg()[0],
        "posc": p["posc"],
        "flying": sum(1 for u in p["uavs"] if u["waypoints_m"]),
    }
    print(name, out[name], flush=True)
Path(sys.argv[1]).write_text(json.dumps(out, indent=1))
