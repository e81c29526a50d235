"""Mission export: GeoJSON, KML and QGroundControl files parse back to the same waypoints."""

import json
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
        back = to_local([(lat, lon) for lon, lat in f["geometry"]["coordinates"]], ORIGIN)
        np.testing.assert_allclose(back, _route(u), atol=1e-6)


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
        assert all(i["command"] == 16 for i in items[1:-1])
        back = to_local([(i["params"][4], i["params"][5]) for i in items], ORIGIN)
        np.testing.assert_allclose(back, _route(u), atol=1e-6)


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
