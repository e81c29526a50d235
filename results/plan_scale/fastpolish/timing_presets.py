"""i24-fastpolish: CPU time of the ``default`` and ``standard`` plans of one case, in turn in
one process after a warm-up (paired), and the planned POS (a script, not a test).

``python results/plan_scale/fastpolish/timing_presets.py CASE ROUNDS OUT.json [VARIANT]``;
CASE ``paper_6_2``, ``large_400`` (their own priors) or ``large_400_160x160_24uav_300blobs``
(the timing case of ``poc-env bench plan --scale --scale-parts timing``); VARIANT (an
``effort_ab.py`` variant, e.g. ``standard+polish_max_cells=0``: the preset without its size
rule) in place of ``standard``.
"""

from __future__ import annotations

import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "planning"))
from effort_ab import _options
from speed_ab import blobs_case

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario


def main(case: str, rounds: int, out: str, variant: str = "standard") -> None:
    if case == "large_400_160x160_24uav_300blobs":
        sc, uavs, prior = blobs_case()
    else:
        sc, uavs, prior = load_scenario(case), None, None
    make_allocation_plan("small", options=PlanOptions.preset("standard"))  # warm-up (JIT)
    recs = []
    for r in range(rounds):
        for effort in ("default", variant):
            w0, c0 = time.perf_counter(), time.process_time()
            p = make_allocation_plan(sc, prior=prior, uavs=uavs, options=_options(effort))
            recs.append({"case": case, "round": r, "effort": effort,
                         "cpu_s": time.process_time() - c0, "wall_s": time.perf_counter() - w0,
                         "load": os.getloadavg()[0], "posc": float(p["posc"]),
                         "polish": p["optimizer"]["settings"].get("polish")})  # fmt: skip
            print(json.dumps(recs[-1]), flush=True)
            with open(out + ".tmp", "w") as f:
                json.dump(recs, f, indent=1)
            os.replace(out + ".tmp", out)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3], *sys.argv[4:5])
