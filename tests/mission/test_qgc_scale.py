"""Exports at scale (export-scale; proposed by the scale audit, results/audit/scale/README.md,
defects 3 and 6, where the first two failed on main at a41356a).

* A QGC mission of thousands of items is written without a word, though autopilots hold a
  bounded number (PX4: CONFIG_NUM_MISSION_ITMES_SUPPORTED, 500 on the smallest boards, 2000
  the long-time NuttX default; MAVLink's MISSION_COUNT is a uint16). A DE plan of 24 UAVs at
  sweep 0.5 km over 500 x 500 km exported missions of up to 6,311 items.
* A plan whose UAV is marked ``feasible: false`` (its flight time beyond the usable endurance,
  eq. 18) is exported as a QGC mission without a word. Found on a 24-UAV DE plan (``plan
  --planner de --popsize 16 --maxiter 20`` on 500 x 500 km): every UAV "NO" in the plan table,
  flight times of 6.2 to 30.4 h on a 5 h UAV, then 24 QGC missions written silently (the HTML
  report's table does say "NO"). Either outcome passes: a refusal naming the UAV, or a warning
  naming it.

Also here: the officer's own limit (``max_mission_items``), ``allow_infeasible``, the viewing
formats' warning, and ``plan --effort standard``'s line when its polish is skipped.

Run: .venv/bin/pytest -q tests/mission/test_qgc_scale.py
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from poc_env.agents.mission.export import export_plan
from poc_env.errors import ConfigError


def _plan(tmp_path, n_waypoints: int = 2, hours: float = 2.0):
    rng = np.random.default_rng(0)
    uav = {
        "id": 1, "spacing_m": 5e3,
        "rectangle": {"center_m": [50e3, 60e3], "length_m": 40e3, "width_m": 20e3,
                      "theta_deg": 30.0},
        "takeoff_m": [20e3, -60e3], "landing_m": [20e3, -60e3],
        "waypoints_m": rng.uniform(0, 150e3, (n_waypoints, 2)).round(3).tolist(),
        "track_length_m": 300e3, "flight_time_s": hours * 3600,
        "pod": 0.79, "poc": 0.2, "pos": 0.158, "feasible": hours <= 2.55,
    }  # fmt: skip
    plan = {
        "schema": 1, "scenario": "paper_6_2", "seed": 1, "map_source": "builtin",
        "optimizer": {"name": "adaptive_de", "settings": {}}, "runtime_s": 0.4,
        "posc": 0.3, "upper_bound": 0.5, "uavs": [uav],
    }  # fmt: skip
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    return path


def _export(path, out, fmt="qgc", **kw):
    """The export's files and the messages of its warnings, or the ConfigError raised."""
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        try:
            files = export_plan(path, fmt, "45.75,126.65", out, **kw)
        except ConfigError as err:
            return None, [], err
    return files, [str(w.message) for w in seen], None


def test_a_mission_beyond_what_autopilots_hold_is_said(tmp_path):
    (out,), said, _ = _export(_plan(tmp_path, n_waypoints=2500), tmp_path / "out")
    n = len(json.loads(out.read_text())["mission"]["items"])
    assert n > 2000
    said = [m for m in said if "item" in m]
    assert said, f"{n} mission items written without a warning"
    assert "plan.uavs[0]" in said[0] and str(n) in said[0]
    # actionable (i24-terrainleft #5): the UAV by id, the count, the option that refuses it
    assert "plan.uavs[0] (UAV 1)" in said[0] and f"a QGC mission of {n} items" in said[0]
    assert "--max-mission-items N" in said[0]


def test_a_mission_beyond_the_endurance_is_refused_or_said(tmp_path):
    _, said, err = _export(_plan(tmp_path, hours=30.4), tmp_path / "out")
    if err is not None:
        assert "plan.uavs[0]" in str(err)
        return
    assert [m for m in said if "plan.uavs[0]" in m], "a 30.4 h mission written without a word"


