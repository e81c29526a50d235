"""Mission export: GeoJSON, KML and QGroundControl files parse back to the same waypoints."""

import json
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from agents.planning.export import export_plan, load_plan, parse_origin, to_geographic, to_local
from poc_env.cli import main
from poc_env.errors import ConfigError

ORIGIN = (45.75, 126.65)


def _plan(tmp_path, **changes):
    rng = np.random.default_rng(0)
    uavs = []
    for k in range(2):
        wps = rng.uniform(0, 150e3, (5, 2)).round(3).tolist()
        uavs.append({
            "id": k + 1,
            "rectangle": {"center_m": [50e3, 60e3], "length_m": 40e3, "width_m": 20e3,
                          "theta_deg": 30.0},
            "spacing_m": 5e3, "takeoff_m": [20e3, -60e3], "landing_m": [20e3, -60e3],
            "waypoints_m": wps, "track_length_m": 300e3, "flight_time_s": 9000.0,
            "pod": 0.79, "poc": 0.2, "pos": 0.158, "feasible": True,
        })  # fmt: skip
    plan = {
        "schema": 1, "scenario": "paper_6_2", "seed": 1, "map_source": "builtin",
        "optimizer": {"name": "adaptive_de", "settings": {}}, "runtime_s": 0.4,
        "posc": 0.3, "upper_bound": 0.5, "uavs": uavs,
    }  # fmt: skip
    plan.update(changes)
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    return path, plan


def _positions(coords):
    """The [lon, lat(, z)] positions of a GeoJSON coordinates array of any depth."""
    if coords and isinstance(coords[0], (int, float)):
        return [coords]
    return [p for c in coords for p in _positions(c)]


def _route(u):
    return np.array([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]])


def test_projection_round_trip_and_scale():
    xy = np.random.default_rng(1).uniform(-200e3, 200e3, (50, 2))
    back = np.array(to_local(to_geographic(xy, ORIGIN), ORIGIN))
    np.testing.assert_allclose(back, xy, atol=1e-6)
    ((lat, _),) = to_geographic([(0.0, 111_132.95)], (45.0, 0.0))  # 1 degree of latitude at 45 N
    assert lat == pytest.approx(46.0, abs=1e-3)


def test_geojson_parses_back(tmp_path):
    path, plan = _plan(tmp_path)
    (out,) = export_plan(path, "geojson", "45.75,126.65")
    data = json.loads(out.read_text())
    routes = [f for f in data["features"] if f["properties"]["kind"] == "route"]
    for f, u in zip(routes, plan["uavs"]):
        back = to_local([(lat, lon) for lon, lat, _ in f["geometry"]["coordinates"]], ORIGIN)
        np.testing.assert_allclose(back, _route(u), atol=0.15)  # rounded to 1e-6 deg


def test_kml_parses_back(tmp_path):
    path, plan = _plan(tmp_path)
    (out,) = export_plan(path, "kml", "45.75,126.65")
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    coords = [c.text for c in ET.parse(out).getroot().iterfind(".//k:coordinates", ns)]
    for text, u in zip(coords, plan["uavs"]):
        pts = [tuple(map(float, t.split(",")[:2])) for t in text.split()]
        back = to_local([(lat, lon) for lon, lat in pts], ORIGIN)
        np.testing.assert_allclose(back, _route(u), atol=1e-2)  # 8 decimals of a degree


def test_qgc_plan_parses_back(tmp_path):
    path, plan = _plan(tmp_path)
    outs = export_plan(path, "qgc", "45.75,126.65")
    assert len(outs) == 2
    for out, u in zip(outs, plan["uavs"]):
        data = json.loads(out.read_text())
        assert data["fileType"] == "Plan" and data["mission"]["version"] == 2
        items = data["mission"]["items"]
        assert [i["command"] for i in (items[0], items[-1])] == [22, 21]  # take-off ... land
        nav = [i for i in items if i["command"] in (16, 21, 22)]
        assert all(i["command"] == 16 for i in nav[1:-1])
        # the route's points, plus the approach waypoint before the landing
        back = to_local([(i["params"][4], i["params"][5]) for i in nav], ORIGIN)
        np.testing.assert_allclose(np.delete(back, -2, axis=0), _route(u), atol=1e-6)


@pytest.mark.parametrize("origin", ["91,0", "0,181", "abc", "45"])
def test_bad_origin(origin):
    with pytest.raises(ConfigError, match="origin"):
        parse_origin(origin)


