"""i24-terrainleft: how much higher the profiles fly with the sub-leg ground (and the climb /
glide check), at the route's vertices, on the property test's first N random cases.

    # 1. the cases' plans, written once (the branch's venv)
    .venv/bin/python results/audit/terrainleft/altitude_cost.py plans 40 /tmp/terrainleft/cases
    # 2. each checkout's vertex altitudes over the same plan.json files (B: this folder)
    (cd /work/main && .venv/bin/python $B/altitude_cost.py vertices /tmp/terrainleft/cases \
        $B/vertices_main.json)
    .venv/bin/python $B/altitude_cost.py vertices /tmp/terrainleft/cases $B/vertices_branch.json
    # 3. the table
    .venv/bin/python $B/altitude_cost.py compare $B/vertices_main.json $B/vertices_branch.json
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import numpy as np


def plans(n: int, root: Path) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "tests" / "mission"))
    from test_mission_property import check_case

    from poc_env.agents.testing.flights import fly

    for s in np.random.default_rng(2024).integers(0, 2**31, size=n).tolist():
        folder = root / f"case{s}"
        folder.mkdir(parents=True, exist_ok=True)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_case(fly, int(s), folder, ("allocation",))


def vertices(root: Path, out: Path) -> None:
    from poc_env.agents.mission.plan import load_plan
    from poc_env.agents.mission.terrain import plan_profiles

    rows = {}
    for pj in sorted(root.glob("case*/allocation/plan.json")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            profs = plan_profiles(load_plan(pj))
        for k, p in enumerate(profs or []):
            at = {str(int(v)): float(z) for v, z in zip(p.vertex, p.amsl_m) if v >= 0}
            at["points"] = len(p.amsl_m)  # the profile's points kept (QGC waypoints)
            rows[f"{pj.parts[-3]}/uav{k}"] = at
    out.write_text(json.dumps(rows) + "\n")


def compare(a: Path, b: Path) -> None:
    old, new = json.loads(a.read_text()), json.loads(b.read_text())
    d = np.array([new[u][v] - old[u][v] for u in old for v in old[u] if v != "points"])
    pts = [(old[u].get("points"), new[u].get("points")) for u in old]
    print(json.dumps({
        "uavs": len(old), "vertices": int(d.size), "higher": int(np.sum(d > 0.05)),
        "lower": int(np.sum(d < -0.05)), "mean_m": round(float(d.mean()), 2),
        "median_m": round(float(np.median(d)), 2), "max_m": round(float(d.max()), 1),
        "min_m": round(float(d.min()), 1),
        "points_kept": [sum(p[0] or 0 for p in pts), sum(p[1] or 0 for p in pts)],
    }))  # fmt: skip


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "plans":
        plans(int(sys.argv[2]), Path(sys.argv[3]))
    elif cmd == "vertices":
        vertices(Path(sys.argv[2]), Path(sys.argv[3]))
    else:
        compare(Path(sys.argv[2]), Path(sys.argv[3]))
