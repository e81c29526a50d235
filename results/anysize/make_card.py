"""The cards of the shipped any-size checkpoints: :func:`poc_env.agents.rl.card.make_card` (the
run's config, the checkpoint's step, its evaluation on its own task) plus the training budget as
measured and the paired results of every condition of the evaluation stream.

    python results/anysize/make_card.py                    # ppo_set_anysize.json
    python results/anysize/make_card.py ppo_set_increments_anysize   # results/setinc
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


#: the second any-size checkpoint (issue 28, 2026-11-28): the set observation at the eq. 19
#: increments level, BC of allocation_plan on every task (results/setinc/README.md)
SETINC_RECIPE = (
    "poc-env train --task UAVSearch-Paper62-Random-Set-Increments-v0 --also-task "
    "UAVSearch-Wide-N3-Random-Set-Increments-v0 UAVSearch-Wide-N6-Random-Set-Increments-v0 "
    "UAVSearch-Wide-N12-Random-Set-Increments-v0 UAVSearch-Wide-N24-Random-Set-Increments-v0 "
    "--net set --return-autopilot --n-envs 2 --seed 1 --n-steps 256 --batch-size 3264 "
    "--overrides reward.alpha=100 reward.violation_penalty=0.5 reward.credit=individual "
    "reward.crash_penalty=5 --bc-teacher allocation_plan --bc-episodes 16 --bc-epochs 30 "
    "--bc-log-std -2.5 --bc-all-tasks --total-timesteps 10000000 --checkpoint-every 522240 "
    "--keep-checkpoints 0 --run-dir runs/setinc_s1"
)
CARDS = {
    "ppo_set_anysize": {
        "step": "runs/anysize_s1/checkpoints/step_3916800.zip",
        "run": "runs/anysize_s1",
        "results": HERE,
        "training": TRAINING,
        "conditions": CONDITIONS,
    },
    "ppo_set_increments_anysize": {
        "step": "runs/setinc_s1/checkpoints/step_8355840.zip",
        "run": "runs/setinc_s1",
        "results": ROOT / "results/setinc",
        "training": {
            "command": SETINC_RECIPE,
            "ppo_transitions": 8355840,
            "bc": "16 allocation_plan episodes of each of the 5 tasks (bc.json of the run: "
            "results/setinc/bc.json)",
            "wall_min": 68.0,
            "load": "load average 5-9 on 2 cores beside two helpers and two other runs, "
            "2026-11-28 13:47-14:44 UTC (BC 9 min of it)",
            "selection": "the checkpoint with the highest mean of paper62 and wide_n12 on "
            "validation priors 5000-5019 (results/setinc/heldout/curve.csv)",
        },
        "conditions": {
            k: v.replace("Set-Heading-v1", "Set-Increments-v0") for k, v in CONDITIONS.items()
        },
    },
}


def main(name: str = "ppo_set_anysize") -> Path:
    spec = CARDS[name]
    policy = f"ppo:{name}"
    results = Path(spec["results"])
    card = make_card(ROOT / spec["step"], ROOT / spec["run"], results / "ppo_paper62", policy)
    card["training"] = spec["training"]
    evals = {}
    for key, cond in spec["conditions"].items():
        folder = results / f"eval_{key}"
        means = {r["policy"]: float(r["posc_mean"]) for r in csv.DictReader(
            (folder / "evaluate.csv").open())}  # fmt: skip
        paired = [r for r in csv.DictReader((folder / "paired.csv").open())
                  if r["policy"] == policy and r["baseline"] == "allocation_plan"]  # fmt: skip
        p = paired[0]
        evals[key] = {
            "condition": cond,
            "seeds": "28000-28049",
            "posc_mean": means[policy],
            "allocation_plan": means["allocation_plan"],
            "greedy_bayes": means["greedy_bayes"],
            "minus_allocation_plan": float(p["diff_mean"]),
            "ci95": float(p["diff_ci95"]),
            "wins": int(p["wins"]),
            "losses": int(p["losses"]),
            "folder": str(folder.relative_to(ROOT)),
        }
    card["evaluations"] = evals
    out = ROOT / f"agents/checkpoints/{name}.json"
    return write_text_atomic(out, json.dumps(card, indent=1) + "\n")


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("name", nargs="?", default="ppo_set_anysize", choices=sorted(CARDS))
    print(f"wrote {main(ap.parse_args().name)}")
