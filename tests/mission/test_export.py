"""Mission export: GeoJSON, KML and QGroundControl files parse back to the same waypoints."""

import itertools
import json
import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from pyproj import Geod, Transformer
from shapely.geometry import LineString, Point

from poc_env.agents.mission.crs import make_crs, parse_origin, to_geographic, to_local
from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.plan import load_plan
from poc_env.cli import main
from poc_env.config import load_scenario
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


def test_hostile_plan_json_is_a_config_error_naming_the_plan(tmp_path):
    """Issue 27: plan.json goes through the one JSON reader (poc_env.io.read_json): nested
    10,000 deep it was a RecursionError; NaN, which Python's parser accepts, is refused as not
    JSON even where the plan check would never look (an extra field)."""
    deep = tmp_path / "deep.json"
    deep.write_text('{"schema": 1, "uavs": ' + "[" * 10_000 + "]" * 10_000 + "}")
    with pytest.raises(ConfigError, match=r"^plan: .*nested at most") as err:
        load_plan(deep)
    assert err.value.field == "plan"
    path, _ = _plan(tmp_path, note=float("nan"))
    assert "NaN" in path.read_text()
    with pytest.raises(ConfigError, match=r"^plan: .*valid JSON.*NaN") as err:
        load_plan(path)
    assert err.value.field == "plan"


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
    out, png = export_plan(path, "kml", "45.75,126.65")  # the route file and the prior's image
    assert (out.name, png.name) == ("plan.kml", "plan_prior.png")
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    routes = ET.parse(out).getroot().findall(".//k:Placemark[k:styleUrl='#route']", ns)
    assert len(routes) == len(plan["uavs"])
    coords = [r.find(".//k:coordinates", ns).text for r in routes]
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
    path, _ = _plan(tmp_path, schema=3)
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


# --------------------------------------------------------------------------- projections (pyproj)

GEOD = Geod(ellps="WGS84")
#: paper_6_2: x in [0, 200] km, y in [-60, 150] km (airfields at y = -60 km), grown by the
#: 20 km boundary margin of eq. 20.
PAPER_6_2_EXTENT = ((-20e3, -80e3), (220e3, 170e3))


def _crs(kind):
    return ORIGIN if kind == "aeqd-origin" else make_crs(kind, ORIGIN)


def _geodesic(p, q, crs):
    (lat1, lon1), (lat2, lon2) = to_geographic([p, q], crs)
    return GEOD.inv(lon1, lat1, lon2, lat2)[2]


@pytest.mark.parametrize("kind", ["aeqd-origin", "aeqd", "utm"])
def test_round_trip_to_millimetres_over_300_km(kind):
    crs = _crs(kind)
    xy = np.random.default_rng(1).uniform(-300e3, 300e3, (500, 2))
    back = np.array(to_local(to_geographic(xy, crs), crs))
    np.testing.assert_allclose(back, xy, rtol=0, atol=1e-3)
    ((lat, _),) = to_geographic([(0.0, 111_132.95)], make_crs("aeqd", (45.0, 0.0)))
    assert lat == pytest.approx(46.0, abs=1e-3)  # 1 degree of latitude at 45 N


@pytest.mark.parametrize("kind", ["aeqd", "utm"])
def test_distances_match_the_ellipsoid_over_the_paper_6_2_extent(kind):
    """Local distances within 0.1 % of geodesic ones (measured: aeqd 0.024 %, utm 0.040 %)."""
    crs = _crs(kind)
    rng = np.random.default_rng(2)
    lo, hi = PAPER_6_2_EXTENT
    a, b = rng.uniform(lo, hi, (2, 400, 2))
    la, lb = np.array(to_geographic(a, crs)), np.array(to_geographic(b, crs))
    geo = GEOD.inv(la[:, 1], la[:, 0], lb[:, 1], lb[:, 0])[2]
    loc = np.hypot(*(a - b).T)
    keep = loc > 1e3
    assert np.max(np.abs(loc[keep] / geo[keep] - 1)) < 1e-3


