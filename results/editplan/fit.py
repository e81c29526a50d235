"""Fit the take-off plan chooser by cross-validation over priors (i28-editplan).

``python results/editplan/fit.py TRAIN.jsonl[,MORE.jsonl] SELECTION.jsonl OUT.json``

Rows: per training prior, one per candidate but ``default`` (:func:`~poc_env.agents.policies.
plan_choice.rows`), the target its flown POSC gain over ``default``. Every combination of
expansion (``kinds``: a constant per candidate; ``interact``: a linear model of the prior per
candidate), ridge strength and fitting (plain, or ``within``: slopes on the deviations from each
prior's mean, :meth:`ChooserModel.fit`'s ``groups``) is scored by 5-fold cross-validation over
the priors (folds from a generator seeded 0): the mean flown gain over ``default`` of the
candidate it picks on the held-out priors (``default`` if no prediction is above 0). The best
is refitted on all the training priors, scored once on the selection priors (the headroom
run's), and saved with its card (``meta``): the CV table, the training seeds, and a replay (a
selection prior where it picks a candidate other than ``default``, and that flight's POSC).
"""

from __future__ import annotations

import itertools
import json
import sys

import numpy as np

from poc_env.agents.policies.plan_choice import KINDS, PlanChoiceModel, rows

RIDGES = (0.001, 0.01, 0.1, 1.0, 10.0, 100.0)


def load(paths: str) -> list[dict]:
    recs = []
    for p in paths.split(","):
        with open(p) as f:
            recs += [json.loads(line) for line in f if line.strip()]
    return recs


def table(recs: list[dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``x`` (priors x candidates rows), ``y`` (flown gains over default), ``g`` (prior
    index of each row)."""
    xs, ys, gs = [], [], []
    for i, r in enumerate(recs):
        d = r["cands"]["default"]["posc"]
        xs.append(rows(np.asarray(r["features"])))
        ys.append([r["cands"][k]["posc"] - d for k in KINDS])
        gs.append([i] * len(KINDS))
    return np.vstack(xs), np.concatenate(ys), np.concatenate(gs)


def picked_gain(model: PlanChoiceModel, recs: list[dict]) -> np.ndarray:
    """The flown gain over ``default`` of the candidate ``model`` picks, per prior."""
    out = []
    for r in recs:
        pred = model.predict(rows(np.asarray(r["features"])))
        j = int(np.argmax(pred))
        name = KINDS[j] if pred[j] > 0 else "default"
        out.append(r["cands"][name]["posc"] - r["cands"]["default"]["posc"])
    return np.asarray(out)


def t95(d: np.ndarray) -> tuple[float, float]:
    from scipy import stats

    d = np.asarray(d, dtype=float)
    if len(d) < 2:
        return float(d.mean()), float("nan")
    half = float(stats.t.ppf(0.975, len(d) - 1) * d.std(ddof=1) / np.sqrt(len(d)))
    return float(d.mean()), half


def cv(recs: list[dict], how: str, ridge: float, within: bool, folds: int = 5) -> np.ndarray:
    order = np.random.default_rng(0).permutation(len(recs))
    gains = np.zeros(len(recs))
    for f in range(folds):
        test = order[f::folds]
        train = [recs[i] for i in order if i not in set(test)]
        x, y, g = table(train)
        m = PlanChoiceModel.fit(x, y, ridge, how, groups=g if within else None)
        gains[test] = picked_gain(m, [recs[i] for i in test])
    return gains


def main(train_paths: str, selection_path: str, out: str) -> None:
    recs = load(train_paths)
    sel = load(selection_path)
    print(f"{len(recs)} training priors, {len(sel)} selection priors")
    for name, data in (("training", recs), ("selection", sel)):
        d = np.array([r["cands"]["default"]["posc"] for r in data])
        best = np.array([max(c["posc"] for c in r["cands"].values()) for r in data])
        m, h = t95(best - d)
        print(f"{name}: oracle best-of-K - default {m:+.4f} +- {h:.4f}")
        for k in KINDS:
            gk = np.array([r["cands"][k]["posc"] for r in data]) - d
            m, h = t95(gk)
            print(f"  {k:>15}: {m:+.4f} +- {h:.4f}  wins {int((gk > 1e-9).sum())} "
                  f"losses {int((gk < -1e-9).sum())}")  # fmt: skip
    results = []
    constant = cv(recs, "kinds", RIDGES[0], False)  # the best constant of each fold's training
    for how, ridge, within in itertools.product(("kinds", "interact"), RIDGES, (False, True)):
        if how == "kinds" and within:
            continue  # a constant per candidate has no within-prior slope beyond its mean
        gains = cv(recs, how, ridge, within)
        m, h = t95(gains)
        mc, hc = t95(gains - constant)
        results.append({"expand": how, "ridge": ridge, "within": within, "cv_gain": m,
                        "cv_half": h, "vs_constant": mc, "vs_constant_half": hc})  # fmt: skip
        print(
            f"cv {how:>8} ridge {ridge:<6} within {within!s:<5}: {m:+.4f} +- {h:.4f} "
            f"(- the constant: {mc:+.4f} +- {hc:.4f})"
        )
    best = max(results, key=lambda r: r["cv_gain"])
    x, y, g = table(recs)
    model = PlanChoiceModel.fit(
        x, y, best["ridge"], best["expand"], groups=g if best["within"] else None
    )
    sg = picked_gain(model, sel)
    m, h = t95(sg)
    print(f"chosen {best}; on the selection priors {m:+.4f} +- {h:.4f}")
    # the replay: a selection prior where the model picks neither default nor its most common
    # pick (so a test of it fails if the model is not read), else the first it does not keep
    picks = []
    for r in sel:
        pred = model.predict(rows(np.asarray(r["features"])))
        j = int(np.argmax(pred))
        picks.append(KINDS[j] if pred[j] > 0 else "default")
    common = max(set(picks), key=picks.count)
    order = [i for i, k in enumerate(picks) if k not in ("default", common)]
    order += [i for i, k in enumerate(picks) if k == common != "default"]
    replay = None
    if order:
        r, k = sel[order[0]], picks[order[0]]
        replay = {"scenario": "paper_6_2", "seed": r["seed"], "chosen": k,
                  "posc": r["cands"][k]["posc"]}  # fmt: skip
    model.meta.update(
        {
            "scenario": "paper_6_2",
            "training_seeds": sorted(r["seed"] for r in recs),
            "cv": results,
            "selection": {"seeds": [r["seed"] for r in sel], "gain": m, "half": h},
            "replay": replay,
        }
    )
    model.save(out)
    print("saved", out)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3])
