"""cpu-audit: the table of README.md from the recorded_*.json files of measure_recorded.py."""

from __future__ import annotations

import json
import sys


def main(paths: list[str]) -> None:
    print(
        "| variant | float64 values not bit-equal | largest abs | largest rel "
        "| float32 not equal | bool/int equal |"
    )
    print("|---|---|---|---|---|---|")
    for path in paths:
        with open(path, encoding="utf-8") as f:
            d = json.load(f)
        t = d["tasks"].values()
        n64 = sum(r["float64"]["n"] for r in t)
        d64 = sum(r["float64"]["n_diff"] for r in t)
        a64 = max(r["float64"]["max_abs"] for r in t)
        r64 = max(r["float64"]["max_rel"] for r in t)
        d32 = sum(r["float32"]["n_diff"] for r in t)
        n32 = sum(r["float32"]["n"] for r in t)
        ok = all(r["exact_other"] for r in t)
        print(
            f"| {path.rsplit('/', 1)[-1]} | {d64} of {n64} | {a64:.2g} | {r64:.2g} "
            f"| {d32} of {n32} | {ok} |"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