def _old_tangent_plane(x, y, origin):
    """The hand-written projection this module used before (kept to show what the test catches)."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    lat0, lon0 = origin
    s = math.sin(math.radians(lat0))
    w = math.sqrt(1 - e2 * s * s)
    m, n = a * (1 - e2) / w**3, a / w
    return lat0 + math.degrees(y / m), lon0 + math.degrees(x / (n * math.cos(math.radians(lat0))))


@pytest.mark.parametrize("kind", ["aeqd", "utm"])
def test_the_issue_case_200_km_east_west_at_y_150_km(kind):
    """Issue 14: the old tangent plane put this line 2.4 % short; pyproj is within 0.1 %."""
    p, q = (0.0, 150e3), (200e3, 150e3)
    assert abs(_geodesic(p, q, _crs(kind)) / 200e3 - 1) < 1e-3
    (lat1, lon1), (lat2, lon2) = (_old_tangent_plane(*p, ORIGIN), _old_tangent_plane(*q, ORIGIN))
    old = GEOD.inv(lon1, lat1, lon2, lat2)[2]
    assert 1 - old / 200e3 > 0.02  # the error the new projection removes


@pytest.mark.parametrize("kind", ["aeqd", "utm"])
def test_an_airfield_projected_with_pyproj_comes_back_in_the_mission(tmp_path, kind):
    """A field given in lat/lon, projected into the scenario by pyproj itself, is where the .plan
    puts the take-off and landing (< 1 m)."""
    crs = make_crs(kind, ORIGIN)
    field = (45.213, 126.917)  # lat, lon
    fwd = Transformer.from_crs("EPSG:4326", crs["proj"], always_xy=True)
    x0, y0 = fwd.transform(ORIGIN[1], ORIGIN[0])
    x, y = fwd.transform(field[1], field[0])
    path, plan = _plan(tmp_path, crs=crs)
    for u in plan["uavs"]:
        u["takeoff_m"] = u["landing_m"] = [x - x0, y - y0]
    path.write_text(json.dumps(plan))
    for out in export_plan(path, "qgc", None, tmp_path / "out"):
        items = json.loads(out.read_text())["mission"]["items"]
        for it in (items[0], items[-1]):
            lat, lon = it["params"][4:6]
            assert GEOD.inv(lon, lat, field[1], field[0])[2] < 1.0


def test_utm_zone_from_the_origin_or_given():
    north = make_crs("utm", ORIGIN)
    assert north["epsg"] == 32652 and "+zone=52" in north["proj"] and "+south" not in north["proj"]
    south = make_crs("utm", (-34.9, 138.6))
    assert south["epsg"] == 32754 and "+south" in south["proj"]
    given = make_crs("utm", ORIGIN, zone=51)
    assert given["epsg"] == 32651
    # UTM metres shifted to the origin: (0, 0) is the origin, north is +y
    (lat, lon), (lat2, _) = to_geographic([(0.0, 0.0), (0.0, 10e3)], north)
    assert (lat, lon) == pytest.approx(ORIGIN, abs=1e-9) and lat2 > lat
    with pytest.raises(ConfigError, match=r"crs\.zone"):
        make_crs("utm", ORIGIN, zone=61)
    assert make_crs("aeqd", np.array(ORIGIN)) == make_crs("aeqd", ORIGIN)  # numpy floats too
    for bad in ("north", (1.0,), (95.0, 0.0)):
        with pytest.raises(ConfigError, match="origin"):
            make_crs("aeqd", bad)


# --------------------------------------------------------------------------- crs in plan.json


def test_plan_crs_is_used_and_origin_must_agree(tmp_path):
    crs = make_crs("aeqd", ORIGIN)
    path, _ = _plan(tmp_path, crs=crs)
    assert load_plan(path)["crs"] == crs
    (a,) = export_plan(path, "geojson", None, tmp_path / "a")  # no --origin needed
    (b,) = export_plan(path, "geojson", "45.75,126.65", tmp_path / "b")  # the same origin
    assert a.read_text() == b.read_text()
    with pytest.raises(ConfigError, match=r"origin: .*crs\.origin_deg"):
        export_plan(path, "geojson", "45.7,126.65", tmp_path / "c")
    (tmp_path / "bare").mkdir()
    bare, _ = _plan(tmp_path / "bare")
    with pytest.raises(ConfigError, match=r"origin: got None; allowed: .*no crs"):
        export_plan(bare, "kml")


def test_utm_plan_exports_in_utm(tmp_path):
    crs = make_crs("utm", ORIGIN)
    path, plan = _plan(tmp_path, crs=crs)
    (out,) = export_plan(path, "qgc", None, tmp_path / "o")[:1]
    items = json.loads(out.read_text())["mission"]["items"]
    lat, lon = items[0]["params"][4:6]
    np.testing.assert_allclose(
        to_local([(lat, lon)], crs), [plan["uavs"][0]["takeoff_m"]], atol=1e-6
    )
    # the same plan without crs, exported with --origin and projection utm, gives the same files
    bare = tmp_path / "bare"
    bare.mkdir()
    p2, _ = _plan(bare)
    (out2,) = export_plan(p2, "qgc", ORIGIN, bare / "o", projection="utm")[:1]
    assert json.loads(out2.read_text()) == json.loads(out.read_text())


BAD_CRS = [
    ({"kind": "lambert", "origin_deg": [45.75, 126.65], "proj": "+proj=lcc"}, r"plan\.crs\.kind"),
    ({"kind": "aeqd", "origin_deg": [45.75, 126.65], "proj": "+proj=nonsense"}, r"plan\.crs\.proj"),
    ({"kind": "epsg", "origin_deg": [45.75, 126.65], "epsg": 4326}, r"plan\.crs\.epsg.*projected"),
    ({"kind": "aeqd", "origin_deg": [95.0, 126.65], "proj": "+proj=aeqd"}, r"plan\.crs\.origin"),
    ({"kind": "aeqd", "origin_deg": [45.0, 126.0], "proj": "+proj=utm +zone=52"}, r"crs\.proj"),
    ({"kind": "aeqd", "origin_deg": [45.0, 126.0], "proj": "+proj=aeqd", "x": 1}, r"plan\.crs\.x"),
    ("EPSG:32652", r"plan\.crs"),
]


@pytest.mark.parametrize("crs,field", BAD_CRS, ids=[str(i) for i in range(len(BAD_CRS))])
def test_bad_crs_is_a_config_error_naming_the_field(tmp_path, crs, field):
    path, _ = _plan(tmp_path, crs=crs)
    with pytest.raises(ConfigError, match=field):
        load_plan(path)


def test_epsg_crs_and_schema_1_plans_without_crs_still_load(tmp_path):
    path, _ = _plan(tmp_path, crs={"kind": "epsg", "origin_deg": list(ORIGIN), "epsg": 32652})
    plan = load_plan(path)
    out, _ = export_plan(path, "kml", None, tmp_path / "o")
    assert out.is_file() and plan["crs"]["epsg"] == 32652
    path, plan = _plan(tmp_path)
    assert "crs" not in load_plan(path)  # a schema-1 plan of before: read with --origin


# --------------------------------------------------------------------------- flyable QGC missions

V_B, V_S = 220 / 3.6, 180 / 3.6


def _geo_plan(tmp_path, **changes):
    area = [[-20e3, -80e3], [220e3, -80e3], [220e3, 170e3], [-20e3, 170e3]]  # counter-clockwise
    zone = [[80e3, 80e3], [90e3, 80e3], [90e3, 95e3]]
    return _plan(
        tmp_path,
        crs=make_crs("aeqd", ORIGIN),
        flight={"cruise_speed_mps": V_B, "search_speed_mps": V_S, "altitude_m": 1200.0,
                "max_altitude_m": 4000.0},
        operating_area_m=area,
        no_fly_zones_m=[zone],
        airfields=[{"name": "A", "position_m": [20e3, -60e3]}],
        **changes,
    )  # fmt: skip


def test_qgc_mission_is_flyable(tmp_path):
    path, plan = _geo_plan(tmp_path)
    out = export_plan(path, "qgc", None, tmp_path / "o")[0]
    doc = json.loads(out.read_text())
    u = plan["uavs"][0]
    assert doc["fileType"] == "Plan" and doc["version"] == 1
    assert doc["groundStation"] == "QGroundControl"
    m = doc["mission"]
    assert (m["version"], m["firmwareType"], m["vehicleType"]) == (2, 12, 1)  # PX4 fixed wing
    assert m["globalPlanAltitudeMode"] == 1 and m["cruiseSpeed"] == pytest.approx(V_B)
    items = m["items"]
    assert [i["doJumpId"] for i in items] == list(range(1, len(items) + 1))
    n = len(u["waypoints_m"])
    assert [i["command"] for i in items] == [
        22, 178, 16, 178, *[16] * (n - 1), 178, 189, 16, 21,
    ]  # fmt: skip
    speeds = [i["params"][1] for i in items if i["command"] == 178]
    assert speeds == pytest.approx([V_B, V_S, V_B], abs=1e-3)  # transit, search, transit
    for i in items:
        assert set(i) >= {"type", "command", "frame", "params", "autoContinue", "doJumpId"}
        assert i["type"] == "SimpleItem" and len(i["params"]) == 7
        if i["command"] in (178, 189):
            assert i["frame"] == 2  # MAV_FRAME_MISSION
        else:
            assert i["frame"] == 3 and i["AltitudeMode"] == 1  # MAV_FRAME_GLOBAL_RELATIVE_ALT
            assert i["params"][6] == i["Altitude"]
    assert items[1]["params"][0] == 0 and items[1]["params"][2] == -1  # airspeed, throttle kept
    # cruise altitude from the plan's flight section; the landing at the field, 0 m above home
    assert {i["Altitude"] for i in items if i["command"] == 16} - {1200.0} == {300.0}
    approach, land = items[-2], items[-1]
    assert land["Altitude"] == 0.0 and approach["Altitude"] == 300.0
    a_xy, l_xy = to_local([approach["params"][4:6], land["params"][4:6]], ORIGIN)
    np.testing.assert_allclose(l_xy, u["landing_m"], atol=1e-6)
    assert math.dist(a_xy, l_xy) == pytest.approx(4000.0, abs=1e-3)
    # the approach comes from the last search point's side
    last = np.asarray(u["waypoints_m"][-1]) - u["landing_m"]
    assert np.dot(np.subtract(a_xy, l_xy), last) > 0


def test_qgc_geofence_and_rally_points(tmp_path):
    path, plan = _geo_plan(tmp_path)
    doc = json.loads(export_plan(path, "qgc", None, tmp_path / "o")[0].read_text())
    fence = doc["geoFence"]
    assert fence["version"] == 2 and fence["circles"] == []
    inc, exc = fence["polygons"]
    assert inc["inclusion"] is True and exc["inclusion"] is False
    assert inc["version"] == exc["version"] == 1
    for poly, ring in ((inc, plan["operating_area_m"]), (exc, plan["no_fly_zones_m"][0])):
        xy = np.array(to_local(poly["polygon"], ORIGIN))
        area2 = np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1])
        assert area2 < 0  # clockwise, as QGC's plan format asks
        # the ring's vertices, and points on its long edges (densified as QGC joins lat/lon)
        assert set(map(tuple, np.round(ring, 3))) <= set(map(tuple, xy.round(3)))
        edge = LineString([*ring, ring[0]])
        assert max(edge.distance(Point(p)) for p in xy) < 1e-3
    rally = doc["rallyPoints"]
    assert rally["version"] == 2
    ((lat, lon, alt),) = rally["points"]  # take-off and landing at the same field
    np.testing.assert_allclose(to_local([(lat, lon)], ORIGIN), [[20e3, -60e3]], atol=1e-6)
    assert alt == 300.0
    # without an operating area in the plan the inclusion fence is left empty
    bare = tmp_path / "bare"
    bare.mkdir()
    p2, _ = _plan(bare)
    doc = json.loads(export_plan(p2, "qgc", ORIGIN)[0].read_text())
    assert doc["geoFence"]["polygons"] == []


@pytest.mark.parametrize("ref,frame,mode,kml_mode", [("home", 3, 1, "relativeToGround"),
                                                     ("amsl", 0, 2, "absolute")])  # fmt: skip
def test_altitude_reference_is_the_same_in_every_format(tmp_path, ref, frame, mode, kml_mode):
    path, plan = _geo_plan(tmp_path)
    kw = {"altitude_m": 1500.0, "altitude_ref": ref, "field_elevation_m": 150.0}
    qgc = json.loads(export_plan(path, "qgc", None, tmp_path / "q", **kw)[0].read_text())
    (gj,) = export_plan(path, "geojson", None, tmp_path / "g", **kw)
    (km,) = export_plan(path, "kml", None, tmp_path / "k", **kw)
    ground = 0.0 if ref == "home" else 150.0
    items = qgc["mission"]["items"]
    assert qgc["mission"]["globalPlanAltitudeMode"] == mode
    assert qgc["mission"]["plannedHomePosition"][2] == 150.0  # AMSL in both references
    nav = [i for i in items if i["command"] in (16, 21, 22)]
    assert all(i["frame"] == frame and i["AltitudeMode"] == mode for i in nav)
    search = [i["Altitude"] for i in nav[1:-2]]
    assert search == [1500.0] * len(plan["uavs"][0]["waypoints_m"])
    assert nav[-1]["Altitude"] == ground and nav[-2]["Altitude"] == ground + 300.0
    route = json.loads(gj.read_text())["features"][0]
    zs = [c[2] for c in route["geometry"]["coordinates"]]
    assert zs == [ground, *search, ground]
    assert route["properties"]["altitude_ref"] == ref
    root = ET.parse(km).getroot()
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    assert {e.text for e in root.iterfind(".//k:altitudeMode", ns)} == {kml_mode}
    text = root.find(".//k:coordinates", ns).text
    assert [float(t.split(",")[2]) for t in text.split()] == zs


@pytest.mark.parametrize(
    "kw,field",
    [
        ({"altitude_m": 0.0}, "altitude_m"),
        ({"altitude_m": -5.0}, "altitude_m"),
        ({"altitude_m": 4500.0}, "altitude_m: .*ceiling 4000"),
        ({"altitude_m": 100.0, "altitude_ref": "amsl", "field_elevation_m": 150.0}, "altitude_m"),
        ({"altitude_ref": "agl"}, "altitude_ref"),
        ({"projection": "mercator"}, "projection"),
    ],
)
def test_bad_altitudes_are_refused_before_writing(tmp_path, kw, field):
    path, _ = _geo_plan(tmp_path)
    with pytest.raises(ConfigError, match=field):
        export_plan(path, "qgc", None, tmp_path / "o", **kw)
    assert not (tmp_path / "o").exists()


def test_geojson_rounded_with_human_units(tmp_path):
    path, plan = _geo_plan(tmp_path)
    (out,) = export_plan(path, "geojson", None, tmp_path / "o")
    text = out.read_text()
    data = json.loads(text)
    for feat in data["features"]:
        for pos in _positions(feat["geometry"]["coordinates"]):
            assert all(round(c, 6) == c for c in pos[:2])
    assert not re.search(r"\d\.\d{7,}", text)  # no 17-digit floats anywhere
    route = data["features"][0]["properties"]
    u = plan["uavs"][0]
    assert route["pos_pct"] == 15.8 and route["pod_pct"] == 79.0 and route["poc_pct"] == 20.0
    assert route["track_km"] == 300.0 and route["flight_time_min"] == 150.0
    assert route["spacing_km"] == u["spacing_m"] / 1e3
    assert route["cruise_speed_kmh"] == 220.0 and route["search_speed_kmh"] == 180.0
    assert data["properties"]["posc_pct"] == 30.0


def test_make_plan_records_crs_and_geography_that_export_uses(tmp_path):
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.planning.planner import make_plan

    plan = make_plan("small", popsize=8, maxiter=2, origin_deg=ORIGIN, projection="utm")
    assert plan["crs"] == make_crs("utm", ORIGIN)
    assert {"flight", "operating_area_m", "no_fly_zones_m", "airfields"} <= set(plan)
    path = write_plan(plan, tmp_path / "plan.json")
    assert load_plan(path)["crs"]["kind"] == "utm"
    outs = export_plan(path, "qgc", None, tmp_path / "o")  # the crs replaces --origin
    doc = json.loads(outs[0].read_text())
    assert doc["geoFence"]["polygons"][0]["inclusion"] is True
    speeds = [i["params"][1] for i in doc["mission"]["items"] if i["command"] == 178]
    fl = plan["flight"]
    assert speeds[:2] == pytest.approx([fl["cruise_speed_mps"], fl["search_speed_mps"]], abs=1e-3)
    assert "crs" not in make_plan("small", popsize=8, maxiter=2)


def test_geojson_and_kml_draw_the_area_zones_airfields_and_the_flown_approach(tmp_path):
    path, _ = _geo_plan(tmp_path)
    (gj,) = export_plan(path, "geojson", None, tmp_path / "g")
    (km,) = export_plan(path, "kml", None, tmp_path / "k")
    qgc = json.loads(export_plan(path, "qgc", None, tmp_path / "q")[0].read_text())
    feats = json.loads(gj.read_text())["features"]
    kinds = [f["properties"]["kind"] for f in feats]
    assert kinds.count("landing_approach") == 2 and kinds.count("no_fly_zone") == 1
    assert kinds.count("operating_area") == 1
    (field,) = [f for f in feats if f["properties"]["kind"] == "airfield"]
    assert field["properties"]["name"] == "A" and field["geometry"]["type"] == "Point"
    np.testing.assert_allclose(
        to_local([field["geometry"]["coordinates"][1::-1]], ORIGIN), [[20e3, -60e3]], atol=0.15
    )
    # the approach drawn is the one the mission flies (same place, same altitude)
    app = next(f for f in feats if f["properties"]["kind"] == "landing_approach")
    item = qgc["mission"]["items"][-2]
    lon, lat, z = app["geometry"]["coordinates"][0]
    assert (lat, lon) == pytest.approx(tuple(item["params"][4:6]), abs=1e-6)
    assert z == item["Altitude"]
    for f in feats:  # RFC 7946: exterior rings counter-clockwise
        if f["geometry"]["type"] == "Polygon":
            xy = np.array(to_local([(b, a) for a, b in f["geometry"]["coordinates"][0]], ORIGIN))
            assert np.sum(xy[:-1, 0] * xy[1:, 1] - xy[1:, 0] * xy[:-1, 1]) > 0
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    root = ET.parse(km).getroot()
    folders = [f.find("k:name", ns).text for f in root.iterfind(".//k:Folder", ns)]
    assert folders == ["UAV 1", "UAV 2", "Area, airfields, no-fly zones"]
    styles = {s.get("id") for s in root.iterfind(".//k:Style", ns)}
    used = {e.text[1:] for e in root.iterfind(".//k:styleUrl", ns)}
    assert used <= styles and {"route", "no_fly_zone", "airfield", "operating_area"} <= used


def test_a_mission_that_would_breach_its_own_geofence_is_refused(tmp_path):
    path, plan = _geo_plan(tmp_path)
    plan["uavs"][1]["waypoints_m"][2] = [235e3, 100e3]  # 15 km east of the operating area
    path.write_text(json.dumps(plan))
    with pytest.raises(ConfigError, match=r"uavs\[1\]\.waypoints_m\[2\].*15\.0 km outside"):
        export_plan(path, "qgc", None, tmp_path / "o")
    assert not (tmp_path / "o").exists()
    outs = export_plan(path, "qgc", None, tmp_path / "o", geofence=False)
    fence = json.loads(outs[1].read_text())["geoFence"]["polygons"]
    assert [p["inclusion"] for p in fence] == [False]  # the no-fly zone stays
    _, plan = _geo_plan(tmp_path)
    plan["uavs"][0]["waypoints_m"][:2] = [[70e3, 85e3], [100e3, 88e3]]  # across the zone
    path.write_text(json.dumps(plan))
    with pytest.raises(ConfigError, match=r"uavs\[0\].*no-fly zone 0"):
        export_plan(path, "qgc", None, tmp_path / "p", geofence=False)


def test_kml_draws_the_prior_as_a_ground_overlay(tmp_path, capsys):
    """The prior as a GroundOverlay: a PNG beside the KML (written as a set by the CLI), on a
    LatLonBox enclosing the grid, each cell centre's pixel coloured by that cell (rows evenly
    spaced in latitude, as Google Earth stretches it)."""
    from PIL import Image

    from poc_env.agents.mission.overlay import colorize, plan_prior
    from poc_env.theory.probability_map import Grid

    path, _ = _plan(tmp_path)
    out = tmp_path / "out"
    assert main(["export", str(path), "--format", "kml", "--origin", "45.75,126.65", "--out",
                 str(out)]) == 0  # fmt: skip
    assert sorted(p.name for p in out.iterdir()) == ["plan.kml", "plan_prior.png"]
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    root = ET.parse(out / "plan.kml").getroot()
    (go,) = root.findall(".//k:GroundOverlay", ns)
    assert go.find("k:Icon/k:href", ns).text == "plan_prior.png"
    box = {k: float(go.find(f"k:LatLonBox/k:{k}", ns).text) for k in ("north", "south", "east",
                                                                       "west")}  # fmt: skip
    ov, _ = plan_prior(load_plan(path), path)
    grid = ov.grid
    assert isinstance(grid, Grid) and grid.shape == ov.values.shape
    corners = np.array(to_geographic([grid.bounds[:2], grid.bounds[2:]], ORIGIN))
    eps = 1e-7  # the box is written with 8 decimals
    assert box["south"] - eps <= corners[:, 0].min() and corners[:, 0].max() <= box["north"] + eps
    assert box["west"] - eps <= corners[:, 1].min() and corners[:, 1].max() <= box["east"] + eps
    img = np.asarray(Image.open(out / "plan_prior.png").convert("RGBA"))
    h, w = img.shape[:2]
    rng = np.random.default_rng(5)
    cells = rng.integers(0, [grid.ny, grid.nx], (40, 2))
    centres = grid.centers[cells[:, 0], cells[:, 1]]
    peak = ov.values.max()
    for (lat, lon), (j, i) in zip(to_geographic(centres, ORIGIN), cells):
        r = int((box["north"] - lat) / (box["north"] - box["south"]) * h)
        c = int((lon - box["west"]) / (box["east"] - box["west"]) * w)
        np.testing.assert_array_equal(img[r, c], colorize(ov.values[j, i] / peak))
    # a plan whose scenario cannot be rebuilt as planned: no overlay, and the KML says why
    moved, _ = _plan(tmp_path, airfields=[{"name": "X", "position_m": [1.0, 2.0]}])
    outs = export_plan(moved, "kml", "45.75,126.65")
    assert [p.name for p in outs] == ["plan.kml"]
    root = ET.parse(outs[0]).getroot()
    assert root.find(".//k:GroundOverlay", ns) is None
    assert "no prior overlay" in root.find("k:Document/k:description", ns).text


@pytest.mark.parametrize("regions", ["paper_6_1_polygons", "paper_6_1_mixed"])
def test_survey_plans_reach_every_export_format(tmp_path, capsys, regions):
    """``poc-env survey --plan-out`` writes a schema-2 plan (per UAV the pattern as
    ``waypoints_m`` and the region as ``areas_m``, no rectangle) that every format exports: the
    GeoJSON routes are the survey's tracks, the search areas its regions, the numbers its table."""
    from poc_env.agents.planning.survey import run_survey

    plan_path = tmp_path / "survey_plan.json"
    assert main(["survey", "--scenario", "paper_6_1", "--regions", regions, "--plan-out",
                 str(plan_path), "--origin", "30.5,114.3"]) == 0  # fmt: skip
    plan = load_plan(plan_path)
    result = run_survey("paper_6_1", regions)
    assert plan["schema"] == 2 and plan["optimizer"]["name"] == "survey"
    assert plan["posc"] == pytest.approx(result.posc) and len(plan["uavs"]) == len(result.rows)
    for u, row, track in zip(plan["uavs"], result.rows, result.tracks):
        assert u["rectangle"] is None and len(u["areas_m"]) == 1
        np.testing.assert_allclose(u["waypoints_m"], track)
        assert u["pos"] == pytest.approx(row.pos) and u["pattern"] == row.pattern
        assert u["flight_time_s"] == pytest.approx(row.flight_time_h * 3600)
    for fmt in ("geojson", "kml", "html"):
        assert main(["export", str(plan_path), "--format", fmt, "--out", str(tmp_path / fmt)]) == 0
    qgc = ["export", str(plan_path), "--format", "qgc", "--out", str(tmp_path / "qgc")]
    if regions == "paper_6_1_mixed":  # a circle pattern leaves the operating area by 1.7 km
        capsys.readouterr()
        assert main(qgc) == 2 and "inclusion geofence" in capsys.readouterr().err
        qgc.append("--no-geofence")
        # two of its UAVs fly beyond the usable endurance (eq. 18): refused, then allowed
        assert main(qgc) == 2
        assert "plan.uavs[2]: got '2 of 6 missions marked infeasible" in capsys.readouterr().err
        qgc.append("--allow-infeasible")
    assert main(qgc) == 0
    doc = json.loads((tmp_path / "geojson" / "survey_plan.geojson").read_text())
    crs = plan["crs"]
    routes = [f for f in doc["features"] if f["properties"]["kind"] == "route"]
    for f, u in zip(routes, plan["uavs"]):
        back = to_local([(lat, lon) for lon, lat, _ in f["geometry"]["coordinates"]], crs)
        np.testing.assert_allclose(back, _route(u), atol=0.15)
    areas = [f for f in doc["features"] if f["properties"]["kind"] == "search_area"]
    assert len(areas) == len(plan["uavs"])
    assert len(list((tmp_path / "qgc").iterdir())) == len(plan["uavs"])
    assert (tmp_path / "kml" / "survey_plan_prior.png").is_file()  # the scenario prior rebuilt
    page = (tmp_path / "html" / "survey_plan.html").read_text(encoding="utf-8")
    assert "prior: paper_6_1" in page
    # --origin is checked before the survey runs; --plan-out must be a file path
    capsys.readouterr()
    assert main(["survey", "--plan-out", str(tmp_path / "x.json"), "--origin", "95,0"]) == 2
    assert "origin" in capsys.readouterr().err and not (tmp_path / "x.json").exists()
    assert main(["survey", "--plan-out", str(tmp_path)]) == 2
    assert "plan_out" in capsys.readouterr().err


