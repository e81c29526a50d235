"""The property test's random scenarios (tests/mission/test_mission_property.py, seeds of
run_property(…, 2024)): allocation plans (refine 0); refused plans by reason, and the final
glide gradient of every UAV against tan(beta_max)."""

import json
import math
import sys
import warnings
from collections import Counter
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(sys.argv[1]) / "tests" / "mission"))
import test_mission_property as tp

from poc_env.agents.mission.terrain import plan_profiles
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

n = int(sys.argv[2])
out = Path(sys.argv[3])
out.mkdir(exist_ok=True)
seeds = np.random.default_rng(2024).integers(0, 2**31, size=n)
c = Counter()
rows = []
for s in map(int, seeds):
    rng = np.random.default_rng(s)
    lay = tp._layout(rng)
    folder = out / f"case{s}"
    folder.mkdir(exist_ok=True)
    if s % 2:
        yml = folder / "prop.yaml"
        yml.write_text(yaml.safe_dump(tp._mapping_case(rng, lay)))
    else:
        yml = tp._imported_case(rng, lay, folder)
    sc = load_scenario(yml)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            plan = make_plan(sc, planner="allocation", refine=0, seed=s)
    except ConfigError as e:
        c["refused"] += 1
        rows.append({"seed": s, "refused": str(e)})
        continue
    tan = math.tan(sc.uav.max_pitch_rad)
    for u, p in zip(plan["uavs"], plan_profiles(plan)):
        d = float(np.hypot(*(np.asarray(u["landing_m"]) - p.points_m[-1])))
        g = (p.amsl_m[-1] - p.landing_field_m) / d
        c["uavs"] += 1
        c["glide_over"] += g > tan + 1e-9
        rows.append({"seed": s, "uav": u["id"], "glide": round(g, 4), "tan": round(tan, 4)})
    c["cases"] += 1
    (out / "rows.json").write_text(json.dumps(rows, indent=0))  # after every case
    print(s, dict(c), flush=True)
print(dict(c))
(out / "rows.json").write_text(json.dumps(rows, indent=0))
