"""export-audit (2026-11-29): the exported missions checked against the definitions of the tools
that read them (results/audit/export/README.md has every probe).

- QGroundControl sends a ``.plan``'s rally points as MAV_CMD_NAV_RALLY_POINT in
  MAV_FRAME_GLOBAL_RELATIVE_ALT (src/MissionManager/RallyPointManager.cc): their altitude is
  above home, the take-off field, not above the field they stand over.
"""

from __future__ import annotations

import importlib.util
import json
import math
from itertools import pairwise
from pathlib import Path

import pytest

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.formats.kml import validate_kml
from poc_env.agents.mission.plan import APPROACH_DISTANCE_M, APPROACH_HEIGHT_M, write_plan
from poc_env.agents.mission.terrain import from_record
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario

pytest.importorskip("rasterio")
HERE = Path(__file__).resolve().parent


def _terrain_test():
    """tests/mission/test_terrain.py as a module (its scenario and terrain grids: one copy)."""
    spec = importlib.util.spec_from_file_location("_terrain_test", HERE / "test_terrain.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _uphill_plan(tmp_path: Path) -> Path:
    """A terrain plan whose UAVs take off in the 600 m valley and land at a field 1,300 m up a
    20 m/km slope (65 km east of it)."""
    tt = _terrain_test()
    data = tt._scenario(None, terrain={"elevation_m": tt._slope(20.0), "cell_km": 1.0,
                                       "origin_km": [-40, -30]})  # fmt: skip
    data["airfields"] = [*data["airfields"], {"name": "upper", "position_km": [55, 20]}]
    data["fleet"] = [{"takeoff": "valley", "landing": "upper", "count": 2}]
    plan = make_plan(load_scenario(data), planner="allocation", refine=0)
    write_plan(plan, tmp_path / "plan.json")
    return tmp_path / "plan.json"


def test_qgc_rally_points_stand_above_their_own_field_not_above_home(tmp_path):
    """Each rally point is APPROACH_HEIGHT_M above the field it marks: relative to home (QGC's
    frame for rally points) that is the field's elevation less home's plus 300 m. Before, both
    were written 300 m above home, so the rally point over a landing field 1,300 m higher than
    the take-off field was 1,000 m under the ground there."""
    path = _uphill_plan(tmp_path)
    plan = json.loads(path.read_text(encoding="utf-8"))
    t = from_record(plan["terrain"])
    fields = [plan["uavs"][0]["takeoff_m"], plan["uavs"][0]["landing_m"]]
    elev = [t.field_elevation(f) for f in fields]
    assert elev[1] - elev[0] > 1000.0  # the case: a landing field far above home
    for f in export_plan(path, "qgc", out_dir=tmp_path / "qgc"):
        doc = json.loads(f.read_text(encoding="utf-8"))
        home_amsl = doc["mission"]["plannedHomePosition"][2]
        assert home_amsl == pytest.approx(elev[0], abs=0.1)
        points = doc["rallyPoints"]["points"]
        assert len(points) == 2
        for (_, _, rel), ground in zip(points, elev):
            assert home_amsl + rel - ground == pytest.approx(APPROACH_HEIGHT_M, abs=0.1)


def _glides_deg(plan_files: list[Path]) -> list[float]:
    """The final glide of each QGC mission, approach waypoint -> NAV_LAND, in degrees, as PX4's
    mission feasibility check measures it (AMSL heights, horizontal distance)."""
    from pyproj import Geod

    out = []
    for f in plan_files:
        doc = json.loads(f.read_text(encoding="utf-8"))
        home = doc["mission"]["plannedHomePosition"][2]
        nav = [it for it in doc["mission"]["items"] if it["command"] in (16, 21, 22)]
        app, land = nav[-2]["params"], nav[-1]["params"]
        assert nav[-1]["command"] == 21
        amsl = [it["params"][6] + (home if it["frame"] == 3 else 0.0) for it in nav[-2:]]
        dist = Geod(ellps="WGS84").inv(app[5], app[4], land[5], land[4])[2]
        out.append(math.degrees(math.atan2(amsl[0] - amsl[1], dist)))
    return out


def test_terrain_missions_glide_to_the_field_no_steeper_than_px4_lands(tmp_path):
    """PX4 (the ``.plan``'s firmwareType 12) refuses a mission whose last waypoint -> NAV_LAND
    glide is steeper than FW_LND_ANG + 0.1 deg (navigator FeasibilityChecker; FW_LND_ANG
    default 5 deg). The flat export glides 300 m over 4 km (4.29 deg); a terrain mission now
    glides no steeper. Before, the Alps plan's approach started at the search height and glided
    at eq. 19's 15 deg bound: 14.0 deg, a mission PX4 would not take."""
    tt = _terrain_test()
    sc = load_scenario(tt._scenario(tt._dem(tmp_path / "d.tif")))
    write_plan(make_plan(sc, planner="allocation", refine=0), tmp_path / "plan.json")
    glides = _glides_deg(export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "q"))
    flat = math.degrees(math.atan2(APPROACH_HEIGHT_M, APPROACH_DISTANCE_M))
    assert max(glides) <= flat + 1e-3 < 5.0


