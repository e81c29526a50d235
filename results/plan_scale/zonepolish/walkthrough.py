"""The SAR walkthrough's sortie 1 (docs/missions.md) planned with the default options, the
``standard`` effort (its polish now runs with the zone) and the zone credit at reach W
(``zone_reach=1``), each flown once in the environment (episode seed 0, the scenario's prior):
planned and flown POS_C, no-fly and collision steps. Run from the repository root:
``OMP_NUM_THREADS=1 .venv/bin/python results/plan_scale/zonepolish/walkthrough.py``."""

import dataclasses
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path[:0] = [str(ROOT / "tests" / "e2e"), str(ROOT / "tests" / "planning")]

import test_sar_walkthrough as W  # noqa: E402
import zone_ab  # noqa: E402

from poc_env.agents.planning.allocation import make_allocation_plan  # noqa: E402
from poc_env.agents.planning.options import PlanOptions  # noqa: E402
from poc_env.agents.testing.flights import fly  # noqa: E402
from poc_env.config import load_scenario  # noqa: E402

tmp = Path(tempfile.mkdtemp(prefix="walk_"))
setup, flight = W._blocks()
W._run(setup, tmp)
W._terrain_test()._dem(tmp / "dem.tif")
W._run(flight.split("\n")[0].rstrip("\\") + " " + flight.split("\n")[1].strip(), tmp)
sc = load_scenario(tmp / "alps.yaml", {"uav.max_altitude_m": 6000})
variants = {
    "default": PlanOptions(),
    "standard": PlanOptions.preset("standard"),
    "reach1": PlanOptions(zone_reach=1.0),
    "standard_reach1": dataclasses.replace(PlanOptions.preset("standard"), zone_reach=1.0),
}
for name, opt in variants.items():
    plan = make_allocation_plan(sc, seed=0, options=opt)
    f = fly(sc, zone_ab._Fly(plan), 0)
    print(json.dumps({"variant": name, "planned": round(plan["posc"], 4),
                      "flown": round(f.posc, 4), "nofly": f.nofly_steps,
                      "collision": f.collision_steps}), flush=True)  # fmt: skip
subprocess.run(["rm", "-rf", str(tmp)], check=False)
