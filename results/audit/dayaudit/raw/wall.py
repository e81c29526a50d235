"""i24-dayaudit: a DEM with a 2,600 m wall 2-5 km north of the South field (a script).

``python wall.py`` in the folder holding make_inputs.py's ``in/`` (README, probes 13-14):
writes ``in/dem_wall.tif``, flat 400 m elsewhere, on ``in/dem.tif``'s grid."""

import json
from pathlib import Path

import numpy as np
import rasterio

fields = json.loads(Path("in/fields.geojson").read_text())["features"]
lon, lat = next(f["geometry"]["coordinates"] for f in fields if f["properties"]["name"] == "South")
with rasterio.open("in/dem.tif") as src:
    z, t, prof = src.read(1), src.transform, src.profile
ny, nx = z.shape
LON, LAT = np.meshgrid(t.c + (np.arange(nx) + 0.5) * t.a, t.f + (np.arange(ny) + 0.5) * t.e)
z = np.full_like(z, 400.0)
z[(np.abs(LAT - (lat + 0.035)) < 0.015) & (np.abs(LON - lon) < 1.0)] = 2600.0
with rasterio.open("in/dem_wall.tif", "w", **prof) as d:
    d.write(z.astype("float32"), 1)
