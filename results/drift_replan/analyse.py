"""How much the oracle's candidates are worth, per decision time, and how much of it a chooser
fitted on decision-time features recovers (cross-validated over training seeds).

    cd results/drift_replan && PYTHONPATH=../.. python analyse.py records/train_*.jsonl.gz

Per decision time: the mean flown gain over ``keep`` of the oracle's pick, of always taking the
default re-plan, of the planner-model's best candidate, and of the rule (the default re-plan if
the planner's model scores it 0.005 above keep), the correlation between the planner-model gain
and the flown gain over all candidates (and Spearman's within each decision), each kind's mean
flown gain; then the cross-validated gain of a ridge chooser fitted on the decisions at one
time only (5 folds of whole episodes, ``train_chooser.py``'s), with its +- 2 standard errors.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr
from train_chooser import FOLDS, load, rows  # type: ignore[import-not-found]

from poc_env.agents.policies.replan_choice import ChooserModel


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("decisions", type=Path, nargs="+")
    args = ap.parse_args()
    decs = load(args.decisions)
    times = sorted({d["time_s"] for d in decs})
    for t in times:
        ds = [d for d in decs if d["time_s"] == t]
        gain = {
            "oracle": [max(d["flown"]) - d["flown"][0] for d in ds],
            "always re-plan": [d["flown"][1] - d["flown"][0] for d in ds],
            "planner-model best": [
                d["flown"][int(np.argmax(d["scores"]))] - d["flown"][0] for d in ds
            ],
            "rule": [
                d["flown"][1] - d["flown"][0] if d["scores"][1] > d["scores"][0] + 0.005 else 0.0
                for d in ds
            ],
        }
        g = np.concatenate([np.subtract(d["scores"][1:], d["scores"][0]) for d in ds])
        y = np.concatenate([np.subtract(d["flown"][1:], d["flown"][0]) for d in ds])
        rho = np.nanmean([spearmanr(d["scores"], d["flown"]).statistic for d in ds])
        print(f"decision at {t / 60:.0f} min ({len(ds)} decisions): mean flown gain over keep")
        for k, v in gain.items():
            print(f"  {k:20s} {np.mean(v):+.4f}")
        print(f"  corr(planner-model gain, flown gain) {np.corrcoef(g, y)[0, 1]:.2f}; "
              f"Spearman within a decision {rho:.2f}")  # fmt: skip
        kinds: dict[str, list[float]] = {}
        for d in ds:
            for n, f in zip(d["names"][1:], d["flown"][1:], strict=True):
                kinds.setdefault(n, []).append(f - d["flown"][0])
        print("  per candidate: " + ", ".join(f"{n} {np.mean(v):+.4f}" for n, v in kinds.items()))
        seeds = sorted({d["seed"] for d in ds})
        fold = {s: k % FOLDS for k, s in enumerate(seeds)}
        for ex, lam in (("linear", 1e-3), ("kinds", 1e-2), ("quadratic", 1e-1)):
            got = []
            for k in range(FOLDS):
                x, yy, _ = rows([d for d in ds if fold[d["seed"]] != k])
                m = ChooserModel.fit(x, yy, lam, ex)
                for d in (d for d in ds if fold[d["seed"]] == k):
                    p = m.predict(np.asarray(d["features"]))
                    j = int(np.argmax(p))
                    got.append(d["flown"][j + 1] - d["flown"][0] if p[j] > 0 else 0.0)
            v = np.asarray(got)
            print(f"  ridge chooser ({ex}, {lam:g}), cross-validated: {v.mean():+.4f} "
                  f"+- {2 * v.std(ddof=1) / np.sqrt(len(v)):.4f}")  # fmt: skip


if __name__ == "__main__":
    main()
