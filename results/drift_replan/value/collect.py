"""Training data of the learned value (i28-lookvalue): fly the oracle (decisions at 10 and 20
min) on training seeds, every candidate's rollout recording its state features and POSC at the
snapshot times; one JSON line per decision (the oracle's record plus ``snaps``).

    PYTHONPATH=. python results/drift_replan/value/collect.py --seeds 23000 23999 \
        --out results/drift_replan/value/records/train_23000.jsonl
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from fly import TASK, fly

from poc_env.agents.policies.replan_choice import ReplanChoicePolicy
from poc_env.io import write_text_atomic
from poc_env.tasks import get_task

SNAP_MIN = (15.0, 20.0, 25.0, 30.0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs=2, required=True, help="first and last seed")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    sc = get_task(TASK).load_scenario({})
    lines = []
    for seed in range(args.seeds[0], args.seeds[1] + 1):
        pol = ReplanChoicePolicy("oracle", decide_min=(10.0, 20.0), snap_min=SNAP_MIN)
        posc, secs = fly(pol, sc, seed)
        lines += [json.dumps({"seed": seed, "posc": posc, **d}) for d in pol.decisions]
        print(seed, f"{posc:.4f}", f"{secs:.2f}s", flush=True)
        write_text_atomic(args.out, "\n".join(lines) + "\n")  # a stopped run keeps its episodes


if __name__ == "__main__":
    main()
