"""i24-terrainleft item 1: how often the new take-off climb / final glide check refuses on the
mission property test's random cases (allocation planner only; the first N of its seeds).

    OMP_NUM_THREADS=1 nice -n 10 .venv/bin/python results/audit/terrainleft/property_probe.py 40
    # every planner that writes a plan (allocation, de, replan, survey) and the greedy baseline
    OMP_NUM_THREADS=1 nice -n 10 .venv/bin/python results/audit/terrainleft/property_probe.py 15 all
"""

from __future__ import annotations

import json
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "tests" / "mission"))
from test_mission_property import check_case

from poc_env.agents.testing.flights import fly


def main(n: int, every: bool = False) -> None:
    from test_mission_property import PLANNERS

    seeds = np.random.default_rng(2024).integers(0, 2**31, size=n).tolist()
    planners = PLANNERS if every else ("allocation",)
    out = Path(__file__).with_name("property_probe_all.json" if every else "property_probe.json")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for s in seeds:
            folder = Path(tmp) / f"case{s}"
            folder.mkdir()
            c: Counter = check_case(fly, int(s), folder, planners)
            why = [k for k in c if ":" in k]
            rows.append(
                {
                    "seed": int(s),
                    "plans": c["plans"],
                    "refused": c["refused"],
                    "refused_by_climb": sum("take-off climb" in k for k in why),
                    "refused_by_glide": sum("final glide to" in k for k in why),
                    "qgc_low": c["qgc_low"],
                    "clearance": c["clearance"],
                    "details": [k[:400] for k in why],
                }
            )
            print(json.dumps({k: v for k, v in rows[-1].items() if k != "details"}), flush=True)
    tot = {
        k: sum(r[k] for r in rows)
        for k in (
            "plans",
            "refused",
            "refused_by_climb",
            "refused_by_glide",
            "qgc_low",
            "clearance",
        )
    }
    tot["cases"] = len(rows)
    out.write_text(json.dumps({"total": tot, "cases": rows}, indent=1) + "\n")
    print("total", tot)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 40, sys.argv[2:] == ["all"])
