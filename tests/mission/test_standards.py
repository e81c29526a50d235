"""Issue 27: every export is valid by its standard's own validator.

- KML: lxml against the OGC KML 2.2 XSD (``ogckml22.xsd`` with its Atom and xAL imports,
  vendored in ``agents/mission/assets/kml22``; :func:`~poc_env.agents.mission.formats.kml.
  validate_kml`).
- GeoJSON: RFC 7946 polygons: exterior rings closed and counter-clockwise.
- QGroundControl ``.plan``: the JSON Schema ``agents/mission/assets/qgc_plan.schema.json``
  written from QGC's documented plan format (:func:`~poc_env.agents.mission.formats.qgc.
  validate_qgc`).
- HTML: parsed by :mod:`html.parser` (the campaign checks its injected strings are escaped).

over plans of every planner: the paper's DE plan, the allocation planner and the survey.
"""

from __future__ import annotations

import json

import pytest

from poc_env.agents.mission.formats.geojson import ring_area
from poc_env.agents.mission.formats.kml import validate_kml
from poc_env.agents.mission.formats.qgc import validate_qgc
from poc_env.cli import main

PLANNERS = {
    "de": ["plan", "--scenario", "small", "--popsize", "8", "--maxiter", "3", "--quiet",
           "--origin", "45.75,126.65"],
    "allocation": ["plan", "--scenario", "small", "--planner", "allocation", "--quiet",
                   "--origin", "30.5,114.3"],
    "survey": ["survey", "--scenario", "paper_6_1", "--regions", "paper_6_1_polygons",
               "--origin", "30.5,114.3"],
}  # fmt: skip


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    out = {}
    for name, argv in PLANNERS.items():
        path = tmp_path_factory.mktemp(name) / f"{name}.json"
        flag = "--plan-out" if argv[0] == "survey" else "--out"
        assert main([*argv, flag, str(path)]) == 0
        out[name] = path
    return out


def _export(path, fmt, out, *extra):
    assert main(["export", str(path), "--format", fmt, "--out", str(out), *extra]) == 0
    return sorted(out.iterdir())


@pytest.mark.parametrize("planner", list(PLANNERS))
def test_kml_is_valid_by_the_ogc_kml_22_schema(plans, planner, tmp_path):
    files = [f for f in _export(plans[planner], "kml", tmp_path) if f.suffix == ".kml"]
    assert files
    for f in files:
        assert validate_kml(f) == []


@pytest.mark.parametrize("planner", list(PLANNERS))
def test_geojson_exterior_rings_are_closed_and_counter_clockwise(plans, planner, tmp_path):
    (f,) = _export(plans[planner], "geojson", tmp_path)
    polys = [x for x in json.loads(f.read_text())["features"] if x["geometry"]["type"] == "Polygon"]
    assert polys
    for feat in polys:
        ring = feat["geometry"]["coordinates"][0]
        assert ring[0] == ring[-1] and len(ring) >= 4
        assert ring_area(ring) > 0, feat["properties"]


@pytest.mark.parametrize("planner", list(PLANNERS))
def test_qgc_plans_are_valid_by_the_schema_from_qgcs_documented_format(plans, planner, tmp_path):
    files = _export(plans[planner], "qgc", tmp_path, "--no-geofence")
    assert files
    for f in files:
        assert validate_qgc(json.loads(f.read_text())) == []


def test_the_validators_reject_what_they_should():
    """Each validator fails the defects issue 27 found (or could find)."""
    ns = 'xmlns="http://www.opengis.net/kml/2.2"'
    # a Style after a Feature, and description after styleUrl: schema order
    bad = (
        f"<kml {ns}><Document><name>x</name><Folder><name>f</name></Folder>"
        '<Style id="s"/></Document></kml>'
    )
    assert any("Style" in e for e in validate_kml(bad))
    bad = (
        f"<kml {ns}><Document><Placemark><name>a</name><styleUrl>#s</styleUrl>"
        "<description>d</description></Placemark></Document></kml>"
    )
    assert any("description" in e for e in validate_kml(bad))
    assert validate_kml(f"<kml {ns}><Document><name>a\x01</name></Document></kml>")
    good = {
        "fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
        "mission": {"version": 2, "firmwareType": 12, "vehicleType": 1, "cruiseSpeed": 60.0,
                    "hoverSpeed": 5, "plannedHomePosition": [45.0, 126.0, 0.0],
                    "items": [{"type": "SimpleItem", "command": 22, "frame": 3,
                               "params": [15, 0, 0, None, 45.0, 126.0, 100.0],
                               "autoContinue": True, "doJumpId": 1, "Altitude": 100.0,
                               "AltitudeMode": 1, "AMSLAltAboveTerrain": None}]},
        "geoFence": {"version": 2, "circles": [], "polygons": []},
        "rallyPoints": {"version": 2, "points": []},
    }  # fmt: skip
    assert validate_qgc(good) == []
    for path, value in (
        (("fileType",), "plan"),
        (("mission", "items", 0, "frame"), 1),
        (("mission", "items", 0, "params", 4), 95.0),
        (("mission", "items", 0, "doJumpId"), 2),
        (("mission", "plannedHomePosition"), [45.0, 126.0]),
    ):
        doc = json.loads(json.dumps(good))
        node = doc
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
        assert validate_qgc(doc), path
