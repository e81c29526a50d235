"""`poc-env replan`: eq. 14 along the flights of the sorties so far, then the next sortie."""

import json

import numpy as np
import pytest

from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.plan import load_plan
from poc_env.agents.planning.replan import searched_belief
from poc_env.cli import main
from poc_env.config import load_scenario, parse_overrides
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import build_prior


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    d = tmp_path_factory.mktemp("replan")
    out = d / "p1.json"
    argv = ["plan", "--scenario", "small", "--planner", "allocation", "--origin", "46.5,7.9"]
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    return d, out


def _tracks(path, plan, **extra):
    feats = []
    for u in plan["uavs"]:
        pts = [u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]
        coords = [[lon, lat] for lat, lon in to_geographic(pts, plan["crs"])]
        feats.append(
            {
                "type": "Feature",
                "properties": {},
                "geometry": {"type": "LineString", "coordinates": coords},
            }
        )
    path.write_text(json.dumps({"type": "FeatureCollection", "features": feats, **extra}))
    return feats


def test_three_sorties_add_up(first, capsys):
    """Sortie 2 starts from the prior less what sortie 1's routes found (eq. 14 on the sample
    points: the same sweep that scored plan 1, so its POS is plan 1's posc); sortie 3 from
    what both left; the cumulative POS grows and stays a probability."""  # issue 24 item 4
    d, p1 = first
    p2, p3 = d / "p2.json", d / "p3.json"
    assert main(["replan", "--scenario", "small", "--plan", str(p1), "--out", str(p2)]) == 0
    assert main(["replan", "--plan", str(p1), "--plan", str(p2), "--out", str(p3)]) == 0
    assert "sortie 3" in capsys.readouterr().out
    a, b, c = (json.loads(p.read_text()) for p in (p1, p2, p3))
    assert b["sortie"] == 2 and c["sortie"] == 3 and b["crs"] == a["crs"]
    assert b["searched_pos"] == pytest.approx(a["posc"], abs=1e-9)
    # sortie 2 was scored on the cells' belief spread evenly over each cell's sample points;
    # the chain keeps the sample points' own belief (sortie 1 left it uneven within cells)
    assert c["searched_pos"] == pytest.approx(a["posc"] + b["posc"], rel=1e-2)
    # ... and sortie 2's own POS on that belief, point by point, is what sortie 3 starts from
    assert c["searched_pos"] == pytest.approx(b["cumulative_posc"], abs=1e-9)
    assert c["searched_pos"] > b["searched_pos"]
    assert a["posc"] < b["cumulative_posc"] < c["cumulative_posc"] <= 1.0
    load_plan(p3)  # a plan export accepts
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    paths = [np.array([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]) for u in a["uavs"]]
    belief, found = searched_belief(sc, prior, paths)
    assert belief.sum() + found == pytest.approx(prior.sum(), abs=1e-12)
    assert np.all(belief <= prior + 1e-15) and found > 0


def test_flown_tracks_as_geojson_give_the_same_belief(first, tmp_path):
    _, p1 = first
    plan = json.loads(p1.read_text())
    _tracks(tmp_path / "t.geojson", plan)
    out = tmp_path / "next.json"
    argv = ["replan", "--scenario", "small", "--plan", str(p1), "--tracks"]
    assert main([*argv, str(tmp_path / "t.geojson"), "--out", str(out)]) == 0
    # lon/lat and back moves points by rounding; a sample point at the sensor's cut-off distance
    # of a line may then fall on the other side of it
    assert json.loads(out.read_text())["searched_pos"] == pytest.approx(plan["posc"], rel=1e-3)


def test_bad_tracks_name_the_field_and_write_nothing(first, tmp_path, capsys):
    _, p1 = first
    plan = json.loads(p1.read_text())
    out = tmp_path / "next.json"
    argv = ["replan", "--plan", str(p1), "--out", str(out), "--tracks", str(tmp_path / "t.geojson")]
    feats = _tracks(tmp_path / "t.geojson", plan)
    feats[1]["geometry"]["coordinates"][2] = [-7.9, -46.5]  # signs slipped: the other hemisphere
    (tmp_path / "t.geojson").write_text(
        json.dumps({"type": "FeatureCollection", "features": feats})
    )
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "tracks.features[1].geometry.coordinates[2]" in err
    assert "within 1000 km of the operating area" in err
    _tracks(
        tmp_path / "t.geojson", plan, crs={"type": "name", "properties": {"name": "EPSG:99999"}}
    )
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "tracks.crs" in err and "EPSG:99999" in err and "pyproj" in err
    assert main(["replan", "--scenario", "paper_6_2", "--plan", str(p1), "--out", str(out)]) == 2
    assert "plan.scenario" in capsys.readouterr().err
    assert not out.exists()


def test_a_track_partly_outside_the_area_counts_the_part_inside(first, tmp_path, capsys):
    """Leftovers #4: UAV 2 diverted to a field about 100 km east of the map after its search.
    Its track is cut to the operating area with a warning naming it, and what it flew inside
    counts (before, the whole file was refused); a track with no point inside is refused."""
    _, p1 = first
    plan = json.loads(p1.read_text())
    out = tmp_path / "next.json"
    argv = ["replan", "--plan", str(p1), "--out", str(out), "--tracks", str(tmp_path / "t.geojson")]
    feats = _tracks(tmp_path / "t.geojson", plan)
    feats[1]["geometry"]["coordinates"].append([9.2, 46.6])  # the diversion, ~100 km east
    (tmp_path / "t.geojson").write_text(
        json.dumps({"type": "FeatureCollection", "features": feats})
    )
    assert main(argv) == 0
    text = capsys.readouterr().err  # warnings on stderr (i24-missionfix)
    assert "warning: tracks.features[1].geometry.coordinates:" in text
    assert "outside the operating area" in text and "the 1 stretch(es) inside are swept" in text
    # every planned route was flown inside (plus a stretch of the diversion): at least plan 1's
    assert json.loads(out.read_text())["searched_pos"] >= plan["posc"] * (1 - 1e-3)
    out.unlink()
    feats[1]["geometry"]["coordinates"] = [[9.2, 46.6], [9.3, 46.7]]  # none of it inside
    (tmp_path / "t.geojson").write_text(
        json.dumps({"type": "FeatureCollection", "features": feats})
    )
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "tracks.features[1].geometry.coordinates[0]" in err and "inside the operating" in err
    assert not out.exists()