def test_allocation_missions_carry_the_speeds_the_plan_was_timed_at(tmp_path):
    """An allocation plan at ``--speed max`` is timed with v_max out and on the route and v_c
    home; its QGC missions set exactly those speeds (DO_CHANGE_SPEED), so the aircraft fly
    the plan's flight_time_s, and a plan without ``transit_speed_mps`` still exports at v_b."""
    plan_path = tmp_path / "alloc.json"
    assert main(["plan", "--scenario", "small", "--planner", "allocation", "--quiet",
                 "--origin", "30.5,114.3", "--out", str(plan_path)]) == 0  # fmt: skip
    plan = load_plan(plan_path)
    sc = load_scenario("small")
    assert plan["flight"]["transit_speed_mps"] == sc.uav.max_speed_mps
    assert plan["flight"]["search_speed_mps"] == sc.uav.max_speed_mps
    assert plan["flight"]["cruise_speed_mps"] == sc.uav.cruise_speed_mps
    assert main(["export", str(plan_path), "--format", "qgc", "--out", str(tmp_path / "q")]) == 0
    for f in sorted((tmp_path / "q").iterdir()):
        items = json.loads(f.read_text())["mission"]["items"]
        speeds = [it["params"][1] for it in items if it["command"] == 178]  # DO_CHANGE_SPEED
        want = [sc.uav.max_speed_mps, sc.uav.max_speed_mps, sc.uav.cruise_speed_mps]
        assert speeds == pytest.approx(want, abs=1e-3)  # written to the mm/s
    old = json.loads(plan_path.read_text())
    del old["flight"]["transit_speed_mps"]
    plan_path.write_text(json.dumps(old))
    assert main(["export", str(plan_path), "--format", "qgc", "--out", str(tmp_path / "o")]) == 0
    items = json.loads(next((tmp_path / "o").iterdir()).read_text())["mission"]["items"]
    first = next(it["params"][1] for it in items if it["command"] == 178)
    assert first == pytest.approx(220 / 3.6, abs=1e-3)


