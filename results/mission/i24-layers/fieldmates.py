"""i24-layers: are the flown eq. 21 conflicts left (results/plan_scale/i24-flownsep/diag_*.log)
between field-mates (UAVs of one take-off field) or between UAVs of different fields?

``python fieldmates.py`` reads each diag log's pair-steps, rebuilds the case's scenario (no
planning, no flight: only ``takeoff_m``) and counts pair-steps by same / other field and by
phase pair. Per-field layers separate the first; only fleet-wide layers separate the second.
The 500 km scenario's logs (``diag_big*``) are classified when its imported scenario is given:
``python fieldmates.py DIR/big.yaml`` (built as results/plan_scale/i24-flownsep/README.md says).
"""

import collections
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
LOGS = HERE.parents[1] / "plan_scale" / "i24-flownsep"
sys.path.insert(0, str(HERE.parents[1] / "plan_scale" / "i24-deconflict"))
from repro import case  # noqa: E402

from poc_env.config import load_scenario  # noqa: E402


def scenario(log: str):
    name = log.removeprefix("diag_").removesuffix(".log")
    if name.startswith("paper_6_2"):
        return load_scenario("paper_6_2")
    kind, _, n = name.rpartition("_")
    if kind in ("mono2", "lanes"):
        return case(kind, int(n))[0]
    if kind == "" and n.startswith("big") and len(sys.argv) > 1:  # big24, big32
        return load_scenario(sys.argv[1]).with_uavs(int(n[3:]))
    return None


def main() -> None:
    for path in sorted(LOGS.glob("diag_*.log")):
        sc = scenario(path.name)
        pairs = [json.loads(s) for s in path.read_text().splitlines()]
        pairs = [r for r in pairs if "uavs" in r]
        rec = {"log": path.name, "pair_steps": len(pairs)}
        if sc is not None:
            t = np.asarray(sc.takeoff_m, float).reshape(-1, 2)
            by = collections.Counter()
            for r in pairs:
                i, j = r["uavs"]
                same = "same_field" if np.hypot(*(t[i] - t[j])) < 1.0 else "other_field"
                phases = "+".join(sorted(r[f"u{k}"]["phase"] for k in (i, j)))
                by[same] += 1
                by[f"{same}:{phases}"] += 1
            rec |= {"uavs": len(t), "fields": len({tuple(p) for p in t.tolist()}), **by}
        print(json.dumps(rec))


if __name__ == "__main__":
    main()