def _utm_tracks(path, plan):
    """The plan's routes as tracks in UTM 32N metres, with a GeoJSON 2008 ``crs`` member."""
    from pyproj import Transformer

    feats = _tracks(path, plan)
    utm = Transformer.from_crs("EPSG:4326", "EPSG:32632", always_xy=True)
    for f in feats:
        f["geometry"]["coordinates"] = [
            list(utm.transform(*p)) for p in f["geometry"]["coordinates"]
        ]
    crs = {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}}
    path.write_text(json.dumps({"type": "FeatureCollection", "crs": crs, "features": feats}))


def test_tracks_in_a_projected_geojson_crs_are_reprojected(first, tmp_path):
    """Leftovers #4: a GeoJSON of 2008 style with a ``crs`` member in metres (UTM 32N, as a
    logger or GIS may still write) is reprojected by pyproj and sweeps what the same tracks in
    longitude/latitude sweep (before: refused)."""
    _, p1 = first
    plan = json.loads(p1.read_text())
    _tracks(tmp_path / "ll.geojson", plan)
    _utm_tracks(tmp_path / "utm.geojson", plan)
    got = []
    for name in ("ll", "utm"):
        out = tmp_path / f"{name}.json"
        argv = ["replan", "--plan", str(p1), "--tracks", str(tmp_path / f"{name}.geojson")]
        assert main([*argv, "--out", str(out)]) == 0
        got.append(json.loads(out.read_text())["searched_pos"])
    assert got[1] == pytest.approx(got[0], rel=1e-4)  # float round trips through UTM


@pytest.mark.parametrize(
    "text, field",
    [
        ('{"type": "FeatureCollection", "features": ' + "[" * 5000 + "]" * 5000 + "}", "tracks"),
        ('{"type": "FeatureCollection", "crs": "EPSG:4326", "features": []}', "tracks.crs"),
        ('{"type": "FeatureCollection", "crs": {"properties": 3}, "features": []}', "tracks.crs"),
        ('{"type": "FeatureCollection", "crs": {"properties": {"name": []}}}', "tracks.crs"),
        ('{"type": "LineString", "coordinates": [[NaN, 45], [126, 45]]}', "tracks"),
        (
            '{"type": "LineString", "coordinates": [[1' + "0" * 400 + ", 45], [126, 45]]}",
            "tracks.coordinates[0]",
        ),
    ],
)
def test_hostile_tracks_are_a_clear_error_nothing_written(first, tmp_path, text, field):
    """Issue 27's campaign (datafiles target): deep nesting was a RecursionError, a crs member
    that is not an object an AttributeError and an integer beyond float range (seed 74) an
    OverflowError; each names the field now."""
    _, p1 = first
    bad = tmp_path / "flown.geojson"
    bad.write_text(text)
    out = tmp_path / "out" / "p2.json"
    argv = ["replan", "--plan", str(p1), "--tracks", str(bad), "--out", str(out)]
    assert main(argv) == 2
    assert not out.parent.exists() or not any(out.parent.iterdir())
    from poc_env.agents.planning.replan import read_tracks

    with pytest.raises(ConfigError) as err:
        read_tracks(bad, (46.5, 7.9))
    assert err.value.field == field


# --------------------------------------------------------------------------- KML and GPX tracks


def _lonlat_lines(plan):
    return [
        [(lon, lat) for lat, lon in to_geographic(
            [u["takeoff_m"], *u["waypoints_m"], u["landing_m"]], plan["crs"])]
        for u in plan["uavs"] if u["waypoints_m"]
    ]  # fmt: skip


def _kml(path, lines, *, head="", coord=lambda lon, lat: f"{lon!r},{lat!r},1500"):
    marks = "".join(
        f"<Placemark><name>UAV {k}</name><LineString><coordinates>"
        + " ".join(coord(lon, lat) for lon, lat in line)
        + "</coordinates></LineString></Placemark>"
        for k, line in enumerate(lines)
    )
    path.write_text(
        f'<?xml version="1.0"?>{head}<kml xmlns="http://www.opengis.net/kml/2.2">'
        f"<Document><Folder>{marks}</Folder></Document></kml>"
    )


def _gpx(path, lines, *, point=lambda lon, lat: f'<trkpt lat="{lat!r}" lon="{lon!r}"/>'):
    trks = "".join(
        f"<trk><name>UAV {k}</name><trkseg>{''.join(point(lon, lat) for lon, lat in line)}"
        "</trkseg></trk>"
        for k, line in enumerate(lines)
    )
    path.write_text(
        '<?xml version="1.0"?><gpx version="1.1" creator="test" '
        f'xmlns="http://www.topografix.com/GPX/1/1">{trks}</gpx>'
    )


@pytest.mark.parametrize("fmt", ["kml", "gpx"])
def test_flown_tracks_as_kml_or_gpx_give_the_same_belief(first, tmp_path, fmt):
    """The routes written as KML LineStrings or GPX track segments sweep what the plan's own
    routes sweep (the same tolerance as GeoJSON: lon/lat rounding at the cut-off)."""
    _, p1 = first
    plan = json.loads(p1.read_text())
    lines = _lonlat_lines(plan)
    f = tmp_path / f"t.{fmt}"
    (_kml if fmt == "kml" else _gpx)(f, lines)
    from poc_env.agents.planning.replan import read_tracks

    got = read_tracks(f, plan["crs"])
    assert len(got) == len(lines) and all(len(a) == len(b) for (_, a), b in zip(got, lines))
    out = tmp_path / "next.json"
    argv = ["replan", "--scenario", "small", "--plan", str(p1), "--tracks", str(f)]
    assert main([*argv, "--out", str(out)]) == 0
    assert json.loads(out.read_text())["searched_pos"] == pytest.approx(plan["posc"], rel=1e-3)


