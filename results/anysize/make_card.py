"""The card of agents/checkpoints/ppo_set_anysize.json: :func:`poc_env.agents.rl.card.make_card`
(the run's config, the checkpoint's step, its evaluation on its own task) plus the training
budget as measured and the paired results of every condition of results/anysize/eval_*.

    python results/anysize/make_card.py
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from poc_env.agents.rl.card import make_card
from poc_env.io import write_text_atomic

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
POLICY = "ppo:ppo_set_anysize"
RECIPE = (
    "poc-env train --task UAVSearch-Paper62-Random-Set-Heading-v1 --also-task "
    "UAVSearch-Wide-N3-Random-Set-Heading-v1 UAVSearch-Wide-N6-Random-Set-Heading-v1 "
    "UAVSearch-Wide-N12-Random-Set-Heading-v1 UAVSearch-Wide-N24-Random-Set-Heading-v1 "
    "--net set --n-envs 2 --seed 1 --n-steps 256 --batch-size 3264 --overrides reward.alpha=100 "
    "reward.violation_penalty=0.5 reward.credit=individual --bc-teacher allocation_plan "
    "--total-timesteps 3916800 --checkpoint-every 261120 --keep-checkpoints 0 "
    "--run-dir runs/anysize_s1"
)
TRAINING = {
    "command": RECIPE,
    "note": "run with a 15,006,720 cap and stopped after this checkpoint (150 rollouts); the "
    "learning rate is constant, so --total-timesteps 3916800 gives the same checkpoint",
    "ppo_transitions": 3916800,
    "bc": "32 allocation_plan episodes of paper_6_2 (bc.json of the run)",
    "wall_min": 74.6,
    "cpu_min": 11.5,
    "load": "load average 7-16 on 2 cores (5-6 other jobs), 2026-11-27 21:39-22:54 UTC",
    "selection": "last checkpoint; the best or within 0.01 of the best on validation priors "
    "5000-5019 at every condition (results/anysize/heldout/curve.csv)",
}
CONDITIONS = {
    "paper62": "UAVSearch-Paper62-Random-Set-Heading-v1",
    "tall": "UAVSearch-Paper62-Random-Set-Heading-v1 with map.width_km=150 map.height_km=200",
    "wide_n6": "UAVSearch-Wide-N6-Random-Set-Heading-v1",
    "wide_n12": "UAVSearch-Wide-N12-Random-Set-Heading-v1",
    "wide_n24": "UAVSearch-Wide-N24-Random-Set-Heading-v1",
}


def main() -> Path:
    card = make_card(
        ROOT / "runs/anysize_s1/checkpoints/step_3916800.zip",
        ROOT / "runs/anysize_s1",
        HERE / "ppo_paper62",
        POLICY,
    )
    card["training"] = TRAINING
    evals = {}
    for key, cond in CONDITIONS.items():
        folder = HERE / f"eval_{key}"
        means = {r["policy"]: float(r["posc_mean"]) for r in csv.DictReader(
            (folder / "evaluate.csv").open())}  # fmt: skip
        paired = [r for r in csv.DictReader((folder / "paired.csv").open())
                  if r["policy"] == POLICY]  # fmt: skip
        p = paired[0]
        evals[key] = {
            "condition": cond,
            "seeds": "28000-28049",
            "posc_mean": means[POLICY],
            "allocation_plan": means["allocation_plan"],
            "greedy_bayes": means["greedy_bayes"],
            "minus_allocation_plan": float(p["diff_mean"]),
            "ci95": float(p["diff_ci95"]),
            "wins": int(p["wins"]),
            "losses": int(p["losses"]),
            "folder": f"results/anysize/eval_{key}",
        }
    card["evaluations"] = evals
    out = ROOT / "agents/checkpoints/ppo_set_anysize.json"
    return write_text_atomic(out, json.dumps(card, indent=1) + "\n")


if __name__ == "__main__":
    print(f"wrote {main()}")
