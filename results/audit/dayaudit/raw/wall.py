import json, numpy as np, rasterio
from rasterio.transform import from_origin
src = rasterio.open("in/dem.tif"); z = src.read(1); t = src.transform
f = {x["properties"]["name"]: x["geometry"]["coordinates"] for x in json.load(open("in/fields.geojson"))["features"]}
lon, lat = f["South"]
ny, nx = z.shape
lats = t.f + (np.arange(ny) + 0.5) * t.e
lons = t.c + (np.arange(nx) + 0.5) * t.a
LON, LAT = np.meshgrid(lons, lats)
z = np.full_like(z, 400.0)
band = (LAT > lat + 0.02) & (LAT < lat + 0.05) & (abs(LON - lon) < 1.0)
z[band] = 2600.0
prof = src.profile
with rasterio.open("in/dem_wall.tif", "w", **prof) as d:
    d.write(z.astype("float32"), 1)
print("wall", band.sum())
