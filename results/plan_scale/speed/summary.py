"""i24-speed: the paired timing records (``speed_ab.py pair``) summarised: per case the
medians of this tree and the base, the median and range of the per-pair ratios, CPU and wall,
and the load range:
``python results/plan_scale/speed/summary.py results/plan_scale/speed/pair_*.json``."""

import json
import statistics
import sys

for path in sys.argv[1:]:
    with open(path) as f:
        d = json.load(f)
    recs = d["records"]
    this = [r for r in recs if r["tree"] == "this"]
    base = [r for r in recs if r["tree"] == "base"]
    same = all(a["digest"] == b["digest"] for a, b in zip(this, base, strict=True))
    loads = [r["load"] for r in recs]
    print(f"{d['case']} ({len(this)} pairs, load {min(loads):.1f}-{max(loads):.1f}, "
          f"plans equal: {same})")  # fmt: skip
    for key in ("cpu_s", "wall_s"):
        ratios = [a[key] / b[key] for a, b in zip(this, base, strict=True)]
        print(f"  {key}: this {statistics.median(r[key] for r in this):.3f}, base "
              f"{statistics.median(r[key] for r in base):.3f}, ratio median "
              f"{statistics.median(ratios):.3f} (range {min(ratios):.3f}-{max(ratios):.3f}, "
              f"this faster in {sum(x < 1 for x in ratios)} of {len(ratios)})")  # fmt: skip
