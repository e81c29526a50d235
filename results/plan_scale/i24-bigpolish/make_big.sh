#!/bin/sh
# The audit's 500 km scenario (results/audit/scale/raw/make_inputs.py: 160 x 160 cells at
# 3.125 km, 24 UAVs, 4 airfields, 3 zones) with its own prior (seed 7: big_7.yaml) and with
# the prior's 12 sightings drawn by validation seeds 5000-5002 (big_5000.yaml ...), the same
# draw as make_inputs.py's with another seed. Usage (from the checkout): sh make_big.sh OUTDIR
set -e
OUT=$1
mkdir -p "$OUT"
P=.venv/bin
$P/python results/audit/scale/raw/make_inputs.py 500 24 "$OUT/in" >/dev/null
for seed in 7 5000 5001 5002; do
  $P/python - "$OUT/in" "$seed" <<'PY'
import sys
from pathlib import Path
import numpy as np
import pyproj
out, seed, s = Path(sys.argv[1]), int(sys.argv[2]), 500.0
crs = pyproj.CRS.from_proj4("+proj=aeqd +lat_0=45.0 +lon_0=5.0 +datum=WGS84")
inv = pyproj.Transformer.from_crs(crs, "EPSG:4326", always_xy=True)
rng = np.random.default_rng(seed)
pts = rng.uniform(0.05 * s, 0.95 * s, (12, 2))
w = rng.uniform(0.2, 1, 12)
w /= w.sum()
lon, lat = inv.transform(pts[:, 0] * 1e3, pts[:, 1] * 1e3)
(out / f"prior_{seed}.csv").write_text(
    "lat,lon,probability\n" + "".join(f"{b:.6f},{a:.6f},{p:.6f}\n" for a, b, p in zip(lon, lat, w))
)
PY
  $P/poc-env scenario import "$OUT/in/area.geojson" --prior "$OUT/in/prior_$seed.csv" \
    --airfields "$OUT/in/fields.geojson" --no-fly "$OUT/in/zones.geojson" --dem "$OUT/in/dem.tif" \
    --cell-km 3.125 --origin 45.0,5.0 --base "$OUT/in/base.yaml" --out "$OUT/big_$seed.yaml" >/dev/null
done
cmp "$OUT/in/prior.csv" "$OUT/in/prior_7.csv" && echo "seed 7 = make_inputs.py's prior"
