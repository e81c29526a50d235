"""Terrain audit probes: DEM variants -> plan -> export (4 formats) -> independent checks."""

from __future__ import annotations

import itertools
import json
import math
import os
import traceback
from pathlib import Path

import numpy as np
import rasterio
from pyproj import Geod, Transformer
from rasterio.transform import Affine, from_origin

from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.plan import write_plan
from poc_env.agents.mission.terrain import load_terrain
from poc_env.agents.planning.planner import make_plan
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

D = Path(os.environ.get("TERRAIN_AUDIT_DIR", "/tmp/terrain-audit"))
ORIGIN = (46.5, 7.9)
KMLON = 111.32 * math.cos(math.radians(ORIGIN[0]))
GEOD = Geod(ellps="WGS84")


def height(lon, lat, kind="valleys"):
    x = (lon - ORIGIN[1]) * KMLON
    y = (lat - ORIGIN[0]) * 111.2
    if kind == "valleys":  # steep valleys: 600 m floors, 3000 m crests every 12 km, east-west
        return 600 + 2400 * np.abs(np.sin(np.pi * y / 12.0)) ** 0.5
    if kind == "ridge":  # narrow 3,400 m ridge at x=30 km
        return 600 + 2800 * np.exp(-(((x - 30) / 1.0) ** 2))
    if kind == "high":
        return 600 + 4400 * np.exp(-(((x - 30) / 4.0) ** 2))
    if kind == "tilt":  # a plane rising east and north: orientation checks
        return 500 + 20 * x + 5 * y
    raise ValueError(kind)


def write_tif(path, z, transform, crs, nodata=-9999.0):
    """Write the float32 grid ``z`` (rows from the north) as a one-band GeoTIFF."""
    ny, nx = z.shape
    with rasterio.open(
        path, "w", driver="GTiff", width=nx, height=ny, count=1, dtype="float32",
        transform=transform, crs=crs, nodata=nodata,
    ) as dst:  # fmt: skip
        dst.write(np.asarray(z, dtype="float32"), 1)
    return path


def write_geo(
    path,
    kind,
    crs="EPSG:4326",
    lon=(7.0, 9.3),
    lat=(45.9, 47.1),
    res=0.005,
    south_up=False,
    void=None,
    nodata=-9999.0,
):
    nx, ny = round((lon[1] - lon[0]) / res), round((lat[1] - lat[0]) / res)
    lons = lon[0] + (np.arange(nx) + 0.5) * res
    lats = lat[1] - (np.arange(ny) + 0.5) * res
    z = height(*np.meshgrid(lons, lats), kind).astype("float32")
    tr = from_origin(lon[0], lat[1], res, res)
    if void is not None:
        z[void] = nodata
    if south_up:
        z = z[::-1].copy()
        tr = Affine(res, 0, lon[0], 0, res, lat[0])
    write_tif(path, z, tr, crs, nodata)
    return path


def write_projected(path, kind, crs, res_m=250.0, rot_deg=0.0, units_per_m=1.0, npix=None):
    """A DEM in a projected CRS around the area (x, y in CRS units), optionally rotated."""
    t = Transformer.from_crs("EPSG:4326", crs, always_xy=True)
    inv = Transformer.from_crs(crs, "EPSG:4326", always_xy=True)
    cx, cy = t.transform(ORIGIN[1] + 0.4, ORIGIN[0] + 0.2)
    half = 110e3 * units_per_m
    res = res_m * units_per_m
    n = npix or int(2 * half / res)
    if npix:
        res = 2 * half / n
    a = math.radians(rot_deg)
    tr = (
        Affine.translation(
            cx - half * (math.cos(a) - math.sin(a)), cy + half * (math.cos(a) + math.sin(a))
        )
        * Affine.rotation(-rot_deg)
        * Affine.scale(res, -res)
    )
    cols, rows = np.meshgrid(np.arange(n) + 0.5, np.arange(n) + 0.5)
    xs, ys = tr * (cols, rows)
    lon, lat = inv.transform(xs, ys)
    z = height(np.asarray(lon), np.asarray(lat), kind).astype("float32")
    write_tif(path, z, tr, crs)
    return path


def scenario(dem, **uav):
    return {
        "name": "alps",
        "map": {
            "width_km": 60,
            "height_km": 40,
            "cell_km": 5,
            "origin_deg": list(ORIGIN),
            "prior": {"components": [{"mean_km": [32, 20], "sigma_km": [10, 8]}]},
        },
        "airfields": [{"name": "valley", "position_km": [-10, 20]}],
        "fleet": [{"takeoff": "valley", "count": 2}],
        "uav": {"max_altitude_m": 6000, **uav},
        "terrain": {"dem": str(dem)},
    }


