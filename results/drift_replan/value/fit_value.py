"""Fit the learned value of a state (the POSC still to come, the rule re-planning after) on the
oracle rollouts' snapshots (collect.py), choose the expansion and ridge strength by 5-fold
cross-validation over seeds, and measure, out of fold:

* R^2 of the POSC to come, and R^2 of its DIFFERENCES between the candidates of one decision
  at one snapshot time (each centred on the decision's mean: what a lookahead ranks on);
* the truncated lookahead offline: at each decision, every candidate scored by its POSC at
  decision + h (``trunc``) or that plus the value (``trunc+value``), the best flown; its flown
  gain over ``keep`` next to the full-rollout oracle's and the rule's.

    PYTHONPATH=. python results/drift_replan/value/fit_value.py \
        results/drift_replan/value/records/train_*.jsonl.gz --out value.json
"""

from __future__ import annotations

import argparse
import gzip
import json
from pathlib import Path

import numpy as np

from poc_env.agents.policies.replan_choice import ValueModel

RIDGES = (1e-4, 1e-3, 1e-2, 1e-1)
EXPANSIONS = ("linear", "quadratic")


def load(paths: list[Path]) -> list[dict]:
    out = []
    for p in paths:
        opener = gzip.open if p.suffix == ".gz" else open
        with opener(p, "rt") as f:
            out += [json.loads(line) for line in f if line.strip()]
    return out


def rows(decisions: list[dict]):
    """x, y, seed, group (decision x snapshot), candidate, snapshot time, decision index."""
    x, y, seed, group, cand, snap, dec = [], [], [], [], [], [], []
    g = 0
    for di, d in enumerate(decisions):
        by_t: dict[float, list] = {}
        seen = set()
        for c, (f, sn) in enumerate(zip(d["flown"], d["snaps"], strict=True)):
            key = json.dumps(sn)
            if key in seen:  # same routes as an earlier candidate: same rollout
                continue
            seen.add(key)
            for t, xs, posc in sn:
                by_t.setdefault(t, []).append((c, xs, f - posc))
        for t, items in sorted(by_t.items()):
            for c, xs, to_come in items:
                x.append(xs)
                y.append(to_come)
                seed.append(d["seed"])
                group.append(g)
                cand.append(c)
                snap.append(t)
                dec.append(di)
            g += 1
    return (
        np.asarray(x),
        np.asarray(y),
        np.asarray(seed),
        np.asarray(group),
        np.asarray(cand),
        np.asarray(snap),
        np.asarray(dec),
    )


def r2(y: np.ndarray, p: np.ndarray) -> float:
    return 1.0 - float(((y - p) ** 2).sum()) / float(((y - y.mean()) ** 2).sum())


def centred(v: np.ndarray, group: np.ndarray) -> np.ndarray:
    sums = np.bincount(group, weights=v)
    counts = np.bincount(group)
    return v - (sums / np.maximum(counts, 1))[group]


def oof(x, y, seed, ridge, how, groups=None, folds=5):
    seeds = np.unique(seed)
    fold = {s: i % folds for i, s in enumerate(seeds)}
    f = np.array([fold[s] for s in seed])
    pred = np.zeros_like(y)
    for k in range(folds):
        g = None if groups is None else groups[f != k]
        m = ValueModel.fit(x[f != k], y[f != k], ridge, how, groups=g)
        pred[f == k] = m.predict(x[f == k])
    return pred


def lookahead(decisions, x, y, group, cand, snap, dec, pred):
    """Per decision time and horizon: mean flown gain over keep of the truncated lookahead
    with and without the value, the oracle's and the rule's (replan if its model says so)."""
    out = []
    posc_t = x[:, 1]
    for d_min in sorted({round(d["time_s"] / 60) for d in decisions}):
        for h in (5, 10, 15, 20):
            t = (d_min + h) * 60.0
            gains = {"trunc": [], "trunc+value": [], "oracle": [], "rule": []}
            for di, d in enumerate(decisions):
                if round(d["time_s"] / 60) != d_min:
                    continue
                sel = (dec == di) & (np.abs(snap - t) < 1e-6)
                if not sel.any():
                    continue
                fl = np.asarray(d["flown"])
                keep = fl[0]
                cs = cand[sel]
                a = cs[np.argmax(posc_t[sel])]  # ties: the first (keep)
                b = cs[np.argmax(posc_t[sel] + pred[sel])]
                gains["trunc"].append(fl[a] - keep)
                gains["trunc+value"].append(fl[b] - keep)
                gains["oracle"].append(fl.max() - keep)
                sc = d["scores"]
                gains["rule"].append((fl[1] if sc[1] > sc[0] + 0.005 else keep) - keep)
            if gains["oracle"]:
                out.append(
                    (
                        d_min,
                        h,
                        len(gains["oracle"]),
                        {k: float(np.mean(v)) for k, v in gains.items()},
                    )
                )
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("records", type=Path, nargs="+")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    decisions = load(args.records)
    x, y, seed, group, cand, snap, dec = rows(decisions)
    print(f"{len(set(seed))} episodes, {len(decisions)} decisions, {len(y)} states")
    best = None
    for within in (False, True):
        for how in EXPANSIONS:
            for ridge in RIDGES:
                p = oof(x, y, seed, ridge, how, group if within else None)
                r_all, r_diff = r2(y, p), r2(centred(y, group), centred(p, group))
                fit = "within" if within else "pooled"
                print(
                    f"{fit} {how:9s} ridge {ridge:g}: R2 to come {r_all:.3f}, "
                    f"R2 differences {r_diff:.3f}"
                )
                if best is None or r_diff > best[0]:
                    best = (r_diff, how, ridge, within, p)
    _, how, ridge, within, p = best
    print(f"chosen (best R2 of differences): {'within' if within else 'pooled'} {how}, {ridge:g}")
    for t in sorted(set(snap)):
        s = snap == t
        print(
            f"  snapshot {t / 60:.0f} min: R2 {r2(y[s], p[s]):.3f}, R2 differences "
            f"{r2(centred(y[s], group[s]), centred(p[s], group[s])):.3f}, n {int(s.sum())}"
        )
    print("offline truncated lookahead (out-of-fold value), mean flown gain over keep:")
    print("decision  h  n  trunc  trunc+value  oracle  rule")
    for d_min, h, n, g in lookahead(decisions, x, y, group, cand, snap, dec, p):
        print(
            f"{d_min:8d} {h:3d} {n:3d} {g['trunc']:+.4f} {g['trunc+value']:+.4f} "
            f"{g['oracle']:+.4f} {g['rule']:+.4f}"
        )
    model = ValueModel.fit(
        x,
        y,
        ridge,
        how,
        meta={"episodes": len(set(seed)), "records": [p.name for p in args.records]},
    )
    model.save(args.out)
    print("saved", args.out)


if __name__ == "__main__":
    main()
