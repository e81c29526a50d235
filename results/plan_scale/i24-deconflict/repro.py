"""i24-deconflict: eq. 21 conflicts of allocation plans, planned and flown (a script, not a test).

``python repro.py smoke CASE N``
    ``large_400`` at 10 km cells with one zone, N UAVs: CASE ``lanes`` (the zone between
    airfield A and two sightings, tests/planning/test_deconflict.py's case) or ``mono2`` (the
    audit's results/audit/scale/raw/mono2.py case: nine sightings, two of them by a zone).
``python repro.py scenario PATH [N]``
    A scenario file (the audit's 500 km ``big.yaml``) on its own prior.

Each plans the default allocation plan twice, every UAV the router's own way round the zones
(``router``: ``in_lanes`` replaced by lane 0, the planner before i24-deconflict) and as
planned (``lanes``), and prints per plan: planned POS_C, UAVs without a route, planned conflict
pairs-steps (:func:`poc_env.agents.planning.deconflict.conflicts`, away from the fields,
120 s slack), planned collision pair-steps (d_s at the same planned time, every step,
fields included) with the worst pairs, and the flown episode (seed 5000): collision UAV-steps,
those away from the fields, flown POSC.
"""

import json
import sys
import time

import numpy as np

import poc_env.agents.planning.allocation as allocation
from poc_env.agents.planning.deconflict import conflicts, planned_positions
from poc_env.agents.planning.flight_rules import SPEED, plan_speeds
from poc_env.agents.planning.refine import track
from poc_env.config import load_scenario
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior

LANES_CASE = ([[40, 20], [120, 20], [120, 60], [40, 60]], [(80, 110, 0.5), (80, 200, 0.5)])
ZONE = [[100, 150], [175, 150], [175, 225], [100, 225]]  # mono2.py's
SIGHTINGS = [
    (160.9, 151.6, 0.1), (139.1, 226.6, 0.1), (301.6, 45.3, 0.06), (123.4, 98.4, 0.12),
    (373.4, 126.6, 0.1), (251.6, 273.4, 0.06), (26.6, 380, 0.15), (160.9, 380, 0.09),
    (307.8, 380, 0.04),
]  # fmt: skip


def case(name: str, n: int):
    """``large_400`` at 10 km cells, one zone, point sightings (the module docstring)."""
    zone, pts = LANES_CASE if name == "lanes" else (ZONE, SIGHTINGS)
    sc = load_scenario("large_400", {"map.cell_km": 10, "map.no_fly_zones_km": [zone]})
    g = Grid.from_config(sc.map)
    prior = np.zeros(g.shape)
    for x, y, w in pts:
        prior[int(y // 10), int(x // 10)] += w
    return sc.with_uavs(n), prior / prior.sum()


def router_way(sc, routes, v, around):
    """Every UAV the router's own way round (lane 0): the planner before i24-deconflict."""
    return [around(k, r, 0) if len(r) else [] for k, r in enumerate(routes)]


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


def flown_collisions(sc, prior, seed=5000, policy=None) -> tuple[int, int, float]:
    """Flown collision UAV-steps (the environment's ``violation_collision``), those of them
    away from the airfields (the UAV farther than ``d_s / sin 20 deg`` from its take-off and
    landing field: what the deconfliction addresses) and POSC of the ``allocation_plan``
    policy on ``prior`` (or of ``policy``, when given)."""
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

    play(env, policy or make_policy("allocation_plan"), seed, prior, count)
    return steps[0], steps[1], float(env.sim_state.posc[0])


def record(sc, prior, label: str) -> dict:
    t0 = time.perf_counter()
    p = allocation.make_allocation_plan(sc, prior=prior)
    plan_s = time.perf_counter() - t0
    v = plan_speeds(sc, SPEED)
    _, pos, act = planned_positions(sc, [u["waypoints_m"] for u in p["uavs"]], v)
    pairs = planned_pairs(sc, p)
    fl, away, pc = flown_collisions(sc, prior)
    return {
        "plan": label,
        "uavs": sc.n_uavs,
        "posc": round(float(p["posc"]), 4),
        "start": p["start"],
        "no_route": sum(1 for u in p["uavs"] if not u["waypoints_m"]),
        "planned_conflicts": int(conflicts(sc, pos, act).sum()) // 2,
        "planned_collision_pair_steps": sum(pairs.values()),
        "worst_pairs": [[a, b, c] for (a, b), c in sorted(pairs.items(), key=lambda x: -x[1])[:4]],
        "flown_collision_steps": fl,
        "flown_away_from_fields": away,
        "flown_posc": round(pc, 4),
        "plan_s": round(plan_s, 1),
    }


if __name__ == "__main__":
    if sys.argv[1] == "smoke":
        sc, prior = case(sys.argv[2], int(sys.argv[3]))
    else:
        sc = load_scenario(sys.argv[2])
        sc = sc.with_uavs(int(sys.argv[3])) if len(sys.argv) > 3 else sc
        prior = build_prior(sc.map)
    real = allocation.in_lanes
    for label, fn in (("router", router_way), ("lanes", real)):
        allocation.in_lanes = fn
        print(json.dumps({"case": " ".join(sys.argv[1:3]), **record(sc, prior, label)}), flush=True)