# --------------------------------------------------------------------------- issue 27
@pytest.mark.parametrize("code", [c for c in range(32) if chr(c) not in "\t\n\r"])
def test_every_c0_control_in_a_plan_string_is_refused_naming_the_field(tmp_path, code):
    """XML 1.0 has no encoding for these: a KML with one is not well-formed."""
    path, plan = _plan(tmp_path)
    plan["uavs"][1]["id"] = "B"
    plan["optimizer"]["name"] = f"de{chr(code)}x"
    path.write_text(json.dumps(plan))
    with pytest.raises(ConfigError, match=rf"plan\.optimizer\.name.*U\+{code:04X}"):
        load_plan(path)


@pytest.mark.parametrize("field", ["scenario", "optimizer.settings.note", "map_source"])
def test_a_lone_surrogate_in_a_plan_string_is_refused_at_load(tmp_path, field):
    path, plan = _plan(tmp_path)
    _set(plan, field, "ab\ud800c")
    path.write_text(json.dumps(plan))  # json escapes it as \ud800
    with pytest.raises(ConfigError, match=rf"plan\.{re.escape(field)}.*surrogate"):
        load_plan(path)


def test_tabs_newlines_and_markup_in_plan_strings_still_load(tmp_path):
    path, plan = _plan(tmp_path, scenario="a\tb\r\nc <b>&amp;</b> ]]> \u2028")
    path.write_text(json.dumps(plan))
    assert load_plan(path)["scenario"] == plan["scenario"]


