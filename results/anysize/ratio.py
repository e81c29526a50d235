"""The generalist's score as a fraction of a specialist's, on the same seeds (issue 28's target:
at least 0.95): the ratio of mean POSC, its 95 % paired-bootstrap interval (seeds resampled
together, 10,000 resamples of a generator seeded here) and the paired difference with its
Student's t interval.

    python results/anysize/ratio.py results/anysize/eval_wide_n6/episodes.csv \
        --generalist ppo:ppo_set_anysize --specialist ppo:runs/spec_n6_s1/...zip
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from poc_env.stats import ci95


def ratio(paths: list[Path], generalist: str, specialist: str, resamples: int = 10_000) -> dict:
    rows = [r for path in paths for r in csv.DictReader(path.open(newline=""))]
    g = {int(r["seed"]): float(r["posc"]) for r in rows if r["policy"] == generalist}
    s = {int(r["seed"]): float(r["posc"]) for r in rows if r["policy"] == specialist}
    seeds = sorted(set(g) & set(s))
    if not seeds or len(seeds) != len(g) or len(seeds) != len(s):
        raise SystemExit(f"{paths}: {generalist} and {specialist} must fly the same seeds")
    a = np.array([g[k] for k in seeds])
    b = np.array([s[k] for k in seeds])
    rng = np.random.default_rng(28)  # the bootstrap's own stream
    idx = rng.integers(0, len(seeds), size=(resamples, len(seeds)))
    boot = a[idx].mean(axis=1) / b[idx].mean(axis=1)
    d = a - b
    return {
        "episodes": len(seeds),
        "generalist": float(a.mean()),
        "specialist": float(b.mean()),
        "ratio": float(a.mean() / b.mean()),
        "ratio_lo": float(np.quantile(boot, 0.025)),
        "ratio_hi": float(np.quantile(boot, 0.975)),
        "diff": float(d.mean()),
        "diff_ci95": float(ci95(d)),
        "wins": int((d > 1e-12).sum()),
        "losses": int((d < -1e-12).sum()),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("episodes", type=Path, nargs="+", help="episodes.csv files (rows joined)")
    ap.add_argument("--generalist", required=True)
    ap.add_argument("--specialist", required=True)
    a = ap.parse_args()
    r = ratio(a.episodes, a.generalist, a.specialist)
    print(
        f"{' '.join(map(str, a.episodes))}: generalist {r['generalist']:.4f}, "
        f"specialist {r['specialist']:.4f}, "
        f"ratio {r['ratio']:.3f} [{r['ratio_lo']:.3f}, {r['ratio_hi']:.3f}], "
        f"paired {r['diff']:+.4f} ± {r['diff_ci95']:.4f}, wins {r['wins']} losses {r['losses']}"
        f" of {r['episodes']}"
    )


if __name__ == "__main__":
    main()
