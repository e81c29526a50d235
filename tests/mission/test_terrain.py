"""Terrain and sensors (issue 24, deliverable 2): a DEM in the scenario and in `scenario import`,
mission altitudes that clear it within eq. 19's pitch bound and the ceiling, QGC/KML altitudes
AMSL from it, the home altitude from it, the camera sensor model used alike by the planner, the
bounds and the environment, and the bad-input cases.

Every fixture is generated here (tmp_path): an Alps-like search area near 46.5 N 7.9 E with a
synthetic 4,000 m ridge written by rasterio and an airfield in a 600 m valley.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.formats.kml import validate_kml
from poc_env.agents.mission.formats.qgc import validate_qgc
from poc_env.agents.mission.plan import load_plan, write_plan
from poc_env.agents.mission.terrain import (
    clearance_violations,
    dem_heights_at,
    from_record,
    load_terrain,
    plan_profiles,
    profile,
    qgc_clearance,
)
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.testing.terrain import ring_around
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

rasterio = pytest.importorskip("rasterio")

ORIGIN = (46.5, 7.9)  # lat, lon of local (0, 0)
RIDGE_X_KM = 30.0  # the ridge runs north-south 30 km east of the origin
VALLEY_M, RIDGE_M = 600.0, 4000.0
KM_PER_DEG_LON = 111.32 * math.cos(math.radians(ORIGIN[0]))


def _height(lon: np.ndarray, lat: np.ndarray) -> np.ndarray:
    x_km = (lon - ORIGIN[1]) * KM_PER_DEG_LON
    return VALLEY_M + (RIDGE_M - VALLEY_M) * np.exp(-(((x_km - RIDGE_X_KM) / 5.0) ** 2))


def _dem(path: Path, *, crs: str | None = "EPSG:4326", lon=(7.0, 9.3), lat=(45.9, 47.1),
         res=0.005, void: tuple | None = None) -> Path:  # fmt: skip
    from rasterio.transform import from_origin

    nx, ny = round((lon[1] - lon[0]) / res), round((lat[1] - lat[0]) / res)
    lons = lon[0] + (np.arange(nx) + 0.5) * res
    lats = lat[1] - (np.arange(ny) + 0.5) * res
    z = _height(*np.meshgrid(lons, lats)).astype("float32")
    if void is not None:
        z[void] = -9999.0
    kw = {"crs": crs} if crs else {}
    with rasterio.open(
        path, "w", driver="GTiff", width=nx, height=ny, count=1, dtype="float32",
        transform=from_origin(lon[0], lat[1], res, res), nodata=-9999.0, **kw,
    ) as dst:  # fmt: skip
        dst.write(z, 1)
    return path


def _scenario(dem: Path | None, **over) -> dict:
    data = {
        "name": "alps",
        "map": {
            "width_km": 60, "height_km": 40, "cell_km": 5, "origin_deg": list(ORIGIN),
            "prior": {"components": [{"mean_km": [32, 20], "sigma_km": [10, 8]}]},
        },
        "airfields": [{"name": "valley", "position_km": [-10, 20]}],
        "fleet": [{"takeoff": "valley", "count": 2}],
        "uav": {"max_altitude_m": 6000},
    }  # fmt: skip
    if dem is not None:
        data["terrain"] = {"dem": str(dem)}
    for k, v in over.items():
        data[k] = v
    return data


# --------------------------------------------------------------------------- the Alps case


def test_alps_import_plan_export_clears_the_ridge(tmp_path):
    """Imported with --dem, planned (allocation, small budget), exported to QGC and KML: every
    mission clears the DEM by the clearance, home altitude and landing at the valley's 600 m,
    altitudes AMSL (MAV_FRAME_GLOBAL) and KML absolute."""
    from poc_env.agents.mission.geoimport import (
        add_scenario_import_arguments,
        cmd_scenario_import,
    )

    dem = _dem(tmp_path / "alps_dem.tif")
    lon0, lat0 = 7.9, 46.5
    dlon, dlat = 60 / KM_PER_DEG_LON, 40 / 111.2
    area = [[lon0, lat0], [lon0 + dlon, lat0], [lon0 + dlon, lat0 + dlat], [lon0, lat0 + dlat]]
    (tmp_path / "area.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {},
         "geometry": {"type": "Polygon", "coordinates": [[*area, area[0]]]}}]}))  # fmt: skip
    (tmp_path / "fields.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"name": "valley"},
         "geometry": {"type": "Point", "coordinates": [lon0 - 0.1, lat0 + 0.2]}}]}))  # fmt: skip
    p = argparse.ArgumentParser()
    add_scenario_import_arguments(p)
    out = tmp_path / "alps.yaml"
    argv = [str(tmp_path / "area.geojson"), "--airfields", str(tmp_path / "fields.geojson")]
    args = p.parse_args([*argv, "--dem", str(dem), "--out", str(out)])
    assert cmd_scenario_import(args) == 0
    sc = load_scenario(out)
    assert sc.terrain.dem == str(dem.resolve())
    # the base UAV's ceiling (4,000 m AMSL) is below ridge + clearance: refused, named
    with pytest.raises(ConfigError, match="clearance impossible") as err:
        make_plan(sc, planner="allocation", uavs=2, refine=0)
    assert "uav.max_altitude_m = 4000" in str(err.value)
    sc = load_scenario(out, {"uav.max_altitude_m": 6000})
    plan = make_plan(sc, planner="allocation", uavs=2, refine=0)
    write_plan(plan, tmp_path / "plan.json")
    t = from_record(load_plan(tmp_path / "plan.json")["terrain"])
    assert t.field_elevation(sc.airfields[0].position_m) == pytest.approx(VALLEY_M, abs=1.0)
    assert t.ground_max_m.max() == pytest.approx(RIDGE_M, abs=5.0)
    files = export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "qgc")
    crossed = 0
    for f in files:
        doc = json.loads(f.read_text())
        assert validate_qgc(doc) == []
        m = doc["mission"]
        assert m["plannedHomePosition"][2] == pytest.approx(VALLEY_M, abs=1.0)
        assert m["globalPlanAltitudeMode"] == 2
        assert {it["frame"] for it in m["items"] if it["command"] in (16, 21, 22)} == {0}
        assert m["items"][-1]["params"][6] == pytest.approx(VALLEY_M, abs=1.0)  # NAV_LAND
        least, legs = qgc_clearance(doc, dem)
        assert legs > 0 and least >= 150.0 - 1e-6, (f.name, least)
        alts = [it["params"][6] for it in m["items"] if it["command"] == 16]
        crossed += max(alts) > RIDGE_M  # some mission flies over the ridge
    assert crossed >= 1
    kml_files = export_plan(tmp_path / "plan.json", "kml", out_dir=tmp_path / "kml")
    (kml_file,) = [f for f in kml_files if f.suffix == ".kml"]
    assert validate_kml(kml_file) == []  # absolute altitudes too, by the OGC KML 2.2 XSD
    root = etree.parse(str(kml_file))
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    routes = [pm for pm in root.iterfind(".//k:Placemark", ns)
              if pm.findtext("k:name", namespaces=ns).endswith(" route")]  # fmt: skip
    assert len(routes) == 2
    for pm in routes:
        assert pm.findtext(".//k:LineString/k:altitudeMode", namespaces=ns) == "absolute"
        xyz = np.array([[float(v) for v in c.split(",")] for c in
                        pm.findtext(".//k:coordinates", namespaces=ns).split()])  # fmt: skip
        assert xyz[0, 2] == pytest.approx(VALLEY_M, abs=1.0)  # the field, on the ground
        above = xyz[1:-1, 2] - dem_heights_at(dem, xyz[1:-1, [1, 0]])
        assert above.min() >= 150.0 - 1e-6
    # a flat-map altitude option is refused for a plan with terrain, nothing written
    with pytest.raises(ConfigError, match="altitude_m"):
        export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "x", altitude_m=1000)
    assert not (tmp_path / "x").exists()


def test_html_report_shades_the_terrain(tmp_path):
    from poc_env.agents.mission.formats.report import expected_layers

    plan = make_plan(load_scenario(_scenario(_dem(tmp_path / "d.tif"))), planner="allocation",
                     refine=0)  # fmt: skip
    write_plan(plan, tmp_path / "plan.json")
    (page,) = export_plan(tmp_path / "plan.json", "html", out_dir=tmp_path / "h")
    text = page.read_text()
    assert '"terrain": {"url": "data:image/png;base64,' in text
    assert "contours every 500 m" in text
    flat = dict(plan)
    del flat["terrain"]
    assert expected_layers(plan, False) == expected_layers(flat, False) + 1


# --------------------------------------------------------------------------- profiles


def test_profile_climbs_within_the_pitch_bound_and_keeps_the_clearance():
    """A route across a 4,000 m wall: eq. 19's gradient tan(beta_max) never exceeded, the
    clearance kept at every sample, the wanted height above ground kept away from the wall."""
    sc = load_scenario(_scenario(None, terrain={"elevation_m": _wall(), "cell_km": 1.0,
                                                "origin_km": [-40, -30]}))  # fmt: skip
    t = load_terrain(sc)
    p = profile(t, [[-10e3, 20e3], [0.0, 0.0], [60e3, 0.0], [60e3, 40e3], [0.0, 40e3]])
    # turns just before and just after the wall: the climb and the descent are both limited
    q = profile(t, [[-10e3, 20e3], [27e3, 0.0], [33e3, 0.0], [33e3, 2e3], [26e3, 2e3]])
    for prof in (p, q):
        grad = np.abs(np.diff(prof.amsl_m)) / np.hypot(*np.diff(prof.points_m, axis=0).T)
        assert grad.max() <= math.tan(sc.uav.max_pitch_rad) + 1e-9
    assert clearance_violations(t, p, step_m=50.0) == 0
    assert p.amsl_m.max() >= RIDGE_M + 150.0
    assert p.amsl_m[0] == pytest.approx(VALLEY_M + sc.uav.cruise_altitude_m)  # over the field
    flat = profile(t, [[-10e3, 20e3], [0.0, 0.0], [5e3, 0.0]])
    assert np.allclose(flat.amsl_m, VALLEY_M + sc.uav.cruise_altitude_m)  # far from the wall
    with pytest.raises(ConfigError, match=r"UAV 7.*a route over the terrain grid"):
        profile(t, [[-10e3, 20e3], [-45e3, 0.0]], "UAV 7")  # off the grid: no ground known
    # the check itself sees a violation: a straight route at 1,600 m AMSL through the wall
    flown = type(p)(p.points_m, np.full(len(p.amsl_m), 1600.0), p.ground_m, p.vertex, 0, 0)
    assert clearance_violations(t, flown) > 0


def _wall() -> list:
    """A 120 x 100 km grid of 1 km cells from (-40, -30) km: 600 m, a 4,000 m wall at x = 30 km."""
    x = -40 + np.arange(120) + 0.5
    row = np.where(np.abs(x - RIDGE_X_KM) < 2.0, RIDGE_M, VALLEY_M)
    return np.tile(row, (100, 1)).tolist()


# --------------------------------------------------------------------------- bad input


def test_dem_without_crs_is_refused_by_import_nothing_written(tmp_path):
    from poc_env.agents.mission.geoimport import import_scenario

    dem = _dem(tmp_path / "nocrs.tif", crs=None)
    (tmp_path / "a.geojson").write_text(json.dumps({"type": "Polygon", "coordinates": [[
        [7.9, 46.5], [8.6, 46.5], [8.6, 46.8], [7.9, 46.8], [7.9, 46.5]]]}))  # fmt: skip
    (tmp_path / "f.geojson").write_text(json.dumps({"type": "Feature", "properties": {
        "name": "valley"}, "geometry": {"type": "Point", "coordinates": [7.8, 46.7]}}))  # fmt: skip
    before = sorted(tmp_path.iterdir())
    with pytest.raises(ConfigError, match=r"terrain\.dem.*coordinate reference system"):
        import_scenario(tmp_path / "a.geojson", airfields=tmp_path / "f.geojson", dem=dem)
    assert sorted(tmp_path.iterdir()) == before


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"lon": (7.6, 8.5)}, r"terrain\.dem.*covering .* of the operating area"),
        ({"void": (slice(150, 160), slice(150, 160))}, r"terrain\.dem.*nodata or NaN"),
    ],
    ids=["not-covering", "void"],
)
def test_dem_not_covering_or_with_voids_is_refused(tmp_path, kwargs, match):
    sc = load_scenario(_scenario(_dem(tmp_path / "d.tif", **kwargs)))
    with pytest.raises(ConfigError, match=match):
        make_plan(sc, planner="allocation", refine=0)


def test_dem_needs_the_scenario_origin(tmp_path):
    data = _scenario(_dem(tmp_path / "d.tif"))
    del data["map"]["origin_deg"]
    with pytest.raises(ConfigError, match=r"terrain\.dem.*map\.origin_deg"):
        load_terrain(load_scenario(data))


def test_elevation_grid_not_covering_the_area_is_refused():
    sc = load_scenario(_scenario(None, terrain={"elevation_m": [[0, 0], [0, 0]]}))
    with pytest.raises(ConfigError, match=r"terrain\.elevation_m.*whole operating area"):
        load_terrain(sc)


def test_export_refuses_a_plan_whose_clearance_the_ceiling_cannot_give(tmp_path):
    plan = make_plan(load_scenario(_scenario(_dem(tmp_path / "d.tif"))), planner="allocation",
                     refine=0)  # fmt: skip
    plan["terrain"]["ceiling_m"] = 3500.0  # below the ridge + clearance
    crossing = [k for k, p in enumerate(plan_profiles({**plan, "terrain": {
        **plan["terrain"], "ceiling_m": 6000.0}})) if p.ground_m.max() > 3350]  # fmt: skip
    assert crossing
    write_plan(plan, tmp_path / "plan.json")
    for fmt in ("qgc", "kml", "geojson", "html"):
        with pytest.raises(
            ConfigError, match=rf"plan\.uavs\[{crossing[0]}\].*clearance impossible"
        ):
            export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
        assert not (tmp_path / fmt).exists()


# --------------------------------------------------------------------------- sensor model


def test_camera_sweep_width_is_the_footprint_and_everyone_reads_it():
    """W = k 2 h tan(fov / 2); the environment, the bound and the planner's objective use the
    model's W exactly as they use the same fixed width."""
    from poc_env.agents.planning.objective import PlanObjective
    from poc_env.sim.core import make_params
    from poc_env.theory.bound import honest_optimum
    from poc_env.theory.probability_map import build_prior

    over = {"sensor.model": "camera", "sensor.fov_deg": 90.0, "sensor.detection_factor": 0.8,
            "uav.cruise_altitude_m": 1500.0}  # fmt: skip
    cam = load_scenario("paper_6_2", over)
    w = 0.8 * 2 * 1500.0 * math.tan(math.radians(45.0))
    assert cam.sensor.sweep_width_m == pytest.approx(w, rel=1e-12)
    fixed = load_scenario("paper_6_2", {"sensor.sweep_width_km": w / 1e3,
                                        "uav.cruise_altitude_m": 1500.0})  # fmt: skip
    prior = build_prior(cam.map)
    assert make_params(cam).cutoff_m == pytest.approx(make_params(fixed).cutoff_m)
    assert make_params(cam).cutoff_m != pytest.approx(
        make_params(load_scenario("paper_6_2")).cutoff_m
    )
    assert honest_optimum(cam, prior).pos == pytest.approx(honest_optimum(fixed, prior).pos)
    assert PlanObjective(cam, prior).sweep_width_m == pytest.approx(w)
    # the model's W round-trips; a different explicit width beside a model is refused
    assert load_scenario(cam.to_dict()).sensor.sweep_width_m == pytest.approx(w)
    with pytest.raises(ConfigError, match=r"sensor\.sweep_width_km.*absent when sensor\.model"):
        load_scenario("paper_6_2", {**over, "sensor.sweep_width_km": 3})
    with pytest.raises(ConfigError, match=r"model.*one of 'fixed', 'camera'"):
        load_scenario("paper_6_2", {"sensor.model": "iamsar"})


