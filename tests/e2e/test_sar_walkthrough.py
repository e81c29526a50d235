"""docs/missions.md, 'A mountain search, two sorties': the SAR walkthrough runs as written (issue
24, "Done when"). The two shell blocks are read from the page (so the page and the test cannot
drift) and run with the installed ``poc-env`` in a temporary folder, on a synthetic DEM with a
4,000 m ridge; then what a planning officer checks before launch is checked."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from poc_env.agents.mission.terrain import qgc_clearance

pytest.importorskip("rasterio")
shapely_geometry = pytest.importorskip("shapely.geometry")

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "missions.md"
SECTION = "## A mountain search, two sorties (the SAR walkthrough)"


def _terrain_test():
    """tests/mission/test_terrain.py as a module: its synthetic DEM and its QGC clearance check
    (one copy of each)."""
    path = ROOT / "tests" / "mission" / "test_terrain.py"
    spec = importlib.util.spec_from_file_location("_terrain_test", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _blocks() -> tuple[str, str]:
    text = PAGE.read_text(encoding="utf-8")
    section = text[text.index(SECTION) :]
    section = section[: section.index("\n## ", 1)]
    setup = re.search(r"```\n(cat > area\.geojson.*?)```", section, flags=re.S)
    flight = re.search(r"```\n(poc-env scenario import.*?)```", section, flags=re.S)
    assert setup and flight, "the walkthrough's two shell blocks"
    return setup.group(1), flight.group(1)


def _run(block: str, cwd: Path) -> str:
    exe = shutil.which("poc-env", path=str(Path(sys.executable).parent))
    assert exe is not None
    env = dict(os.environ, PATH=f"{Path(exe).parent}{os.pathsep}{os.environ['PATH']}")
    done = subprocess.run(
        ["bash", "-e", "-c", block], cwd=cwd, env=env, capture_output=True, text=True,
        timeout=600, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def test_the_walkthrough_lists_every_step():
    setup, flight = _blocks()
    for name in ("area.geojson", "airfield.geojson", "zone.geojson", "prior.csv"):
        assert f"cat > {name}" in setup
    steps = (
        "scenario import",
        "--dem dem.tif",
        "--no-fly zone.geojson",
        "--planner allocation",
        "--effort standard",
        "--format qgc",
        "--format kml",
        "--format geojson",
        "--format html",
        "replan",
    )
    for step in steps:
        assert step in flight, step


def test_sar_walkthrough_runs_as_written(tmp_path, figures_in):
    from poc_env.agents.mission.formats.kml import validate_kml
    from poc_env.agents.mission.formats.qgc import validate_qgc

    terrain = _terrain_test()
    setup, flight = _blocks()
    _run(setup, tmp_path)
    dem = terrain._dem(tmp_path / "dem.tif")
    out = _run(flight, tmp_path)
    assert "sortie 2" in out
    # the printed lines the page shows under the commands (its "..." elide the rest) are what
    # the commands print: its figures stay the commands' (docs-audit)
    text = PAGE.read_text(encoding="utf-8")
    shown = re.search(r"```\n(area \d+ km\^2.*?)```", text[text.index(SECTION) :], flags=re.S)
    assert shown, "the walkthrough's printed lines"
    for line in shown.group(1).splitlines():
        wrong = figures_in(line.split("...")[0], out)
        assert wrong is None, wrong

    # the zone as the officer drew it (lon/lat), and every route of both sorties around it
    zone_doc = json.loads((tmp_path / "zone.geojson").read_text())
    zone_name = zone_doc["features"][0]["properties"]["name"]
    zone = shapely_geometry.shape(zone_doc["features"][0]["geometry"])
    gj = json.loads((tmp_path / "sortie1" / "p1.geojson").read_text())
    routes = [f for f in gj["features"] if f["properties"].get("kind") == "route"]
    assert len(routes) == 3
    lines = [shapely_geometry.shape(f["geometry"]) for f in routes]
    for f, line in zip(routes, lines):
        assert not line.intersects(zone), f["properties"]["id"]
    # not vacuous: the zone lies on the straight way from the airfield to the likeliest position
    field = json.loads((tmp_path / "airfield.geojson").read_text())["features"][0]["geometry"]
    rows = (tmp_path / "prior.csv").read_text().split()[1:]
    lat, lon, _ = max((tuple(map(float, r.split(","))) for r in rows), key=lambda r: r[2])
    way = shapely_geometry.LineString([field["coordinates"], (lon, lat)])
    assert way.intersects(zone)
    assert any(zone_name in str(f["properties"].get("name")) for f in gj["features"])

    # QGC: valid, AMSL, clear of the DEM itself along every leg (both sorties)
    for folder, stem in (("sortie1", "p1"), ("sortie2", "p2")):
        files = sorted((tmp_path / folder).glob(f"{stem}_uav*.plan"))
        assert len(files) == 3
        for f in files:
            doc = json.loads(f.read_text())
            assert validate_qgc(doc) == []
            least, legs = qgc_clearance(doc, dem)  # the campaign's check too
            assert legs > 0 and least >= 150.0 - 1e-6, (f.name, least)
            nav = [it for it in doc["mission"]["items"] if it["command"] == 16]
            line = shapely_geometry.LineString([(it["params"][5], it["params"][4]) for it in nav])
            assert not line.intersects(zone), f.name

    # KML valid by the OGC XSD; the report written, naming the zone
    assert validate_kml(tmp_path / "sortie1" / "p1.kml") == []
    html = (tmp_path / "sortie1" / "p1.html").read_text(encoding="utf-8")
    assert html.lstrip().lower().startswith("<!doctype html") and zone_name in html

    # sortie 2 starts where sortie 1 left the belief, and adds to it
    p1 = json.loads((tmp_path / "p1.json").read_text())
    p2 = json.loads((tmp_path / "p2.json").read_text())
    # both sorties polished round the zone at --effort standard, as the page says (a polish
    # skipped would give the default plan: i24-walkstandard)
    for plan in (p1, p2):
        polish = plan["optimizer"]["settings"]["polish"]
        assert polish["moves"] > 0 and "skipped" not in polish, polish
    assert p2["sortie"] == 2
    assert p2["searched_pos"] == pytest.approx(p1["posc"], abs=1e-9)
    assert p1["posc"] < p2["cumulative_posc"] <= 1.0
    assert p2["crs"] == p1["crs"]
