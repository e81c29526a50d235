"""Scratch inputs: a 500 x 500 km area near 47 N 8 E, 4 airfields, 3 zones, DEM, prior CSV,
a 24-UAV base scenario. Usage: python make_inputs.py SIDE_KM N_UAVS OUTDIR"""

import json
import sys
from pathlib import Path

import numpy as np
import pyproj
import rasterio
import yaml
from rasterio.transform import from_origin

side = float(sys.argv[1])
n = int(sys.argv[2])
out = Path(sys.argv[3])
out.mkdir(exist_ok=True)
lat0, lon0 = 45.0, 5.0
crs = pyproj.CRS.from_proj4(f"+proj=aeqd +lat_0={lat0} +lon_0={lon0} +datum=WGS84")
inv = pyproj.Transformer.from_crs(crs, "EPSG:4326", always_xy=True)


def ll(xkm, ykm):
    lon, lat = inv.transform(np.asarray(xkm) * 1e3, np.asarray(ykm) * 1e3)
    return lon, lat


# area polygon, densified edges, inset 0.5 km
e = np.linspace(0.5, side - 0.5, 50)
xs = np.r_[e, np.full(50, side - 0.5), e[::-1], np.full(50, 0.5)]
ys = np.r_[np.full(50, 0.5), e, np.full(50, side - 0.5), e[::-1]]
lon, lat = ll(xs, ys)
ring = [[float(a), float(b)] for a, b in zip(lon, lat)] + [[float(lon[0]), float(lat[0])]]


def fc(feats):
    return {"type": "FeatureCollection", "features": feats}


(out / "area.geojson").write_text(
    json.dumps(
        fc(
            [
                {
                    "type": "Feature",
                    "properties": {"name": "big area"},
                    "geometry": {"type": "Polygon", "coordinates": [ring]},
                }
            ]
        )
    )
)
s = side
fields = {
    "North": (s / 2, s + 15),
    "South": (s / 2, -15),
    "West": (-15, s / 2),
    "East": (s + 15, s / 2),
}
feats = []
for name, (x, y) in fields.items():
    a, b = ll(x, y)
    feats.append(
        {
            "type": "Feature",
            "properties": {"name": name},
            "geometry": {"type": "Point", "coordinates": [float(a), float(b)]},
        }
    )
(out / "fields.geojson").write_text(json.dumps(fc(feats)))
zones = {
    "R-1 range": (0.2 * s, 0.3 * s, 0.35 * s, 0.45 * s),
    "R-2 prison": (0.6 * s, 0.55 * s, 0.7 * s, 0.62 * s),
    "TRA 3": (0.45 * s, 0.8 * s, 0.55 * s, 0.9 * s),
}
feats = []
for name, (x0, y0, x1, y1) in zones.items():
    lon, lat = ll([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0])
    feats.append(
        {
            "type": "Feature",
            "properties": {"name": name},
            "geometry": {
                "type": "Polygon",
                "coordinates": [[[float(a), float(b)] for a, b in zip(lon, lat)]],
            },
        }
    )
(out / "zones.geojson").write_text(json.dumps(fc(feats)))
rng = np.random.default_rng(7)
pts = rng.uniform(0.05 * s, 0.95 * s, (12, 2))
w = rng.uniform(0.2, 1, 12)
w /= w.sum()
lon, lat = ll(pts[:, 0], pts[:, 1])
(out / "prior.csv").write_text(
    "lat,lon,probability\n" + "".join(f"{b:.6f},{a:.6f},{p:.6f}\n" for a, b, p in zip(lon, lat, w))
)
# DEM in EPSG:4326 covering the operating area + margin
lonc, latc = ll([-80, s + 80, s + 80, -80], [-80, -80, s + 80, s + 80])
lo0, lo1, la0, la1 = min(lonc) - 0.3, max(lonc) + 0.3, min(latc) - 0.3, max(latc) + 0.3
res = 0.01
nx, ny = round((lo1 - lo0) / res), round((la1 - la0) / res)
LON, LAT = np.meshgrid(lo0 + (np.arange(nx) + 0.5) * res, la1 - (np.arange(ny) + 0.5) * res)
z = (
    400
    + 1800 * np.exp(-((LON - (lo0 + lo1) / 2) ** 2 / 2 + (LAT - (la0 + la1) / 2) ** 2 / 1.0))
    + 300 * np.sin(LON * 3) * np.cos(LAT * 4)
)
with rasterio.open(
    out / "dem.tif",
    "w",
    driver="GTiff",
    width=nx,
    height=ny,
    count=1,
    dtype="float32",
    transform=from_origin(lo0, la1, res, res),
    nodata=-9999.0,
    crs="EPSG:4326",
) as d:
    d.write(z.astype("float32"), 1)
base = yaml.safe_load(
    Path(sys.argv[4] if len(sys.argv) > 4 else "configs/large_400.yaml").read_text()
)
base["fleet"] = [{"takeoff": "A", "count": n}]
base["uav"]["endurance_h"] = 5
base["uav"]["max_altitude_m"] = 5000
base.pop("airfields", None)
base["airfields"] = [{"name": "A", "position_km": [0, -10]}]
(out / "base.yaml").write_text(yaml.safe_dump(base))
print("dem", nx, ny, "z max", z.max())