def test_tracks_from_several_files_and_formats_add_up(first, tmp_path):
    """UAV 1 from a GPX logger, the others from KML: together the plan's whole sweep."""
    _, p1 = first
    plan = json.loads(p1.read_text())
    lines = _lonlat_lines(plan)
    _gpx(tmp_path / "a.gpx", lines[:1])
    _kml(tmp_path / "b.kml", lines[1:])
    out = tmp_path / "next.json"
    argv = ["replan", "--plan", str(p1), "--tracks", str(tmp_path / "a.gpx"), "--tracks"]
    assert main([*argv, str(tmp_path / "b.kml"), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["searched_pos"] == pytest.approx(plan["posc"], rel=1e-3)
    _gpx(tmp_path / "a.gpx", lines[:1])
    assert main([*argv[:-1], "--out", str(out)]) == 0  # one UAV's track alone finds less
    assert json.loads(out.read_text())["searched_pos"] < plan["posc"] * 0.9


def _bad_cases():
    far = lambda lon, lat: f"{lon + 1.6!r},{lat!r}"  # ~120 km east: off the map  # noqa: E731
    nan = lambda lon, lat: f'<trkpt lat="NaN" lon="{lon!r}"/>'  # noqa: E731
    bomb = '<!DOCTYPE kml [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;">]>'
    return [
        ("kml", {"coord": far}, "tracks.Placemark[0].LineString[0]", "operating area"),
        ("gpx", {"point": nan}, "tracks.trk[0].trkseg[0].trkpt[0]", "WGS 84 degrees"),
        ("kml", {"head": bomb}, "tracks", "no DTD"),
        (
            "kml",
            {"coord": lambda lon, lat: f"{lon!r}"},
            "tracks.Placemark[0].LineString[0]",
            "lon,lat",
        ),
    ]


@pytest.mark.parametrize(("fmt", "kw", "field", "allowed"), _bad_cases(),
                         ids=["kml-off-map", "gpx-nan", "kml-entities", "kml-no-lat"])  # fmt: skip
def test_bad_kml_or_gpx_tracks_name_the_field_and_write_nothing(
    first, tmp_path, capsys, fmt, kw, field, allowed
):
    _, p1 = first
    plan = json.loads(p1.read_text())
    f = tmp_path / f"t.{fmt}"
    (_kml if fmt == "kml" else _gpx)(f, _lonlat_lines(plan), **kw)
    out = tmp_path / "next.json"
    assert main(["replan", "--plan", str(p1), "--tracks", str(f), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert field in err and allowed in err, err
    assert not out.exists()


def test_deeply_nested_or_foreign_xml_tracks_are_refused(first, tmp_path, capsys):
    from poc_env.agents.planning.replan import MAX_XML_DEPTH

    _, p1 = first
    out = tmp_path / "next.json"
    deep = tmp_path / "deep.kml"
    n = MAX_XML_DEPTH + 5
    deep.write_text('<kml xmlns="http://www.opengis.net/kml/2.2">' + "<Folder>" * n
                    + "</Folder>" * n + "</kml>")  # fmt: skip
    assert main(["replan", "--plan", str(p1), "--tracks", str(deep), "--out", str(out)]) == 2
    assert f"at most {MAX_XML_DEPTH} levels deep" in capsys.readouterr().err
    foreign = tmp_path / "t.gpx"
    foreign.write_text('<gpx xmlns="http://example.com/not-gpx"><trk/></gpx>')
    assert main(["replan", "--plan", str(p1), "--tracks", str(foreign), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "tracks.gpx" in err and "topografix" in err
    nested = tmp_path / "t.geojson"
    nested.write_text("[" * 200 + "]" * 200)
    assert main(["replan", "--plan", str(p1), "--tracks", str(nested), "--out", str(out)]) == 2
    assert "levels deep" in capsys.readouterr().err
    assert not out.exists()


def test_replan_of_a_yaml_scenario_finds_it_by_the_plan(tmp_path, monkeypatch, capsys):
    """Issue 24's property test: `replan --plan p1.json` of a plan made on a YAML scenario
    looked for the scenario by name only (an error unless the YAML lay in the current folder);
    it reads the plan's scenario_file, and the next plan records it for export's prior."""
    import yaml

    data = load_scenario("small").to_dict()
    data["name"] = "mine"
    data["map"]["origin_deg"] = [46.5, 7.9]
    (tmp_path / "scen").mkdir()
    yml = tmp_path / "scen" / "mine.yaml"
    yml.write_text(yaml.safe_dump(data))
    monkeypatch.chdir(tmp_path)  # neither the plans' folders nor this one hold mine.yaml
    p1, p2 = tmp_path / "s1" / "p1.json", tmp_path / "s2" / "p2.json"
    argv = ["plan", "--scenario", str(yml), "--planner", "allocation", "--refine", "0"]
    assert main([*argv, "--quiet", "--out", str(p1)]) == 0
    assert main(["replan", "--plan", str(p1), "--out", str(p2)]) == 0, capsys.readouterr().err
    assert load_plan(p2)["scenario_file"] == str(yml.resolve())
    assert main(["export", str(p2), "--format", "kml"]) == 0
    assert (tmp_path / "s2" / "p2_prior.png").is_file()  # the prior placed on the map


def test_gpx_segments_without_a_line_are_skipped(first, tmp_path):
    """Audit i24: a logger's GPX holds empty ``<trkseg/>`` (logging paused) and one-point
    segments (a fix between dropouts); both are valid GPX 1.1 and sweep no line. The whole file
    was refused (``trkseg[1].trkpt: got []; allowed: 2 or more [lon, lat]``); they are skipped
    and the other segments sweep what they swept alone. A file with no segment of two points
    is still refused."""
    from poc_env.agents.planning.replan import read_tracks

    _, p1 = first
    plan = json.loads(p1.read_text())
    lines = _lonlat_lines(plan)
    plain, gappy = tmp_path / "plain.gpx", tmp_path / "gappy.gpx"
    _gpx(plain, lines)
    _gpx(gappy, [lines[0], [], lines[0][2:3], *lines[1:]])
    want = read_tracks(plain, plan["crs"])
    got = read_tracks(gappy, plan["crs"])
    assert len(got) == len(want)
    for (_, a), (_, b) in zip(got, want):
        np.testing.assert_array_equal(a, b)
    _gpx(tmp_path / "none.gpx", [[], lines[0][:1]])
    with pytest.raises(ConfigError, match="at least one track of 2 or more points"):
        read_tracks(tmp_path / "none.gpx", plan["crs"])


def test_replan_says_which_flights_it_swept(first, tmp_path, capsys):
    """Audit i24: with ``--tracks`` the tracks stand for the flights of every ``--plan`` given
    (sortie 1's routes are not swept when only sortie 2's log is given). The command now says
    which flights it swept, so an officer replanning sortie 3 from sortie 2's log sees that
    sortie 1 is not in it."""
    _, p1 = first
    plan = json.loads(p1.read_text())
    p2 = tmp_path / "p2.json"
    assert main(["replan", "--plan", str(p1), "--out", str(p2)]) == 0
    assert f"swept: the routes of {p1}" in capsys.readouterr().out
    _gpx(tmp_path / "s2.gpx", _lonlat_lines(plan)[:1])
    argv = ["replan", "--plan", str(p1), "--plan", str(p2), "--tracks", str(tmp_path / "s2.gpx")]
    assert main([*argv, "--out", str(tmp_path / "p3.json")]) == 0
    out = capsys.readouterr().out
    assert f"swept: 1 track from {tmp_path / 's2.gpx'}, in place of the routes of {p1}, {p2}" in out


@pytest.mark.parametrize(
    "name",
    ["http://www.opengis.net/def/crs/OGC/1.3/CRS84", "epsg:4326", "urn:ogc:def:crs:EPSG:6.6:4326"],
)
def test_track_crs_names_are_the_import_s(first, tmp_path, name):
    """Audit i24: ``scenario import`` and ``replan --tracks`` each kept a list of the GeoJSON
    ``crs`` names meaning WGS 84; a layer declaring one of these was imported but its tracks
    were refused. One list now (:func:`poc_env.crs.is_wgs84_name`)."""
    from poc_env.agents.planning.replan import read_tracks

    _, p1 = first
    plan = json.loads(p1.read_text())
    crs = {"type": "name", "properties": {"name": name}}
    _tracks(tmp_path / "t.geojson", plan, crs=crs)
    assert len(read_tracks(tmp_path / "t.geojson", plan["crs"])) == len(plan["uavs"])


def test_replan_of_a_plan_whose_scenario_file_is_gone_says_where_it_looked(
    tmp_path, monkeypatch, capsys
):
    """Audit i24: a plan made on a YAML scenario, replanned after the YAML was moved, said only
    ``scenario: got 'mine'; allowed: a built-in name (...) or a path to a YAML file``; export
    of the same plan lists the files it looked for. ``replan`` now says the same (one text,
    :func:`poc_env.agents.mission.plan.scenario_not_found`) and names ``--scenario``."""
    import yaml

    data = load_scenario("small").to_dict()
    data["name"] = "mine"
    data["map"]["origin_deg"] = [46.5, 7.9]
    yml = tmp_path / "scen" / "mine.yaml"
    yml.parent.mkdir()
    yml.write_text(yaml.safe_dump(data))
    monkeypatch.chdir(tmp_path)
    p1 = tmp_path / "s1" / "p1.json"
    argv = ["plan", "--scenario", str(yml), "--planner", "allocation", "--refine", "0"]
    assert main([*argv, "--quiet", "--out", str(p1)]) == 0
    yml.rename(tmp_path / "scen" / "elsewhere.yaml")
    capsys.readouterr()
    assert main(["replan", "--plan", str(p1), "--out", str(tmp_path / "p2.json")]) == 2
    err = capsys.readouterr().err
    assert f"looked for {yml}" in err and "--scenario" in err, err
    assert not (tmp_path / "p2.json").exists()


def test_kml_gx_tracks_of_one_fix_are_skipped_like_gpx_segments(first, tmp_path):
    """Audit i24: a ``gx:Track`` (a logger's KML) may hold a single ``gx:coord``; like a GPX
    segment of one point it sweeps no line and is skipped, not a reason to refuse the file.
    A ``LineString`` needs two positions by the KML schema and is still checked."""
    from poc_env.agents.planning.replan import read_tracks

    _, p1 = first
    plan = json.loads(p1.read_text())
    lines = _lonlat_lines(plan)

    def track(pts):
        coords = "".join(f"<gx:coord>{lon!r} {lat!r} 1500</gx:coord>" for lon, lat in pts)
        return f"<Placemark><gx:Track>{coords}</gx:Track></Placemark>"

    kml = (
        '<?xml version="1.0"?><kml xmlns="http://www.opengis.net/kml/2.2" '
        'xmlns:gx="http://www.google.com/kml/ext/2.2"><Document>{}</Document></kml>'
    )
    f = tmp_path / "t.kml"
    f.write_text(kml.format(track(lines[0]) + track(lines[0][:1])))
    got = read_tracks(f, plan["crs"])
    assert len(got) == 1 and len(got[0][1]) == len(lines[0])
    f.write_text(kml.format(track(lines[0][:1])))
    with pytest.raises(ConfigError, match="at least one track of 2 or more points"):
        read_tracks(f, plan["crs"])


def test_geojson_points_and_areas_beside_the_tracks_are_skipped(first, tmp_path):
    """Audit i24 (noticed): a GeoJSON collection of a logger's tracks with its waypoints or the
    search area beside them was refused whole (``features[0].geometry.type: got 'Point'``), where
    KML's other placemarks and GPX's waypoints are skipped. Now skipped in a collection holding a
    line; a collection of points alone is still refused, naming the first."""
    from poc_env.agents.planning.replan import read_tracks

    _, p1 = first
    plan = json.loads(p1.read_text())
    lines = tmp_path / "lines.geojson"
    feats = _tracks(lines, plan)
    lon, lat = feats[0]["geometry"]["coordinates"][0]
    point = {
        "type": "Feature",
        "properties": {},
        "geometry": {"type": "Point", "coordinates": [lon, lat]},
    }
    ring = [[lon, lat], [lon + 0.1, lat], [lon + 0.1, lat + 0.1], [lon, lat]]
    area = {
        "type": "Feature",
        "properties": {},
        "geometry": {"type": "Polygon", "coordinates": [ring]},
    }
    mixed = tmp_path / "mixed.geojson"
    mixed.write_text(json.dumps({"type": "FeatureCollection", "features": [point, *feats, area]}))
    want = read_tracks(lines, plan["crs"])
    got = read_tracks(mixed, plan["crs"])
    assert [f for f, _ in got] == [
        f"tracks.features[{i + 1}].geometry.coordinates" for i in range(len(want))
    ]
    for (_, a), (_, b) in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)
    only = tmp_path / "points.geojson"
    only.write_text(json.dumps({"type": "FeatureCollection", "features": [point, point]}))
    with pytest.raises(ConfigError) as err:
        read_tracks(only, plan["crs"])
    assert err.value.field == "tracks.features[0].geometry.type" and err.value.value == "Point"


def test_plan_and_replan_of_a_moving_target_say_they_plan_a_standing_one(first, tmp_path, capsys):
    """Issue 25 audit: ``plan`` and ``replan`` on a scenario whose target drifts planned on the
    prior at take-off (replan: swept on it, no drift over the elapsed sortie) and printed the
    static bounds "for the environment" without a word. Both now warn, naming the model and
    the moving-target planners; a standing target gets no warning."""
    _, p1 = first
    drift = ["--overrides", "target.model=drift", "target.current_kmh=[25,0]"]
    out = tmp_path / "p.json"
    argv = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet"]
    assert main([*argv, *drift, "--out", str(out)]) == 0
    said = capsys.readouterr().err  # warnings on stderr (i24-missionfix)
    assert "warning: target.model 'drift'" in said and "spacetime_receding" in said
    assert main(["replan", "--plan", str(p1), *drift, "--out", str(tmp_path / "r.json")]) == 0
    said = capsys.readouterr().err
    assert "warning: target.model 'drift'" in said and "elapsed" in said
    assert main(["replan", "--plan", str(p1), "--out", str(tmp_path / "s.json")]) == 0
    assert "warning" not in capsys.readouterr().err


@pytest.mark.parametrize("fmt", ["kml", "geojson"])
def test_the_plans_own_export_as_tracks_sweeps_its_routes_once(first, tmp_path, capsys, fmt):
    """Terrain audit follow-up: the exporter draws each UAV's landing approach beside its route
    (KML style ``#landing_approach``, GeoJSON ``kind: landing_approach``); the route already
    flies to the field (over terrain its last leg is that very approach), so the approach is
    not a second flown track. ``replan --tracks`` of the plan's own export sweeps the routes
    once: the same POS as replanning from the plan, and it says what it skipped."""
    from poc_env.agents.mission.export import export_plan

    _, p1 = first
    plan = json.loads(p1.read_text())
    (f,) = [f for f in export_plan(p1, fmt, out_dir=tmp_path / "x") if f.suffix == "." + fmt]
    out = tmp_path / "next.json"
    argv = ["replan", "--scenario", "small", "--plan", str(p1), "--tracks", str(f)]
    assert main([*argv, "--out", str(out)]) == 0
    n = sum(1 for u in plan["uavs"] if u["waypoints_m"])
    text = capsys.readouterr().out
    assert f"swept: {n} track{'s' if n != 1 else ''} from {f}" in text
    assert f"{len(plan['uavs'])} landing-approach lines skipped" in text
    assert json.loads(out.read_text())["searched_pos"] == pytest.approx(plan["posc"], rel=1e-3)


def test_cumulative_pos_is_eq14_over_every_flight(first):
    """replan-audit: the next plan was scored by the planner on each cell's belief spread
    evenly over its sample points, though sortie 1 left it uneven within the cells, and
    ``cumulative_posc`` added that score to what sortie 1 found (Alps walkthrough: 0.8480
    promised, 0.8108 found by the two sorties' routes). The next sortie's POS is now its routes
    swept over the belief the flights left, point by point (``sortie_posc``), and
    ``cumulative_posc`` is eq. 14 over every flight, as sweeping them all from the prior."""
    from poc_env.agents.planning.replan import next_sortie, plan_paths

    _, p1 = first
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    a = json.loads(p1.read_text())
    b = next_sortie(sc, prior, [a], refine=0)
    _, one = searched_belief(sc, prior, plan_paths(a))
    _, both = searched_belief(sc, prior, plan_paths(a) + plan_paths(b))
    assert b["searched_pos"] == pytest.approx(one, abs=1e-12)
    assert b["sortie_posc"] == pytest.approx(both - one, abs=1e-9)
    assert b["cumulative_posc"] == pytest.approx(both, abs=1e-9)


def test_a_replanned_sortie_needs_the_plans_it_was_planned_after(first, tmp_path, capsys):
    """replan-audit: ``replan --plan p2.json`` alone (replan on its own output, sortie 1's plan
    forgotten) swept sortie 2's routes over the full prior and printed "sortie 2: the flights
    so far found 0.5763 ... cumulative 0.8322" -- sortie 1's search lost, its area planned
    again. A plan that records ``sortie: k`` must now be the k-th ``--plan``; plans made by
    ``plan`` (no ``sortie``) go anywhere (another seed flown as sortie 2 is a sortie)."""
    _, p1 = first
    p2, out = tmp_path / "p2.json", tmp_path / "p3.json"
    assert main(["replan", "--plan", str(p1), "--out", str(p2)]) == 0
    capsys.readouterr()
    assert main(["replan", "--plan", str(p2), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "plan.sortie: got 2" in err and "the 2nd --plan" in err
    assert main(["replan", "--plan", str(p2), "--plan", str(p1), "--out", str(out)]) == 2
    assert "plan[0].sortie: got 2" in capsys.readouterr().err
    assert not out.exists()


def test_replan_sweeps_the_prior_the_plan_was_made_on(tmp_path, capsys):
    """replan-audit: a plan made with ``--map prior.npy`` was replanned on the scenario's
    built-in prior (``--map`` not given again): sortie 1 "found" 0.6336 of the wrong prior
    where its routes find 0.6441 of its own (the plan's ``posc``), sortie 2 was planned on it
    and recorded ``map_source: builtin``
    (export then drew the wrong prior). replan now reads the plan's ``map_source``, records
    it, and refuses, naming ``map``, when that file is gone."""
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    f = tmp_path / "flipped.npy"
    np.save(f, prior[::-1, ::-1] / prior.sum())
    p1, p2 = tmp_path / "p1.json", tmp_path / "p2.json"
    argv = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet"]
    assert main([*argv, "--map", str(f), "--origin", "46.5,7.9", "--out", str(p1)]) == 0
    assert main(["replan", "--plan", str(p1), "--out", str(p2)]) == 0
    a, b = json.loads(p1.read_text()), json.loads(p2.read_text())
    assert b["searched_pos"] == pytest.approx(a["posc"], abs=1e-9)
    assert b["map_source"] == a["map_source"] == str(f)
    f.rename(tmp_path / "moved.npy")
    out = tmp_path / "p2b.json"
    capsys.readouterr()
    assert main(["replan", "--plan", str(p1), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: map: got") and str(f) in err and not out.exists()


def test_replan_origin_must_agree_with_the_plans_crs(first, tmp_path, capsys):
    """replan-audit: ``replan --tracks t.geojson --origin 46.6,7.95`` on a plan whose crs is at
    46.5, 7.9 ignored the origin without a word (export refuses it); it is now refused as
    export refuses it, naming ``origin``. For a plan that records no crs, ``--origin`` gives the
    tracks' frame and the next plan records it (export and the next replan need no origin)."""
    _, p1 = first
    plan = json.loads(p1.read_text())
    _tracks(tmp_path / "t.geojson", plan)
    out = tmp_path / "next.json"
    argv = ["replan", "--plan", str(p1), "--tracks", str(tmp_path / "t.geojson")]
    capsys.readouterr()
    assert main([*argv, "--origin", "46.6,7.95", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: origin: got") and "crs.origin_deg" in err and not out.exists()
    bare = {k: v for k, v in plan.items() if k != "crs"}
    (tmp_path / "bare.json").write_text(json.dumps(bare))
    argv[2] = str(tmp_path / "bare.json")
    assert main([*argv, "--origin", "46.5,7.9", "--out", str(out)]) == 0
    assert json.loads(out.read_text())["crs"] == plan["crs"]


def test_geojson_null_geometries_and_geometry_collections_are_read(first, tmp_path):
    """replan-audit: RFC 7946 lets a Feature's geometry be null (an unlocated feature: a GIS
    layer's row for a UAV that did not fly) and a GeometryCollection hold the lines; both were
    refused whole (``tracks.features[3].geometry.type: got None``, ``tracks.type: got
    'GeometryCollection'``). A null geometry beside lines is skipped as a Point is; a
    collection's lines are read, each named by its place; neither alone is a track."""
    from poc_env.agents.planning.replan import read_tracks

    _, p1 = first
    plan = json.loads(p1.read_text())
    lines = tmp_path / "lines.geojson"
    feats = _tracks(lines, plan)
    want = read_tracks(lines, plan["crs"])
    unlocated = {"type": "Feature", "properties": {"uav": 4}, "geometry": None}
    mixed = tmp_path / "mixed.geojson"
    mixed.write_text(json.dumps({"type": "FeatureCollection", "features": [*feats, unlocated]}))
    gc = {"type": "GeometryCollection", "geometries": [f["geometry"] for f in feats]}
    coll = tmp_path / "gc.geojson"
    coll.write_text(json.dumps({"type": "Feature", "properties": {}, "geometry": gc}))
    for path, names in [
        (mixed, [f"tracks.features[{i}].geometry.coordinates" for i in range(len(feats))]),
        (coll, [f"tracks.geometry.geometries[{i}].coordinates" for i in range(len(feats))]),
    ]:
        got = read_tracks(path, plan["crs"])
        assert [f for f, _ in got] == names
        for (_, a), (_, b) in zip(got, want, strict=True):
            np.testing.assert_array_equal(a, b)
    alone = tmp_path / "alone.geojson"
    alone.write_text(json.dumps({"type": "FeatureCollection", "features": [unlocated] * 2}))
    with pytest.raises(ConfigError) as err:
        read_tracks(alone, plan["crs"])
    assert err.value.field == "tracks.features[0].geometry.type" and err.value.value is None


@pytest.mark.parametrize(
    "old, new",
    [  # GPX 1.0 written with a namespace prefix; KML 2.3 (OGC 12-007r2, the current standard)
        ("<gpx ", "<g:gpx xmlns:g='http://www.topografix.com/GPX/1/0' "),
        ("kml/2.2", "kml/2.3"),
    ],
)
def test_gpx_with_a_prefix_and_kml_2_3_are_read(first, tmp_path, old, new):
    """replan-audit: a GPX file whose elements carry a namespace prefix was refused as having
    no ``trk/trkseg/trkpt`` (the reader looked in the default namespace only), and a KML 2.3
    file for its namespace; both read now, the same tracks as the plain files."""
    from poc_env.agents.planning.replan import read_tracks

    _, p1 = first
    plan = json.loads(p1.read_text())
    gpx = old.startswith("<gpx")
    plain = tmp_path / ("plain.gpx" if gpx else "plain.kml")
    (_gpx if gpx else _kml)(plain, _lonlat_lines(plan))
    text = plain.read_text().replace(old, new)
    if gpx:  # every element in the prefixed namespace; the 1.1 default declaration dropped
        text = text.replace(' xmlns="http://www.topografix.com/GPX/1/1"', "")
        text = text.replace("<", "<g:").replace("<g:/", "</g:").replace("<g:?", "<?")
        text = text.replace("<g:g:", "<g:").replace("</g:g:", "</g:")
    other = tmp_path / plain.name.replace("plain", "other")
    other.write_text(text)
    want, got = read_tracks(plain, plan["crs"]), read_tracks(other, plan["crs"])
    assert [f for f, _ in got] == [f for f, _ in want] and len(got) == len(_lonlat_lines(plan))
    for (_, a), (_, b) in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_track_off_the_area_is_named_in_degrees_and_a_swap_is_suspected(first, tmp_path, capsys):
    """replan-audit: GeoJSON written in lat, lon order (a common slip) was refused as
    ``got [4493731.8, -3360645.2]; allowed: a point in metres inside the operating area``: the
    metres of a point the officer wrote in degrees. The error now gives the point as read
    (lon, lat) and its distance from the area, and says when swapping the two would put it
    inside; a point merely far off gets no such hint."""
    _, p1 = first
    plan = json.loads(p1.read_text())
    feats = _tracks(tmp_path / "t.geojson", plan)
    for f in feats:
        f["geometry"]["coordinates"] = [[lat, lon] for lon, lat in f["geometry"]["coordinates"]]
    swapped = tmp_path / "swapped.geojson"
    swapped.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    out = tmp_path / "next.json"
    argv = ["replan", "--plan", str(p1), "--out", str(out), "--tracks"]
    capsys.readouterr()
    assert main([*argv, str(swapped)]) == 2
    err = capsys.readouterr().err
    a, b = feats[0]["geometry"]["coordinates"][0]  # the file's first pair: lat, lon by mistake
    assert err.startswith("error: tracks.features[0].geometry.coordinates[0]: got 'lon ")
    assert f"'lon {a:.5f}, lat {b:.5f}'" in err and "km from it" in err
    assert "lat, lon order" in err
    far = tmp_path / "far.geojson"
    _tracks(far, plan)
    text = json.loads(far.read_text())
    text["features"][1]["geometry"]["coordinates"][2] = [30.0, 47.5]  # ~1,700 km off
    far.write_text(json.dumps(text))
    assert main([*argv, str(far)]) == 2
    err = capsys.readouterr().err
    assert "tracks.features[1].geometry.coordinates[2]: got 'lon 30.00000, lat 47.50000'" in err
    assert "lat, lon order" not in err and not out.exists()


def test_flights_of_a_plan_in_another_frame_are_swept_where_they_were_flown(tmp_path, capsys):
    """replan-audit: the search area re-imported a little larger (``scenario import`` over the
    same YAML: the map's origin moved 5.6 km south) and sortie 1's plan, in the old frame, was
    swept in the new map's metres -- 5.6 km off where it was flown (Alps: found 0.4888 for
    0.6645) -- and sortie 2's plan, made in the new frame, recorded the old frame's crs, so
    its export put every route 5.6 km off. A plan whose crs is not the scenario's frame is now
    carried over through longitude/latitude, and the next plan records the scenario's frame."""
    from poc_env.agents.planning.replan import plan_paths
    from poc_env.crs import to_local

    old, new = "map.origin_deg=[46.5,7.9]", "map.origin_deg=[46.45,7.9]"
    p1, p2 = tmp_path / "p1.json", tmp_path / "p2.json"
    argv = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet"]
    assert main([*argv, "--overrides", old, "--out", str(p1)]) == 0
    capsys.readouterr()
    assert main(["replan", "--plan", str(p1), "--overrides", new, "--out", str(p2)]) == 0
    assert "carried through longitude/latitude into this map's" in capsys.readouterr().out
    a, b = json.loads(p1.read_text()), json.loads(p2.read_text())
    assert a["crs"]["origin_deg"] == [46.5, 7.9] and b["crs"]["origin_deg"] == [46.45, 7.9]
    sc = load_scenario("small", parse_overrides([new]))
    flown = [np.array(to_local(to_geographic(p, a["crs"]), b["crs"])) for p in plan_paths(a)]
    assert abs(flown[0][0][1] - plan_paths(a)[0][0][1] - 5560) < 10  # 5.6 km north in the new map
    _, want = searched_belief(sc, build_prior(sc.map), flown)
    assert b["searched_pos"] == pytest.approx(want, abs=1e-9)


def test_kmz_tracks_are_read_as_their_kml(first, tmp_path):
    """replan-audit: Google Earth and QGC save KMZ (EXPORT.md even zips the exported KML into
    one); ``--tracks flown.kmz`` was refused for its suffix. Its KML (``doc.kml``, else the
    first ``.kml`` in the archive, as KML 2.2 says) is read now, the same tracks; an archive
    without one, or not a zip, is refused naming ``tracks``."""
    import zipfile

    from poc_env.agents.planning.replan import read_tracks

    _, p1 = first
    plan = json.loads(p1.read_text())
    kml = tmp_path / "flown.kml"
    _kml(kml, _lonlat_lines(plan))
    want = read_tracks(kml, plan["crs"])
    kmz = tmp_path / "flown.kmz"
    with zipfile.ZipFile(kmz, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("files/prior.png", b"\x89PNG")
        z.writestr("doc.kml", kml.read_text())
    got = read_tracks(kmz, plan["crs"])
    assert [f for f, _ in got] == [f for f, _ in want]
    for (_, a), (_, b) in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)
    empty = tmp_path / "empty.kmz"
    with zipfile.ZipFile(empty, "w") as z:
        z.writestr("prior.png", b"\x89PNG")
    for bad in (empty, kml.rename(tmp_path / "plain.kmz")):
        with pytest.raises(ConfigError) as err:
            read_tracks(bad, plan["crs"])
        assert err.value.field == "tracks" and "KMZ" in err.value.allowed


def test_geojson_positions_with_and_without_altitude_are_read(first, tmp_path):
    """replan-audit: RFC 7946 positions hold 2 or 3 numbers; a line mixing both (a logger that
    lost its altitude fix for a while) was refused as ``coordinates: got 'array'``. Each
    position's lon, lat is read now; a position that is not numbers is named by its index."""
    from poc_env.agents.planning.replan import read_tracks

    _, p1 = first
    plan = json.loads(p1.read_text())
    lines = tmp_path / "lines.geojson"
    feats = _tracks(lines, plan)
    want = read_tracks(lines, plan["crs"])
    for f in feats:
        cs = f["geometry"]["coordinates"]
        f["geometry"]["coordinates"] = [[*c, 1500.0] if k % 2 else c for k, c in enumerate(cs)]
    mixed = tmp_path / "mixed.geojson"
    mixed.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    got = read_tracks(mixed, plan["crs"])
    for (_, a), (_, b) in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)
    feats[1]["geometry"]["coordinates"][3] = [8.0, "46.5", 1500.0]
    mixed.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    with pytest.raises(ConfigError) as err:
        read_tracks(mixed, plan["crs"])
    assert err.value.field == "tracks.features[1].geometry.coordinates[3]"


def test_exports_of_a_replanned_sortie_show_what_it_finds_and_the_cumulative_pos(first, tmp_path):
    """A replanned plan's ``posc`` is the planner's model (each cell's belief spread evenly);
    what its routes find on the belief the flights left is ``sortie_posc`` and the search so
    far ``cumulative_posc`` (replan-audit): the report and the GeoJSON give those two."""
    from poc_env.agents.mission.export import export_plan

    _, p1 = first
    p2 = tmp_path / "p2.json"
    assert main(["replan", "--scenario", "small", "--plan", str(p1), "--out", str(p2)]) == 0
    plan = json.loads(p2.read_text())
    assert abs(plan["posc"] - plan["sortie_posc"]) >= 5e-5  # the two differ here
    (gj,) = export_plan(p2, "geojson", None, tmp_path / "gj")
    props = json.loads(gj.read_text())["properties"]
    assert props["sortie"] == 2
    assert props["sortie_posc_pct"] == round(100 * plan["sortie_posc"], 2)
    assert props["cumulative_posc_pct"] == round(100 * plan["cumulative_posc"], 2)
    (html,) = export_plan(p2, "html", None, tmp_path / "html")
    text = html.read_text()
    assert f"sortie 2: POS_C {100 * plan['sortie_posc']:.2f} %" in text
    assert f"cumulative {100 * plan['cumulative_posc']:.2f} %" in text
    (gj1,) = export_plan(p1, "geojson", None, tmp_path / "gj1")  # a first sortie: as before
    assert "sortie_posc_pct" not in json.loads(gj1.read_text())["properties"]


@pytest.mark.parametrize(
    ("key", "value"),
    [("sortie_posc", "x"), ("sortie_posc", float("nan")), ("cumulative_posc", 1.5),
     ("cumulative_posc", None)],
)  # fmt: skip
def test_a_replanned_sortie_s_figures_are_checked_before_an_export(first, tmp_path, key, value):
    """A hand-edited replanned plan whose sortie figures are not probabilities is refused by
    the export, naming the field (it was a ValueError/KeyError traceback, or 'nan %' printed)."""
    from poc_env.agents.mission.export import export_plan

    _, p1 = first
    p2 = tmp_path / "p2.json"
    assert main(["replan", "--scenario", "small", "--plan", str(p1), "--out", str(p2)]) == 0
    plan = json.loads(p2.read_text())
    if value is None:
        del plan[key]
    else:
        plan[key] = value
    p2.write_text(json.dumps(plan))
    with pytest.raises(ConfigError) as err:
        export_plan(p2, "geojson", None, tmp_path / "gj")
    assert err.value.field == f"plan.{key}"
    assert not (tmp_path / "gj").exists()


def test_replan_takes_plan_s_effort(first, tmp_path, capsys):
    """i24-walkstandard: ``replan --effort standard`` plans the next sortie as ``plan --effort
    standard`` plans (the default plan polished; the SAR walkthrough replans so), the default
    without it; ``--effort`` with the DE planner is refused as ``plan`` refuses it, nothing
    written."""
    _, p1 = first
    base = ["replan", "--scenario", "small", "--plan", str(p1)]
    outs = {e: tmp_path / f"p2_{e}.json" for e in ("default", "standard")}
    assert main([*base, "--out", str(outs["default"])]) == 0
    assert main([*base, "--effort", "standard", "--out", str(outs["standard"])]) == 0
    plain, polished = (json.loads(p.read_text()) for p in outs.values())
    assert not plain["optimizer"]["settings"].get("polish")
    assert polished["optimizer"]["settings"]["polish"]["moves"] > 0
    assert polished["posc"] > plain["posc"]
    assert polished["searched_pos"] == plain["searched_pos"]  # the same flights swept
    bad = tmp_path / "p2_de.json"
    capsys.readouterr()
    assert main([*base, "--planner", "de", "--effort", "standard", "--out", str(bad)]) != 0
    err = capsys.readouterr().err
    assert "effort" in err and "standard" in err and "allocation" in err
    assert not bad.exists()


def test_replan_takes_the_floor_per_flight_hour_as_plan_does(first, tmp_path, capsys):
    """i24-leftovers, item 1: ``replan --gain-per-hour G`` plans the next sortie with the floor
    G (recorded in the plan's options, as ``plan --gain-per-hour`` records it); a bad G is
    refused naming the option before any planning, and so is G with the DE planner, nothing
    written."""
    _, p1 = first
    out = tmp_path / "p2.json"
    argv = ["replan", "--plan", str(p1), "--out", str(out)]
    assert main([*argv, "--gain-per-hour", "0.005"]) == 0, capsys.readouterr().err
    assert json.loads(out.read_text())["optimizer"]["settings"]["options"] == {
        "gain_per_hour": 0.005
    }
    out.unlink()
    assert main([*argv, "--gain-per-hour", "0.02"]) == 2
    err = capsys.readouterr().err
    assert "gain_per_hour: got 0.02; allowed: a number in [0, 0.01]" in err, err
    assert main([*argv, "--gain-per-hour", "0", "--planner", "de"]) == 2
    err = capsys.readouterr().err
    assert "gain_per_hour" in err and "only with planner allocation" in err, err
    assert not out.exists()
