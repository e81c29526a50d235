"""Fly ``spacetime_receding`` (and ``spacetime_plan``) and log every re-plan decision: when it
was due, whether it was made (and why not), which UAVs, the two scores (kept, new), the pick.

    PYTHONPATH=. python results/moving/recede/instrument.py \
        --task UAVSearch-Paper61-Drift-Heading-v1 --seeds 8000 8001 --out records/p61.jsonl \
        [--overrides target.random_current_kmh=60] [--no-plan]

One JSON line per episode: task, seed, both POSCs, the re-plan log. A debug script (the
policy's own ``scores`` and ``switches`` are what it keeps; this adds the skipped calls).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from poc_env.agents.policies.moving import SpacetimePlanPolicy, SpacetimeRecedingPolicy
from poc_env.config import parse_overrides
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.io import write_text_atomic
from poc_env.tasks import get_task


class Logged(SpacetimeRecedingPolicy):
    """``spacetime_receding`` with a log of every due re-plan."""

    def reset(self, env, seed):
        super().reset(env, seed)
        self.log: list[dict] = []

    def _replan(self, observations, now):
        n_scores, n_plans = len(self.scores), self.plans
        super()._replan(observations, now)
        row: dict = {"min": round(now / 60.0, 2)}
        if self.plans == n_plans:
            left = self.env.scenario.uav.endurance_s - now
            row["made"] = False
            row["why"] = "late" if left < 0.2 * self.env.scenario.uav.endurance_s else "no UAV"
        else:
            kept, new = self.scores[n_scores]
            row.update(
                made=True, kept=kept, new=new, diff=new - kept, switched=new > kept + self.margin
            )
        self.log.append(row)


def fly(policy, scenario, seed):
    env = UAVSearchParallelEnv(scenario=scenario)
    obs, _ = env.reset(seed=seed)
    policy.reset(env, seed)
    while env.agents:
        actions, _ = policy.predict(obs)
        obs, *_ = env.step(actions)
    return float(env.sim_state.posc[0]), env


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--task", required=True)
    ap.add_argument("--seeds", type=int, nargs=2, required=True)
    ap.add_argument("--overrides", nargs="*", default=[])
    ap.add_argument("--no-plan", action="store_true", help="skip the spacetime_plan episode")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    sc = get_task(args.task).load_scenario(
        parse_overrides(args.overrides) if args.overrides else {}
    )
    lines = []
    for seed in range(args.seeds[0], args.seeds[1] + 1):
        t0 = time.perf_counter()
        pol = Logged()
        posc_r, env = fly(pol, sc, seed)
        rec = {
            "task": args.task,
            "overrides": args.overrides,
            "seed": seed,
            "drift_kmh": float(np.hypot(*env.sim_state.drift[0]) * 3.6),
            "receding": posc_r,
            "switches": pol.switches,
            "log": pol.log,
        }
        if not args.no_plan:
            rec["plan"] = fly(SpacetimePlanPolicy(), sc, seed)[0]
        rec["seconds"] = round(time.perf_counter() - t0, 1)
        lines.append(json.dumps(rec))
        made = [r for r in pol.log if r["made"]]
        print(
            seed,
            f"drift {rec['drift_kmh']:.1f} km/h receding {posc_r:.4f}",
            f"plan {rec.get('plan', float('nan')):.4f}",
            f"due {len(pol.log)} made {len(made)} switched {pol.switches}",
            "diffs",
            [round(r["diff"], 4) for r in made],
            f"{rec['seconds']}s",
            flush=True,
        )
        write_text_atomic(args.out, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