@pytest.mark.parametrize(
    "origin, zone, ok",
    [
        (ORIGIN, 22, False),  # the issue: 177.7 degrees away, every distance 19 % short
        (ORIGIN, 50, False),  # 9.65 degrees
        (ORIGIN, 51, True),
        (ORIGIN, 53, True),
        ((10.0, 179.5), 1, True),  # across the antimeridian
        ((10.0, 179.5), 59, True),
        ((10.0, 179.5), 30, False),
    ],
)
def test_a_utm_zone_far_from_the_origin_is_refused(tmp_path, origin, zone, ok):
    if ok:
        assert make_crs("utm", origin, zone=zone)["kind"] == "utm"
        return
    with pytest.raises(ConfigError, match=r"crs\.zone: got \d+; allowed: .*one of "):
        make_crs("utm", origin, zone=zone)
    # the same zone recorded in a plan, as a PROJ string or an EPSG code
    proj = f"+proj=utm +zone={zone} +datum=WGS84 +units=m +no_defs"
    for crs, field in (
        ({"kind": "utm", "origin_deg": list(origin), "proj": proj}, "proj"),
        ({"kind": "epsg", "origin_deg": list(origin), "epsg": 32600 + zone}, "epsg"),
    ):
        path, _ = _plan(tmp_path, crs=crs)
        with pytest.raises(ConfigError, match=rf"plan\.crs\.{field}.*UTM zone"):
            load_plan(path)


