"""One re-plan decision of ``spacetime_receding`` taken apart: fly the take-off plan to
``--at`` minutes, then score the routes being flown and the re-plan several ways.

    PYTHONPATH=. python results/moving/recede/probe.py --task UAVSearch-Paper61-Drift-Heading-v1 \
        --seed 8000 --at 20
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from poc_env.agents.planning.allocation import make_allocation_plan, sampled_sweep
from poc_env.agents.planning.spacetime import (
    airborne_poc,
    airborne_scenario,
    choose_routes,
    comoving_route,
    ground_plan,
    spacetime_plan,
)
from poc_env.agents.policies.moving import SpacetimeRecedingPolicy, drift_of
from poc_env.agents.policies.replan_choice import ReplanChoicePolicy, _kept, _plan_routes
from poc_env.config import parse_overrides
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.sim.core import operating_area
from poc_env.tasks import get_task
from poc_env.theory.probability_map import Grid


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--task", required=True)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--at", type=float, nargs="+", default=[20.0])
    ap.add_argument("--overrides", nargs="*", default=[])
    args = ap.parse_args()
    sc = get_task(args.task).load_scenario(
        parse_overrides(args.overrides) if args.overrides else {}
    )
    env = UAVSearchParallelEnv(scenario=sc)
    obs, _ = env.reset(seed=args.seed)
    pol = SpacetimeRecedingPolicy(replan_min=1e4)  # never re-plans: the take-off plan flown
    pol.reset(env, args.seed)
    p = env.params
    v0 = pol.follower
    plan0 = spacetime_plan(
        sc,
        np.array(env.sim_state.belief[0], dtype=float),
        drift_of(env),
        env.params.s,
        seed=args.seed,
        **pol.alloc,
    )
    print("take-off plan's own posc", plan0.get("posc"), "cut", plan0.get("cut_outside_area", 0))
    print(
        "take-off plan: waypoints per UAV",
        [len(w) for w in v0.waypoints],
        "speeds out/line",
        v0.transit_speed,
        v0.pattern_speed,
    )
    for at in args.at:
        while env.agents and float(env.sim_state.step[0]) * p.dt < at * 60.0:
            actions, _ = pol.predict(obs)
            obs, *_ = env.step(actions)
        now = float(env.sim_state.step[0]) * p.dt
        ks, xy = ReplanChoicePolicy.searching(pol, obs)  # type: ignore[arg-type]
        drift = drift_of(env)
        belief = np.array(env.sim_state.belief[0], dtype=float)
        poc = airborne_poc(sc, belief, drift, p.s, xy, now, ks)
        asc = airborne_scenario(sc, xy, now, ks)
        raw = make_allocation_plan(asc, prior=poc, seed=args.seed + 1, **pol.alloc)
        plan = ground_plan(raw, xy, drift, operating_area(sc))  # what replan returns
        nocut = ground_plan(raw, xy, drift, None)  # the same routes, none dropped
        old = pol.follower
        kept, kept_v = _kept(old, ks)
        new, new_v, v = _plan_routes(plan, len(ks), old)
        new_nc, new_nc_v, _ = _plan_routes(nocut, len(ks), old)
        cands = [(kept, kept_v), (new, new_v), (new_nc, new_nc_v)]
        at_now = (sc, belief, drift, p.s, xy, now, ks)
        pick, scores = choose_routes(*at_now, cands, pol.margin, poc=poc)
        grid = Grid.from_config(asc.map)
        usable = asc.uav.usable_endurance_s

        def durations(routes, speeds, xy=xy):
            out = []
            for j in range(len(xy)):
                g = np.vstack([xy[j], np.asarray(routes[j]).reshape(-1, 2)])
                legs = np.hypot(*np.diff(g, axis=0).T)
                out.append(float(np.sum(legs / np.asarray(speeds[j][: len(legs)]))) / 60.0)
            return out

        def per_uav(routes, speeds, xy=xy, asc=asc, grid=grid, poc=poc, drift=drift):
            paths = [
                np.vstack([xy[j], comoving_route(xy[j], routes[j], drift, speeds[j])])
                for j in range(len(xy))
            ]
            return sampled_sweep(asc, grid, poc, paths)[0]

        rec = {
            "at_min": now / 60,
            "ks": ks,
            "drift_mps": drift.tolist(),
            "indices": [int(old.index[k]) for k in ks],
            "usable_left_min": usable / 60,
            "poc_sum": float(poc.sum()),
            "belief_sum": float(belief.sum()),
            "scores(kept,new,new without the cut)": scores,
            "pick": pick,
            "new plan's own posc": plan.get("posc"),
            "new plan cut_outside_area": plan.get("cut_outside_area", 0),
            "new speeds": v,
            "kept waypoints": [len(w) for w in kept],
            "new waypoints": [len(w) for w in new],
            "kept duration min": [round(d, 1) for d in durations(kept, kept_v)],
            "new duration min": [round(d, 1) for d in durations(new, new_v)],
            "kept pos per uav": [round(x, 4) for x in per_uav(kept, kept_v)],
            "new pos per uav": [round(x, 4) for x in per_uav(new, new_v)],
        }
        print(json.dumps(rec, indent=1))


if __name__ == "__main__":
    main()
