"""The headroom of the plan choice on a collection's records (i28-editplan): per candidate its
flown POSC minus ``default``'s (Student's t 95 %, wins / ties / losses), violation steps and
planning CPU time over ``default``'s (median ratio), and best-of-K (the oracle) minus default.

``python results/editplan/headroom.py RECORDS.jsonl[,MORE.jsonl]``
"""

from __future__ import annotations

import json
import sys

import numpy as np

sys.path.insert(0, "results/editplan")
from fit import t95

from poc_env.agents.policies.plan_choice import CANDIDATES


def main(path: str) -> None:
    recs = []
    for p in path.split(","):
        with open(p) as f:
            recs += [json.loads(line) for line in f if line.strip()]
    d = np.array([r["cands"]["default"]["posc"] for r in recs])
    dt = np.array([r["cands"]["default"]["plan_s"] for r in recs])
    print(f"{len(recs)} priors ({recs[0]['seed']}-{recs[-1]['seed']}); default POSC {d.mean():.4f}")
    print("| candidate | - default | wins / ties / losses | violation steps (mean) | plan CPU "
          "/ default (median) | planned - flown (mean) |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for k in CANDIDATES:
        p = np.array([r["cands"][k]["posc"] for r in recs])
        v = np.array([r["cands"][k]["violations"] for r in recs])
        t = np.array([r["cands"][k]["plan_s"] for r in recs])
        pl = np.array([r["cands"][k]["planned"] for r in recs])
        g = p - d
        m, h = t95(g)
        w, ls = int((g > 1e-9).sum()), int((g < -1e-9).sum())
        print(f"| `{k}` | {m:+.4f} ± {h:.4f} | {w} / {len(g) - w - ls} / {ls} | {v.mean():.1f} | "
              f"{np.median(t / dt):.2f} | {np.mean(pl - p):+.5f} |")  # fmt: skip
    best = np.array([max(c["posc"] for c in r["cands"].values()) for r in recs])
    arg = [max(r["cands"], key=lambda k: r["cands"][k]["posc"]) for r in recs]
    m, h = t95(best - d)
    print(f"| best of K (oracle) | {m:+.4f} ± {h:.4f} | | | {len(CANDIDATES)} plans | |")
    by_plan = np.array([max(r["cands"].values(), key=lambda c: c["planned"])["posc"] for r in recs])
    m, h = t95(by_plan - d)
    print(f"| the most planned POS of K (the planner at K times its cost) | {m:+.4f} ± {h:.4f} | "
          f"| | {len(CANDIDATES)} plans | |")  # fmt: skip
    print("oracle's picks:", {k: arg.count(k) for k in CANDIDATES if arg.count(k)})
    print(f"default plan CPU s: median {np.median(dt):.2f}")


if __name__ == "__main__":
    main(sys.argv[1])
