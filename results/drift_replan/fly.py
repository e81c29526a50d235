"""Fly receding-choice policies on a seed range and write one CSV row per episode (and, for
the oracle, its decisions as JSON lines): the measurement script of results/drift_replan.

    PYTHONPATH=. python results/drift_replan/fly.py --seeds 3100 3119 --chooser oracle \
        --decide 10 20 30 --out runs/drift_replan/oracle_sel.csv [--decisions FILE.jsonl]
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import time
from pathlib import Path

from poc_env.agents.policies.replan_choice import ReplanChoicePolicy, from_spec
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.io import write_text_atomic
from poc_env.tasks import get_task

TASK = "UAVSearch-Small-Drift-Heading-v1"


def fly(policy: ReplanChoicePolicy, scenario, seed: int) -> tuple[float, float]:
    env = UAVSearchParallelEnv(scenario=scenario)
    t0 = time.perf_counter()
    obs, _ = env.reset(seed=seed)
    policy.reset(env, seed)
    while env.agents:
        actions, _ = policy.predict(obs)
        obs, *_ = env.step(actions)
    return float(env.sim_state.posc[0]), time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs=2, required=True, help="first and last seed")
    ap.add_argument("--chooser", default="oracle")
    ap.add_argument("--spec", default=None, help="a receding_choice SPEC instead of --chooser")
    ap.add_argument("--model", default=None)
    ap.add_argument("--decide", type=float, nargs="+", default=[20.0])
    ap.add_argument("--no-variants", action="store_true")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--decisions", type=Path, default=None)
    args = ap.parse_args()
    sc = get_task(TASK).load_scenario({})
    rows, lines = [], []
    for seed in range(args.seeds[0], args.seeds[1] + 1):
        if args.spec is not None:
            pol = from_spec(args.spec)
        else:
            pol = ReplanChoicePolicy(
                args.chooser, args.model, tuple(args.decide), variants=not args.no_variants
            )
        posc, secs = fly(pol, sc, seed)
        picks = ";".join(d["names"][d["pick"]] for d in pol.decisions)
        rows.append({"seed": seed, "posc": posc, "seconds": round(secs, 3), "picks": picks})
        for d in pol.decisions:
            lines.append(json.dumps({"seed": seed, **d}))
        print(seed, f"{posc:.4f}", f"{secs:.2f}s", picks, flush=True)
        # the episodes so far, rewritten whole after each (a stopped run keeps them)
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
        write_text_atomic(args.out, buf.getvalue())
        if args.decisions is not None:
            write_text_atomic(args.decisions, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
