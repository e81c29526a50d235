"""The final glide (approach waypoint -> NAV_LAND) of QGC missions against tan(15 deg):
``over`` beyond the 0.1 m altitude resolution of the export, ``rounding`` within it."""

import json
import math
import sys

from pyproj import Geod

G = Geod(ellps="WGS84")
TAN = math.tan(math.radians(15))
RES = 0.1  # the exports write altitudes to 0.1 m
for f in sys.argv[1:]:
    with open(f) as fh:
        m = json.load(fh)["mission"]
    nav = [it for it in m["items"] if it["command"] in (16, 21, 22)]
    a, b = nav[-2]["params"], nav[-1]["params"]
    d = G.inv(a[5], a[4], b[5], b[4])[2]
    g = (a[6] - b[6]) / d
    verdict = "over" if (a[6] - b[6] - RES) / d > TAN else ("rounding" if g > TAN else "ok")
    name = "/".join(f.split("/")[-3:])
    print(f"{name} approach {a[6]} field {b[6]} dist {d:.0f} glide {g:.4f} ({verdict})")