def test_qgc_refuses_a_geofence_across_the_antimeridian(tmp_path):
    """PX4 tests a fence point in latitude/longitude (navigator Geofence::insidePolygon, PNPOLY,
    "only supports non-complex polygons"): a fence polygon whose longitudes jump from 180 to
    -180 is, to it, the rest of the globe. The small scenario 10 km west of the antimeridian
    near Fiji: its operating area crosses it, so the QGC export is refused naming
    plan.operating_area_m (nothing written); without the inclusion fence it is written. Before,
    the .plan carried that fence, and a UAV on its own airfield was outside it."""
    from poc_env.errors import ConfigError

    plan = make_plan("small", planner="allocation", refine=0, origin_deg=(-16.5, 179.8))
    write_plan(plan, tmp_path / "plan.json")
    with pytest.raises(ConfigError, match=r"plan\.operating_area_m.*antimeridian") as err:
        export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "q")
    assert "--no-geofence" in str(err.value) and "zone" not in str(err.value)  # its remedy
    assert not (tmp_path / "q").exists() or not any((tmp_path / "q").iterdir())
    files = export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "q", geofence=False)
    for f in files:
        doc = json.loads(f.read_text(encoding="utf-8"))
        assert doc["geoFence"]["polygons"] == []  # small has no zones; no inclusion fence


#: An allocation plan's search area (the Chile probe's UAV 2, metres): a cut line runs out and
#: back along y = 9166.67 m, its two ends 2e-12 m apart, so the ring is valid in metres.
_CUT_RING = [
    [35000.0, 5000.0], [35000.0, 6250.0], [34583.333333333336, 6250.0],
    [34583.333333333336, 7083.333333333334], [35000.0, 7083.333333333334],
    [35000.0, 7916.666666666668], [34583.333333333336, 7916.666666666668],
    [34583.333333333336, 8750.0], [35000.0, 8750.0], [35000.0, 9166.666666666666],
    [39583.333333333336, 9166.666666666666], [35000.0, 9166.666666666668], [35000.0, 10000.0],
    [40000.0, 10000.0], [40000.0, 9583.333333333334], [40416.666666666664, 9583.333333333334],
    [40416.666666666664, 8750.0], [40000.0, 8750.0], [40000.0, 7916.666666666668],
    [40416.666666666664, 7916.666666666668], [40416.666666666664, 7083.333333333334],
    [40000.0, 7083.333333333334], [40000.0, 6250.0], [40416.666666666664, 6250.0],
    [40416.666666666664, 5416.666666666668], [40000.0, 5416.666666666668], [40000.0, 5000.0],
]  # fmt: skip


