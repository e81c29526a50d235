"""i24-fast2s: paired table of an ``effort_ab.py polish`` run (a script, not a test).

``python results/plan_scale/i24-fast2s/table.py REF RECORDS.json...``: per variant, planned
POS_C / rule-aware bound (2 x 2) and on the 8 x 8 lattice paired against variant ``REF``
(Student's t 95 %, wins / ties / losses), and the CPU ratio to ``default`` on the same prior
(median, max, priors over 3.70 = 2 s at the default's quiet 0.54 s), the default planned in
the same run (the same process, in turn).
"""

import json
import statistics
import sys

import numpy as np

from poc_env.stats import ci95


def main(ref: str, paths: list[str]) -> None:
    recs, dflt = [], {}
    for p in paths:  # each variant's CPU paired with the default planned in the same run
        with open(p) as f:
            got = json.load(f)
        base = {r["seed"]: r["cpu_s"] for r in got if r["variant"] == "default"}
        for r in got:
            if r["variant"] != "default" or r["seed"] not in dflt:
                recs.append(r)
                dflt.setdefault(r["seed"], r)
            r["ratio"] = r["cpu_s"] / base[r["seed"]]
    by = {(r["seed"], r["variant"]): r for r in recs}
    seeds = sorted({r["seed"] for r in recs})
    names = list(dict.fromkeys(r["variant"] for r in recs))
    print(f"priors {seeds[0]}..{seeds[-1]}; reference {ref}")
    for v in names:
        ss = [s for s in seeds if (s, v) in by and (s, ref) in by and (s, "default") in by]
        if not ss:
            continue
        row = [v, f"n {len(ss)}"]
        for key in ("planned_posc", "fine_posc"):
            x = np.array([by[s, v][key] / by[s, v]["rule_bound"] for s in ss])
            y = np.array([by[s, ref][key] / by[s, ref]["rule_bound"] for s in ss])
            d = x - y
            h = ci95(d) if len(d) > 1 else float("nan")
            w = f"{(d > 1e-9).sum()}/{(abs(d) <= 1e-9).sum()}/{(d < -1e-9).sum()}"
            row.append(f"{key[:4]} {x.mean():.4f} {d.mean():+.4f} +- {h:.4f} ({w})")
        rat = [by[s, v]["ratio"] for s in ss]
        over = [s for s, q in zip(ss, rat) if q > 3.70]
        row.append(f"cpu ratio {statistics.median(rat):.2f} (max {max(rat):.2f}) over3.70 {over}")
        row.append(f"cpu med {statistics.median(by[s, v]['cpu_s'] for s in ss):.2f} s")
        print(" | ".join(row))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
