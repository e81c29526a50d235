"""The SAR walkthrough's synthetic DEM (tests/mission/test_terrain.py's _height/_dem)."""

import math

import numpy as np
import rasterio
from rasterio.transform import from_origin

ORIGIN = (46.5, 7.9)
RIDGE_X_KM = 30.0
VALLEY_M, RIDGE_M = 600.0, 4000.0
K = 111.32 * math.cos(math.radians(ORIGIN[0]))
lon, lat, res = (7.0, 9.3), (45.9, 47.1), 0.005
nx, ny = round((lon[1] - lon[0]) / res), round((lat[1] - lat[0]) / res)
LON, LAT = np.meshgrid(lon[0] + (np.arange(nx) + 0.5) * res, lat[1] - (np.arange(ny) + 0.5) * res)
z = (
    VALLEY_M + (RIDGE_M - VALLEY_M) * np.exp(-(((((LON - ORIGIN[1]) * K) - RIDGE_X_KM) / 5.0) ** 2))
).astype("float32")
with rasterio.open(
    "dem.tif",
    "w",
    driver="GTiff",
    width=nx,
    height=ny,
    count=1,
    dtype="float32",
    transform=from_origin(lon[0], lat[1], res, res),
    nodata=-9999.0,
    crs="EPSG:4326",
) as d:
    d.write(z, 1)
