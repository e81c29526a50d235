"""Is a nonlinear chooser better than the ridge one? A small torch MLP on the same rows and the
same cross-validation folds as train_chooser.py (regression of the flown gain over keep, and a
listwise loss: cross-entropy between the candidates' predicted scores, keep's fixed at 0, and
the softmax of their flown gains). Prints the cross-validated gain per decision.

    PYTHONPATH=. python results/drift_replan/mlp_try.py runs/drift_replan/train/*.jsonl
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import torch
from train_chooser import FOLDS, load, rule_gain  # type: ignore[import-not-found]


def fit(decs: list[dict], loss: str, wd: float, seed: int, epochs: int = 300):
    torch.manual_seed(seed)
    x = np.vstack([np.asarray(d["features"], dtype=float) for d in decs])
    mean, std = x.mean(0), x.std(0) + 1e-9
    xs = [torch.tensor((np.asarray(d["features"]) - mean) / std, dtype=torch.float32) for d in decs]
    ys = [
        torch.tensor(np.asarray(d["flown"][1:]) - d["flown"][0], dtype=torch.float32) for d in decs
    ]
    net = torch.nn.Sequential(
        torch.nn.Linear(x.shape[1], 32), torch.nn.Tanh(), torch.nn.Linear(32, 1)
    )
    opt = torch.optim.Adam(net.parameters(), lr=3e-3, weight_decay=wd)
    xa, ya = torch.cat(xs), torch.cat(ys)
    for _ in range(epochs):
        opt.zero_grad()
        if loss == "mse":
            lo = ((net(xa)[:, 0] - ya * 100) ** 2).mean()
        else:
            lo = 0.0
            for xi, yi in zip(xs, ys, strict=True):
                s = torch.cat([torch.zeros(1), net(xi)[:, 0]])
                t = torch.softmax(torch.cat([torch.zeros(1), yi]) / 0.005, 0)
                lo = lo - (t * torch.log_softmax(s, 0)).sum()
            lo = lo / len(xs)
        lo.backward()
        opt.step()

    def predict(f):
        with torch.no_grad():
            z = torch.tensor((np.asarray(f) - mean) / std, dtype=torch.float32)
            return net(z)[:, 0].numpy()

    return predict


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("decisions", type=Path, nargs="+")
    args = ap.parse_args()
    torch.set_num_threads(1)
    decs = load(args.decisions)
    seeds = sorted({d["seed"] for d in decs})
    fold = {s: k % FOLDS for k, s in enumerate(seeds)}
    print(f"{len(decs)} decisions, rule {np.mean([rule_gain(d) for d in decs]):+.5f}")
    for loss in ("mse", "listwise"):
        for wd in (1e-4, 1e-2):
            g = []
            for k in range(FOLDS):
                tr = [d for d in decs if fold[d["seed"]] != k]
                te = [d for d in decs if fold[d["seed"]] == k]
                pred = fit(tr, loss, wd, seed=k)
                for d in te:
                    p = pred(d["features"])
                    j = int(np.argmax(p))
                    g.append(d["flown"][j + 1] - d["flown"][0] if p[j] > 0 else 0.0)
            print(f"{loss:8s} wd={wd:g}: cross-validated gain {np.mean(g):+.5f}")


if __name__ == "__main__":
    main()