def test_a_short_feasible_mission_says_nothing(tmp_path):
    files, said, err = _export(_plan(tmp_path), tmp_path / "out")
    assert err is None and len(files) == 1
    assert not [m for m in said if "item" in m or "plan.uavs[0]" in m]


def test_the_officers_limit_refuses_a_longer_mission_and_nothing_is_written(tmp_path):
    files, _, err = _export(_plan(tmp_path, n_waypoints=600), tmp_path / "a")
    n = len(json.loads(files[0].read_text())["mission"]["items"])
    _, _, err = _export(_plan(tmp_path, n_waypoints=600), tmp_path / "b", max_mission_items=n - 1)
    assert err is not None and err.field == "plan.uavs[0] (UAV 1)", err
    assert f"{n} items" in str(err) and f"at most {n - 1}" in str(err)
    assert not (tmp_path / "b").exists() or not any((tmp_path / "b").iterdir())
    files, _, err = _export(_plan(tmp_path, n_waypoints=600), tmp_path / "c",
                               max_mission_items=n)  # fmt: skip
    assert err is None and len(files) == 1
    with pytest.raises(ConfigError, match="max_mission_items"):
        export_plan(_plan(tmp_path), "qgc", "45.75,126.65", tmp_path / "d", max_mission_items=0)


def test_a_mission_beyond_every_autopilot_is_refused(tmp_path):
    from poc_env.agents.mission.formats.qgc import MISSION_ITEM_LIMITS, check_mission_size

    top = max(MISSION_ITEM_LIMITS.values())
    with pytest.raises(ConfigError, match=f"a QGC mission of {top + 1} items"):
        check_mission_size("plan.uavs[3] (UAV 4)", top + 1)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        check_mission_size("plan.uavs[3] (UAV 4)", top)
    assert len(seen) == 1 and "PX4 on RAM-constrained boards (500)" in str(seen[0].message)


def test_infeasible_missions_are_written_when_allowed_with_a_warning(tmp_path):
    files, said, err = _export(_plan(tmp_path, hours=30.4), tmp_path / "q", allow_infeasible=True)
    assert err is None and len(files) == 1
    assert [m for m in said if "plan.uavs[0] (UAV 1, 30.40 h)" in m and "eq. 18" in m], said
    for fmt in ("geojson", "kml"):  # the viewing formats draw it and say so
        files, said, err = _export(_plan(tmp_path, hours=30.4), tmp_path / fmt, fmt)
        assert err is None and files
        assert [m for m in said if "plan.uavs[0] (UAV 1, 30.40 h)" in m], (fmt, said)


def test_plan_says_when_the_standard_effort_skipped_its_polish(tmp_path, capsys):
    from poc_env.cli import effort_skip_note, main

    args = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet", "--effort",
            "standard", "--out", str(tmp_path / "p.json")]  # fmt: skip
    zone = "map.no_fly_zones_km=[[[15, 10], [25, 10], [25, 30], [15, 30]]]"
    # i24-zonepolish: maps with zones are polished too (options.polish_zones), nothing said
    assert main([*args, "--overrides", zone]) == 0
    assert "skipped its polish" not in capsys.readouterr().out
    assert main(args) == 0  # no zone, a small map: polished, nothing said
    assert "skipped its polish" not in capsys.readouterr().out
    zones = {"optimizer": {"settings": {"polish": {"skipped": "no-fly zones"}}}}
    assert "note: --effort standard skipped its polish (no-fly zones): this is the default " \
        "plan" in str(effort_skip_note(zones, "standard"))  # fmt: skip
    big = {"optimizer": {"settings": {"polish": {"skipped": "map larger than polish_max_cells"}}}}
    assert "--effort thorough skipped its polish (map larger than polish_max_cells)" in str(
        effort_skip_note(big, "thorough")
    )
    assert effort_skip_note(big, None) is None
