"""Fit the re-planning chooser (ridge regression, agents/policies/replan_choice.py) on the
oracle's counterfactual rollouts from the training seeds, choosing the ridge strength and the
feature expansion by cross-validation over seeds (folds of whole episodes).

    PYTHONPATH=. python results/drift_replan/train_chooser.py runs/drift_replan/train/*.jsonl \
        --out runs/drift_replan/chooser.json

Each decision of the oracle (``fly.py --decisions``) gives, for every candidate but ``keep``,
its features and its flown gain over ``keep`` (POSC at the episode's end, the rule deciding
after): the regression's rows. A fold's score is the mean flown gain of the chooser's picks
over ``keep`` (the highest predicted gain if above 0, else ``keep``), next to the rule's
(``spacetime_receding``'s, at 20 min) and the oracle's on the same decisions. ``--model-min``:
the decision times the model is fitted for and decides at (the rule decides at the others:
at 20 min it was ahead of every fitted model in cross-validation, results/drift_replan).
"""

from __future__ import annotations

import argparse
import gzip
import json
from pathlib import Path

import numpy as np

from poc_env.agents.policies.replan_choice import EXPANSIONS, ChooserModel

RIDGES = (1e-4, 1e-3, 1e-2, 1e-1, 1.0)
FOLDS = 5


def load(paths: list[Path]) -> list[dict]:
    out = []
    for p in paths:
        text = gzip.decompress(p.read_bytes()).decode() if p.suffix == ".gz" else p.read_text()
        for line in text.splitlines():
            if line.strip():
                d = json.loads(line)
                if d.get("flown") and len(d["names"]) > 1:
                    out.append(d)
    return out


def rows(decisions: list[dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Features, gains over keep, and the decision each row belongs to."""
    xs, ys, ids = [], [], []
    for i, d in enumerate(decisions):
        f = np.asarray(d["flown"], dtype=float)
        xs.append(np.asarray(d["features"], dtype=float))
        ys.append(f[1:] - f[0])
        ids.append(np.full(len(f) - 1, i))
    return np.vstack(xs), np.concatenate(ys), np.concatenate(ids)


def rule_gain(d: dict, margin: float = 0.005) -> float:
    """The flown gain over keep of spacetime_receding's rule at this decision (it decides at
    20 min only: keep elsewhere)."""
    if abs(d["time_s"] - 1200.0) > 1e-6:
        return 0.0
    s = d["scores"]
    return d["flown"][1] - d["flown"][0] if s[1] > s[0] + margin else 0.0


def value(model: ChooserModel, decisions: list[dict]) -> float:
    """Mean flown gain over keep of the model's picks."""
    g = []
    for d in decisions:
        pred = model.predict(np.asarray(d["features"], dtype=float))
        j = int(np.argmax(pred))
        g.append(d["flown"][j + 1] - d["flown"][0] if pred[j] > 0 else 0.0)
    return float(np.mean(g))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("decisions", type=Path, nargs="+")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--decide", type=float, nargs="+", default=[10.0, 20.0])
    ap.add_argument(
        "--model-min", type=float, nargs="+", default=[10.0], help="times the model decides"
    )
    args = ap.parse_args()
    at = {float(t) * 60.0 for t in args.model_min}
    decs = [d for d in load(args.decisions) if d["time_s"] in at]
    seeds = sorted({d["seed"] for d in decs})
    fold = {s: k % FOLDS for k, s in enumerate(seeds)}
    print(f"{len(decs)} decisions of {len(seeds)} training episodes")
    oracle = float(np.mean([max(d["flown"]) - d["flown"][0] for d in decs]))
    rule = float(np.mean([rule_gain(d) for d in decs]))
    print(f"mean gain over keep per decision: oracle {oracle:+.5f}  rule {rule:+.5f}")
    results = []
    for ex in EXPANSIONS:
        for lam in RIDGES:
            vals = []
            for k in range(FOLDS):
                train = [d for d in decs if fold[d["seed"]] != k]
                test = [d for d in decs if fold[d["seed"]] == k]
                x, y, _ = rows(train)
                m = ChooserModel.fit(x, y, lam, ex)
                vals.append(value(m, test) * len(test))
            v = float(np.sum(vals) / len(decs))
            results.append((v, ex, lam))
            print(f"expand={ex:10s} ridge={lam:g}: cross-validated gain {v:+.5f}")
    v, ex, lam = max(results)
    x, y, _ = rows(decs)
    meta = {
        "decide_min": list(args.decide),
        "model_min": list(args.model_min),
        "training": {
            "seeds": [seeds[0], seeds[-1]],
            "episodes": len(seeds),
            "decisions": len(decs),
            "rows": len(y),
            "cv_gain": v,
            "oracle_gain": oracle,
            "rule_gain": rule,
            "cv_table": [{"expand": e, "ridge": r, "gain": g} for g, e, r in results],
        },
    }
    model = ChooserModel.fit(x, y, lam, ex, meta=meta)
    print(f"chosen expand={ex} ridge={lam:g} (cv {v:+.5f}); wrote {model.save(args.out)}")


if __name__ == "__main__":
    main()
