"""A shipped checkpoint's card: where the model came from and how it scored.

    python -m poc_env.agents.rl.card MODEL.zip --run RUN_DIR --evaluation EVAL_DIR --policy SPELLING
                             --out CARD.json

A card sits beside its model as ``<name>.json`` (``agents/checkpoints/ppo_heading_paper_6_2.json``)
and holds:

* ``task``, ``recipe``, ``agent_index`` and the rest of the run's ``config.json`` (what
  :class:`poc_env.agents.rl.policy.PPOPolicy` reads to fly the model at its control level with its
  observation; the run folder itself is not shipped);
* ``model_step``: the checkpoint's step (``checkpoints/step_N.zip``);
* ``evaluation``: the held-out evaluation of the model as ``poc-env evaluate --out EVAL_DIR``
  wrote it for the run's task (the seeds, every episode's POSC for the row ``--policy``,
  their mean, Student's t 95 % interval (:func:`poc_env.stats.ci95`) and minimum, the
  ``floor``). The shipped-checkpoint tests replay the first of these episodes and require the
  recorded POSC, and fly a further unseen episode that must reach the floor with every UAV
  landed.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.errors import ConfigError
from poc_env.io import read_json
from poc_env.stats import ci95


def make_card(
    model: Path, run: Path | None, evaluation: Path, policy: str, recipe: str | None = None
) -> dict[str, Any]:
    """The card of ``model`` (a checkpoint of ``run``) scored as ``policy`` in ``evaluation``;
    without ``run`` (a model whose run folder is gone) only ``recipe`` is recorded."""
    if run is None:
        config: dict[str, Any] = {"recipe": recipe} if recipe else {}
    else:
        cfg_path = run / "config.json"
        if not cfg_path.is_file():
            raise ConfigError("run", str(run), "a run folder of poc-env train (with config.json)")
        config = read_json(cfg_path, "config.json")
    eps_path = evaluation / "episodes.csv"
    txt_path = evaluation / "evaluate.txt"
    if not eps_path.is_file() or not txt_path.is_file():
        raise ConfigError(
            "evaluation", str(evaluation), "a folder of poc-env evaluate --out (episodes.csv)"
        )
    rows = [r for r in csv.DictReader(eps_path.open()) if r["policy"] == policy]
    if not rows:
        raise ConfigError("policy", policy, f"a policy evaluated in {eps_path}")
    posc = np.array([float(r["posc"]) for r in rows])
    stem = model.stem
    tail = stem.split("_", 1)[1] if stem.startswith("step_") else ""
    step = int(tail) if tail.isdigit() else None
    return {
        **{k: v for k, v in config.items() if k not in ("run_dir", "resume", "progress")},
        "model_step": step,
        "evaluation": {
            "policy": policy,
            "seeds": [int(r["seed"]) for r in rows],
            "posc": [float(x) for x in posc],
            "posc_mean": float(posc.mean()),
            "posc_ci95": ci95(posc),  # Student's t; one episode: 0 (as evaluate reports it)
            "normalised": float(np.mean([float(r["normalised"]) for r in rows])),
            "violation_steps": float(np.mean([float(r["violation_steps"]) for r in rows])),
            "floor": float(posc.min()),
        },
    }


def main(argv: list[str] | None = None) -> Path:
    from poc_env.io import write_text_atomic

    p = argparse.ArgumentParser(
        prog="python -m poc_env.agents.rl.card", description=__doc__.split("\n")[0]
    )
    p.add_argument("model", type=Path)
    p.add_argument("--run", type=Path, default=None, help="the model's run folder")
    p.add_argument("--recipe", default=None, help="without --run: the recipe to record")
    p.add_argument("--evaluation", type=Path, required=True)
    p.add_argument("--policy", required=True, help="the model's row in the evaluation")
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args(argv)
    card = make_card(args.model, args.run, args.evaluation, args.policy, args.recipe)
    return write_text_atomic(args.out, json.dumps(card, indent=1) + "\n")


if __name__ == "__main__":
    try:
        print(f"wrote {main()}")
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