def test_default_sensor_keeps_every_builtin_width():
    from poc_env.config import builtin_scenarios

    for name in builtin_scenarios():
        sc = load_scenario(name)
        assert sc.sensor.model == "fixed"
        assert sc.sensor.sweep_width_at(123.0) == sc.sensor.sweep_width_m


@pytest.mark.parametrize("height", [3e38, -2e4, 15_000.0])  # float32: 3e38 near its top
def test_dem_heights_beyond_the_earths_are_refused_by_import_nothing_written(tmp_path, height):
    """Issue 27's campaign (datafiles target): a DEM with 1e308 m (3e38 in float32) or 20 km
    below sea level was imported, and only the plan then refused it; the import refuses it,
    naming terrain.dem."""
    dem = _dem(tmp_path / "d.tif")
    with rasterio.open(dem, "r+") as ds:
        z = ds.read(1)
        z[100:104, 200:204] = height
        ds.write(z, 1)
    with pytest.raises(ConfigError, match="within \\+-12000 m") as err:
        load_terrain(load_scenario(_scenario(dem)))
    assert err.value.field == "terrain.dem"


# --------------------------------------------------------------------------- audit (terrain-audit)


def _slope(m_per_km: float) -> list:
    """120 x 100 cells of 1 km from (-40, -30) km: ground rising east from 600 m at x = -10 km
    (to at most 5,000 m)."""
    x = -40 + np.arange(120) + 0.5
    return np.tile(np.minimum(VALLEY_M + m_per_km * (x + 10.0), 5000.0), (100, 1)).tolist()


