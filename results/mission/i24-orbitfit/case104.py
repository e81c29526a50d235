"""i24-orbitfit: case 104 (seed 1474536988) of the mission property test, planned through the
command line as check_case plans it (allocation --refine 1; de --popsize 8 --maxiter 4), each
UAV's flight, orbits and 0.85 T, and the plan's POS_C before and after the orbit fit.

Usage: python results/mission/i24-orbitfit/case104.py OUTDIR [SEED]
"""

import json
import sys
from pathlib import Path

import numpy as np

sys.path[:0] = ["tests/mission", "tests"]
import test_mission_property as t  # noqa: E402

from poc_env.agents.mission.plan import load_plan  # noqa: E402
from poc_env.agents.mission.terrain import orbit_time_s, plan_profiles  # noqa: E402

out = Path(sys.argv[1])
seed = int(sys.argv[2]) if len(sys.argv) > 2 else 1474536988
out.mkdir(parents=True, exist_ok=True)
rng = np.random.default_rng(seed)
lay = t._layout(rng)
assert seed % 2 == 0  # a DEM case, as check_case builds it
yml = t._imported_case(rng, lay, out)
s = ["--seed", str(seed), "--out"]
argv = {
    "allocation": ["plan", "--scenario", str(yml), "--planner", "allocation", "--refine", "1", *s],
    "de": ["plan", "--scenario", str(yml), "--planner", "de", "--popsize", "8", "--maxiter", "4",
           *s],
}  # fmt: skip
rec = {}
for name, a in argv.items():
    f = out / name / "plan.json"
    error = t._cli([*a, str(f)])
    if error:
        print(name, "REFUSED", error)
        rec[name] = {"refused": error}
        continue
    plan = dict(load_plan(f))
    usable = plan["terrain"]["usable_endurance_s"]
    fit = plan.get("orbit_fit")
    print(f"{name}: POS_C {plan['posc']:.4f}" + (
        f" (before the fit {fit['posc_before']:.4f}, {plan['posc'] - fit['posc_before']:+.4f})"
        if fit else " (no fit needed)"))  # fmt: skip
    rows = []
    for u, p in zip(plan["uavs"], plan_profiles(plan)):
        r = {"id": u["id"], "flight_min": u["flight_time_s"] / 60,
             "orbits_min": orbit_time_s(p) / 60, "usable_min": usable / 60,
             "feasible": u["feasible"],
             "fit": (fit or {}).get("uavs", {}).get(str(u["id"]))}  # fmt: skip
        rows.append(r)
        print(f"  UAV {r['id']}: flight {r['flight_min']:.2f} + orbits {r['orbits_min']:.2f} = "
              f"{r['flight_min'] + r['orbits_min']:.2f} / {r['usable_min']:.2f} min"
              f"{'' if u['feasible'] else ' (infeasible)'}  {r['fit'] or ''}")  # fmt: skip
    rec[name] = {"posc": plan["posc"], "orbit_fit": fit, "uavs": rows}
(out / "case104.json").write_text(json.dumps(rec, indent=1))