def test_geojson_polygons_stay_valid_after_rounding(tmp_path):
    """A ring valid in metres whose two vertices 2e-12 m apart become one at 1e-6 degree: the
    rounded ring must not fold back on itself (OGC simple-feature validity, what a GIS's
    "check validity" and shapely's ``is_valid`` test). Before, 5 search areas of the probes'
    allocation plans (Chile, near 60 N, 24 UAVs) were self-intersecting in the GeoJSON."""
    from shapely.geometry import Polygon, shape

    from poc_env.agents.mission.crs import plan_crs
    from poc_env.agents.mission.formats.geojson import geojson

    plan = make_plan("small", planner="allocation", refine=0, origin_deg=(-33.7, -71.0))
    assert Polygon(_CUT_RING).is_valid  # in the planner's metres
    plan["uavs"][0]["areas_m"] = [_CUT_RING]
    doc = geojson(plan, plan_crs(plan["crs"], None, "aeqd", None))
    polys = [f for f in doc["features"] if f["geometry"]["type"] == "Polygon"]
    assert any(f["properties"]["kind"] == "search_area" for f in polys)
    for f in polys:
        assert shape(f["geometry"]).is_valid, f["properties"]


def _idle(u: dict) -> None:
    """``u`` as the allocation planner writes a UAV it gives no search (no mass in reach)."""
    u.update(rectangle=None, areas_m=[], spacing_m=0.0, waypoints_m=[], transit_waypoints=0,
             track_length_m=0.0, flight_time_s=0.0, pod=0.0, poc=0.0, pos=0.0)  # fmt: skip


@pytest.mark.parametrize("fmt", ["qgc", "kml", "geojson", "html"])
def test_a_uav_without_a_search_route_is_left_out_and_named(tmp_path, capsys, fmt):
    """A UAV with no waypoints (no reachable mass, or a teammate covers it) is left out of every
    format with a warning naming it; the others are written (leftovers #2: before, GeoJSON and
    KML drew a zero-length route for it, QGC a take-off and landing on the spot)."""
    plan = make_plan("small", planner="allocation", refine=0, origin_deg=(45.75, 126.65))
    _idle(plan["uavs"][1])
    write_plan(plan, tmp_path / "plan.json")
    files = export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / "o")
    assert "warning: plan.uavs[1] (UAV 2): no search planned" in capsys.readouterr().err
    text = "\n".join(f.read_text(encoding="utf-8") for f in files if f.suffix != ".png")
    if fmt == "qgc":
        assert sorted(f.name for f in files) == ["plan_uav1.plan", "plan_uav3.plan"]
    elif fmt == "geojson":
        ids = {f["properties"].get("id") for f in json.loads(text)["features"]}
        assert ids == {None, 1, 3}  # areas and fields (no id), UAVs 1 and 3
    elif fmt == "kml":
        assert "UAV 1" in text and "UAV 3" in text and "UAV 2" not in text
    else:  # the page's data: one entry per UAV drawn
        assert '"id": "1"' in text and '"id": "3"' in text and '"id": "2"' not in text


def test_uavs_left_out_are_named_in_one_warning_line(tmp_path, capsys):
    """Many UAVs without a search route give one warning line naming the first six and the
    count of the rest (a 64-UAV plan printed 49 lines, one per idle UAV: i24-dayaudit)."""
    plan = make_plan("small", planner="allocation", refine=0, origin_deg=(45.75, 126.65))
    plan["uavs"] = [dict(plan["uavs"][0], id=k + 1) for k in range(10)]
    for u in plan["uavs"][1:]:
        _idle(u)
    write_plan(plan, tmp_path / "plan.json")
    export_plan(tmp_path / "plan.json", "geojson", out_dir=tmp_path / "o")
    lines = [x for x in capsys.readouterr().err.splitlines() if "no search planned" in x]
    assert lines == [
        "warning: plan.uavs[1] (UAV 2), plan.uavs[2] (UAV 3), plan.uavs[3] (UAV 4), "
        "plan.uavs[4] (UAV 5), plan.uavs[5] (UAV 6), plan.uavs[6] (UAV 7) and 3 more: no search "
        "planned for them (no waypoints_m); left out of the export"
    ]