def test_bad_plans(tmp_path):
    path, _ = _plan(tmp_path, schema=2)
    with pytest.raises(ConfigError, match="schema"):
        load_plan(path)
    path, plan = _plan(tmp_path)
    del plan["uavs"][1]["waypoints_m"]
    path.write_text(json.dumps(plan))
    with pytest.raises(ConfigError, match=r"uavs\[1\]\.waypoints_m"):
        load_plan(path)
    path.write_text("{not json")
    with pytest.raises(ConfigError, match="valid JSON"):
        load_plan(path)
    with pytest.raises(ConfigError, match="plan"):
        load_plan(tmp_path / "missing.json")


def test_cli_export(tmp_path, capsys):
    path, _ = _plan(tmp_path)
    assert main(["export", str(path), "--format", "kml", "--origin", "45.75,126.65"]) == 0
    assert (tmp_path / "plan.kml").is_file()
    assert main(["export", str(path), "--format", "shp", "--origin", "45,126"]) == 2
    assert "format" in capsys.readouterr().err


def _set(plan, dotted, value):
    """Set ``uavs[0].waypoints_m[0]``-style paths in a plan dict."""
    import re

    obj = plan
    parts = re.findall(r"[^.\[\]]+", dotted)
    for p in parts[:-1]:
        obj = obj[int(p)] if p.isdigit() else obj[p]
    last = parts[-1]
    obj[int(last) if last.isdigit() else last] = value


HOSTILE = [
    ("uavs.0.waypoints_m.0", [float("nan"), 0.0], r"uavs\[0\]\.waypoints_m\[0\]"),
    ("uavs.0.waypoints_m.0", [1e300, 1e300], r"uavs\[0\]\.waypoints_m\[0\]"),
    ("uavs.0.waypoints_m.0", [float("inf"), 0.0], r"uavs\[0\]\.waypoints_m\[0\]"),
    ("uavs.0.takeoff_m", [1], r"uavs\[0\]\.takeoff_m"),
    ("uavs.0.landing_m", [float("nan"), 0.0], r"uavs\[0\]\.landing_m"),
    ("uavs.0.rectangle.theta_deg", "north", r"rectangle\.theta_deg"),
    ("uavs.0.rectangle", None, r"uavs\[0\]\.rectangle"),
    ("uavs.0.pos", "high", r"uavs\[0\]\.pos"),
    ("uavs.0.pod", float("nan"), r"uavs\[0\]\.pod"),
    ("uavs.0.id", "../../../escaped", r"uavs\[0\]\.id"),
    ("uavs.0.id", "a/b", r"uavs\[0\]\.id"),
    ("uavs.1.id", 1, r"uavs\[1\]\.id"),  # the same id twice
    ("posc", float("inf"), r"plan\.posc"),
]


@pytest.mark.parametrize("fmt", ["qgc", "geojson", "kml"])
@pytest.mark.parametrize(
    "dotted,value,field", HOSTILE, ids=[h[0] + "=" + repr(h[1]) for h in HOSTILE]
)
def test_hostile_plan_fields_are_refused_before_writing(
    tmp_path, capsys, fmt, dotted, value, field
):
    """NaN or huge coordinates, malformed fields and unsafe ids end with a clear error naming
    the field, exit status 2, and no file written anywhere (not even outside --out)."""
    _, plan = _plan(tmp_path)
    _set(plan, dotted, value)
    src = tmp_path / "in" / "plan.json"
    src.parent.mkdir()
    src.write_text(json.dumps(plan))  # NaN/inf become the non-standard tokens Python reads back
    out = tmp_path / "a" / "b" / "out"
    before = sorted(p for p in tmp_path.rglob("*"))
    code = main(["export", str(src), "--format", fmt, "--origin", "45.5,126.6", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert re.search(field, err), err
    assert "Traceback" not in err
    assert sorted(p for p in tmp_path.rglob("*")) == before


def test_exports_hold_only_finite_coordinates(tmp_path):
    """A valid plan near the antimeridian exports strict JSON with longitudes in [-180, 180]."""
    path, _ = _plan(tmp_path)
    for fmt in ("geojson", "qgc"):
        for f in export_plan(path, fmt, (10.0, 179.5), tmp_path / fmt):
            text = f.read_text()
            assert "NaN" not in text and "Infinity" not in text, f.name
            data = json.loads(text)
            coords = (
                [
                    c
                    for feat in data["features"]
                    for pos in _positions(feat["geometry"]["coordinates"])
                    for c in pos[:2]  # lon, lat (z is an altitude)
                ]
                if fmt == "geojson"
                else [v for it in data["mission"]["items"] for v in it["params"][4:6]]
            )
            assert np.all(np.isfinite(coords)) and np.all(np.abs(coords) <= 180.0)
