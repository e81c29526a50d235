import sys

sys.path.insert(0, __import__("os").path.dirname(__file__))
from probe import (
    ORIGIN,
    ConfigError,
    D,
    load_scenario,
    load_terrain,
    np,
    run,
    scenario,
    write_geo,
    write_projected,
    write_tif,
)

which = sys.argv[1:] or ["all"]


def want(n):
    return "all" in which or n in which


if want("valleys"):
    run("valleys", write_geo(D / "valleys.tif", "valleys"))
if want("ridge"):  # narrow ridge between low waypoints
    run("ridge", write_geo(D / "ridge.tif", "ridge", res=0.002))
if want("ceiling"):
    run(
        "ceiling", write_geo(D / "high.tif", "high"), formats=("qgc",), uav={"max_altitude_m": 4500}
    )
if want("utm"):
    run("utm", write_projected(D / "utm.tif", "valleys", "EPSG:32632"))
if want("feet"):
    run(
        "feet",
        write_projected(
            D / "feet.tif",
            "valleys",
            "+proj=utm +zone=32 +datum=WGS84 +units=ft +no_defs",
            units_per_m=1 / 0.3048,
        ),
    )
if want("void"):
    run(
        "void",
        write_geo(D / "void.tif", "valleys", void=(slice(100, 104), slice(200, 204))),
        formats=("qgc",),
    )
if want("partial"):
    run("partial", write_geo(D / "partial.tif", "valleys", lon=(7.6, 8.5)), formats=("qgc",))
if want("area"):  # the tilted plane, area convention (the glide case)
    run("area", write_geo(D / "area.tif", "tilt"), formats=("qgc",))
if want("southup"):
    run("southup", write_geo(D / "southup.tif", "tilt", south_up=True), formats=("qgc",))
if want("rotated"):
    run(
        "rotated",
        write_projected(D / "rotated.tif", "tilt", "EPSG:32632", rot_deg=20.0),
        formats=("qgc",),
    )
if want("tight"):  # low search height: the profile hugs the ground; ridge between waypoints
    run(
        "tight",
        write_geo(D / "ridge.tif", "ridge", res=0.002),
        uav={"cruise_altitude_m": 160, "max_altitude_m": 3600},
    )
    run("tightv", write_geo(D / "valleys.tif", "valleys"), uav={"cruise_altitude_m": 160})
if want("tiny2"):
    run("tiny2", write_geo(D / "tiny2.tif", "tilt", lon=(7.3, 9.1), lat=(45.8, 47.6), res=0.9))
if want("point2"):
    import rasterio

    p = write_geo(D / "point2.tif", "tilt")
    with rasterio.open(p, "r+") as ds:
        ds.update_tags(AREA_OR_POINT="Point")
    with rasterio.open(p) as ds:
        print("point2 transform", ds.transform, ds.tags())
    with rasterio.open(D / "area.tif") as ds:
        print("area transform", ds.transform, ds.tags())
    run("point2", p, formats=("qgc",))
if want("scaled"):  # int16 decimetres with scale 0.1 (GDAL scale/offset metadata)
    import numpy as _np
    import rasterio

    src = write_geo(D / "tiltm.tif", "tilt")
    with rasterio.open(src) as s:
        z, prof = s.read(1), s.profile
    prof.update(dtype="int16", nodata=-32768)
    with rasterio.open(D / "scaled.tif", "w", **prof) as d:
        d.write(_np.round(z * 10).astype("int16"), 1)
        d.scales = (0.1,)
        d.offsets = (0.0,)
    with rasterio.open(D / "scaled.tif") as s:
        print("scaled: scales", s.scales, "offsets", s.offsets, "raw max", s.read(1).max())
    run("scaled", D / "scaled.tif", formats=("qgc",))
if want("feetz"):  # heights in feet, the band's unit type says so
    import rasterio

    src = write_geo(D / "tiltm.tif", "tilt")
    with rasterio.open(src) as s:
        z, prof = s.read(1), s.profile
    with rasterio.open(D / "feetz.tif", "w", **prof) as d:
        d.write((z / 0.3048).astype("float32"), 1)
        d.units = ("ft",)
    with rasterio.open(D / "feetz.tif") as s:
        print("feetz: units", s.units)
    run("feetz", D / "feetz.tif", formats=("qgc",))
if want("edge"):  # a DEM covering the operating area but not the terrain grid's outer cells
    import rasterio
    from rasterio.transform import from_origin as _fo

    from poc_env.agents.mission.crs import crs_text, make_crs

    crs = crs_text(make_crs("aeqd", ORIGIN))
    x0, x1, y0, y1 = -30.65e3, 81e3, -21e3, 61e3
    res = 250.0
    nx, ny = round((x1 - x0) / res), round((y1 - y0) / res)
    z = np.full((ny, nx), 800.0, dtype="float32")
    write_tif(D / "edge.tif", z, _fo(x0, y1, res, res), crs)
    data = scenario(D / "edge.tif")
    data["airfields"][0]["position_km"] = [-10.3, 20.7]
    sc = load_scenario(data)
    from poc_env.sim.core import operating_area

    print(
        "edge: operating area km",
        [round(v / 1e3, 3) for v in operating_area(sc)],
        "DEM x0 -30.65 km",
    )
    try:
        t = load_terrain(sc)
        print(
            "edge: loaded, grid bounds km",
            [round(v / 1e3, 3) for v in t.bounds],
            "max",
            float(t.ground_max_m.max()),
        )
    except ConfigError as e:
        print("edge: refused:", e)
