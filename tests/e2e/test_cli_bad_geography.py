"""Issue 24's bad input, through the command line: zones covering an airfield or the whole area,
a DEM without a CRS or not covering the area, clearance impossible within the UAVs' ceiling (at
plan and at export). Each ends in ``error: <field>: got ...; allowed: ...`` with exit 2, no
traceback, and the folder exactly as it was (nothing written). Flown tracks outside the map or
in another CRS are tests/planning/test_replan.py's."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
import yaml

from poc_env.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _terrain_test():
    """tests/mission/test_terrain.py as a module: its synthetic Alps DEM and scenario."""
    spec = importlib.util.spec_from_file_location(
        "_terrain_test", ROOT / "tests" / "mission" / "test_terrain.py"
    )
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _tree(root: Path) -> list[tuple[str, bytes]]:
    return sorted((str(p.relative_to(root)), p.read_bytes() if p.is_file() else b"")
                  for p in root.rglob("*"))  # fmt: skip


def _refused(tmp_path, capsys, argv: list[str], *needles: str) -> str:
    """Run ``poc-env ARGV`` in ``tmp_path``: exit 2, ``error: ...`` naming every needle, no
    traceback, nothing written or changed."""
    before = _tree(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "allowed:" in err, err
    assert "Traceback" not in err
    for n in needles:
        assert n in err, (n, err)
    assert _tree(tmp_path) == before
    return err


@pytest.mark.parametrize(
    ("zone", "needles"),
    [
        ([[15, -8], [25, -8], [25, 2]], ("airfields[A]", "no-fly zone 0 ('R-1')")),
        ([[-1, -1], [41, -1], [41, 41], [-1, 41]], ("no_fly_zones_km[0]", "covers all of it")),
    ],
    ids=["over-the-airfield", "over-the-whole-area"],
)
def test_zone_over_an_airfield_or_the_area_is_refused_by_plan(tmp_path, monkeypatch, capsys,
                                                              zone, needles):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    over = [f"map.no_fly_zones_km={json.dumps([zone])}", 'map.no_fly_names=["R-1"]']
    argv = ["plan", "--scenario", "small", "--overrides", *over, "--out", "plan.json", "--quiet"]
    _refused(tmp_path, capsys, argv, *needles)


@pytest.fixture
def alps(tmp_path):
    """The Alps-like area (60 x 40 km near 46.5 N 7.9 E) as GeoJSON layers, and the terrain
    test's module (its DEM writer and scenario)."""
    t = _terrain_test()
    lon0, lat0 = t.ORIGIN[1], t.ORIGIN[0]
    dlon, dlat = 60 / t.KM_PER_DEG_LON, 40 / 111.2
    ring = [[lon0, lat0], [lon0 + dlon, lat0], [lon0 + dlon, lat0 + dlat], [lon0, lat0 + dlat]]
    (tmp_path / "area.geojson").write_text(json.dumps(
        {"type": "Polygon", "coordinates": [[*ring, ring[0]]]}))  # fmt: skip
    (tmp_path / "fields.geojson").write_text(json.dumps(
        {"type": "Feature", "properties": {"name": "valley"},
         "geometry": {"type": "Point", "coordinates": [lon0 - 0.1, lat0 + 0.2]}}))  # fmt: skip
    return t


@pytest.mark.parametrize(
    ("kwargs", "needles"),
    [
        ({"crs": None}, ("terrain.dem", "coordinate reference system")),
        ({"lon": (7.6, 8.5)}, ("terrain.dem", "covering")),
    ],
    ids=["no-crs", "not-covering"],
)
def test_dem_without_crs_or_not_covering_is_refused_by_import(tmp_path, monkeypatch, capsys,
                                                              alps, kwargs, needles):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    alps._dem(tmp_path / "dem.tif", **kwargs)
    argv = ["scenario", "import", "area.geojson", "--airfields", "fields.geojson", "--dem",
            "dem.tif", "--out", "alps.yaml"]  # fmt: skip
    _refused(tmp_path, capsys, argv, *needles)


def test_dem_not_covering_is_refused_by_plan(tmp_path, monkeypatch, capsys, alps):
    """A scenario file naming a DEM that stops short of its operating area."""
    monkeypatch.chdir(tmp_path)
    dem = alps._dem(tmp_path / "dem.tif", lon=(7.6, 8.5))
    (tmp_path / "alps.yaml").write_text(yaml.safe_dump(alps._scenario(dem)))
    argv = ["plan", "--scenario", "alps.yaml", "--planner", "allocation", "--refine", "0",
            "--out", "plan.json", "--quiet"]  # fmt: skip
    _refused(tmp_path, capsys, argv, "terrain.dem", "covering")


def test_clearance_impossible_within_the_ceiling_is_refused_by_plan_and_export(
    tmp_path, monkeypatch, capsys, alps
):
    """Ridge 4,000 m + 150 m clearance over a 4,000 m ceiling: plan refuses, naming the UAV
    and uav.max_altitude_m; a plan whose recorded ceiling is lowered so is refused by every
    export format."""
    monkeypatch.chdir(tmp_path)
    dem = alps._dem(tmp_path / "dem.tif")
    (tmp_path / "alps.yaml").write_text(yaml.safe_dump(alps._scenario(dem)))
    argv = ["plan", "--scenario", "alps.yaml", "--planner", "allocation", "--refine", "0",
            "--quiet"]  # fmt: skip
    low = ["--overrides", "uav.max_altitude_m=4000"]
    _refused(tmp_path, capsys, [*argv, *low, "--out", "plan.json"], "clearance impossible",
             "uav.max_altitude_m = 4000")  # fmt: skip
    assert main([*argv, "--out", "ok/plan.json"]) == 0
    capsys.readouterr()
    plan = json.loads((tmp_path / "ok" / "plan.json").read_text())
    plan["terrain"]["ceiling_m"] = 3500.0  # below the ridge + clearance
    (tmp_path / "ok" / "plan.json").write_text(json.dumps(plan))
    for fmt in ("qgc", "kml", "geojson", "html"):
        _refused(tmp_path, capsys, ["export", "ok/plan.json", "--format", fmt, "--out", fmt],
                 "plan.uavs[", "clearance impossible")  # fmt: skip