@pytest.mark.parametrize("fmt", ["qgc", "kml", "geojson", "html"])
def test_a_plan_that_reaches_nothing_is_refused_by_every_format(tmp_path, fmt):
    """The airfield 80 km south of ``small``: no UAV reaches any mass, the plan says why, and an
    export of it is refused naming ``plan.uavs`` and the plan's reason; nothing is written."""
    from poc_env.errors import ConfigError

    data = load_scenario("small").to_dict()
    data["airfields"] = [{"name": "A", "position_km": [20, -80]}]
    plan = make_plan(load_scenario(data), planner="allocation", refine=0,
                     origin_deg=(45.75, 126.65))  # fmt: skip
    assert plan["reason"] and not any(u["waypoints_m"] for u in plan["uavs"])
    write_plan(plan, tmp_path / "plan.json")
    with pytest.raises(ConfigError, match=r"plan\.uavs: .*none with a search route.*0\.85 T"):
        export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / "o")
    assert not (tmp_path / "o").exists()


def _plan_imported_at_the_antimeridian(tmp_path: Path) -> Path:
    """A search area imported from GeoJSON at 179.6-179.98 E near Fiji, its airfield at
    179.97 W (across the 180th meridian): routes, approaches and the operating area cross it."""
    from poc_env.agents.mission.geoimport import import_scenario, write_imported

    def fc(geometry: dict, **props) -> str:
        feat = {"type": "Feature", "properties": props, "geometry": geometry}
        return json.dumps({"type": "FeatureCollection", "features": [feat]})

    ring = [[179.6, -16.7], [179.98, -16.7], [179.98, -16.3], [179.6, -16.3], [179.6, -16.7]]
    (tmp_path / "area.geojson").write_text(fc({"type": "Polygon", "coordinates": [ring]}))
    field = {"type": "Point", "coordinates": [-179.97, -16.45]}
    (tmp_path / "fields.geojson").write_text(fc(field, name="Taveuni"))
    res = import_scenario(tmp_path / "area.geojson", airfields=tmp_path / "fields.geojson",
                          base="small", name="fiji")  # fmt: skip
    write_imported(res, tmp_path / "fiji.yaml")
    plan = make_plan(load_scenario(str(tmp_path / "fiji.yaml")), planner="allocation", refine=0)
    write_plan(plan, tmp_path / "plan.json")
    return tmp_path / "plan.json"


def _lines_of(coords: list) -> list[list[list[float]]]:
    """Every line or ring of a GeoJSON geometry's coordinates."""
    if coords and isinstance(coords[0], (int, float)):
        return [[coords]]
    if coords and isinstance(coords[0][0], (int, float)):
        return [coords]
    return [line for c in coords for line in _lines_of(c)]


def test_exports_across_the_antimeridian_are_cut_or_continuous(tmp_path):
    """Leftovers #3. GeoJSON (RFC 7946 section 3.1.9): a geometry crossing the antimeridian is cut
    into a Multi* of its parts, every longitude in [-180, 180], no part jumping across the
    globe, each valid. KML and the report: longitudes continuous around the area (Google Earth
    and Leaflet join points the short way only then; OGC KML 2.2 section 9.14.3.4 lets the
    prior's LatLonBox go beyond 180). Before, all three drew routes and the operating area
    from 180 to -180, across the globe, and the prior's box spanned every longitude."""
    import re

    from shapely.geometry import shape

    path = _plan_imported_at_the_antimeridian(tmp_path)
    (gj,) = export_plan(path, "geojson", out_dir=tmp_path / "g")
    multi = set()
    for f in json.loads(gj.read_text(encoding="utf-8"))["features"]:
        geom = f["geometry"]
        assert shape(geom).is_valid, f["properties"]
        for line in _lines_of(geom["coordinates"]):
            lon = [p[0] for p in line]
            assert all(-180.0 <= v <= 180.0 for v in lon)
            assert all(abs(b - a) < 1.0 for a, b in pairwise(lon)), f["properties"]
        if geom["type"].startswith("Multi"):
            multi.add(f["properties"]["kind"])
    assert {"route", "operating_area"} <= multi  # the case: they cross it
    files = export_plan(path, "kml", out_dir=tmp_path / "k")
    text = next(f for f in files if f.suffix == ".kml").read_text(encoding="utf-8")
    for coords in re.findall(r"<coordinates>([^<]*)</coordinates>", text):
        lon = [float(t.split(",")[0]) for t in coords.split()]
        assert all(179.0 < v < 181.0 for v in lon)  # continuous around 180
    box = {k: float(v) for k, v in re.findall(r"<(east|west)>([^<]*)</", text)}
    assert 179.0 < box["west"] < 180.0 < box["east"] < 181.0
    assert validate_kml(text) == []  # the box across 180 as the KML reference allows it
    (page,) = export_plan(path, "html", out_dir=tmp_path / "h")
    m = re.search(r'id="plan-data">(.*?)</script>', page.read_text(encoding="utf-8"), re.S)
    assert m
    data = json.loads(m.group(1))
    lons = [float(v) for v in re.findall(r"\[-?[0-9.]+, (-?[0-9.]+)\]", json.dumps(data["uavs"]))]
    lons += [a["latlon"][1] for a in data["airfields"]]
    lons += [p[1] for z in data["operating_area"] for p in z["latlon"]]
    lons += [data["overlay"]["bounds"][0][1], data["overlay"]["bounds"][1][1]]
    assert lons and all(179.0 < v < 181.0 for v in lons)