def test_final_glide_to_the_field_keeps_the_pitch_bound():
    """The approach point 4 km up a slope from the field: the glide from it to the field (the
    mission's last leg, approach -> NAV_LAND) is flown within eq. 19's tan(beta_max) too; a
    slope too steep for any such glide that keeps the clearance is refused, naming the UAV
    and the landing field's glide (audit: glides of 0.278-0.308 against tan 15 deg = 0.268
    were exported)."""
    sc = load_scenario(_scenario(None, terrain={"elevation_m": _slope(30.0), "cell_km": 1.0,
                                                "origin_km": [-40, -30]}))  # fmt: skip
    t = load_terrain(sc)
    field, approach = np.array([-10e3, 20e3]), np.array([-6e3, 20e3])
    p = profile(t, [field, [20e3, 20e3], [20e3, 25e3], approach], "UAV 3", field)
    grad = math.tan(sc.uav.max_pitch_rad)
    glide = (p.amsl_m[-1] - t.field_elevation(field)) / float(np.hypot(*(approach - field)))
    assert glide <= grad + 1e-9
    legs = np.abs(np.diff(p.amsl_m)) / np.hypot(*np.diff(p.points_m, axis=0).T)
    assert legs.max() <= grad + 1e-9
    assert clearance_violations(t, p, step_m=50.0) == 0
    assert p.amsl_m.max() >= t.field_elevation(field) + sc.uav.cruise_altitude_m  # still cruising
    steep = load_scenario(_scenario(None, terrain={"elevation_m": _slope(250.0), "cell_km": 1.0,
                                                   "origin_km": [-40, -30]}))  # fmt: skip
    with pytest.raises(ConfigError, match=r"UAV 3.*glide to the landing field.*max_pitch_deg"):
        profile(load_terrain(steep), [field, [-2e3, 20e3], approach], "UAV 3", field)


