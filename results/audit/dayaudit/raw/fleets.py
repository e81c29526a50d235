from poc_env.agents.planning.allocation import plan_fleets
import numpy as np
for sizes in [0, 65, [], "x", [2, 0], [1.5], [True], np.array([2.0]), None, [3, 3], "3", [np.int64(2)], {2: 1}, [[2, 3]]]:
    try:
        plans = plan_fleets("small", sizes)
        print(repr(sizes), "->", [len(p["uavs"]) for p in plans], [round(float(p["posc"]), 4) for p in plans])
    except Exception as e:
        print(repr(sizes), "->", type(e).__name__, e)
