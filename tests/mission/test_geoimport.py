"""Geographic scenarios in (issue 14): GeoJSON/KML/GeoTIFF/CSV -> scenario YAML + .npy + CRS.

Every fixture is generated here (tmp_path): a search area around 45.7 N 126.6 E, a GeoTIFF
with a Gaussian blob written by rasterio, airfields and no-fly zones.
"""

from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from pyproj import Transformer

from poc_env.agents.mission import geoimport
from poc_env.agents.mission.geoimport import (
    add_scenario_import_arguments,
    cmd_scenario_import,
    import_scenario,
    write_imported,
)
from poc_env.config import load_scenario
from poc_env.errors import ConfigError, GeometryError
from poc_env.theory.probability_map import build_prior

# a 1.2 deg x 0.8 deg area (about 94 km x 89 km) around 45.7 N 126.6 E
AREA = [[126.0, 45.3], [127.2, 45.3], [127.2, 46.1], [126.0, 46.1], [126.0, 45.3]]
BLOB = (45.75, 126.7)  # lat, lon of the blob's centre
FIELDS = [("Harbin", 126.25, 45.62), ("Acheng", 126.95, 45.25)]
ZONE = [[126.4, 45.9], [126.4, 46.0], [126.6, 46.0], [126.6, 45.9], [126.4, 45.9]]


def _fc(features: list) -> dict:
    return {"type": "FeatureCollection", "features": features}


def _poly(rings: list, **props) -> dict:
    return {
        "type": "Feature",
        "properties": props,
        "geometry": {"type": "Polygon", "coordinates": rings},
    }


def _pt(lon: float, lat: float, **props) -> dict:
    geom = {"type": "Point", "coordinates": [lon, lat]}
    return {"type": "Feature", "properties": props, "geometry": geom}


def _write(path: Path, doc: dict) -> Path:
    path.write_text(json.dumps(doc))
    return path


def _tif(path: Path, *, crs: str | None = "EPSG:4326", lon0=125.8, lat1=46.3, w=170, h=120):
    rasterio = pytest.importorskip("rasterio")
    from affine import Affine

    res = 0.01
    lons = lon0 + (np.arange(w) + 0.5) * res
    lats = lat1 - (np.arange(h) + 0.5) * res
    lon, lat = np.meshgrid(lons, lats)
    z = np.exp(-(((lon - BLOB[1]) / 0.12) ** 2 + ((lat - BLOB[0]) / 0.08) ** 2) / 2)
    z /= z.sum()
    kw = {"crs": crs} if crs else {}
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=w,
        height=h,
        count=1,
        dtype="float64",
        transform=Affine(res, 0.0, lon0, 0.0, -res, lat1),
        **kw,
    ) as dst:
        dst.write(z, 1)
    return path, float(z.sum())


@pytest.fixture
def layers(tmp_path: Path) -> dict[str, Path]:
    return {
        "area": _write(tmp_path / "area.geojson", _fc([_poly([AREA], name="search")])),
        "fields": _write(
            tmp_path / "fields.geojson", _fc([_pt(lon, lat, name=n) for n, lon, lat in FIELDS])
        ),
        "zones": _write(tmp_path / "zones.geojson", _fc([_poly([ZONE])])),
    }


def _centre_of_mass(m: np.ndarray, sc) -> tuple[float, float]:
    c = sc.map.cell_m
    x0, y0 = sc.map.origin_m
    ys, xs = np.mgrid[0 : m.shape[0], 0 : m.shape[1]]
    return (
        float((m * (x0 + (xs + 0.5) * c)).sum()),
        float((m * (y0 + (ys + 0.5) * c)).sum()),
    )