def test_geojson_approach_height_is_the_approach_drawn(tmp_path):
    """The landing approach's ``approach_height_m`` is the height its own LineString descends
    over (approach point -> field), with terrain and on a flat map below 300 m (audit: it was
    the constant 300 m while a terrain approach started 826 m above its field)."""
    sc = load_scenario(_scenario(_dem(tmp_path / "d.tif")))
    plan = make_plan(sc, planner="allocation", refine=0)
    write_plan(plan, tmp_path / "plan.json")
    flat = {k: v for k, v in plan.items() if k != "terrain"}
    write_plan(flat, tmp_path / "flat.json")
    cases = [("plan.json", {}), ("flat.json", {"altitude_m": 200.0})]
    seen = []
    for name, kw in cases:
        (f,) = export_plan(tmp_path / name, "geojson", out_dir=tmp_path / name[:-5], **kw)
        for ft in json.loads(f.read_text())["features"]:
            if ft["properties"]["kind"] == "landing_approach":
                (_, _, za), (_, _, zf) = ft["geometry"]["coordinates"]
                assert ft["properties"]["approach_height_m"] == pytest.approx(za - zf, abs=0.1)
                seen.append(za - zf)
    # the terrain approach glides at most 300 m over 4 km (PX4's landing slope, export-audit;
    # it was 826 m at the audit), the flat one at 200 m from a 200 m cruise
    assert max(seen) <= 300.0 + 0.1 and min(seen) == pytest.approx(200.0)


