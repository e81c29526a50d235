"""i24-flownsep: where the flown eq. 21 collisions of an allocation plan come from (a script).

``python diag.py smoke CASE N`` (repro.py's cases), ``python diag.py scenario PATH [N]`` or
``python diag.py prior MAP SEED`` (the random prior of SEED, flown with SEED): plans the
default allocation plan as the ``allocation_plan`` policy does (seed 5000, or SEED), flies it
(the same seed) and prints one JSON line per collision pair-step away from the fields: step,
UAVs, distance, and per UAV where it is, its phase (``transit`` to its first waypoint,
``search`` on its route, ``home`` after its last waypoint or cut short by eq. 18's return --
the follower marks both alike; ``wp`` shows how far it got), the planned time at the flown
point (the planned sample nearest the flown position, within the UAV's own plan; ``null``
for a UAV without a route), its distance and the flown time minus it (``drift_s``); then a
summary by phase pair.
"""

import collections
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "i24-deconflict"))
from repro import case

from poc_env.agents.experiments.evaluate import play
from poc_env.agents.planning.deconflict import FAN_DEG, planned_positions
from poc_env.agents.planning.flight_rules import Speeds
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.theory.probability_map import build_prior


def main(sc, prior, seed=5000, quiet=False):
    env = UAVSearchParallelEnv(scenario=sc)
    pol = make_policy("allocation_plan")
    takeoff = np.asarray(sc.takeoff_m, float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, float).reshape(-1, 2)
    near = sc.constraints.safety_distance_m / np.sin(np.radians(FAN_DEG))
    d_s = sc.constraints.safety_distance_m
    dt = sc.episode.dt_s
    rows = []
    state = {"t": 0, "planned": None, "cut": None}

    def each(infos):
        f = pol.follower
        if state["planned"] is None:
            sp = pol.plan.get("speeds_mps")
            v = Speeds(sp["out"], sp["line"], sp["home"]) if sp else None
            routes = [u["waypoints_m"] for u in pol.plan["uavs"]]
            state["planned"] = planned_positions(sc, routes, v)
            state["cut"] = np.zeros(len(takeoff), bool)
        state["t"] += 1
        t = state["t"] * dt
        st = env.sim_state
        xy = st.pos[0, :, :2]
        times, ppos, pact = state["planned"]
        away = (np.hypot(*(xy - takeoff).T) > near) & (np.hypot(*(xy - landing).T) > near)
        flag = np.array(
            [
                bool(infos.get(f"uav_{k}", {}).get("violation_collision", False))
                for k in range(len(takeoff))
            ]
        )
        d = np.hypot(*(xy[:, None] - xy[None]).transpose(2, 0, 1))
        for i in range(len(takeoff)):
            for j in range(i + 1, len(takeoff)):
                if flag[i] and flag[j] and d[i, j] < d_s and (away[i] or away[j]):
                    rec = {
                        "step": state["t"],
                        "t_s": t,
                        "uavs": [i, j],
                        "d_m": round(float(d[i, j])),
                    }
                    for k in (i, j):
                        n = len(f.waypoints[k])
                        idx = int(f.index[k])
                        phase = "transit" if idx == 0 else "search" if idx < n else "home"
                        gap = np.hypot(*(ppos[:, k] - xy[k]).T)
                        gap[~pact[:, k]] = np.inf
                        s = int(np.argmin(gap))
                        ok = bool(np.isfinite(gap[s]))
                        rec[f"u{k}"] = {
                            "phase": phase,
                            "wp": f"{idx}/{n}",
                            "xy_km": [round(float(c) / 1e3, 1) for c in xy[k]],
                            "planned_t_s": float(times[s]) if ok else None,
                            "off_plan_m": round(float(gap[s])) if ok else None,
                            "drift_s": float(t - times[s]) if ok else None,
                        }
                    rows.append(rec)

    play(env, pol, seed, prior, each)
    summ = collections.Counter()
    for r in rows:
        ks = r["uavs"]
        summ[tuple(sorted(r[f"u{k}"]["phase"] for k in ks))] += 1
        if not quiet:
            print(json.dumps(r))
    print(
        json.dumps(
            {
                "pair_steps": len(rows),
                "by_phase": {"+".join(k): v for k, v in summ.items()},
                "posc": round(float(env.sim_state.posc[0]), 4),
            }
        )
    )
    return rows


if __name__ == "__main__":
    if sys.argv[1] == "smoke":
        sc, prior = case(sys.argv[2], int(sys.argv[3]))
    elif sys.argv[1] == "prior":  # MAP SEED: the random prior of that seed, flown with it
        from poc_env.agents.experiments.evaluate import episode_prior

        sc = load_scenario(sys.argv[2])
        main(sc, episode_prior(sc, int(sys.argv[3])), int(sys.argv[3]))
        sys.exit()
    else:
        sc = load_scenario(sys.argv[2])
        sc = sc.with_uavs(int(sys.argv[3])) if len(sys.argv) > 3 else sc
        prior = build_prior(sc.map)
    main(sc, prior)
