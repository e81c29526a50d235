"""Paired summary of an ``effort_ab.py polish`` run of ``default``, ``standard`` and a variant:
``python results/plan_scale/regrade/timing.py RECORDS.json VARIANT [BASE]`` prints VARIANT -
BASE (default ``standard``) over the rule-aware bound on the 2 x 2 and 8 x 8 lattices
(Student's t 95 %, wins / ties / losses) and each variant's CPU time over the ``default``
plan's on the same prior (planned in turn in one process: paired ratios), median and max,
with the quiet estimate at the default's quiet 0.54 s."""

from __future__ import annotations

import json
import statistics
import sys

from stage import t95


def main(path: str, variant: str, base: str = "standard") -> None:
    with open(path) as f:
        recs = json.load(f)
    by = {(r["seed"], r["variant"]): r for r in recs}
    seeds = sorted({s for s, v in by if v == variant} & {s for s, v in by if v == base})
    for key in ("planned_posc", "fine_posc"):
        d = [(by[s, variant][key] - by[s, base][key]) / by[s, base]["rule_bound"] for s in seeds]
        print(f"{variant} - {base} ({key}, n {len(d)}): {t95(d)}")
    for v in ("default", base, variant):
        m = statistics.mean(by[s, v]["planned_posc"] / by[s, v]["rule_bound"] for s in seeds)
        cpu = [by[s, v]["cpu_s"] for s in seeds]
        ratio = [by[s, v]["cpu_s"] / by[s, "default"]["cpu_s"] for s in seeds]
        load = [by[s, v]["load"] for s in seeds]
        print(f"{v}: planned {m:.4f} of the bound; CPU median {statistics.median(cpu):.2f} s "
              f"(max {max(cpu):.2f}); ratio to default median {statistics.median(ratio):.2f} "
              f"(max {max(ratio):.2f}): quiet estimate {0.54 * statistics.median(ratio):.2f} s "
              f"(max {0.54 * max(ratio):.2f} s); load {min(load):.1f}-{max(load):.1f}")  # fmt: skip


if __name__ == "__main__":
    main(*sys.argv[1:])
