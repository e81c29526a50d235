"""Proposed test (scale-audit; not collected by the suite: agents/mission/ and poc_env/cli.py
are other helpers' lanes). It fails on main at a41356a: a plan whose UAV is marked
``feasible: false`` (its flight time beyond the usable endurance, eq. 18) is exported as a QGC
mission without a word. Found on a 24-UAV DE plan (``plan --planner de --popsize 16 --maxiter
20`` on 500 x 500 km): every UAV "NO" in the plan table, flight times of 6.2 to 30.4 h on a 5 h
UAV, ``plan`` exit status 0 and no warning line, then 24 QGC missions written silently (the
HTML report's table does say "NO"). Either outcome passes: a refusal naming the UAV, or a
warning naming it.

Run: .venv/bin/pytest -q results/audit/scale/proposed_tests/test_qgc_infeasible_uav.py
"""

from __future__ import annotations

import json
import warnings

from poc_env.agents.mission.export import export_plan
from poc_env.errors import ConfigError


def _plan(tmp_path, feasible: bool):
    uav = {
        "id": 1, "spacing_m": 5e3,
        "rectangle": {"center_m": [50e3, 60e3], "length_m": 40e3, "width_m": 20e3,
                      "theta_deg": 30.0},
        "takeoff_m": [20e3, -60e3], "landing_m": [20e3, -60e3],
        "waypoints_m": [[40e3, 40e3], [60e3, 80e3]], "track_length_m": 300e3,
        "flight_time_s": 30.4 * 3600 if not feasible else 2 * 3600,
        "pod": 0.79, "poc": 0.2, "pos": 0.158, "feasible": feasible,
    }  # fmt: skip
    plan = {
        "schema": 1, "scenario": "paper_6_2", "seed": 1, "map_source": "builtin",
        "optimizer": {"name": "adaptive_de", "settings": {}}, "runtime_s": 0.4,
        "posc": 0.3, "upper_bound": 0.5, "uavs": [uav],
    }  # fmt: skip
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    return path


def test_a_mission_beyond_the_endurance_is_refused_or_said(tmp_path):
    path = _plan(tmp_path, feasible=False)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        try:
            export_plan(path, "qgc", "45.75,126.65", tmp_path / "out")
        except ConfigError as err:
            assert "plan.uavs[0]" in str(err)
            return
    said = [str(w.message) for w in seen if "plan.uavs[0]" in str(w.message)]
    assert said, "a 30.4 h mission of a plan marked infeasible written without a word"


def test_a_feasible_mission_says_nothing(tmp_path):
    path = _plan(tmp_path, feasible=True)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        export_plan(path, "qgc", "45.75,126.65", tmp_path / "out")
    assert not [w for w in seen if "plan.uavs[0]" in str(w.message)]
