"""Paired difference of two variants of stage.py records (same base plans): ``python
results/plan_scale/regrade/pair.py OUT.json[,OUT.json...] VARIANT_A VARIANT_B`` prints B - A
over the rule-aware bound on 2 x 2 and 8 x 8 sample points a cell (Student's t 95 %,
wins / ties / losses) and the stage's CPU time of each."""

from __future__ import annotations

import json
import statistics
import sys

from stage import t95


def main(paths: list[str], a: str, b: str) -> None:
    recs = []
    for p in paths:
        with open(p) as f:
            recs += json.load(f)
    ra = {r["seed"]: r for r in recs if r["variant"] == a}
    rb = {r["seed"]: r for r in recs if r["variant"] == b}
    seeds = sorted(set(ra) & set(rb))
    for key in ("planned_posc", "fine_posc"):
        d = [(rb[s][key] - ra[s][key]) / ra[s]["rule_bound"] for s in seeds]
        print(f"{b} - {a} ({key}, n {len(d)}): {t95(d)}")
    ca = [ra[s]["stage_cpu_s"] for s in seeds]
    cb = [rb[s]["stage_cpu_s"] for s in seeds]
    print(
        f"stage CPU median {statistics.median(ca):.2f} s -> {statistics.median(cb):.2f} s; "
        f"ratio median {statistics.median(y / x for x, y in zip(ca, cb)):.3f}"
    )


if __name__ == "__main__":
    main(sys.argv[1].split(","), sys.argv[2], sys.argv[3])