def test_cli_plan_refuses_a_utm_zone_across_the_globe(tmp_path, capsys):
    code = main(["plan", "--scenario", "small", "--planner", "allocation", "--quiet",
                 "--origin", "45.75,126.65", "--projection", "utm", "--utm-zone", "22",
                 "--out", str(tmp_path / "p.json")])  # fmt: skip
    assert code != 0 and not (tmp_path / "p.json").exists()
    assert "crs.zone" in capsys.readouterr().err


def test_large_polygons_are_drawn_where_the_planner_has_them(tmp_path):
    """Audit i24: GeoJSON, KML and the map report join a polygon's vertices with lines straight
    in longitude/latitude; the planner's operating area and zones are straight in the map's
    metres. On a 600 km operating area near 46 N the exported edges ran up to kilometres off
    the planner's (6.4 km on the audit's 500 km scenario). Long edges now get points along
    them (:func:`poc_env.crs.densify_ring`) so that every lon/lat-straight piece stays within
    10 m (plus the 1e-6 degree rounding) of the planner's edge; short edges keep their
    vertices."""
    from shapely.geometry import Polygon

    big = [[-300e3, -300e3], [300e3, -300e3], [300e3, 300e3], [-300e3, 300e3]]
    zone = [[10e3, 10e3], [20e3, 10e3], [20e3, 20e3], [10e3, 20e3]]
    path, _ = _plan(tmp_path, operating_area_m=big, no_fly_zones_m=[zone])
    (out,) = export_plan(path, "geojson", "45.75,126.65", geofence=False)
    feats = json.loads(out.read_text())["features"]
    for kind, ring_m in (("operating_area", big), ("no_fly_zone", zone)):
        (f,) = [f for f in feats if f["properties"]["kind"] == kind]
        lonlat = np.array(f["geometry"]["coordinates"][0])
        edge = Polygon(ring_m).exterior
        t = np.linspace(0, 1, 21)[:, None]
        worst = 0.0
        for a, b in itertools.pairwise(lonlat):  # each piece as a GIS draws it
            pts = a + t * (b - a)
            xy = to_local([(lat, lon) for lon, lat in pts], ORIGIN)
            worst = max(worst, max(edge.distance(Point(p)) for p in xy))
        assert worst < 10.5, (kind, worst)
        if kind == "no_fly_zone":
            assert len(lonlat) == 5  # 10 km edges: left as they are