def test_a_steep_final_glide_is_said_by_plan_and_the_qgc_export_only(tmp_path, capsys):
    """Leftovers #6: the warning that a UAV's final glide needs FW_LND_ANG above PX4's default
    is for the officer who can still re-plan (``plan``) and for the mission that flies
    (``export --format qgc``), once per UAV each, as a ``warning:`` line; the viewing formats
    (KML, GeoJSON, HTML) say nothing. Before, every export printed it in Python's warning
    format (file, line and a source line ``return [``)."""
    import yaml

    from poc_env.cli import main

    tt = _terrain_test()
    data = tt._scenario(None, terrain={"elevation_m": tt._slope(150.0), "cell_km": 1.0,
                                       "origin_km": [-40, -30]})  # fmt: skip
    (tmp_path / "steep.yaml").write_text(yaml.safe_dump(data), encoding="utf-8")
    plan = tmp_path / "p.json"
    argv = ["plan", "--scenario", str(tmp_path / "steep.yaml"), "--planner", "allocation"]
    assert main([*argv, "--quiet", "--out", str(plan)]) == 0

    def glides() -> list[str]:
        err = capsys.readouterr().err
        assert "UserWarning" not in err and "Warning:" not in err
        return [ln for ln in err.splitlines() if "final glide of" in ln]

    said = glides()
    assert len(said) == 2 and all(ln.startswith("warning: plan.uavs[") for ln in said)
    for fmt, expected in (("qgc", said), ("kml", []), ("geojson", []), ("html", [])):
        assert main(["export", str(plan), "--format", fmt, "--out", str(tmp_path / fmt)]) == 0
        assert glides() == expected, fmt


def test_validate_kml_takes_a_box_across_the_antimeridian_and_nothing_else_past_180():
    """The KML reference lets a LatLonBox that overlaps the 180 degree meridian give ``east``
    beyond 180, which the OGC XSD's maxInclusive refuses; the campaign (seed 1, an origin at
    88 S) counted every such KML export as invalid. ``validate_kml`` takes exactly that case:
    an ``east`` past 180 whose box does not cross it (wider than the globe) stays a complaint."""

    def doc(west: float, east: float) -> str:
        return (
            '<kml xmlns="http://www.opengis.net/kml/2.2"><Document><GroundOverlay>'
            "<Icon><href>p.png</href></Icon><LatLonBox><north>-87</north><south>-89</south>"
            f"<east>{east!r}</east><west>{west!r}</west></LatLonBox></GroundOverlay>"
            "</Document></kml>"
        )

    assert validate_kml(doc(150.0, 170.0)) == []
    assert validate_kml(doc(150.0, 191.85)) == []  # across 180
    assert validate_kml(doc(-170.0, 191.0)) != []  # 361 degrees wide: not a crossing box
    assert validate_kml(doc(150.0, 560.0)) != []
