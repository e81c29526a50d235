"""i24-monotone: the default plan of each fleet size on one scenario, planned only (a script,
not a test; run it from the checkout).

``python diag.py SCENARIO SIZES OUT_DIR [FIELD=VALUE,...]``
    SCENARIO a scenario file (the audit's 500 km ``big.yaml``) planned on its own prior, or
    ``mini:SIDE_KM:CELL_KM`` (tests/planning/test_fleet.py's ``mini``), or a built-in name;
    SIZES ``16,24,32``; optional PlanOptions fields changed (bools, ints or floats). One JSON
    line per size: planned POS_C, the pick's criterion (planned POS less ``gain_per_hour`` of
    the mass per flight hour times the plan's flight hours), UAVs flying, their hours, the
    start kept, ``optimizer.settings.fleet`` / ``own_apart`` / the UAVs kept home, CPU s and
    the 1-minute load. The plans are written to OUT_DIR (``nN.json``).
"""

import json
import os
import sys
import time

from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior


def scenario(name: str):
    """The scenario (all its UAVs) and its prior."""
    if name.startswith("mini"):
        sys.path.insert(0, "tests/planning")
        from test_fleet import mini

        return mini(*map(float, name.split(":")[1:3]), 64)
    sc = load_scenario(name)
    return sc, build_prior(sc.map)


def value(v: str):
    """A command-line option value: a bool, an int or a float."""
    if v.lower() in ("true", "false"):
        return v.lower() == "true"
    return float(v) if "." in v or "e" in v else int(v)


def record(name: str, n: int, plan: dict, cpu: float, prior_mass: float, rate: float) -> dict:
    """One size's line (module docstring)."""
    hours = sum(u["flight_time_s"] for u in plan["uavs"] if u["waypoints_m"]) / 3600
    st = plan["optimizer"]["settings"]
    return {
        "case": name,
        "uavs": n,
        "posc": round(float(plan["posc"]), 6),
        "criterion": round(float(plan["posc"]) - rate * prior_mass * hours, 6),
        "flying": sum(1 for u in plan["uavs"] if u["waypoints_m"]),
        "hours": round(hours, 2),
        "start": plan["start"],
        "fleet": st.get("fleet"),
        "own_apart": st.get("own_apart"),
        "home": len(st.get("home", [])),
        "cpu_s": round(cpu, 1),
        "load1": round(os.getloadavg()[0], 1),
    }


def main() -> None:
    name, sizes, out = sys.argv[1], sys.argv[2], sys.argv[3]
    changes = dict(kv.split("=") for kv in sys.argv[4].split(",")) if len(sys.argv) > 4 else {}
    opt = PlanOptions(**{k: value(v) for k, v in changes.items()})
    sc_all, prior = scenario(name)
    os.makedirs(out, exist_ok=True)
    for n in [int(s) for s in sizes.split(",")]:
        c0 = time.process_time()
        plan = make_allocation_plan(sc_all.with_uavs(n), prior=prior, options=opt)
        cpu = time.process_time() - c0
        with open(os.path.join(out, f"n{n}.json"), "w") as f:
            json.dump(plan, f)
        rec = record(name, n, plan, cpu, float(prior.sum()), opt.gain_per_hour)
        print(json.dumps({**rec, "options": changes}), flush=True)


if __name__ == "__main__":
    main()
