import math

import numpy as np
import rasterio
from rasterio.transform import from_origin

lon0, lat0, res = 7.0, 47.1, 0.005
nx, ny = round(2.3 / res), round(1.2 / res)
lons = lon0 + (np.arange(nx) + 0.5) * res
x_km = (lons - 7.9) * 111.32 * math.cos(math.radians(46.5))
z = np.tile(np.clip(600 + 20 * x_km, 200, None), (ny, 1)).astype("float32")
with rasterio.open(
    "dem2.tif",
    "w",
    driver="GTiff",
    width=nx,
    height=ny,
    count=1,
    dtype="float32",
    transform=from_origin(lon0, lat0, res, res),
    nodata=-9999.0,
    crs="EPSG:4326",
) as d:
    d.write(z, 1)
