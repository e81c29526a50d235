"""i24-relax: paired differences of planned POS over the rule-aware bound, per prior.

``python results/plan_scale/relax/paired.py A.json[,A2.json] VARIANT_A B.json[,B2.json]
VARIANT_B``: A - B per seed (2 x 2 sample points a cell, the environment's; and 8 x 8) and
the mean ± Student's t 95 % (wins / ties / losses), over the seeds both hold; also each
variant's mean share of the bound. Files are comma-separated lists (records of measure.py or
of results/plan_scale/lines/cache_plans.py / stage2.py); a VARIANT may list several names
separated by ``|`` (any of them).
"""

import json
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "boxes"))

from stage2 import t95


def _load(paths: str, variant: str) -> dict:
    out = {}
    for p in paths.split(","):
        with open(p) as f:
            out.update({r["seed"]: r for r in json.load(f) if r["variant"] in variant.split("|")})
    return out


def main(a_path: str, a_var: str, b_path: str, b_var: str) -> None:
    a, b = _load(a_path, a_var), _load(b_path, b_var)
    seeds = sorted(set(a) & set(b))
    d2 = [(a[s]["planned_posc"] - b[s]["planned_posc"]) / a[s]["rule_bound"] for s in seeds]
    d8 = [(a[s]["fine_posc"] - b[s]["fine_posc"]) / a[s]["rule_bound"] for s in seeds]
    for s, x, y in zip(seeds, d2, d8, strict=True):
        print(s, a[s].get("start", "-"), b[s].get("start", "-"), f"{x:+.4f}", f"{y:+.4f}")
    ra = [a[s]["planned_posc"] / a[s]["rule_bound"] for s in seeds]
    rb = [b[s]["planned_posc"] / b[s]["rule_bound"] for s in seeds]
    print(f"{a_var}: {statistics.mean(ra):.4f}  {b_var}: {statistics.mean(rb):.4f}")
    print(f"{a_var} - {b_var}: n={len(seeds)} 2x2 {t95(d2)}  8x8 {t95(d8)}")


if __name__ == "__main__":
    main(*sys.argv[1:5])
