"""Ship a chooser model: its file with the card's evaluation in ``meta["evaluation"]`` (the
fields of :func:`poc_env.agents.rl.card.make_card`'s ``evaluation``), written to
``agents/checkpoints/choosers/NAME.json``.

    PYTHONPATH=. python results/drift_replan/card.py runs/drift_replan/chooser.json \
        --evaluation results/drift_replan/evaluation --policy receding_choice:PATH \
        --name receding_chooser_drift_small
"""

from __future__ import annotations

import argparse
from pathlib import Path

from poc_env.agents.policies.replan_choice import ChooserModel
from poc_env.agents.rl.card import make_card

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("model", type=Path)
    ap.add_argument("--evaluation", type=Path, required=True)
    ap.add_argument("--policy", required=True, help="the model's row in the evaluation")
    ap.add_argument("--name", required=True)
    args = ap.parse_args()
    model = ChooserModel.load(args.model)
    card = make_card(args.model, None, args.evaluation, args.policy, recipe="replan_chooser")
    model.meta["task"] = "UAVSearch-Small-Drift-Heading-v1"
    model.meta["evaluation"] = card["evaluation"]
    out = ROOT / "agents" / "checkpoints" / "choosers" / f"{args.name}.json"
    print(f"wrote {model.save(out)}")


if __name__ == "__main__":
    main()
