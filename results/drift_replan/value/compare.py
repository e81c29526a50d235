"""Paired differences of fly.py CSVs (one row per seed) against a baseline CSV: mean POSC,
mean difference with its paired Student's t 95 % half-width, wins / ties / losses, seconds per
episode (fly.py's own timing, environment steps and decisions only).

    python results/drift_replan/value/compare.py BASELINE.csv OTHER.csv...
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np
from scipy import stats


def read(path: Path) -> dict[int, tuple[float, float]]:
    with open(path) as f:
        return {int(r["seed"]): (float(r["posc"]), float(r["seconds"])) for r in csv.DictReader(f)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("baseline", type=Path)
    ap.add_argument("others", type=Path, nargs="+")
    args = ap.parse_args()
    base = read(args.baseline)
    print("policy | n | POSC | - baseline | wins / ties / losses | s / episode")
    for p in [args.baseline, *args.others]:
        got = read(p)
        seeds = sorted(set(got) & set(base))
        a = np.array([got[s][0] for s in seeds])
        d = a - np.array([base[s][0] for s in seeds])
        half = stats.t.ppf(0.975, len(d) - 1) * d.std(ddof=1) / np.sqrt(len(d)) if len(d) > 1 else 0
        win, tie, lose = (
            int((d > 1e-12).sum()),
            int((np.abs(d) <= 1e-12).sum()),
            int((d < -1e-12).sum()),
        )
        secs = np.mean([got[s][1] for s in seeds])
        print(
            f"{p.stem} | {len(d)} | {a.mean():.4f} | {d.mean():+.4f} ± {half:.4f} | "
            f"{win} / {tie} / {lose} | {secs:.1f}"
        )


if __name__ == "__main__":
    main()