def test_camera_search_legs_below_the_search_height_are_warned(tmp_path):
    """A camera's W is resolved at ``uav.cruise_altitude_m`` above the ground; where the ceiling
    holds a search leg lower over the ridge, its footprint is narrower than the plan assumes:
    the plan says so, naming the UAV, the least height and the W there (audit: 32-50 % of the
    search-leg points flew as low as 602 m, W 695 m against the planned 1155 m, silently). The
    fixed width (the paper's) does not depend on the height: no warning."""
    import warnings

    cam = {"sensor": {"model": "camera", "fov_deg": 60.0}}
    dem = _dem(tmp_path / "d.tif")
    low = _scenario(dem, uav={"max_altitude_m": 4600}, **cam)
    with pytest.warns(UserWarning, match=r"UAV \d.*as low as \d+ m above the ground.*"
                      r"uav\.cruise_altitude_m = 1000 m.*W \d+ m .*1155 m"):  # fmt: skip
        make_plan(load_scenario(low), planner="allocation", refine=0)
    for data in (_scenario(dem, **cam), _scenario(dem, uav={"max_altitude_m": 4600})):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            make_plan(load_scenario(data), planner="allocation", refine=0)


def _rewrite(src: Path, dst: Path, scale: float, dtype: str, offset: float = 0.0, **meta) -> Path:
    """``src``'s heights stored as ``(height - offset) / scale`` in ``dtype``, with GDAL
    metadata ``meta`` (``scales``/``offsets``, ``units``)."""
    with rasterio.open(src) as s:
        z, prof = s.read(1).astype(float), s.profile
    prof.update(dtype=dtype, nodata=-32768 if dtype == "int16" else -9999.0)
    with rasterio.open(dst, "w", **prof) as d:
        raw = (z - offset) / scale
        d.write(np.round(raw).astype(dtype) if dtype == "int16" else raw.astype(dtype), 1)
        for key, value in meta.items():
            setattr(d, key, value)
    return dst


@pytest.mark.parametrize(
    ("scale", "dtype", "meta"),
    [(0.2, "int16", {"offset": 100.0, "scales": (0.2,), "offsets": (100.0,)}),  # GDAL scale
     (0.3048, "float32", {"units": ("ft",)}),  # feet, the band's unit type
     (1200 / 3937, "float32", {"units": ("US survey foot",)})],
    ids=["int16-scale-offset", "feet", "us-survey-feet"],
)  # fmt: skip
def test_dem_scale_offset_and_feet_are_read_as_metres(tmp_path, scale, dtype, meta):
    """The heights a GeoTIFF declares (GDAL scale/offset; a band unit in feet) are read as
    metres AMSL, as the same DEM written in metres (audit: a 2,412 m DEM in feet was read as
    7,913 m, one in int16 decimetres as 24,119 m)."""
    metres = _dem(tmp_path / "m.tif")
    other = _rewrite(metres, tmp_path / "o.tif", scale, dtype, **meta)
    want, got = (load_terrain(load_scenario(_scenario(p))) for p in (metres, other))
    assert got.ground_max_m.max() == pytest.approx(RIDGE_M, abs=5.0)
    assert np.allclose(got.ground_m, want.ground_m, atol=0.1)
    assert got.fields[0][2] == pytest.approx(want.fields[0][2], abs=0.1)
    lat_lon = [[46.6, 8.3], [46.7, 7.8]]
    assert np.allclose(dem_heights_at(other, lat_lon), dem_heights_at(metres, lat_lon), atol=0.1)


def test_dem_in_an_unknown_height_unit_is_refused(tmp_path):
    dem = _rewrite(_dem(tmp_path / "m.tif"), tmp_path / "o.tif", 1.0, "float32",
                   units=("fathom",))  # fmt: skip
    with pytest.raises(ConfigError, match=r"fathom.*metres or feet") as err:
        load_terrain(load_scenario(_scenario(dem)))
    assert err.value.field == "terrain.dem"


