"""i24-chain: fleet-chained plans (``plan_fleets``) against one size at a time, planned and
flown, with the flown eq. 21 collision UAV-steps split by who meets whom (a script, not a test;
run it from the checkout).

``python chain.py SCENARIO MODE SIZES OUT_DIR``
    SCENARIO a scenario file (the audit's 500 km ``big.yaml``) planned on its own prior, or
    ``mini:SIDE_KM:CELL_KM`` (tests/planning/test_fleet.py's ``mini``); MODE ``chain`` (the
    sizes planned by :func:`~poc_env.agents.planning.allocation.plan_fleets`, each on the plan
    of the one before) or ``single`` (each size its own default plan, ``plan --uavs N``);
    SIZES ``16,32,48,64``. One JSON line per size on stdout; the plans written to OUT_DIR
    (``MODE_nN.json``) for re-flying.

Per size: planned POS_C, UAVs without a route, the kept plan (``fleet.kept``: floor / own),
planning CPU seconds, and the plan flown once by the waypoint follower (``allocation_plan``'s
episode, seed 5000: deterministic here) -- flown POSC, collision UAV-steps in all and away from
the fields (results/plan_scale/i24-deconflict/repro.py's rule: farther than d_s / sin FAN_DEG
from the UAV's take-off and landing fields), and of those, the UAV-steps of a *floor* UAV
(one flying its route of the smaller fleet's plan) in collision with floor UAVs only
(``floor_only``) against those where an added UAV (any other: given a new route) takes
part (``with_added``).
"""

import json
import os
import sys
import time

import numpy as np

from poc_env.agents.experiments.evaluate import play
from poc_env.agents.planning.allocation import (
    FAN_DEG,
    _mapped,
    make_allocation_plan,
    plan_fleets,
)
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.theory.probability_map import build_prior


def scenario(name: str):
    """The scenario (all its UAVs) and its prior."""
    if name.startswith("mini"):
        sys.path.insert(0, "tests/planning")
        from test_fleet import mini

        sc, prior = mini(*map(float, name.split(":")[1:3]), 64)
        return sc, prior
    sc = load_scenario(name)
    return sc, build_prior(sc.map)


def flown(sc, prior, plan, added: set[int], seed: int = 5000) -> dict:
    """The plan flown by the follower: POSC and collision UAV-steps, split (module docstring)."""
    env = UAVSearchParallelEnv(scenario=sc)
    takeoff = np.asarray(sc.takeoff_m, float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, float).reshape(-1, 2)
    near = sc.constraints.safety_distance_m / np.sin(np.radians(FAN_DEG))
    d_s = sc.constraints.safety_distance_m
    n = len(takeoff)
    is_added = np.array([k in added for k in range(n)])
    c = {"all": 0, "away": 0, "away_floor_only": 0, "away_with_added": 0}

    def count(infos) -> None:
        flag = np.zeros(n, bool)
        for a, i in infos.items():
            flag[int(a.rsplit("_", 1)[1])] = bool(i["violation_collision"])
        xy = env.sim_state.pos[0, :, :2]
        away = (np.hypot(*(xy - takeoff).T) > near) & (np.hypot(*(xy - landing).T) > near)
        c["all"] += int(flag.sum())
        c["away"] += int((flag & away).sum())
        d = np.hypot(*(xy[:, None] - xy[None]).transpose(2, 0, 1))
        for k in np.flatnonzero(flag & away):
            mates = flag & (d[k] < d_s)
            mates[k] = False
            if is_added[k] or (mates & is_added).any():
                c["away_with_added"] += 1
            else:
                c["away_floor_only"] += 1

    pol = make_policy("allocation_plan")
    pol.make = lambda env, prior, seed, plan=plan: plan  # type: ignore[method-assign]
    play(env, pol, seed, prior, count)
    return {"flown_posc": round(float(env.sim_state.posc[0]), 4), **c}


def main() -> None:
    name, mode, sizes, out = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
    # optional: PlanOptions fields changed, e.g. ``half_fleet=false`` (bools only)
    changes = dict(kv.split("=") for kv in sys.argv[5].split(",")) if len(sys.argv) > 5 else {}
    opt = PlanOptions(**{k: v.lower() == "true" for k, v in changes.items()})
    ns = [int(s) for s in sizes.split(",")]
    sc_all, prior = scenario(name)
    os.makedirs(out, exist_ok=True)
    plans, cpu = [], []
    if mode == "chain":
        t = [time.process_time()]

        def each(p) -> None:
            cpu.append(time.process_time() - t[0])
            t[0] = time.process_time()

        plans = plan_fleets(sc_all, ns, prior=prior, each=each, options=opt)
    else:
        for n in ns:
            t0 = time.process_time()
            plans.append(make_allocation_plan(sc_all.with_uavs(n), prior=prior, options=opt))
            cpu.append(time.process_time() - t0)
    prev = None
    for n, plan, s in zip(ns, plans, cpu, strict=True):
        sc = sc_all.with_uavs(n)
        fl = plan["optimizer"]["settings"].get("fleet", {})
        base = _mapped(sc, prev) if (mode == "chain" and prev is not None) else None
        kept_floor = fl.get("kept") == "floor"
        added = {k for k in range(n) if base is not None and kept_floor
                 and plan["uavs"][k]["waypoints_m"] != base[k]}  # fmt: skip
        with open(os.path.join(out, f"{mode}_n{n}.json"), "w") as f:
            json.dump(plan, f)
        rec = {
            "case": name,
            "mode": mode,
            "options": changes,
            "uavs": n,
            "posc": round(float(plan["posc"]), 4),
            "no_route": sum(1 for u in plan["uavs"] if not u["waypoints_m"]),
            "kept": fl.get("kept"),
            "start": plan["start"],
            "plan_cpu_s": round(s, 1),
            "load1": round(os.getloadavg()[0], 1),
            **flown(sc, prior, plan, added),
        }
        print(json.dumps(rec), flush=True)
        prev = plan


if __name__ == "__main__":
    main()
