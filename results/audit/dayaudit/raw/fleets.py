"""i24-dayaudit: ``plan_fleets`` with bad fleet sizes (a script, not a test)."""

import numpy as np

from poc_env.agents.planning.allocation import plan_fleets

CASES = [0, 65, [], "x", [2, 0], [4, "x"], [1.5], [True], np.array([2.0]), None, [3, 3], "3",
         [np.int64(2)], {2: 1}, [[2, 3]]]  # fmt: skip
for sizes in CASES:
    try:
        plans = plan_fleets("small", sizes)
        print(
            repr(sizes), "->", [len(p["uavs"]) for p in plans], [round(p["posc"], 4) for p in plans]
        )
    except Exception as e:
        print(repr(sizes), "->", type(e).__name__, e)
