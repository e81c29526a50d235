"""i24-fastpolish: the validation table (planned POS_C over the rule-aware bound, paired per
prior against ``default``, Student's t 95 %, wins / ties / losses; CPU time ratio to the
default's on the same prior, median and max; the quiet estimate 0.54 s x the median ratio).

``python results/plan_scale/fastpolish/table.py RECORDS.json``
"""

from __future__ import annotations

import json
import statistics
import sys

import numpy as np

from poc_env.stats import ci95

QUIET_DEFAULT_S = 0.54  # the default's quiet CPU time a plan on paper_6_2 (issue 24)


def table(path: str) -> None:
    with open(path) as f:
        recs = json.load(f)
    base = {r["seed"]: r for r in recs if r["variant"] == "default"}
    names = list(dict.fromkeys(r["variant"] for r in recs if r["variant"] != "default"))
    mean0 = statistics.mean(b["planned_posc"] / b["rule_bound"] for b in base.values())
    print(f"priors: {sorted(base)}; default planned {mean0:.4f}")
    for v in names:
        rs = [r for r in recs if r["variant"] == v and r["seed"] in base]
        if not rs:
            continue
        row = [v, f"n {len(rs)}"]
        for key in ("planned_posc", "fine_posc"):
            d = np.array(
                [r[key] / r["rule_bound"] - base[r["seed"]][key] / r["rule_bound"] for r in rs]
            )
            half = ci95(d) if len(d) > 1 else float("nan")
            wtl = f"{(d > 1e-9).sum()}/{(abs(d) <= 1e-9).sum()}/{(d < -1e-9).sum()}"
            row.append(f"{key}: {d.mean():+.4f} +- {half:.4f} ({wtl})")
        ratio = [r["cpu_s"] / base[r["seed"]]["cpu_s"] for r in rs]
        med = statistics.median(ratio)
        row.append(
            f"CPU ratio {med:.2f} (max {max(ratio):.2f}) -> {QUIET_DEFAULT_S * med:.2f} s quiet"
        )
        mean = statistics.mean(r["planned_posc"] / r["rule_bound"] for r in rs)
        row.append(f"planned {mean:.4f}")
        print("; ".join(row))
    loads = [r["load"] for r in recs]
    print(f"load {min(loads):.1f}-{max(loads):.1f}")


if __name__ == "__main__":
    table(sys.argv[1])
