"""Proposed test (scale-audit; not collected by the suite: agents/mission/ is another helper's
lane). It fails on main at a41356a: one ``export --format geojson`` (or kml, html) of a terrain
plan computes every UAV's terrain profile three times (``features.routes_3d``,
``features.overlays`` and ``export._terrain_altitudes`` each call
``terrain.plan_profiles``), and each profile's ``_simplify`` makes O(m^2) ``np.all`` calls over
the m samples of a leg. A 24-UAV DE plan (23,264 waypoints, 500 x 500 km, DEM) took about 2 min
a format at load 6-7; under cProfile 251 s, 243 s of it in ``plan_profiles`` (72 profiles for
24 UAVs; 175 s in ``_simplify``, 7.7 M ``np.all`` calls).

Run: .venv/bin/pytest -q results/audit/scale/proposed_tests/test_export_profiles_once.py
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from poc_env.agents.mission import terrain
from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.plan import write_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario

_spec = importlib.util.spec_from_file_location(
    "_terrain_tests", Path(__file__).parents[4] / "tests" / "mission" / "test_terrain.py"
)
_t = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_t)


@pytest.mark.parametrize("fmt", ["geojson", "kml", "qgc"])
def test_each_uavs_profile_is_computed_once_an_export(tmp_path, fmt, monkeypatch):
    plan = make_plan(load_scenario(_t._scenario(_t._dem(tmp_path / "d.tif"))),
                     planner="allocation", refine=0)  # fmt: skip
    write_plan(plan, tmp_path / "plan.json")
    calls = []
    real = terrain.profile
    monkeypatch.setattr(terrain, "profile", lambda *a, **k: calls.append(1) or real(*a, **k))
    export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
    assert len(calls) == len(plan["uavs"]), f"{len(calls)} profiles for {len(plan['uavs'])} UAVs"
