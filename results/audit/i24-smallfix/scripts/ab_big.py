"""i24-smallfix, F1: default allocation plans on the audit's 500 km scenario (a script).

``python ab_big.py OUT.json N [N ...]``: ``/tmp/dayaudit/big_3.125.yaml`` (160 x 160 cells,
4 fields, 3 zones; results/audit/dayaudit/README.md) with ``--uavs N`` (``with_uavs``): per
size the digest, planned POS_C, UAVs flying and total flight hours. Run with main's and the
branch's interpreter and compare.
"""

import json
import sys
import time
from pathlib import Path

from ab_f1 import record

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario

recs = {}
for n in [int(a) for a in sys.argv[2:]]:
    sc = load_scenario("/tmp/dayaudit/big_3.125.yaml").with_uavs(n)
    t = time.perf_counter()
    p = make_allocation_plan(sc)
    recs[str(n)] = record(p, t)
    print(n, recs[str(n)], flush=True)
    Path(sys.argv[1]).write_text(json.dumps(recs, indent=1))
