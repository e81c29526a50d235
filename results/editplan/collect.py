"""Fly every plan-choice candidate on random priors (i28-editplan; results/editplan/README.md).

``python results/editplan/collect.py SEED0 SEED1 OUT.jsonl [KEY=VALUE ...]``: for each episode
seed in ``[SEED0, SEED1)`` the random prior of ``poc-env evaluate --random-priors``
(:func:`~poc_env.agents.experiments.evaluate.episode_prior`) on ``paper_6_2`` (with scenario
overrides ``KEY=VALUE``, e.g. ``map.width_km=150 map.height_km=200``), its
:func:`~poc_env.agents.policies.plan_choice.prior_features`, and per candidate of
:data:`~poc_env.agents.policies.plan_choice.CANDIDATES` the plan's CPU seconds and planned POS,
its flown POSC and violation steps. One JSON line per seed, appended after each seed (a rerun
resumes). Run one thread: ``OMP_NUM_THREADS=1 nice -n 10 python ...``.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from poc_env.agents.experiments.evaluate import episode_prior, play
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.policies.base import PlanPolicy
from poc_env.agents.policies.plan_choice import CANDIDATES, options_of, prior_features
from poc_env.config import load_scenario
from poc_env.envs.parallel import UAVSearchParallelEnv


class _Given(PlanPolicy):
    """Flies a plan made beforehand."""

    def __init__(self, plan: dict) -> None:
        self.given = plan

    def make(self, env, prior, seed):
        return self.given


def scenario(overrides: list[str]):
    from poc_env.config import parse_overrides

    return load_scenario("paper_6_2", parse_overrides(overrides))


def main(seed0: int, seed1: int, out: str, overrides: list[str]) -> None:
    sc = scenario(overrides)
    path = Path(out)
    done = set()
    if path.exists():
        done = {json.loads(line)["seed"] for line in path.read_text().splitlines() if line}
    make_allocation_plan(sc, prior=episode_prior(sc, seed0), seed=seed0)  # compile and warm up
    for seed in range(seed0, seed1):
        if seed in done:
            continue
        prior = episode_prior(sc, seed)
        rec: dict = {"seed": seed, "features": prior_features(sc, prior).tolist(), "cands": {}}
        for name in CANDIDATES:
            t = time.process_time()
            plan = make_allocation_plan(sc, prior=prior, seed=seed, options=options_of(name))
            plan_s = time.process_time() - t
            env = UAVSearchParallelEnv(scenario=sc)
            play(env, _Given(plan), seed, prior)
            st = env.sim_state
            rec["cands"][name] = {
                "posc": float(st.posc[0]),
                "planned": float(plan["posc"]),
                "violations": int(st.violations[0].sum()),
                "plan_s": plan_s,
                "start": plan.get("start"),
            }
        with path.open("a") as f:
            f.write(json.dumps(rec) + "\n")
        d = rec["cands"]["default"]["posc"]
        best = max(c["posc"] for c in rec["cands"].values())
        print(f"seed {seed} default {d:.4f} best-of-K {best - d:+.4f}", flush=True)


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4:])