def test_dem_covering_the_operating_area_is_enough(tmp_path):
    """A DEM clipped to the operating area (as the error states it) loads, though the terrain
    grid, aligned with the map, reaches up to a cell beyond it (audit: a DEM from x = -30.65
    km was refused for an area from -30.3 km, the message giving -31.0 km as the area's edge);
    one short of the area is refused, naming the area's own edge."""
    from rasterio.transform import from_origin

    from poc_env.agents.mission.crs import crs_text, make_crs
    from poc_env.sim.core import operating_area

    def dem(x0_km: float) -> Path:
        x0, y1, res = x0_km * 1e3, 61e3, 250.0
        nx, ny = round((81e3 - x0) / res), round((y1 + 21e3) / res)
        path = tmp_path / f"edge{x0_km}.tif"
        with rasterio.open(
            path, "w", driver="GTiff", width=nx, height=ny, count=1, dtype="float32",
            transform=from_origin(x0, y1, res, res), crs=crs_text(make_crs("aeqd", ORIGIN)),
        ) as dst:  # fmt: skip
            dst.write(np.full((ny, nx), 800.0, dtype="float32"), 1)
        return path

    def scenario(path: Path):
        data = _scenario(path)
        data["airfields"][0]["position_km"] = [-10.3, 20.7]
        return load_scenario(data)

    sc = scenario(dem(-30.65))
    assert operating_area(sc)[0] == pytest.approx(-30.3e3)
    t = load_terrain(sc)
    assert t.bounds[0] == pytest.approx(-31e3) and np.allclose(t.ground_max_m, 800.0)
    with pytest.raises(ConfigError, match=r"terrain\.dem.*x0, y0, x1, y1 = \[-30\.3, -20\.0"):
        load_terrain(scenario(dem(-30.2)))


def test_geojson_route_altitude_properties_describe_the_line(tmp_path):
    """A route over terrain carries no flat ``altitude_m`` (it was field + search height while
    its z follow the DEM, terrain audit follow-up): its search height above the ground and the
    AMSL range its own z span; a flat plan keeps ``altitude_m``, the z of its search points."""
    sc = load_scenario(_scenario(_dem(tmp_path / "d.tif")))
    plan = make_plan(sc, planner="allocation", refine=0)
    write_plan(plan, tmp_path / "plan.json")
    flat = {k: v for k, v in plan.items() if k != "terrain"}
    write_plan(flat, tmp_path / "flat.json")
    for name in ("plan.json", "flat.json"):
        (f,) = export_plan(tmp_path / name, "geojson", out_dir=tmp_path / name[:-5])
        routes = [ft for ft in json.loads(f.read_text())["features"]
                  if ft["properties"]["kind"] == "route"]  # fmt: skip
        assert routes
        for ft in routes:
            p, z = ft["properties"], [c[2] for c in ft["geometry"]["coordinates"][1:-1]]
            if name == "flat.json":
                assert p["altitude_m"] == pytest.approx(max(z)) == pytest.approx(min(z))
                continue
            assert "altitude_m" not in p and p["altitude_ref"] == "amsl"
            assert p["search_height_m"] == sc.uav.cruise_altitude_m
            assert p["altitude_min_m"] == pytest.approx(min(z), abs=0.05)
            assert p["altitude_max_m"] == pytest.approx(max(z), abs=0.05)
            assert p["altitude_max_m"] - p["altitude_min_m"] > 100.0  # the DEM's relief


def test_a_width_given_beside_a_camera_model_is_refused_even_the_default():
    """Terrain audit follow-up: ``sensor.sweep_width_km: 5`` (the default's value) given beside
    ``sensor.model: camera`` was silently replaced by the model's W; a width given with a model
    that computes it is refused by name, whatever its value, unless it is the model's own W
    (a scenario's ``to_dict`` writes that, and loads back)."""
    from poc_env.config import SensorConfig

    cam = {"sensor.model": "camera", "sensor.fov_deg": 60.0}
    w = load_scenario("paper_6_2", cam).sensor.sweep_width_m
    for given in (5, 5.0, 3):
        with pytest.raises(ConfigError, match=r"sensor\.sweep_width_km.*absent when sensor\.model"):
            load_scenario("paper_6_2", {**cam, "sensor.sweep_width_km": given})
    data = load_scenario("paper_6_2").to_dict()  # a file giving both, as the audit wrote it
    data["sensor"].update(model="camera", sweep_width_km=5)
    with pytest.raises(ConfigError, match=r"sensor\.sweep_width_km: got 5"):
        load_scenario(data)
    assert load_scenario("paper_6_2", {**cam, "sensor.sweep_width_km": w / 1e3}).sensor == (
        load_scenario("paper_6_2", cam).sensor
    )
    assert SensorConfig().sweep_width_m == 5000.0  # the fixed model's default is unchanged
    assert load_scenario("paper_6_2", {"sensor.sweep_width_km": 5}).sensor.sweep_width_m == 5000.0