def test_geotiff_round_trip(tmp_path, layers, monkeypatch):
    tif, raster_total = _tif(tmp_path / "prior.tif")
    res = import_scenario(
        layers["area"], prior=tif, airfields=layers["fields"], no_fly=layers["zones"], name="my"
    )
    files = write_imported(res, tmp_path / "my.yaml")
    assert [f.name for f in files] == ["my.yaml", "my.npy", "my.crs.json"]
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # prior.file is read relative to the YAML's folder
    sc = load_scenario(str(tmp_path / "my.yaml"))
    prior = build_prior(sc.map)
    assert prior.shape == (sc.map.ny, sc.map.nx)
    assert abs(prior.sum() - 1.0) < 1e-9
    # mass conserved: kept + outside = the raster's total, to 1e-9
    rep = res["report"]["prior"]
    assert abs(rep["inside"] + rep["outside"] - raster_total) < 1e-9
    assert rep["outside_share"] < 0.01
    # the default origin is the area's south-west corner; the CRS is recorded
    crs = json.loads((tmp_path / "my.crs.json").read_text())
    assert crs["kind"] == "aeqd" and crs["origin_deg"] == [45.3, 126.0]
    assert "lat 45.3, lon 126.0" in (tmp_path / "my.yaml").read_text()
    # the scenario carries its geography: a plan records the same CRS without --origin
    assert sc.map.origin_deg == (45.3, 126.0) and sc.map.projection == "aeqd"
    from poc_env.agents.planning.planner import make_plan

    plan = make_plan(str(tmp_path / "my.yaml"), popsize=4, maxiter=1)
    assert plan["crs"] == crs
    with pytest.raises(ConfigError, match=r"origin: got .*map.origin_deg \[45.3, 126.0\]"):
        make_plan(str(tmp_path / "my.yaml"), popsize=4, maxiter=1, origin_deg=(45.0, 126.0))
    fwd = Transformer.from_crs("EPSG:4326", crs["proj"], always_xy=True)
    # the centre of mass lands within one cell of the blob's projected centre
    bx, by = fwd.transform(BLOB[1], BLOB[0])
    cx, cy = _centre_of_mass(prior, sc)
    assert np.hypot(cx - bx, cy - by) < sc.map.cell_m
    # airfields: local km match pyproj to < 1 m
    for (name, lon, lat), af in zip(FIELDS, sc.airfields):
        ex, ey = fwd.transform(lon, lat)
        assert af.name == name
        assert np.hypot(af.position_m[0] - ex, af.position_m[1] - ey) < 1.0
    # the grid covers the area; the no-fly zone is in the scenario
    zx, zy = fwd.transform([p[0] for p in AREA], [p[1] for p in AREA])
    x0, y0 = sc.map.origin_m
    assert x0 <= min(zx) and y0 <= min(zy)
    assert x0 + sc.map.width_m >= max(zx) and y0 + sc.map.height_m >= max(zy)
    assert len(sc.map.no_fly_zones_m) == 1
    assert sc.n_uavs == 6 and {g.takeoff for g in sc.fleet} == {"Harbin", "Acheng"}


def test_csv_prior_and_origin(tmp_path, layers):
    rng = np.random.default_rng(3)
    lat = BLOB[0] + 0.05 * rng.standard_normal(400)
    lon = BLOB[1] + 0.05 * rng.standard_normal(400)
    p = rng.uniform(0.5, 1.5, 400)
    lines = ["lat,lon,probability"] + [f"{a},{b},{c}" for a, b, c in zip(lat, lon, p)]
    lines.append("47.5,126.5,50")  # outside the area: dropped and reported
    csv_path = tmp_path / "prior.csv"
    csv_path.write_text("\n".join(lines) + "\n")
    with pytest.warns(UserWarning, match="outside the search area"):
        res = import_scenario(
            layers["area"], prior=csv_path, airfields=layers["fields"], origin="45.7,126.6"
        )
    rep = res["report"]["prior"]
    assert abs(rep["outside"] - 50) < 1e-9 and abs(rep["inside"] - p.sum()) < 1e-9
    assert abs(res["prior"].sum() - 1.0) < 1e-12
    assert res["crs"]["origin_deg"] == [45.7, 126.6]
    origin_km = res["scenario"]["map"]["origin_km"]
    assert origin_km[0] < 0 and origin_km[1] < 0 and origin_km[0] % 5 == 0
    # every point binned into the cell that contains it
    fwd = Transformer.from_crs("EPSG:4326", res["crs"]["proj"], always_xy=True)
    x, y = fwd.transform(lon, lat)
    ix = np.floor((np.asarray(x) / 1000 - origin_km[0]) / 5).astype(int)
    iy = np.floor((np.asarray(y) / 1000 - origin_km[1]) / 5).astype(int)
    expect = np.zeros_like(res["prior"])
    np.add.at(expect, (iy, ix), p)
    np.testing.assert_allclose(res["prior"], expect / p.sum(), atol=1e-12)


def test_kml_and_clockwise_winding_and_uniform_prior(tmp_path, layers):
    ring = " ".join(f"{lon},{lat},0" for lon, lat in reversed(AREA))  # clockwise
    kml = (
        '<?xml version="1.0"?><kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        f"<Placemark><name>area</name><Polygon><outerBoundaryIs><LinearRing><coordinates>{ring}"
        "</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark></Document></kml>"
    )
    (tmp_path / "area.kml").write_text(kml)
    fields = "".join(
        f"<Placemark><name>{n}</name><Point><coordinates>{lon},{lat}</coordinates></Point>"
        "</Placemark>"
        for n, lon, lat in FIELDS
    )
    (tmp_path / "fields.kml").write_text(f"<kml><Document>{fields}</Document></kml>")
    a = import_scenario(tmp_path / "area.kml", airfields=tmp_path / "fields.kml")
    b = import_scenario(layers["area"], airfields=layers["fields"])
    assert a["scenario"]["map"] == {**b["scenario"]["map"]}
    assert a["scenario"]["airfields"] == b["scenario"]["airfields"]
    np.testing.assert_allclose(a["prior"], b["prior"])
    assert a["prior"].max() > 0 and abs(a["prior"].sum() - 1) < 1e-12


