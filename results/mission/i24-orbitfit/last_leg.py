"""i24-orbitfit: what the last-leg bisection keeps, against whole waypoints only, on the test's
valley -> bowl case (the 3,100 m ring 6-8 km round bowl) and case 104's allocation plan.

Usage: python results/mission/i24-orbitfit/last_leg.py
"""

import sys

sys.path[:0] = ["tests/mission", "tests"]

from test_orbit_fit import VALLEY_M, _scenario  # noqa: E402

import poc_env.agents.planning.geography as geo  # noqa: E402
from poc_env.agents.planning.planner import make_plan  # noqa: E402

sc = _scenario(VALLEY_M + 2500.0)
for steps in (geo.BISECT_STEPS, 0):
    geo.BISECT_STEPS = steps
    p = make_plan(sc, planner="allocation", uavs=2, refine=0)
    fit = p["orbit_fit"]
    print(f"valley->bowl, bisection steps {steps}: POS_C {p['posc']:.4f} (before the fit "
          f"{fit['posc_before']:.4f}); " + "; ".join(
              f"UAV {i}: {r['waypoints_before']} -> {r['waypoints_after']} waypoints, last leg "
              f"{r['last_leg_kept']:.3f}" for i, r in fit["uavs"].items()))  # fmt: skip
