"""Legs of QGC missions (take-off item and waypoints) climbing or descending steeper than
tan(15 deg): ``over`` beyond the 0.1 m altitude resolution of the export, else ``rounding``."""

import itertools
import json
import math
import sys

from pyproj import Geod

G = Geod(ellps="WGS84")
TAN = math.tan(math.radians(15))
RES = 0.1
for f in sys.argv[1:]:
    with open(f) as fh:
        m = json.load(fh)["mission"]
    nav = [it for it in m["items"] if it["command"] in (16, 22)]
    for a, b in itertools.pairwise(nav):
        pa, pb = a["params"], b["params"]
        d = G.inv(pa[5], pa[4], pb[5], pb[4])[2]
        dz = abs(pb[6] - pa[6])
        if d > 0 and dz / d > TAN:
            verdict = "over" if (dz - RES) / d > TAN else "rounding"
            name = "/".join(f.split("/")[-3:])
            print(f"{name} leg {d:.1f} m dz {dz:.2f} grad {dz / d:.6f} ({verdict})")
