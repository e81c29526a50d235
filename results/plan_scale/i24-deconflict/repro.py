"""i24-deconflict: planned eq. 21 conflicts of allocation plans (a script, not a test).

``python repro.py CELL_KM N[,N...] [fly]``: ``large_400`` at CELL_KM cells with one zone over two
of nine point sightings (results/audit/scale/raw/mono2.py's case), N UAVs: planned POS_C, UAVs
without a route, planned collision steps (eq. 21 at the planned positions every dt, d_s) and
the pairs; with ``fly`` the plan is flown too (seed 5000) and its flown collision steps counted.
"""

import sys

import numpy as np

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.flight_rules import SPEED, plan_speeds
from poc_env.agents.planning.refine import track
from poc_env.config import load_scenario
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid

ZONE = [[100, 150], [175, 150], [175, 225], [100, 225]]
SIGHTINGS = [
    (160.9, 151.6, 0.1), (139.1, 226.6, 0.1), (301.6, 45.3, 0.06), (123.4, 98.4, 0.12),
    (373.4, 126.6, 0.1), (251.6, 273.4, 0.06), (26.6, 380, 0.15), (160.9, 380, 0.09),
    (307.8, 380, 0.04),
]  # fmt: skip


def case(cell: float, n: int):
    sc = load_scenario("large_400", {"map.cell_km": cell, "map.no_fly_zones_km": [ZONE]})
    g = Grid.from_config(sc.map)
    prior = np.zeros(g.shape)
    for x, y, w in SIGHTINGS:
        prior[int(y // cell), int(x // cell)] += w
    return sc.with_uavs(n), prior / prior.sum()


def planned_pairs(sc, plan) -> dict:
    """Collision steps (eq. 21, d_s) per pair at the planned positions every dt."""
    u = sc.uav
    v = plan_speeds(sc, SPEED)
    takeoff = np.asarray(sc.takeoff_m, float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, float).reshape(-1, 2)
    h0 = takeoff_heading(Grid.from_config(sc.map).bounds, takeoff)
    times = np.arange(int(np.ceil(u.usable_endurance_s / sc.episode.dt_s)) + 1) * sc.episode.dt_s
    n = len(takeoff)
    pos = np.zeros((len(times), n, 2))
    act = np.zeros((len(times), n), bool)
    for k, uu in enumerate(plan["uavs"]):
        if uu["waypoints_m"]:
            path = np.vstack([takeoff[k], np.asarray(uu["waypoints_m"]), landing[k]])
            pos[:, k], act[:, k] = track(path, v, u.max_turn_rate_rad_s, times, h0[k])
    d = np.hypot(*(pos[:, :, None] - pos[:, None]).transpose(3, 0, 1, 2))
    close = (d < sc.constraints.safety_distance_m) & act[:, :, None] & act[:, None]
    out = {}
    for i in range(n):
        for j in range(i + 1, n):
            c = int(close[:, i, j].sum())
            if c:
                out[(i + 1, j + 1)] = c
    return out


def flown_collisions(sc, prior, seed=5000) -> tuple[int, int, float]:
    """Flown collision UAV-steps (the environment's ``violation_collision``), those of them
    away from the airfields (the UAV farther than ``d_s / sin 20 deg`` from its take-off and
    landing field: what the deconfliction addresses) and POSC of the ``allocation_plan``
    policy on ``prior``."""
    from poc_env.agents.experiments.evaluate import play
    from poc_env.agents.planning.allocation import FAN_DEG
    from poc_env.agents.policies.registry import make_policy
    from poc_env.envs.parallel import UAVSearchParallelEnv

    env = UAVSearchParallelEnv(scenario=sc)
    takeoff = np.asarray(sc.takeoff_m, float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, float).reshape(-1, 2)
    near = sc.constraints.safety_distance_m / np.sin(np.radians(FAN_DEG))
    steps = [0, 0]

    def count(infos) -> None:
        flag = np.zeros(len(takeoff), bool)
        for a, i in infos.items():
            flag[int(a.rsplit("_", 1)[1])] = bool(i["violation_collision"])
        xy = env.sim_state.pos[0, :, :2]
        away = (np.hypot(*(xy - takeoff).T) > near) & (np.hypot(*(xy - landing).T) > near)
        steps[0] += int(flag.sum())
        steps[1] += int((flag & away).sum())

    play(env, make_policy("allocation_plan"), seed, prior, count)
    return steps[0], steps[1], float(env.sim_state.posc[0])


if __name__ == "__main__":
    cell = float(sys.argv[1])
    for n in [int(v) for v in sys.argv[2].split(",")]:
        sc, prior = case(cell, n)
        p = make_allocation_plan(sc, prior=prior)
        pairs = planned_pairs(sc, p)
        line = (
            f"cell {cell} uavs {n} posc {p['posc']:.4f} start {p['start']} "
            f"no_route {sum(1 for x in p['uavs'] if not x['waypoints_m'])} "
            f"planned_collision_steps {sum(pairs.values())} pairs {pairs}"
        )
        if len(sys.argv) > 3:
            fl, away, pc = flown_collisions(sc, prior)
            line += f" flown_collision_steps {fl} away_from_fields {away} flown_posc {pc:.4f}"
        print(line, flush=True)
