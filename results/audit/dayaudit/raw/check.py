"""i24-dayaudit: validate export folders (a script, not a test).

``python check.py DIR [DIR ...]``: per file, KML against the OGC XSD (``validate_kml``), QGC
by the project's schema (``validate_qgc``), GeoJSON by RFC 7946's rules (a FeatureCollection,
no ``crs`` member, positions of 2-3 finite numbers in range, closed rings, the exterior
counter-clockwise and holes clockwise, polygons valid by shapely, lines of 2+ positions), HTML
parsed; then what shows the altitude layers.
"""

import json
import math
import sys
from html.parser import HTMLParser
from pathlib import Path

import shapely.geometry as sg

from poc_env.agents.mission.formats.geojson import ring_area
from poc_env.agents.mission.formats.kml import validate_kml
from poc_env.agents.mission.formats.qgc import validate_qgc


def pos_ok(p):
    """An RFC 7946 position: 2 or 3 finite numbers, lon and lat in range."""
    return (
        isinstance(p, list)
        and len(p) in (2, 3)
        and all(isinstance(v, (int, float)) and math.isfinite(v) for v in p)
        and -180 <= p[0] <= 180
        and -90 <= p[1] <= 90
    )


def positions(g):
    """Every position of geometry ``g``."""
    t, c = g["type"], g.get("coordinates")
    if t == "Point":
        return [c]
    if t in ("LineString", "MultiPoint"):
        return c
    if t in ("Polygon", "MultiLineString"):
        return [p for r in c for p in r]
    if t == "MultiPolygon":
        return [p for poly in c for r in poly for p in r]
    if t == "GeometryCollection":
        return [p for gg in g["geometries"] for p in positions(gg)]
    raise ValueError(t)


def check_geojson(f):
    """The complaints about GeoJSON file ``f``, and the parsed document."""
    d = json.loads(f.read_text())
    errs = []
    if d.get("type") != "FeatureCollection":
        errs.append("not a FeatureCollection")
    if "crs" in d:
        errs.append("crs member (RFC 7946 4)")
    for i, feat in enumerate(d["features"]):
        g = feat["geometry"]
        if feat.get("type") != "Feature" or "properties" not in feat:
            errs.append(f"feature {i} shape")
        if g is None:
            continue
        bad = [p for p in positions(g) if not pos_ok(p)]
        if bad:
            errs.append(f"feature {i} bad positions {bad[:2]}")
        polys = {"Polygon": [g.get("coordinates")], "MultiPolygon": g.get("coordinates")}
        for poly in polys.get(g["type"], []):
            for k, r in enumerate(poly):
                if r[0] != r[-1] or len(r) < 4:
                    errs.append(f"feature {i} ring not closed")
                a = ring_area(r)
                if (k == 0 and a <= 0) or (k > 0 and a >= 0):
                    errs.append(f"feature {i} ring {k} winding")
        if g["type"] in polys and not sg.shape(g).is_valid:
            errs.append(f"feature {i} invalid polygon")
        if g["type"] == "LineString" and len(g["coordinates"]) < 2:
            errs.append(f"feature {i} line < 2")
    return errs, d


for folder in sys.argv[1:]:
    for f in sorted(Path(folder).iterdir()):
        if f.suffix == ".kml":
            e, extra = validate_kml(f), "layer" in f.read_text()
        elif f.suffix == ".plan":
            e, extra = validate_qgc(json.loads(f.read_text())), ""
        elif f.suffix == ".geojson":
            e, d = check_geojson(f)
            layers = {x["properties"].get("layer_m") for x in d["features"]} - {None}
            extra = (d.get("properties", {}).get("altitude_layers"), sorted(layers))
        elif f.suffix == ".html":
            HTMLParser().feed(f.read_text())
            e, extra = [], f.read_text().count("layer +")
        else:
            continue
        print(f"{f}: {'OK' if not e else e[:3]} {extra}")
