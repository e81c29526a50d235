"""Paired POSC differences between policies flown on the same seeds, from ``poc-env evaluate``
folders' ``episodes.csv`` (or a held-out ``curve.csv`` row set: ``RUN@STEP``), Student's t 95 %.

    python results/dagger/paired.py --ref val_bc0_old:ppo:runs-bcinc/bc0_s1/model.zip \
        --other val_b1:ppo:runs-dagger/dagb_s1/bc_dagger/iter_1.zip

``FOLDER:POLICY`` names one policy's rows of ``FOLDER/episodes.csv``; ``CSV@RUN@STEP`` one
run's checkpoint in a ``heldout_curve.py`` ``curve.csv``.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np
from scipy import stats


def rows(spec: str) -> dict[int, float]:
    if "@" in spec:
        path, run, step = spec.split("@")
        with open(path) as fh:
            found = [r for r in csv.DictReader(fh) if r["run"] == run and r["step"] == step]
        return {int(r["seed"]): float(r["posc"]) for r in found}
    folder, policy = spec.split(":", 1)
    with open(Path(folder) / "episodes.csv") as fh:
        found = [r for r in csv.DictReader(fh) if r["policy"] == policy]
    return {int(r["seed"]): float(r["posc"]) for r in found}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref")
    ap.add_argument("--other", nargs="+", default=[])
    ap.add_argument(
        "--pool", nargs="+", default=[], metavar="REF=OTHER",
        help="pairs pooled into one difference (e.g. one per training seed)",
    )  # fmt: skip
    a = ap.parse_args(argv)
    if a.pool:
        d, x_all, r_all = [], [], []
        for pair in a.pool:
            r_spec, o_spec = pair.split("=", 1)
            r, x = rows(r_spec), rows(o_spec)
            for s in sorted(set(r) & set(x)):
                d.append(x[s] - r[s])
                x_all.append(x[s])
                r_all.append(r[s])
        dd = np.array(d)
        half = stats.t.ppf(0.975, len(dd) - 1) * dd.std(ddof=1) / np.sqrt(len(dd))
        print(f"pooled {len(dd)} pairs: {np.mean(r_all):.4f} -> {np.mean(x_all):.4f}, "
              f"{dd.mean():+.4f} ± {half:.4f} ({int((dd > 0).sum())} wins)")  # fmt: skip
        return
    ref = rows(a.ref)
    print(f"reference {a.ref}: {np.mean(list(ref.values())):.4f} over {len(ref)} seeds")
    for o in a.other:
        x = rows(o)
        seeds = sorted(set(ref) & set(x))
        d = np.array([x[s] - ref[s] for s in seeds])
        half = stats.t.ppf(0.975, len(d) - 1) * d.std(ddof=1) / np.sqrt(len(d))
        wins = int((d > 0).sum())
        print(f"{o}: {np.mean([x[s] for s in seeds]):.4f}, - ref {d.mean():+.4f} ± {half:.4f} "
              f"({wins} wins of {len(d)})")  # fmt: skip


if __name__ == "__main__":
    main()