def test_cli_writes_the_set_atomically(tmp_path, layers, capsys, monkeypatch):
    p = argparse.ArgumentParser()
    add_scenario_import_arguments(p)
    out = tmp_path / "out" / "sc.yaml"
    args = p.parse_args(
        [str(layers["area"]), "--airfields", str(layers["fields"]), "--out", str(out)]
    )
    assert cmd_scenario_import(args) == 0
    assert "wrote" in capsys.readouterr().out
    assert sorted(f.name for f in out.parent.iterdir()) == ["sc.crs.json", "sc.npy", "sc.yaml"]
    before = {f.name: f.read_bytes() for f in out.parent.iterdir()}

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(geoimport.np, "save", boom)
    args.cell_km = 2.5
    with pytest.raises(OSError):
        cmd_scenario_import(args)
    # nothing new published, nothing left behind: the old set is intact
    assert {f.name: f.read_bytes() for f in out.parent.iterdir()} == before


# --------------------------------------------------------------------------- bad input
def _bad(tmp_path, layers, match, err=ConfigError, **kw):
    args = {"airfields": layers["fields"]}
    args.update(kw)
    area = args.pop("area", layers["area"])
    with pytest.raises(err, match=match):
        import_scenario(area, **args)


def test_bad_polygons(tmp_path, layers):
    bow = [[126.0, 45.3], [127.2, 46.1], [127.2, 45.3], [126.0, 46.1], [126.0, 45.3]]
    f = _write(tmp_path / "bow.geojson", _fc([_poly([AREA]), _poly([bow])]))
    _bad(tmp_path, layers, r"bow\.geojson feature 1: invalid polygon", GeometryError, no_fly=f)
    hole = [[126.5, 45.5], [126.7, 45.5], [126.7, 45.7], [126.5, 45.5]]
    f = _write(tmp_path / "hole.geojson", _poly([AREA, hole]))
    _bad(tmp_path, layers, r"hole\.geojson feature 0: a polygon with 1 hole", GeometryError, area=f)
    swapped = [[lat, lon] for lon, lat in AREA]
    f = _write(tmp_path / "sw.geojson", _fc([_poly([swapped])]))
    _bad(tmp_path, layers, r"sw\.geojson feature 0 vertex 0.*swapped", area=f)
    doc = _fc([_poly([AREA])])
    doc["crs"] = {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::99999"}}
    f = _write(tmp_path / "bad_crs.geojson", doc)
    _bad(tmp_path, layers, r"bad_crs\.geojson crs: got .*EPSG::99999.*pyproj", area=f)
    doc["crs"]["properties"]["name"] = "urn:ogc:def:crs:OGC:1.3:CRS84"
    f = _write(tmp_path / "ok.geojson", doc)
    import_scenario(f, airfields=layers["fields"])  # the declared WGS84 crs is accepted
    f = _write(tmp_path / "two.geojson", _fc([_poly([AREA]), _poly([ZONE])]))
    _bad(tmp_path, layers, r"2 polygons.*exactly one Polygon", area=f)
    f = _write(tmp_path / "pt.geojson", _fc([_pt(126.5, 45.5)]))
    _bad(tmp_path, layers, r"pt\.geojson feature 0.*a Polygon", area=f)


def test_a_layer_in_a_projected_geojson_crs_is_reprojected(tmp_path, layers):
    """Leftovers #4: a GeoJSON of 2008 style whose ``crs`` member is Web Mercator (positions in
    metres) is reprojected by pyproj and imports as the same area in longitude/latitude does
    (before: refused, 'reproject the layer to EPSG:4326 in your GIS first')."""
    from pyproj import Transformer

    merc = Transformer.from_crs("EPSG:4326", "EPSG:3857", always_xy=True)
    doc = _fc([_poly([[list(merc.transform(lon, lat)) for lon, lat in AREA]])])
    doc["crs"] = {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::3857"}}
    f = _write(tmp_path / "merc.geojson", doc)
    got = import_scenario(f, airfields=layers["fields"])
    want = import_scenario(layers["area"], airfields=layers["fields"])
    assert np.allclose(got["crs"]["origin_deg"], want["crs"]["origin_deg"], atol=1e-9)
    assert got["report"]["area_km2"] == pytest.approx(want["report"]["area_km2"], rel=1e-9)
    assert got["report"]["cells"] == want["report"]["cells"]


def test_bad_points(tmp_path, layers):
    f = _write(
        tmp_path / "f.geojson", _fc([_pt(126.3, 45.6, name="A"), _pt(45.6, 126.3, name="B")])
    )
    _bad(tmp_path, layers, r"f\.geojson feature 1 vertex 0.*swapped", airfields=f)
    f = _write(tmp_path / "far.geojson", _fc([_pt(2.35, 48.85, name="Paris")]))
    _bad(tmp_path, layers, r"far\.geojson feature 0.*within 1000 km", airfields=f)
    f = _write(tmp_path / "sw2.geojson", _fc([_pt(46.0, 47.0, name="X")]))
    # (lat 47, lon 46) is far; read as (lat 46, lon 47)... also far: no swap hint
    _bad(tmp_path, layers, r"sw2\.geojson feature 0.*km away\)$", airfields=f)
    f = _write(tmp_path / "noname.geojson", _fc([_pt(126.3, 45.6)]))
    _bad(tmp_path, layers, r"noname\.geojson feature 0 name", airfields=f)
    f = _write(
        tmp_path / "dup.geojson", _fc([_pt(126.3, 45.6, name="A"), _pt(126.4, 45.6, name="A")])
    )
    _bad(tmp_path, layers, r"distinct airfield names", airfields=f)
    inside = _write(tmp_path / "in.geojson", _fc([_pt(126.5, 45.95, name="A")]))
    _bad(
        tmp_path,
        layers,
        r"airfields\[A\].*outside no-fly zone 0",
        airfields=inside,
        no_fly=layers["zones"],
    )


def test_bad_files(tmp_path, layers):
    (tmp_path / "empty.geojson").write_text("")
    _bad(tmp_path, layers, r"area: got '.*empty\.geojson'.*it is an empty file",
         area=tmp_path / "empty.geojson")  # fmt: skip
    (tmp_path / "area.shp").write_text("x")
    _bad(tmp_path, layers, r"area: got '.*area\.shp'.*geojson.*it ends in '\.shp'",
         area=tmp_path / "area.shp")  # fmt: skip
    _bad(tmp_path, layers, r"area: got .*it does not exist", area=tmp_path / "nope.geojson")
    (tmp_path / "junk.geojson").write_text("{not json")
    _bad(tmp_path, layers, r"junk\.geojson: got 'not JSON", area=tmp_path / "junk.geojson")
    (tmp_path / "p.png").write_text("x")
    _bad(tmp_path, layers, r"prior: got .*p\.png.*\.tif / \.tiff / \.csv", prior=tmp_path / "p.png")
    (tmp_path / "bomb.kml").write_text('<!DOCTYPE kml [<!ENTITY a "x">]><kml/>')
    _bad(tmp_path, layers, r"bomb\.kml.*no DTD", area=tmp_path / "bomb.kml")


@pytest.mark.parametrize(
    "text, match",
    [
        ("lat,lon\n45.7,126.6\n", r"p\.csv header.*missing: \['probability'\]"),
        ("45.7,126.6,1\n", r"p\.csv header"),
        ("lat,lon,probability\n45.7,east,1\n", r"p\.csv line 2 lon: got 'east'"),
        ("lat,lon,probability\n45.7,126.6,nan\n", r"p\.csv line 2 probability"),
        ("lat,lon,probability\n45.7,126.6,-1\n", r"p\.csv line 2 probability: got -1"),
        ("lat,lon,probability\n126.6,45.7,1\n", r"p\.csv line 2 lat.*swapped"),
        ("lat,lon,probability\n", r"p\.csv: got 'a header and no data rows'"),
        ("lat,lon,probability\n47.5,126.6,1\n", r"no probability mass inside the area"),
    ],
)
def test_bad_csv(tmp_path, layers, text, match):
    (tmp_path / "p.csv").write_text(text)
    _bad(tmp_path, layers, match, prior=tmp_path / "p.csv")


def test_csv_lat_lon_swapped_columns_detected(tmp_path):
    # an area where both readings are valid coordinates: (lat 40, lon 60) vs (lat 60, lon 40)
    area = [[59.5, 39.5], [60.5, 39.5], [60.5, 40.5], [59.5, 40.5], [59.5, 39.5]]
    a = _write(tmp_path / "a.geojson", _poly([area]))
    f = _write(tmp_path / "f.geojson", _fc([_pt(60.0, 40.0, name="F")]))
    (tmp_path / "p.csv").write_text("lat,lon,probability\n60.0,40.0,1\n60.1,40.1,1\n")
    with pytest.raises(ConfigError, match=r"p\.csv.*swapped"):
        import_scenario(a, airfields=f, prior=tmp_path / "p.csv")


def test_bad_geotiff(tmp_path, layers):
    tif, _ = _tif(tmp_path / "nocrs.tif", crs=None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # rasterio: "Dataset has no geotransform..." variants
        _bad(tmp_path, layers, r"nocrs\.tif crs: got None", prior=tif)
    tif, _ = _tif(tmp_path / "small.tif", w=60)  # ends at 126.4 E, the area at 127.2 E
    _bad(
        tmp_path,
        layers,
        r"small\.tif: got 'a raster covering about 3\d% of the search area'",
        prior=tif,
    )
    (tmp_path / "junk.tif").write_bytes(b"not a tiff")
    _bad(tmp_path, layers, r"junk\.tif: got .unreadable", prior=tmp_path / "junk.tif")


def test_import_needs_airfields_and_sane_options(tmp_path, layers):
    with pytest.raises(ConfigError, match=r"^airfields"):
        import_scenario(layers["area"])
    _bad(tmp_path, layers, r"^cell_km", cell_km=-1)
    _bad(tmp_path, layers, r"^name", name="../x")
    _bad(tmp_path, layers, r"^origin", origin="126.6,45.7")
    with pytest.raises(ConfigError, match=r"^out"):
        write_imported(
            import_scenario(layers["area"], airfields=layers["fields"]), tmp_path / "x.txt"
        )


def test_geotiff_sub_pixels_on_a_fine_grid(tmp_path, layers):
    # 2 km cells: sub-pixels of at most 0.5 km, so each 0.01 deg pixel is cut 3 x 3
    tif, raster_total = _tif(tmp_path / "prior.tif")
    res = import_scenario(layers["area"], prior=tif, airfields=layers["fields"], cell_km=2.0)
    rep = res["report"]["prior"]
    # pixels whose 3 x 3 sub-pixels were projected (those near the area) + 1 for the far mass
    assert (rep["samples"] - 1) % 9 == 0 and 100 * 80 * 9 < rep["samples"] < 170 * 120 * 9
    assert abs(rep["inside"] + rep["outside"] - raster_total) < 1e-9
    assert abs(res["prior"].sum() - 1.0) < 1e-9
    fwd = Transformer.from_crs("EPSG:4326", res["crs"]["proj"], always_xy=True)
    bx, by = fwd.transform(BLOB[1], BLOB[0])
    sc = load_scenario(res["scenario"])
    cx, cy = _centre_of_mass(res["prior"], sc)
    assert np.hypot(cx - bx, cy - by) < 2000.0


def test_geotiff_in_a_projected_crs(tmp_path, layers):
    # a UTM zone 52N raster (1 km pixels): the raster CRS -> WGS84 -> local path
    rasterio = pytest.importorskip("rasterio")
    from affine import Affine

    utm = Transformer.from_crs("EPSG:4326", "EPSG:32652", always_xy=True)
    bx, by = utm.transform(BLOB[1], BLOB[0])
    x0, y1, n = bx - 80_000.0, by + 80_000.0, 160
    xs = x0 + (np.arange(n) + 0.5) * 1000.0
    ys = y1 - (np.arange(n) + 0.5) * 1000.0
    X, Y = np.meshgrid(xs, ys)
    z = np.exp(-(((X - bx) / 9000.0) ** 2 + ((Y - by) / 7000.0) ** 2) / 2)
    tif = tmp_path / "utm.tif"
    with rasterio.open(
        tif, "w", driver="GTiff", width=n, height=n, count=1, dtype="float64",
        crs="EPSG:32652", transform=Affine(1000.0, 0.0, x0, 0.0, -1000.0, y1),
    ) as dst:  # fmt: skip
        dst.write(z, 1)
    res = import_scenario(layers["area"], prior=tif, airfields=layers["fields"])
    rep = res["report"]["prior"]
    assert abs(rep["inside"] + rep["outside"] - z.sum()) < 1e-9 * z.sum()
    fwd = Transformer.from_crs("EPSG:4326", res["crs"]["proj"], always_xy=True)
    ex, ey = fwd.transform(BLOB[1], BLOB[0])
    cx, cy = _centre_of_mass(res["prior"], load_scenario(res["scenario"]))
    assert np.hypot(cx - ex, cy - ey) < 5000.0


def test_geotiff_needs_the_geo_extra(tmp_path, layers, monkeypatch):
    import importlib.util

    from poc_env.errors import MissingExtraError

    tif, _ = _tif(tmp_path / "prior.tif")
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda m, *a: None if m == "rasterio" else real(m, *a)
    )
    with pytest.raises(MissingExtraError, match=r"'geo' extra"):
        import_scenario(layers["area"], prior=tif, airfields=layers["fields"])
    # GeoJSON and CSV input need no rasterio
    (tmp_path / "p.csv").write_text("lat,lon,probability\n45.7,126.6,1\n")
    import_scenario(layers["area"], prior=tmp_path / "p.csv", airfields=layers["fields"])


# ----------------------------------------------------------------- issue 27: hostile input
def test_csv_prior_of_huge_probabilities_keeps_its_proportions(tmp_path, layers):
    """Two 1e308 samples sum past float range: the prior is scaled by its largest sample first
    (as probability_map.validate_map does), so it is not an all-zero (or NaN) grid."""
    c = tmp_path / "big.csv"
    c.write_text("lat,lon,probability\n45.7,126.6,1e308\n45.8,126.7,1e308\n")
    res = import_scenario(layers["area"], prior=c, airfields=layers["fields"])
    m = res["prior"]
    assert np.all(np.isfinite(m)) and abs(m.sum() - 1.0) < 1e-12
    assert sorted(m[m > 0].tolist()) == pytest.approx([0.5, 0.5])
    assert res["report"]["prior"]["outside_share"] == 0.0


@pytest.mark.parametrize(
    "name, data",
    [
        ("binary.csv", b"\x89PNG\r\n\x1a\n\xff\xfe\x00\x00" * 40),
        ("latin1.csv", "lat,lon,probability\n45.7,126.6,1\n# caf\xe9\n".encode("latin-1")),
    ],
)
def test_binary_or_undecodable_csv_is_a_config_error(tmp_path, layers, name, data):
    c = tmp_path / name
    c.write_bytes(data)
    _bad(tmp_path, layers, "UTF-8 CSV text", prior=c)


def test_numbers_beyond_float_range_and_deep_nesting_in_gis_files(tmp_path, layers):
    area = tmp_path / "huge.geojson"
    area.write_text(
        '{"type":"Polygon","coordinates":[[[1e400,45.3],[127.2,45.3],[127.2,46.1],[1e400,45.3]]]}'
    )
    _bad(tmp_path, layers, "finite", area=area)
    kml = tmp_path / "huge.kml"
    kml.write_text(
        "<kml><Placemark><Polygon><outerBoundaryIs><LinearRing><coordinates>1e400,45.3 "
        "127.2,45.3 127.2,46.1 1e400,45.3</coordinates></LinearRing></outerBoundaryIs>"
        "</Polygon></Placemark></kml>"
    )
    _bad(tmp_path, layers, "finite", area=kml)
    deep = tmp_path / "deep.geojson"
    deep.write_text('{"type":"Polygon","coordinates":' + "[" * 100_000 + "]" * 100_000 + "}")
    _bad(tmp_path, layers, "not JSON", area=deep)
    nan = tmp_path / "nan.geojson"  # Python's parser takes NaN; GeoJSON (RFC 8259) does not
    nan.write_text('{"type":"Polygon","coordinates":[[[126.0,45.3],[127.2,45.3],[NaN,46.1]]]}')
    _bad(tmp_path, layers, r"nan\.geojson: got 'not JSON \(.*NaN is not JSON", area=nan)


def test_truncated_geotiff_is_a_config_error(tmp_path, layers):
    tif, _ = _tif(tmp_path / "full.tif")
    raw = tif.read_bytes()
    cut = tmp_path / "cut.tif"
    cut.write_bytes(raw[: len(raw) // 2])
    _bad(tmp_path, layers, "unreadable", prior=cut)


@pytest.mark.parametrize(
    "stem",
    [
        "evil\nname: 3\nmap: {}",
        "a\rb\x85c\u2028d\u2029e",
        "x\n- list\n# comment\n---\nother: doc",
        "tab\there 'quoted' \"double\" #hash: colon",
    ],
)
def test_area_file_name_in_the_yaml_header_adds_no_keys(tmp_path, layers, stem):
    """The area file's name is written into the scenario YAML (comment header and
    description): any name reads back as the same mapping, with no key added."""
    area = tmp_path / f"{stem}.geojson"
    area.write_text(layers["area"].read_text())
    res = import_scenario(area, airfields=layers["fields"])
    out = tmp_path / "imported.yaml"
    write_imported(res, out)
    import yaml

    text = out.read_text(encoding="utf-8")
    doc = yaml.safe_load(text)
    assert doc == yaml.safe_load(yaml.safe_dump(res["scenario"]))
    assert set(doc) == set(res["scenario"])
    head = [ln for ln in text.splitlines() if not ln.startswith("#")]
    assert yaml.safe_load("\n".join(head)) == doc  # the header is comments only
    assert load_scenario(str(out)).name == "imported"


# --------------------------------------------------------------------------- audit i24


def test_csv_prior_with_a_byte_order_mark(tmp_path, layers):
    """Audit i24: a CSV saved by a spreadsheet as 'CSV UTF-8' starts with a byte-order mark;
    its header read as ``['\\ufefflat', ...]`` and the import said the lat column was missing."""
    text = "lat,lon,probability\n45.75,126.7,0.6\n45.8,126.8,0.4\n"
    plain, bom = tmp_path / "plain.csv", tmp_path / "bom.csv"
    plain.write_text(text, encoding="utf-8")
    bom.write_text(text, encoding="utf-8-sig")
    a = import_scenario(layers["area"], prior=plain, airfields=layers["fields"])["prior"]
    b = import_scenario(layers["area"], prior=bom, airfields=layers["fields"])["prior"]
    np.testing.assert_array_equal(a, b)


def test_names_no_export_can_carry_are_refused_at_import(tmp_path, layers):
    """Audit i24: an airfield name over 64 characters, a zone name over 200, or a name with a
    control character was imported and planned, and then every export refused the plan.json
    (``plan.airfields[0].name: ... allowed: 1-64 characters``). The import now refuses it,
    naming the file and feature, with the plan schema's own rule; the scenario loader too."""
    long_field = _write(tmp_path / "lf.geojson", _fc([_pt(126.25, 45.62, name="H" * 65)]))
    _bad(tmp_path, layers, r"lf\.geojson feature 0 name.*1-64 characters", airfields=long_field)
    bell = _write(tmp_path / "bf.geojson", _fc([_pt(126.25, 45.62, name="Har\x07bin")]))
    _bad(tmp_path, layers, r"bf\.geojson feature 0 name.*control character U\+0007", airfields=bell)
    long_zone = _write(tmp_path / "lz.geojson", _fc([_poly([ZONE], name="R" * 201)]))
    _bad(tmp_path, layers, r"lz\.geojson feature 0 name.*at most 200 characters", no_fly=long_zone)
    ok = _write(tmp_path / "ok.geojson", _fc([_poly([ZONE], name="R" * 200)]))
    import_scenario(layers["area"], airfields=layers["fields"], no_fly=ok)  # the limit itself
    data = import_scenario(layers["area"], airfields=layers["fields"])["scenario"]
    data["airfields"][0]["name"] = "H" * 65
    with pytest.raises(ConfigError, match=r"name.*1-64 characters"):
        load_scenario(data)


def test_zones_covering_the_whole_search_area_are_refused(tmp_path, layers):
    """Audit i24 (issue 24, Bad input: zones covering the whole area): a zone drawn over the
    whole search polygon, but not over the grid's extra cells beyond it, and two zones that
    cover the area only together, were imported; the plan then had nothing to search (DE: POS
    0 after 33 s). Both are refused, naming the zones, and nothing is returned."""
    lon0, lat0, lon1, lat1 = 125.99, 45.29, 127.21, 46.11  # just around AREA
    whole = [[lon0, lat0], [lon1, lat0], [lon1, lat1], [lon0, lat1], [lon0, lat0]]
    f = _write(tmp_path / "whole.geojson", _fc([_poly([whole], name="all of it")]))
    _bad(tmp_path, layers, r"no_fly_zones_km\[0\].*'all of it'.*leaves part of the search area",
         no_fly=f)  # fmt: skip
    mid = 126.6
    west = [[lon0, lat0], [mid, lat0], [mid, lat1], [lon0, lat1], [lon0, lat0]]
    east = [[mid, lat0], [lon1, lat0], [lon1, lat1], [mid, lat1], [mid, lat0]]
    f = _write(tmp_path / "halves.geojson", _fc([_poly([west], name="W"), _poly([east], name="E")]))
    _bad(tmp_path, layers, r"no_fly_zones_km\[0, 1\].*'W'.*'E'.*leave part", no_fly=f)
    # a zone over part of the area is fine
    import_scenario(layers["area"], airfields=layers["fields"], no_fly=layers["zones"])


def test_zones_covering_the_whole_map_together_are_refused_by_the_loader():
    """The scenario loader's rule is the union of the zones, not each zone alone."""
    base = {"name": "z", "map": {"width_km": 40, "height_km": 40, "cell_km": 5},
            "airfields": [{"name": "A", "position_km": [-10, 20]}],
            "fleet": [{"takeoff": "A", "count": 1}]}  # fmt: skip
    halves = [[[-1, -1], [21, -1], [21, 41], [-1, 41]], [[20, -1], [41, -1], [41, 41], [20, 41]]]
    with pytest.raises(ConfigError, match=r"no_fly_zones_km\[0, 1\].*leave part"):
        load_scenario({**base, "map": {**base["map"], "no_fly_zones_km": halves}})
    load_scenario({**base, "map": {**base["map"], "no_fly_zones_km": halves[:1]}})


def test_geojson_edges_are_straight_in_longitude_latitude(tmp_path):
    """Audit i24: a GeoJSON edge is a straight line in longitude/latitude (RFC 7946, 3.1.1),
    so a rectangle drawn along parallels keeps its parallels. The import joined the projected
    vertices with straight lines in the map's metres: on a 500 x 500 km area near 45 N the
    southern edge ran up to 4.6 km north of latitude 43, and sightings 2.2 km inside it were
    dropped as outside the area (11.5 % of that prior's mass). Points 2.2 km inside an edge
    are kept, points 2.2 km outside are still dropped, and short edges are left as they are."""
    area = [[5.0, 43.0], [11.14, 43.0], [11.14, 47.5], [5.0, 47.5], [5.0, 43.0]]
    area_f = _write(tmp_path / "big.geojson", _fc([_poly([area])]))
    fields = _write(tmp_path / "f.geojson", _fc([_pt(4.8, 45.0, name="W")]))
    lons = np.linspace(7.0, 9.0, 9)
    rows = ["lat,lon,probability", "45.0,8.0,1"]
    rows += [f"43.02,{lon},1" for lon in lons] + [f"47.48,{lon},1" for lon in lons]
    rows += [f"42.98,{lon},1" for lon in lons]  # just outside the southern edge
    csv_path = tmp_path / "p.csv"
    csv_path.write_text("\n".join(rows) + "\n")
    with pytest.warns(UserWarning, match="outside the search area"):
        res = import_scenario(area_f, prior=csv_path, airfields=fields, cell_km=10)
    rep = res["report"]["prior"]
    assert rep["outside"] == pytest.approx(len(lons), abs=1e-9)  # only the points outside
    # a small zone's edges (a few km) are not densified: the ring keeps its 4 vertices
    zones = _write(tmp_path / "z.geojson", _fc([_poly([ZONE])]))
    field = _write(tmp_path / "g.geojson", _fc([_pt(126.25, 45.62, name="H")]))
    area_f = _write(tmp_path / "a.geojson", _fc([_poly([AREA])]))
    res = import_scenario(area_f, airfields=field, no_fly=zones)
    assert len(res["scenario"]["map"]["no_fly_zones_km"][0]) == 4


def test_kml_placemark_of_another_geometry_is_named(tmp_path, layers):
    """Audit i24: a KML airfield file with a LineString placemark (a drawn runway, a track)
    was refused as ``got '(none)'``; the error now names the geometry found."""
    kml = (
        '<?xml version="1.0"?><kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        "<Placemark><name>Harbin</name><Point><coordinates>126.25,45.62</coordinates></Point>"
        "</Placemark><Placemark><name>runway</name><LineString><coordinates>126.25,45.62 "
        "126.26,45.63</coordinates></LineString></Placemark></Document></kml>"
    )
    f = tmp_path / "fields.kml"
    f.write_text(kml)
    want = r"fields\.kml feature 1: got 'LineString'; allowed: a Point"
    _bad(tmp_path, layers, want, airfields=f)


def test_an_origin_far_from_the_area_is_refused(tmp_path, layers):
    """Audit i24: ``--origin`` is the centre of the map's projection; the import took any. An
    origin at a headquarters 4,300 km away made the 8,310 km^2 area 8,987 km^2 on the map (+8
    %; aeqd's scale error grows as (distance / R)^2 / 6), silently. An origin more than 1,000
    km from the area (the airfields' limit; 0.4 % of scale error at most) is refused, naming
    it; one 145 km away is fine."""
    kw = {"airfields": layers["fields"]}
    with pytest.raises(ConfigError, match=r"^origin: got \[45\.0, 70\.0\]; allowed: a point "
                       r"within 1000 km of the search area \(it is \d+ km away"):  # fmt: skip
        import_scenario(layers["area"], origin="45.0,70.0", **kw)
    res = import_scenario(layers["area"], origin="44.0,126.6", **kw)  # ~150 km south
    assert res["crs"]["origin_deg"] == [44.0, 126.6]


def test_sightings_on_the_area_s_edge_are_kept(tmp_path, layers):
    """Audit i24: a sighting exactly on the area's edge as drawn (a road the officer drew the
    area along) was dropped as outside it (``contains`` excludes the boundary, and a parallel
    lies within the 10 m edge tolerance on either side of the projected edge). Points within
    that tolerance of the area are inside; 100 m out they are still dropped."""
    rows = ["lat,lon,probability", "45.75,126.7,1", "45.7,126.0,1", "45.3,126.6,1"]
    rows += ["45.299,126.6,1"]  # ~110 m south of the southern edge
    csv_path = tmp_path / "edge.csv"
    csv_path.write_text("\n".join(rows) + "\n")
    with pytest.warns(UserWarning, match="outside the search area"):
        res = import_scenario(layers["area"], prior=csv_path, airfields=layers["fields"])
    assert res["report"]["prior"]["outside"] == pytest.approx(1.0, abs=1e-9)


def test_an_area_cut_at_the_antimeridian_is_joined(tmp_path):
    """RFC 7946 3.1.9 asks for a geometry crossing the 180th meridian to be cut there: an area
    near Fiji (178.5 E to 178.5 W, 17.5-16.5 S) as a MultiPolygon of its two parts imports as
    one area, the same as the area 10 degrees west of it (which crosses nothing), its origin at
    the south-west corner (178.5 E), a CSV sighting on either side kept. A ring whose
    longitudes jump from 180 to -180 is still refused (read straight in lon/lat it spans the
    globe), as are parts that do not meet at 180 (i24-terrainleft: before, the cut area was
    refused as '2 polygons')."""
    west = [[178.5, -17.5], [180.0, -17.5], [180.0, -16.5], [178.5, -16.5], [178.5, -17.5]]
    east = [[-180.0, -17.5], [-178.5, -17.5], [-178.5, -16.5], [-180.0, -16.5], [-180.0, -17.5]]
    multi = {"type": "MultiPolygon", "coordinates": [[west], [east]]}
    area = _write(tmp_path / "fiji.geojson", _fc([{"type": "Feature", "properties": {},
                                                   "geometry": multi}]))  # fmt: skip
    fields = _write(tmp_path / "f.geojson", _fc([_pt(-179.9, -16.3, name="Labasa")]))
    csv_path = tmp_path / "p.csv"
    csv_path.write_text("lat,lon,probability\n-17.0,179.5,1\n-17.0,-179.5,1\n")
    res = import_scenario(area, prior=csv_path, airfields=fields, cell_km=10)
    assert res["crs"]["origin_deg"] == [-17.5, 178.5]
    assert res["report"]["prior"]["outside"] == 0.0
    shifted = [[[lon - 10.0, lat] for lon, lat in [[178.5, -17.5], [181.5, -17.5], [181.5, -16.5],
                                                   [178.5, -16.5], [178.5, -17.5]]]]  # fmt: skip
    ref = import_scenario(_write(tmp_path / "ref.geojson", _fc([_poly(shifted)])),
                          airfields=_write(tmp_path / "g.geojson", _fc([_pt(170.1, -16.3,
                                                                          name="L")])),
                          cell_km=10)  # fmt: skip
    assert res["report"]["area_km2"] == pytest.approx(ref["report"]["area_km2"], rel=1e-6)
    assert res["scenario"]["map"]["width_km"] == ref["scenario"]["map"]["width_km"]
    jump = [[178.5, -17.5], [-178.5, -17.5], [-178.5, -16.5], [178.5, -16.5], [178.5, -17.5]]
    with pytest.raises(GeometryError, match=r"spans more than 180 deg.*MultiPolygon"):
        import_scenario(_write(tmp_path / "j.geojson", _fc([_poly([jump])])), airfields=fields)
    apart = {"type": "MultiPolygon", "coordinates": [[west], [[[v[0] + 0.5, v[1]] for v in east]]]}
    two = _write(tmp_path / "two.geojson", _fc([{"type": "Feature", "properties": {},
                                                 "geometry": apart}]))  # fmt: skip
    with pytest.raises(ConfigError, match="2 polygons"):
        import_scenario(two, airfields=fields)
