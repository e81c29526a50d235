"""i24-gainhour: the planning CPU of the floor (a script): ``python cost.py OUT.json N``.

The 500 km scenario (``/tmp/gainhour/big.yaml``) with ``with_uavs(N)`` planned by default
(``gain_per_hour`` 1e-4) and with ``gain_per_hour=0`` (no floor: no marginals computed),
alternately, twice each, in one process; CPU seconds (``time.process_time``) and the
1-minute load beside each. Loaded machine: compare the pairs, not the absolute times.
"""

import json
import os
import sys
import time
from pathlib import Path

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario

out, n = sys.argv[1], int(sys.argv[2])
sc = load_scenario("/tmp/gainhour/big.yaml").with_uavs(n)
recs = []
for rnd in range(2):
    for name, opt in (
        ("default", PlanOptions()),
        ("gain_per_hour=0", PlanOptions(gain_per_hour=0.0)),
    ):
        c = time.process_time()
        p = make_allocation_plan(sc, options=opt)
        recs.append({"round": rnd, "plan": name, "cpu_s": time.process_time() - c,
                     "posc": p["posc"], "load": os.getloadavg()[0]})  # fmt: skip
        print(recs[-1], flush=True)
        Path(out).write_text(json.dumps(recs, indent=1))
