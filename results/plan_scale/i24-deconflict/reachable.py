"""i24-deconflict: how much of the unfound mass is reachable at all (a script, not a test).

``python reachable.py`` -- on repro.py's ``mono2`` case (large_400 at 10 km, nine sightings,
two by a zone): the prior mass, the mass the sensor reaches from outside the zones
(``ZoneRouter.reach_share``, a sweep of W/2 from outside: what the allocation plans on) and
the mass each plan finds, at 12 and 24 UAVs, per sighting.
"""

import numpy as np
from repro import SIGHTINGS, case

from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import Grid

for n in (12, 24):
    sc, prior = case("mono2", n)
    g = Grid.from_config(sc.map)
    share = ZoneRouter.for_scenario(sc).reach_share(g, sc.sensor.sweep_width_m)
    p = make_allocation_plan(sc, prior=prior)
    to = np.asarray(sc.takeoff_m, float).reshape(-1, 2)
    la = np.asarray(sc.landing_m, float).reshape(-1, 2)
    paths = [
        [to[k], *u["waypoints_m"], la[k]] if u["waypoints_m"] else []
        for k, u in enumerate(p["uavs"])
    ]
    _, found = sampled_sweep(sc, g, prior, paths)
    got = sum(found)
    print(
        f"uavs {n} posc {p['posc']:.4f} reachable {float((prior * share).sum()):.4f} "
        f"idle {sum(1 for u in p['uavs'] if not u['waypoints_m'])}"
    )
    for x, y, _ in SIGHTINGS:
        i, j = int(y // 10), int(x // 10)
        print(
            f"  sighting ({x}, {y}) km: mass {prior[i, j]:.4f} reachable share {share[i, j]:.3f} "
            f"found {got[i, j]:.4f}"
        )
