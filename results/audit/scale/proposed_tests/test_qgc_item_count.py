"""Proposed test (scale-audit; not collected by the suite: agents/mission/ is another helper's
lane). It fails on main at a41356a: a QGC mission of thousands of items is written without a
word, though autopilots hold a bounded number (PX4: CONFIG_NUM_MISSION_ITMES_SUPPORTED, 500 on
the smallest boards, 2000 the long-time NuttX default; MAVLink's MISSION_COUNT is a uint16).
A DE plan of 24 UAVs at sweep 0.5 km over 500 x 500 km exported missions of up to 6,311 items.

Run: .venv/bin/pytest -q results/audit/scale/proposed_tests/test_qgc_item_count.py
"""

from __future__ import annotations

import json
import warnings

import numpy as np

from poc_env.agents.mission.export import export_plan


def _plan(tmp_path, n_waypoints: int):
    rng = np.random.default_rng(0)
    wps = rng.uniform(0, 150e3, (n_waypoints, 2)).round(3).tolist()
    uav = {
        "id": 1, "spacing_m": 5e3,
        "rectangle": {"center_m": [50e3, 60e3], "length_m": 40e3, "width_m": 20e3,
                      "theta_deg": 30.0},
        "takeoff_m": [20e3, -60e3], "landing_m": [20e3, -60e3],
        "waypoints_m": wps, "track_length_m": 300e3, "flight_time_s": 9000.0,
        "pod": 0.79, "poc": 0.2, "pos": 0.158, "feasible": True,
    }  # fmt: skip
    plan = {
        "schema": 1, "scenario": "paper_6_2", "seed": 1, "map_source": "builtin",
        "optimizer": {"name": "adaptive_de", "settings": {}}, "runtime_s": 0.4,
        "posc": 0.3, "upper_bound": 0.5, "uavs": [uav],
    }  # fmt: skip
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    return path


def test_a_mission_beyond_what_autopilots_hold_is_said(tmp_path):
    path = _plan(tmp_path, 2500)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        (out,) = export_plan(path, "qgc", "45.75,126.65")
    n = len(json.loads(out.read_text())["mission"]["items"])
    assert n > 2000
    said = [str(w.message) for w in seen if "item" in str(w.message)]
    assert said, f"{n} mission items written without a warning"
    assert "plan.uavs[0]" in said[0] and str(n) in said[0]


def test_a_short_mission_says_nothing(tmp_path):
    path = _plan(tmp_path, 20)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        export_plan(path, "qgc", "45.75,126.65")
    assert not [w for w in seen if "item" in str(w.message)]
