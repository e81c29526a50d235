"""Issue 24's scale table (docs/PLANNER.md, "Measured"): from the ``poc-env bench plan --scale``
JSON files of a folder, per map, flown ``allocation_plan`` and ``greedy_rectangles`` over each
prior's rule-aware bound (means, Student's t 95 %), the lead (paired per seed), its wins and
smallest value, the planned figure, and, given an earlier folder of the same runs, the paired
change of ``allocation_plan`` per seed (wins / ties / losses).

    PYTHONPATH=. python results/plan_scale/paired.py results/plan_scale \
        results/plan_scale/earlier_596d5ce
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from poc_env.stats import ci95

FILES = {"paper_6_2": ["paper_6_2.json"], "large_400": ["large_400.json", "large_400_b.json"]}


def load(folder: Path, name: str) -> dict[tuple[int, str], dict]:
    out: dict[tuple[int, str], dict] = {}
    for f in FILES[name]:
        for r in json.loads((folder / f).read_text())["episodes"]:
            if r["map"] == name:
                out[(r["seed"], r["policy"])] = r
    return out


def ratios(recs: dict, policy: str, key: str = "posc") -> dict[int, float]:
    return {s: r[key] / r["rule_bound"] for (s, p), r in recs.items() if p == policy}


def main(folder: Path, earlier: Path | None) -> None:
    for name in FILES:
        now = load(folder, name)
        a, g = ratios(now, "allocation_plan"), ratios(now, "greedy_rectangles")
        planned = ratios(now, "allocation_plan", "planned_posc")
        seeds = sorted(a)
        if sorted(g) != seeds:
            raise SystemExit(f"{name}: the two policies flew other seeds")
        av, gv = np.array([a[s] for s in seeds]), np.array([g[s] for s in seeds])
        d = av - gv
        line = (
            f"{name}: {len(seeds)} priors; allocation_plan {av.mean():.3f} +- {ci95(av):.3f}; "
            f"greedy_rectangles {gv.mean():.3f} +- {ci95(gv):.3f}; lead {d.mean():+.3f} +- "
            f"{ci95(d):.3f}, ahead on {int((d > 0).sum())} / {len(seeds)}, "
            f"smallest {d.min():+.3f}; "
            f"planned {np.mean([planned[s] for s in seeds]):.3f}; priors >= 0.90: "
            f"{int((av >= 0.90).sum())}"
        )
        if earlier is not None:
            then = load(earlier, name)
            # the earlier flights over this run's bound of the same prior (earlier records of
            # maps with 3+ airfields hold the merged relaxation, before i24-tightbound)
            b = {s: then[(s, "allocation_plan")]["posc"] / now[(s, "allocation_plan")]["rule_bound"]
                 for s in seeds}  # fmt: skip
            gb = {s: then[(s, "greedy_rectangles")]["posc"]
                  / now[(s, "greedy_rectangles")]["rule_bound"] for s in seeds}  # fmt: skip
            if any(gb[s] != g[s] for s in seeds):
                line += "; NOTE greedy_rectangles differs from the earlier run"
            e = np.array([a[s] - b[s] for s in seeds])
            line += (
                f"; against {earlier.name}: {np.mean([b[s] for s in seeds]):.3f} -> "
                f"{av.mean():.3f}, {e.mean():+.4f} +- {ci95(e):.4f} "
                f"({int((e > 1e-12).sum())} / {int((abs(e) <= 1e-12).sum())} / "
                f"{int((e < -1e-12).sum())} wins / ties / losses)"
            )
        print(line)


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]) if len(sys.argv) > 2 else None)
