"""The final landing glide of terrain missions over the mission property test's random cases
(export-audit): per UAV the glide approach point -> landing field of the export's own altitude
profile (``plan_profiles``, what the QGC mission flies), the allocation planner (refine 1).

Run from a checkout whose ``poc_env`` is the one to measure (PYTHONPATH=<tree> for another):

    OMP_NUM_THREADS=1 python results/audit/export/glide_ab.py N OUT.json

Seeds: ``default_rng(2024).integers(0, 2**31, N)``, the 200-case property run's first N.
"""

from __future__ import annotations

import json
import math
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
import yaml

from poc_env.agents.mission.plan import APPROACH_DISTANCE_M
from poc_env.agents.mission.terrain import plan_profiles
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

ROOT = Path(__file__).resolve().parents[3]


def _property_module():
    """tests/mission/test_mission_property.py (its random cases: one copy)."""
    sys.path.insert(0, str(ROOT / "tests" / "mission"))
    return __import__("test_mission_property")


def main(n: int, out: Path) -> None:
    prop = _property_module()
    seeds = [int(v) for v in np.random.default_rng(2024).integers(0, 2**31, size=n)]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for s in seeds:
            folder = Path(tmp) / f"case{s}"
            folder.mkdir()
            rng = np.random.default_rng(s)
            lay = prop._layout(rng)
            if s % 2:
                yml = folder / "prop.yaml"
                yml.write_text(yaml.safe_dump(prop._mapping_case(rng, lay)))
            else:
                yml = prop._imported_case(rng, lay, folder)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the steep-glide warning: counted below
                try:
                    plan = make_plan(load_scenario(yml), planner="allocation", refine=1, seed=s)
                    profs = plan_profiles(plan)
                except ConfigError as err:
                    rows.append({"seed": s, "refused": str(err)})
                    continue
            assert profs is not None
            for u, p in zip(plan["uavs"], profs):
                rise = p.amsl_m[-1] - p.landing_field_m
                deg = math.degrees(math.atan(rise / APPROACH_DISTANCE_M))
                rows.append({"seed": s, "uav": u["id"], "glide_deg": round(deg, 3)})
    g = np.array([r["glide_deg"] for r in rows if "glide_deg" in r])
    summary = {
        "cases": n,
        "uavs": int(g.size),
        "refused": sum("refused" in r for r in rows),
        "glide_deg_max": float(g.max()),
        "glide_deg_median": float(np.median(g)),
        "over_5_1_deg": int((g > 5.1).sum()),
        "over_4_3_deg": int((g > 4.29 + 1e-3).sum()),
    }
    out.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1) + "\n")
    print(json.dumps(summary))


if __name__ == "__main__":
    main(int(sys.argv[1]), Path(sys.argv[2]))