def dem_at(dem, lat, lon, how="bilinear"):
    """The DEM's own height at (lat, lon): bilinear between pixel centres (independent)."""
    with rasterio.open(dem) as src:
        band = src.read(1).astype(float) * src.scales[0] + src.offsets[0]
        band *= {"ft": 0.3048}.get(src.units[0] or "", 1.0)  # as declared (independent)
        sx, sy = Transformer.from_crs("EPSG:4326", src.crs, always_xy=True).transform(lon, lat)
        c, r = ~src.transform @ (np.asarray(sx), np.asarray(sy))
    c, r = np.asarray(c) - 0.5, np.asarray(r) - 0.5
    c0 = np.clip(np.floor(c).astype(int), 0, band.shape[1] - 2)
    r0 = np.clip(np.floor(r).astype(int), 0, band.shape[0] - 2)
    tc, tr = np.clip(c - c0, 0, 1), np.clip(r - r0, 0, 1)
    return (
        band[r0, c0] * (1 - tc) * (1 - tr)
        + band[r0, c0 + 1] * tc * (1 - tr)
        + band[r0 + 1, c0] * (1 - tc) * tr
        + band[r0 + 1, c0 + 1] * tc * tr
    )


def check_line(dem, lla, step=50.0):
    """(least height above the DEM along the polyline, worst |gradient|) of (lat, lon, alt)."""
    least, worst = math.inf, 0.0
    for a, b in itertools.pairwise(lla):
        d = GEOD.inv(a[1], a[0], b[1], b[0])[2]
        if d > 1:
            worst = max(worst, abs(b[2] - a[2]) / d)
        n = max(2, math.ceil(d / step) + 1)
        s = np.linspace(0, 1, n)
        lat = a[0] + (b[0] - a[0]) * s
        lon = a[1] + (b[1] - a[1]) * s
        alt = a[2] + (b[2] - a[2]) * s
        least = min(least, float(np.min(alt - dem_at(dem, lat, lon))))
    return least, worst


def run(name, dem, planner="allocation", uav=None, formats=("qgc", "kml", "geojson", "html")):
    out = D / name
    out.mkdir(exist_ok=True)
    rec = {"probe": name, "dem": str(dem)}
    try:
        sc = load_scenario(scenario(dem, **(uav or {})))
        t = load_terrain(sc)
        rec["field_m"] = t.fields[0][2]
        lat_f, lon_f = ORIGIN[0] + 20 / 111.2, ORIGIN[1] - 10 / KMLON
        rec["field_dem_m"] = float(dem_at(dem, lat_f, lon_f))
        rec["terrain_max_m"] = float(t.ground_max_m.max())
        plan = make_plan(sc, planner=planner, uavs=2, refine=0)
        write_plan(plan, out / "plan.json")
        tan = math.tan(sc.uav.max_pitch_rad)
        rec["tan_beta"] = tan
        for fmt in formats:
            files = export_plan(out / "plan.json", fmt, out_dir=out / fmt)
            if fmt == "qgc":
                res = []
                for f in files:
                    m = json.loads(f.read_text())["mission"]
                    nav = [it for it in m["items"] if it["command"] in (16, 22)]
                    lla = [(it["params"][4], it["params"][5], it["params"][6]) for it in nav]
                    least, grad = check_line(dem, lla)
                    home = m["plannedHomePosition"]
                    res.append(
                        {
                            "least_agl_m": round(least, 1),
                            "max_grad": round(grad, 6),
                            "home_m": home[2],
                            "home_dem_m": round(float(dem_at(dem, home[0], home[1])), 1),
                            "land_m": m["items"][-1]["params"][6],
                        }
                    )
                rec["qgc"] = res
            if fmt == "kml":
                from lxml import etree

                ns = {"k": "http://www.opengis.net/kml/2.2"}
                kml = next(f for f in files if f.suffix == ".kml")
                res = []
                for pm in etree.parse(str(kml)).iterfind(".//k:Placemark", ns):
                    if not pm.findtext("k:name", namespaces=ns).endswith(" route"):
                        continue
                    xyz = [
                        [float(v) for v in c.split(",")]
                        for c in pm.findtext(".//k:coordinates", namespaces=ns).split()
                    ]
                    lla = [(c[1], c[0], c[2]) for c in xyz]
                    least, grad = check_line(dem, lla[1:-1])
                    res.append(
                        {
                            "least_agl_m": round(least, 1),
                            "max_grad": round(grad, 6),
                            "first_m": lla[0][2],
                            "last_m": lla[-1][2],
                        }
                    )
                rec["kml"] = res
            if fmt == "geojson":
                res = []
                for f in files:
                    doc = json.loads(f.read_text())
                    for ft in doc.get("features", []):
                        g = ft["geometry"]
                        if g["type"] == "LineString":
                            c = g["coordinates"]
                            res.append({"dims": len(c[0]), "props": sorted(ft["properties"])[:12]})
                            if len(c[0]) == 3:
                                lla = [(p[1], p[0], p[2]) for p in c]
                                least, grad = check_line(dem, lla[1:-1])
                                res[-1].update(least_agl_m=round(least, 1), max_grad=round(grad, 6))
                rec["geojson"] = res
            rec.setdefault("files", []).append(fmt)
    except ConfigError as e:
        rec["error"] = str(e)
    except Exception as e:
        rec["crash"] = "".join(traceback.format_exception_only(e)).strip()
        traceback.print_exc()
    print(json.dumps(rec, default=float))
    return rec