def test_dem_nodata_refusal_counts_a_small_hole(tmp_path):
    """Terrain audit follow-up: a 2 x 2 pixel hole was refused as ``nodata or NaN over 0.0% of
    the operating area``; the message counts the grid cells and gives a share that is not 0.
    (A one-pixel hole, which the resampling fills, is refused too: the test below.)"""
    import re

    sc = load_scenario(_scenario(_dem(tmp_path / "d.tif", void=(slice(150, 152), slice(150, 152)))))
    with pytest.raises(ConfigError, match=r"terrain\.dem.*nodata or NaN") as err:
        make_plan(sc, planner="allocation", refine=0)
    m = re.search(r"at (\d+) of the (\d+) cells .*\(([0-9.e+-]+) %", str(err.value))
    assert m is not None, str(err.value)
    n, total, pct = int(m[1]), int(m[2]), float(m[3])
    assert 0 < n < total / 1000  # a small hole
    assert pct == pytest.approx(100 * n / total, rel=5e-3)  # 3 significant digits, not 0.0


def test_dem_one_pixel_hole_inside_the_area_is_refused(tmp_path):
    """Terrain follow-up, left open: a one-pixel nodata hole inside the operating area was
    filled by the resampling from its neighbours and accepted, so a peak under that pixel was
    invisible to the clearance check. Any nodata pixel under a cell of the operating area is
    now refused, naming the DEM; the same DEM without the hole plans."""
    hole = (slice(150, 151), slice(150, 151))
    sc = load_scenario(_scenario(_dem(tmp_path / "d.tif", void=hole)))
    with pytest.raises(ConfigError, match=r"terrain\.dem.*nodata or NaN"):
        make_plan(sc, planner="allocation", refine=0)
    make_plan(load_scenario(_scenario(_dem(tmp_path / "e.tif"))), planner="allocation", refine=0)


# ----------------------------------------------------- the take-off climb (i24-terrainleft)


def _bump(height_m: float) -> list:
    """120 x 100 cells of 1 km from (-40, -30) km at 600 m, the column x in [-8, -7] km at
    ``height_m`` (2-3 km east of a field at x = -10 km)."""
    x = -40 + np.arange(120) + 0.5
    return np.tile(np.where(np.abs(x + 7.5) < 0.5, height_m, VALLEY_M), (100, 1)).tolist()


def test_take_off_climb_and_final_glide_stay_above_the_ground():
    """The climb from the field's elevation at eq. 19's tan(beta_max) along the first leg, and
    the straight glide from the approach point to the field, are checked against the ground
    the legs' clearance reads: ground rising 250 m/km from the field (the climb at 268 m/km
    meets the highest ground 1.5 km out) and a 900 m rise under the 4.29 deg glide are
    refused, naming the UAV and the phase. Before (i24-terrainleft) both were accepted: the
    profile starts at the search height over the field and ends at the approach point. Since
    i24-climb a straight climb that meets the ground is flown on a spiral over the field
    (tests/mission/test_climb_spiral.py): on ground rising 400 m/km it is; on ground rising
    1,000 m/km the orbit of 1.17 km must start so high over the rising ground that the
    straight take-off to it meets the ground, refused naming the UAV, the take-off and the
    orbit."""
    field = np.array([-10e3, 20e3])
    route = [field, [10e3, 20e3], [10e3, 25e3], [-6e3, 25e3]]
    slope = load_terrain(load_scenario(_scenario(None, terrain={
        "elevation_m": _slope(400.0), "cell_km": 1.0, "origin_km": [-40, -30]})))  # fmt: skip
    assert profile(slope, route, "UAV 3").climb is not None
    steep_m = np.maximum(np.asarray(_slope(1000.0)), 0.0).tolist()  # sea level to the west
    steep = load_terrain(load_scenario(_scenario(None, terrain={
        "elevation_m": steep_m, "cell_km": 1.0, "origin_km": [-40, -30]})))  # fmt: skip
    sp = profile(steep, route, "UAV 3").climb  # since i24-missionfix: it departs off the route
    assert sp is not None and sp.depart_m > 0.0 and abs(math.sin(sp.start_rad)) > 0.25
    x, y = np.meshgrid(-40 + np.arange(120) + 0.5, -30 + np.arange(100) + 0.5)
    pit_m = np.minimum(VALLEY_M + 1000.0 * np.hypot(x + 10.0, y - 20.0), 5000.0).tolist()
    pit = load_terrain(load_scenario(_scenario(None, terrain={
        "elevation_m": pit_m, "cell_km": 1.0, "origin_km": [-40, -30]})))  # fmt: skip
    with pytest.raises(  # ground rising 1,000 m/km every way: no heading clears
        ConfigError, match=r"UAV 3: .* km from the take-off field.*climb \(to .*orbit"
    ):
        profile(pit, route, "UAV 3")
    gentle = load_terrain(load_scenario(_scenario(None, terrain={
        "elevation_m": _slope(250.0), "cell_km": 1.0, "origin_km": [-40, -30]})))  # fmt: skip
    assert clearance_violations(gentle, profile(gentle, route, "UAV 3"), step_m=50.0) == 0
    approach = np.array([-6e3, 20e3])
    back = [field, [10e3, 20e3], [10e3, 25e3], approach]
    bump = load_terrain(load_scenario(_scenario(None, terrain={
        "elevation_m": _bump(900.0), "cell_km": 1.0, "origin_km": [-40, -30]})))  # fmt: skip
    with pytest.raises(ConfigError, match=r"UAV 4: .*from the landing field.*final glide"):
        profile(bump, back, "UAV 4", field)
    low = load_terrain(load_scenario(_scenario(None, terrain={
        "elevation_m": _bump(700.0), "cell_km": 1.0, "origin_km": [-40, -30]})))  # fmt: skip
    p = profile(low, back, "UAV 4", field)
    assert p.amsl_m[-1] == pytest.approx(VALLEY_M + 300.0)  # the flat export's glide, above 700


