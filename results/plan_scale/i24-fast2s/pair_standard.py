"""i24-fast2s: the chosen variant's flights paired with the stored ones (a script, not a test).

``python results/plan_scale/i24-fast2s/pair_standard.py RECORDS.json...`` (this branch's
``effort_ab.py fly`` records): flown POSC over the rule-aware bound of the variant flown on
every prior, paired per prior (Student's t 95 %, wins / ties / losses, least difference)
against `standard` (i24-sampled's flights, with their violation steps), the default and
`greedy_rectangles` (results/plan_scale/paper_6_2.json); eq. 21 / 24 violation steps per
flight paired against `standard`'s; `standard` flown here checked equal to the stored flight.
"""

import json
import sys

import numpy as np

from poc_env.stats import ci95

STD = "results/plan_scale/i24-sampled/rep_paper_6_2.json"
BENCH = "results/plan_scale/paper_6_2.json"


def main(paths: list[str]) -> None:
    mine = []
    for p in paths:
        with open(p) as f:
            mine += json.load(f)
    with open(STD) as f:
        std = {r["seed"]: r for r in json.load(f) if r["variant"] == "allocation_plan@standard"}
    with open(BENCH) as f:
        bench = {(e["seed"], e["policy"]): e for e in json.load(f)["episodes"]}
    for r in mine:
        if r["variant"] == "allocation_plan@standard":
            same = abs(r["posc"] - std[r["seed"]]["posc"]) <= 1e-12
            print(f"check seed {r['seed']} standard: flown {r['posc']:.6f} stored "
                  f"{std[r['seed']]['posc']:.6f} {'equal' if same else 'DIFFERENT'}")  # fmt: skip
    var = sorted({r["variant"] for r in mine} - {"allocation_plan@standard"})
    for v in var:
        rs = sorted((r for r in mine if r["variant"] == v), key=lambda r: r["seed"])
        a = np.array([r["posc"] / r["rule_bound"] for r in rs])
        pf = [r["planned_posc"] / r["posc"] - 1 for r in rs]
        print(f"{v} (n {len(rs)}): flown/rule {a.mean():.4f} +- {ci95(a):.4f} "
              f"({a.min():.3f}-{a.max():.3f}); priors >= 0.90: {(a >= 0.9).sum()}; "
              f"planned/flown - 1 mean {np.mean(pf):+.4f} max {max(pf):+.4f}")  # fmt: skip
        for name, get in (
            ("standard (i24-sampled's flights)", lambda s: std[s]["posc"]),
            ("default (allocation_plan)", lambda s: bench[s, "allocation_plan"]["posc"]),
            ("greedy_rectangles", lambda s: bench[s, "greedy_rectangles"]["posc"]),
        ):
            b = np.array([get(r["seed"]) / r["rule_bound"] for r in rs])
            d = a - b
            print(f"  - {name}: {d.mean():+.4f} +- {ci95(d):.4f} "
                  f"{(d > 1e-9).sum()}/{(abs(d) <= 1e-9).sum()}/{(d < -1e-9).sum()}; least "
                  f"{d.min():+.4f}; theirs {b.mean():.4f}, priors >= 0.90 "
                  f"{(b >= 0.9).sum()}")  # fmt: skip
        dv = np.array([r["violations"] - std[r["seed"]]["violations"] for r in rs], float)
        print(f"  violation steps per flight: standard "
              f"{np.mean([std[r['seed']]['violations'] for r in rs]):.2f} -> "
              f"{np.mean([r['violations'] for r in rs]):.2f}, paired {dv.mean():+.2f} +- "
              f"{ci95(dv):.2f} (more on {(dv > 0).sum()}, equal {(dv == 0).sum()}, fewer "
              f"{(dv < 0).sum()})")  # fmt: skip
        cpu = [r["cpu_s"] for r in rs]
        print(f"  plan CPU median {np.median(cpu):.2f} s (max {max(cpu):.2f}); standard's "
              f"stored flights {np.median([std[r['seed']]['cpu_s'] for r in rs]):.2f} s "
              f"(another run, load 8.5-13.2: not paired)")  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1:])
