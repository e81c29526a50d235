"""Do the teacher's labels make sense off its own route? (DAgger's precondition, issue 28.)

For each episode (a random ``paper_6_2`` prior from this script's own stream, never a training,
demonstration, DAgger or evaluation stream) the teacher (``allocation_plan``) plans on the prior
and is asked every step for its action at the states a *learner* (a ``ppo:`` checkpoint) flies
it into, as DAgger asks it (:func:`poc_env.agents.rl.bc.dagger_rollouts`). The script records

* how the teacher's waypoint follower advances along its routes while the learner flies:
  waypoints *reached* (within half a step), *passed* (the closest-approach rule: the UAV came
  within the capture radius and moves away again), or dropped by the *return* rule (eq. 18);
  the same counts when the teacher flies itself;
* the distance of each searching UAV from the teacher's current leg (its pure-pursuit target
  line) while the learner flies;
* hand-over episodes: the learner flies the first ``h`` steps, then the teacher (which has been
  tracking the learner's flight all along) flies the rest. If its labels at the learner's
  states are sound, it steers back to its route (the leg distance falls after the hand-over)
  and the episode's POSC lies between the learner's and the teacher's.

    PYTHONPATH=. python results/dagger/label_check.py ppo:RUN/bc_dagger/iter_0.zip \
        --episodes 10 --handover 20,50,90 --out results/dagger/label_check.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from poc_env.agents.policies.registry import make_policy
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.io import write_text_atomic
from poc_env.sim.autopilot import must_return
from poc_env.sim.engine import RandomPrior
from poc_env.sim.observations import decode_vector, split_observation

#: this script's stream: SeedSequence(seed, spawn_key=CHECK_KEY)
CHECK_KEY = (0xBC, 0x10)


def leg_distance(follower, k: int, xy: np.ndarray) -> float | None:
    """Metres from ``xy`` to UAV ``k``'s current leg (the first waypoint before the route
    starts), None once the follower has finished the route."""
    wps, i = follower.waypoints[k], int(follower.index[k])
    if i >= len(wps):
        return None
    if i == 0:
        return float(np.hypot(*(wps[0] - xy)))
    p, q = wps[i - 1], wps[i]
    d = q - p
    t = float(np.clip(np.dot(xy - p, d) / max(float(np.dot(d, d)), 1e-12), 0.0, 1.0))
    return float(np.hypot(*(p + t * d - xy)))


def episode(scenario, teacher, learner, seed, prior, handover):
    """One episode: the learner flies the first ``handover`` steps (None: all of them; 0: the
    teacher flies alone), the teacher is asked every step. Returns POSC, advance counts and
    leg distances (before and after the hand-over)."""
    env = UAVSearchParallelEnv(scenario=scenario)
    p = env.params
    obs, _ = env.reset(seed=seed, options={"prior": prior})
    t = make_policy(teacher)
    t.reset(env, seed)
    f = t.follower
    if learner is not None:
        pol = make_policy(learner)
        pol.reset(env, seed)
    counts = {"reached": 0, "passed": 0, "return": 0}
    dist_before: list[float] = []
    dist_after: list[list[float]] = []  # per step after the hand-over
    step = 0
    agents = list(env.possible_agents)
    while env.agents:
        before = f.index.copy()
        qs = {a: decode_vector(p, split_observation(obs[a], p.grid.shape)[1]) for a in env.agents}
        t_act, _ = t.predict(obs)
        for a in env.agents:
            k = agents.index(a)
            adv = int(f.index[k] - before[k])
            if adv <= 0:
                continue
            if f.index[k] >= len(f.waypoints[k]) and must_return(p, qs[a], k):
                counts["return"] += 1  # the route was cut short: eq. 18's rule
                continue
            xy = np.asarray(qs[a]["xy"], dtype=float)
            reach = 0.5 * float(qs[a]["speed"]) * p.dt
            d = float(np.hypot(*(f.waypoints[k][before[k]] - xy)))
            counts["reached" if d <= reach else "passed"] += 1
            counts["reached"] += adv - 1  # further waypoints within reach at once
        ds = [leg_distance(f, agents.index(a), np.asarray(qs[a]["xy"], float)) for a in env.agents]
        ds = [d for d in ds if d is not None]
        learner_flies = learner is not None and (handover is None or step < handover)
        if learner_flies:
            act, _ = pol.predict(obs)
            dist_before.extend(ds)
        else:
            act = t_act
            if handover is not None and handover > 0 and learner is not None:
                while len(dist_after) <= step - handover:
                    dist_after.append([])
                dist_after[step - handover].extend(ds)
        obs, *_ = env.step(act)
        step += 1
    posc = float(env.sim_state.posc[0])
    env.close()
    return {
        "posc": posc,
        "counts": counts,
        "leg_km_learner_median": float(np.median(dist_before)) / 1e3 if dist_before else None,
        "leg_km_after_handover_median": [
            float(np.median(d)) / 1e3 if d else None for d in dist_after[:15]
        ],
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("learner", help="ppo:PATH of the learner")
    ap.add_argument("--teacher", default="allocation_plan")
    ap.add_argument("--scenario", default="paper_6_2")
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--handover", default="20,50,90", help="comma-separated steps")
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args(argv)
    handovers = [int(h) for h in a.handover.split(",") if h]
    env = UAVSearchParallelEnv(scenario=a.scenario)
    rng = np.random.default_rng(np.random.SeedSequence(a.seed, spawn_key=CHECK_KEY))
    rows = []
    for e in range(a.episodes):
        seed = int(rng.integers(0, 2**31))
        prior = RandomPrior().draw(env.params.grid, rng)
        row = {"seed": seed}
        row["teacher"] = episode(a.scenario, a.teacher, None, seed, prior, None)
        row["learner"] = episode(a.scenario, a.teacher, a.learner, seed, prior, None)
        for h in handovers:
            row[f"handover_{h}"] = episode(a.scenario, a.teacher, a.learner, seed, prior, h)
        rows.append(row)
        print(
            e,
            seed,
            {k: round(v["posc"], 4) for k, v in row.items() if isinstance(v, dict)},
            flush=True,
        )
    keys = [k for k in rows[0] if k != "seed"]
    summary = {}
    for k in keys:
        posc = np.array([r[k]["posc"] for r in rows])
        kinds = ("reached", "passed", "return")
        counts = {c: int(sum(r[k]["counts"][c] for r in rows)) for c in kinds}
        after = [r[k]["leg_km_after_handover_median"] for r in rows]
        curve = []
        for j in range(15):
            v = [x[j] for x in after if len(x) > j and x[j] is not None]
            curve.append(round(float(np.median(v)), 2) if v else None)
        lk = [r[k]["leg_km_learner_median"] for r in rows]
        lk = [x for x in lk if x is not None]
        summary[k] = {
            "posc_mean": round(float(posc.mean()), 4),
            "posc_minus_teacher": round(
                float((posc - np.array([r["teacher"]["posc"] for r in rows])).mean()), 4
            ),
            "advances": counts,
            "leg_km_while_learner_flies_median": round(float(np.median(lk)), 2) if lk else None,
            "leg_km_after_handover_by_step": curve if any(c is not None for c in curve) else None,
        }
    out = {"learner": a.learner, "teacher": a.teacher, "episodes": a.episodes, "summary": summary,
           "rows": rows}  # fmt: skip
    write_text_atomic(a.out, json.dumps(out, indent=1) + "\n")
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