def test_export_refuses_a_take_off_climb_into_the_ground(tmp_path):
    """A plan whose recorded ground rises beside its field faster than the UAV climbs: every
    export format refuses it naming the UAV, nothing written (QGC must not emit a mission
    whose take-off meets the ground)."""
    sc = load_scenario(_scenario(None, terrain={"elevation_m": _slope(30.0), "cell_km": 1.0,
                                                "origin_km": [-40, -30]}))  # fmt: skip
    plan = make_plan(sc, planner="allocation", uavs=2, refine=0)
    (k,) = [k for k, u in enumerate(plan["uavs"]) if u["waypoints_m"][0][1] < 15e3]  # south
    u = plan["uavs"][k]
    # a 2,500 m ring 1.5-3.5 km round the field (a hill across the first leg alone is flown
    # since i24-missionfix: the take-off departs on another heading)
    field_km = np.asarray(u["takeoff_m"]) / 1e3
    write_plan(ring_around(plan, field_km, 1.5, 3.5, 2500.0), tmp_path / "plan.json")
    for fmt in ("qgc", "kml", "geojson", "html"):
        with pytest.raises(ConfigError, match=r"plan\.uavs\[\d\] \(UAV \w+\).*take-off"):
            export_plan(tmp_path / "plan.json", fmt, out_dir=tmp_path / fmt)
        assert not (tmp_path / fmt).exists()


def test_dem_in_ellipsoidal_heights_is_refused_and_msl_heights_are_read(tmp_path):
    """The missions fly above mean sea level (QGC MAV_FRAME_GLOBAL): a DEM whose CRS declares
    ellipsoidal heights (EPSG:4979) is refused naming terrain.dem, nothing converted (pyproj
    ships no geoid grid); one with EGM96 heights (EPSG:4326+5773) reads as the 2D one does
    (i24-terrainleft: before, both were read alike)."""
    with pytest.raises(ConfigError, match=r"terrain\.dem: got .*ellipsoidal heights"):
        load_terrain(load_scenario(_scenario(_dem(tmp_path / "e.tif", crs="EPSG:4979"))))
    flat = load_terrain(load_scenario(_scenario(_dem(tmp_path / "f.tif"))))
    egm = load_terrain(load_scenario(_scenario(_dem(tmp_path / "g.tif", crs="EPSG:4326+5773"))))
    assert np.array_equal(egm.ground_max_m, flat.ground_max_m)
    assert egm.fields == flat.fields


def test_profile_keeps_the_clearance_between_its_samples_on_diagonal_legs():
    """The profile read the ground at samples half a cell apart; a point between two samples
    reads cells one or neither sample reads (on a diagonal leg, the corner of its 2 x 2
    window). The legs are now also sampled where the cells a point reads change
    (:meth:`Terrain.window_changes`), and each sample takes the ground of the sub-legs either
    side of it, so a single 2,500 m cell beside a diagonal leg is cleared all along it
    (i24-terrainleft: before, 3 points every 50 m flew below the clearance here, and 6 of 40 of
    the property test's random cases had such points)."""
    g = np.full((100, 120), VALLEY_M)
    g[45, 45] = 2500.0  # the cell x in [5, 6] km, y in [15, 16] km
    route = [[-10e3, 20e3], [6.8e3, 14.9e3], [2.9e3, 10.5e3], [20e3, 30e3]]
    terrain = {"elevation_m": g.tolist(), "cell_km": 1.0, "origin_km": [-40, -30]}
    for uav in ({"max_altitude_m": 6000}, {"max_altitude_m": 6000, "cruise_altitude_m": 150}):
        # the search height, and a search height at the clearance (no margin above it)
        t = load_terrain(load_scenario(_scenario(None, terrain=terrain, uav=uav)))
        p = profile(t, route, "UAV 1")
        assert clearance_violations(t, p, step_m=10.0) == 0, uav
        assert p.amsl_m.max() >= 2500.0 + t.min_clearance_m
    # on points, the ground is the 2 x 2 cells around each, as before
    assert t.ground_at([[5.5e3, 16.4e3]])[0] == 2500.0 and t.ground_at([[4.4e3, 15.5e3]]) == 600
