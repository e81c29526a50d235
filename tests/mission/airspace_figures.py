"""The airspace figures of docs/missions.md ("Airspace"): a script, not a test.

Flies ``allocation_plan`` and ``de_plan`` on the two maps of ``tests/planning/test_airspace.py``
and prints, per case, the no-fly and out-of-bounds steps (the environment's eq. 20 infos), the
flown POS (``posc`` at the episode's end, episode seed 0, the map's own prior) and the planned
POS; then the planned POS of both planners on ``paper_6_2`` without zones.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 python
tests/mission/airspace_figures.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE.parent)]

from poc_env.agents.planning.allocation import make_allocation_plan  # noqa: E402
from poc_env.agents.planning.planner import make_plan  # noqa: E402
from poc_env.agents.policies.allocation import AllocationPlanPolicy  # noqa: E402
from poc_env.agents.policies.de_plan import DEPlanPolicy  # noqa: E402
from poc_env.agents.testing.flights import fly as fly_episode  # noqa: E402
from poc_env.config import load_scenario  # noqa: E402

#: the zones of tests/planning/test_airspace.py (km): across ``small``'s search area, and a
#: 30 x 100 km zone on ``paper_6_2``.
CASES = {
    "small": {"map.no_fly_zones_km": [[[15, 10], [25, 10], [25, 30], [15, 30]]],
              "map.no_fly_names": ["range R-12"]},
    "paper_6_2": {"map.no_fly_zones_km": [[[60, 20], [90, 20], [90, 120], [60, 120]]]},
}  # fmt: skip


def fly(sc: Any, policy: Any, seed: int = 0) -> dict[str, Any]:
    """One episode of ``policy`` on ``sc``: eq. 20 steps, flown and planned POS."""
    f = fly_episode(sc, policy, seed)
    return {"nofly_steps": f.nofly_steps, "oob_steps": f.oob_steps, "flown_pos": f.posc,
            "planned_pos": float(policy.plan["posc"])}  # fmt: skip


def main() -> None:
    out: dict[str, Any] = {}
    for name, zones in CASES.items():
        sc = load_scenario(name, zones)
        # the test flies DE at popsize 16, maxiter 15 on small; paper_6_2 at its defaults
        de = DEPlanPolicy(16, 15) if name == "small" else DEPlanPolicy()
        out[f"{name}+zone"] = {"allocation_plan": fly(sc, AllocationPlanPolicy()),
                               "de_plan": fly(sc, de)}  # fmt: skip
    sc = load_scenario("paper_6_2")
    out["paper_6_2 planned, no zones"] = {
        "allocation": float(make_allocation_plan(sc)["posc"]),
        "de (seed 0)": float(make_plan(sc, seed=0)["posc"]),
    }
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
