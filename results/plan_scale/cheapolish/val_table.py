"""i24-cheapolish: the validation table (a script, not a test).

``python results/plan_scale/cheapolish/val_table.py RECORDS.json...``: from ``effort_ab.py
polish`` records, per variant its planned POS_C over the rule-aware bound on the environment's
2 x 2 sample points and on 8 x 8, paired per prior against ``standard`` (Student's t 95 %,
wins / ties / losses), and its CPU time over the default's on the same prior (planned in turn in
one process: paired; several files: each against its own run's default), median and max,
with the quiet estimate 0.54 s x ratio (the default's quiet 0.54 s on ``paper_6_2``,
i24-fastpolish; 2 s = 3.7 x). Planned values are deterministic, so a variant planned in two
runs is the same plan; its CPU ratio is taken from the last run given.
"""

import json
import statistics
import sys

from poc_env.stats import ci95


def main(paths):
    recs = []
    for i, p in enumerate(paths):
        with open(p) as f:
            recs += [{**r, "run": i} for r in json.load(f)]
    by = {(r["seed"], r["variant"]): r for r in recs}
    # each record's CPU ratio against the default planned in the same run (process)
    default = {(r["run"], r["seed"]): r["cpu_s"] for r in recs if r["variant"] == "default"}
    seeds = sorted({r["seed"] for r in recs if (r["seed"], "standard") in by})
    names = list(dict.fromkeys(r["variant"] for r in recs))
    for v in names:
        ss = [s for s in seeds if (s, v) in by and (s, "default") in by]
        if not ss:
            continue
        out = [f"{v}: n {len(ss)}"]
        for key in ("planned_posc", "fine_posc"):
            mean = statistics.mean(by[s, v][key] / by[s, v]["rule_bound"] for s in ss)
            d = [(by[s, v][key] - by[s, "standard"][key]) / by[s, v]["rule_bound"] for s in ss]
            half = ci95(d) if len(d) > 1 else float("nan")
            w = (sum(x > 1e-9 for x in d), sum(abs(x) <= 1e-9 for x in d),
                 sum(x < -1e-9 for x in d))  # fmt: skip
            out.append(f"{key} {mean:.4f}, vs standard {statistics.mean(d):+.4f} +- {half:.4f} "
                       f"({w[0]} / {w[1]} / {w[2]})")  # fmt: skip
        ratio = [by[s, v]["cpu_s"] / default[by[s, v]["run"], s] for s in ss]
        cpu = [by[s, v]["cpu_s"] for s in ss]
        med = statistics.median(ratio)
        out.append(f"CPU ratio median {med:.2f} (max {max(ratio):.2f}), CPU median "
                   f"{statistics.median(cpu):.2f} s (loaded), quiet estimate {0.54 * med:.2f} s "
                   f"(max {0.54 * max(ratio):.2f} s)")  # fmt: skip
        print("\n  ".join(out))


if __name__ == "__main__":
    main(sys.argv[1:])
