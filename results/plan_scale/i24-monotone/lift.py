"""i24-monotone: one half-fleet plan lifted onto larger fleets (a script, not a test).

``python lift.py SCENARIO BASE SIZES [FIELD=VALUE,...]``
    The default plan of BASE UAVs as the half fleet's plan is made (``_half=True``), then given
    as ``floor`` to the default plan of each of SIZES UAVs of the same fields: per size one JSON
    line with the floor's lifted value in the pick's criterion (``fleet.value[1]``: its routes
    through the fill's clearance, the other UAVs filled, the floor per flight hour applied;
    planned POS less ``gain_per_hour`` x hours), the fleet's own plan's (``value[0]``), the
    UAVs flying in each, and the kept plan's POS_C. Does the fill find less with more idle
    UAVs?
"""

import json
import os
import sys
import time

from diag import scenario, value

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions


def main() -> None:
    name, base, sizes = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    changes = dict(kv.split("=") for kv in sys.argv[4].split(",")) if len(sys.argv) > 4 else {}
    opt = PlanOptions(**{k: value(v) for k, v in changes.items()})
    sc_all, prior = scenario(name)
    half = make_allocation_plan(sc_all.with_uavs(base), prior=prior, options=opt, _half=True)
    print(
        json.dumps(
            {
                "base": base,
                "posc": half["posc"],
                "flying": sum(1 for u in half["uavs"] if u["waypoints_m"]),
            }
        ),
        flush=True,
    )
    for n in [int(s) for s in sizes.split(",")]:
        c0 = time.process_time()
        plan = make_allocation_plan(sc_all.with_uavs(n), prior=prior, options=opt, floor=half)
        fl = plan["optimizer"]["settings"]["fleet"]
        print(
            json.dumps(
                {
                    "base": base,
                    "uavs": n,
                    "own": fl["value"][0],
                    "lifted": fl["value"][1],
                    "flying": fl["flying"],
                    "dropped": fl["dropped"][0],
                    "kept": fl["kept"],
                    "posc": plan["posc"],
                    "cpu_s": round(time.process_time() - c0, 1),
                    "load1": round(os.getloadavg()[0], 1),
                    "options": changes,
                }
            ),
            flush=True,
        )


if __name__ == "__main__":
    main()
