"""Branch minus main, paired by seed, of one policy's POSC in two ``evaluate`` folders:
``python paired.py BRANCH_DIR MAIN_DIR`` (mean difference, Student's t 95 % half-width,
wins/ties/losses, mean violation steps of each)."""

import csv
import sys

import numpy as np

from poc_env.stats import ci95


def rows(folder: str) -> dict[tuple[str, int], dict]:
    with open(f"{folder}/episodes.csv", encoding="utf-8") as f:
        return {(r["policy"], int(r["seed"])): r for r in csv.DictReader(f)}


a, b = rows(sys.argv[1]), rows(sys.argv[2])
for pol in sorted({p for p, _ in a}):
    keys = sorted(k for k in a if k[0] == pol and k in b)
    d = np.array([float(a[k]["posc"]) - float(b[k]["posc"]) for k in keys])
    va = np.mean([int(a[k]["violation_steps"]) for k in keys])
    vb = np.mean([int(b[k]["violation_steps"]) for k in keys])
    w, t, lo = int((d > 1e-12).sum()), int((abs(d) <= 1e-12).sum()), int((d < -1e-12).sum())
    print(
        f"{pol}: n={len(d)} branch-main {d.mean():+.4f} ± {float(ci95(d)):.4f} "
        f"(W/T/L {w}/{t}/{lo}); violation steps branch {va:.1f}, main {vb:.1f}"
    )