def test_qgc_geofence_is_drawn_where_the_planner_has_its_polygons(tmp_path):
    """A QGC geofence polygon is a list of (lat, lon) vertices that the autopilot and QGC join
    straight in latitude/longitude; the planner's operating area is straight in the map's
    metres. On a 600 km operating area near 46 N the inclusion fence ran kilometres inside
    or outside the area the routes were checked against (the other exports were densified by
    the i24 audit, the fence was not). Its long edges now get points along them, the same
    rule as the other exports (:func:`poc_env.crs.densify_ring`): every piece within 10 m of
    the planner's edge, short edges (the zone's) left as they are, still clockwise."""
    from shapely.geometry import Polygon

    big = [[-300e3, -300e3], [300e3, -300e3], [300e3, 300e3], [-300e3, 300e3]]
    zone = [[-200e3, 200e3], [-190e3, 200e3], [-190e3, 210e3], [-200e3, 210e3]]  # off the routes
    path, _ = _plan(tmp_path, operating_area_m=big, no_fly_zones_m=[zone])
    doc = json.loads(export_plan(path, "qgc", "45.75,126.65", tmp_path / "o")[0].read_text())
    inc, exc = doc["geoFence"]["polygons"]
    t = np.linspace(0, 1, 21)[:, None]
    for poly, ring_m in ((inc, big), (exc, zone)):
        latlon = np.array(poly["polygon"])
        edge = Polygon(ring_m).exterior
        worst = 0.0
        for a, b in itertools.pairwise([*latlon, latlon[0]]):  # each piece as QGC joins it
            xy = to_local(a + t * (b - a), ORIGIN)
            worst = max(worst, max(edge.distance(Point(p)) for p in xy))
        assert worst < 10.5, (poly["inclusion"], worst)
        xy = np.array(to_local(latlon, ORIGIN))
        area2 = np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1])
        assert area2 < 0  # still clockwise
    assert len(exc["polygon"]) == 4  # 10 km edges: left as they are


def test_kml_overlay_href_survives_any_plan_file_name(tmp_path):
    """Audit i24: the KML's GroundOverlay ``href`` is a URI reference, written as the PNG's
    bare file name: a plan named ``sortie #2 (100%).json`` gave ``sortie #2 (100%)_prior.png``,
    which a KML reader takes as the file ``sortie `` with a fragment (``#``) and a bad escape
    (``%)``). The href is now percent-encoded and resolves to the PNG written beside it."""
    from urllib.parse import urljoin, urlparse
    from urllib.request import url2pathname

    path, _ = _plan(tmp_path)
    odd = tmp_path / "sortie #2 (100%) ü.json"
    path.rename(odd)
    out = tmp_path / "out"
    kml, png = export_plan(odd, "kml", "45.75,126.65", out)
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    href = ET.parse(kml).getroot().find(".//k:GroundOverlay/k:Icon/k:href", ns).text
    assert "#" not in href and " " not in href
    url = urljoin(kml.resolve().as_uri(), href)  # as a reader resolves it against the KML
    assert url2pathname(urlparse(url).path) == str(png.resolve())
    assert png.is_file()
