"""Validate every export folder given: KML (OGC XSD), QGC (schema), GeoJSON (RFC 7946 checks), HTML (layers)."""
import json, sys, math
from pathlib import Path
from html.parser import HTMLParser
from poc_env.agents.mission.formats.kml import validate_kml
from poc_env.agents.mission.formats.qgc import validate_qgc
from poc_env.agents.mission.formats.geojson import ring_area
import shapely.geometry as sg

def pos_ok(p):
    return isinstance(p, list) and len(p) in (2, 3) and all(isinstance(v, (int, float)) and math.isfinite(v) for v in p) and -180 <= p[0] <= 180 and -90 <= p[1] <= 90

def walk_positions(g):
    t = g["type"]; c = g.get("coordinates")
    if t == "Point": return [c]
    if t in ("LineString", "MultiPoint"): return c
    if t in ("Polygon", "MultiLineString"): return [p for r in c for p in r]
    if t == "MultiPolygon": return [p for poly in c for r in poly for p in r]
    if t == "GeometryCollection": return [p for gg in g["geometries"] for p in walk_positions(gg)]
    raise ValueError(t)

def check_geojson(f):
    d = json.loads(f.read_text()); errs = []
    if d.get("type") != "FeatureCollection": errs.append("not FC")
    if "crs" in d: errs.append("crs member (RFC 7946 4)")
    for i, feat in enumerate(d["features"]):
        g = feat["geometry"]
        if feat.get("type") != "Feature" or "properties" not in feat: errs.append(f"feature {i} shape")
        if g is None: continue
        bad = [p for p in walk_positions(g) if not pos_ok(p)]
        if bad: errs.append(f"feature {i} bad positions {bad[:2]}")
        polys = [g["coordinates"]] if g["type"] == "Polygon" else g["coordinates"] if g["type"] == "MultiPolygon" else []
        for poly in polys:
            for k, r in enumerate(poly):
                if r[0] != r[-1] or len(r) < 4: errs.append(f"feature {i} ring not closed")
                a = ring_area(r)
                if (k == 0 and a <= 0) or (k > 0 and a >= 0): errs.append(f"feature {i} ring {k} winding")
        if g["type"] in ("Polygon", "MultiPolygon") and not sg.shape(g).is_valid: errs.append(f"feature {i} invalid polygon")
        if g["type"] == "LineString" and len(g["coordinates"]) < 2: errs.append(f"feature {i} line < 2")
    return errs, d

for folder in sys.argv[1:]:
    for f in sorted(Path(folder).iterdir()):
        s = f.suffix
        if s == ".kml": e = validate_kml(f); extra = "layer" in f.read_text()
        elif s == ".plan": e = validate_qgc(json.loads(f.read_text())); extra = ""
        elif s == ".geojson":
            e, d = check_geojson(f); extra = (d.get("properties", {}).get("altitude_layers"), sorted({x["properties"].get("layer_m") for x in d["features"] if "layer_m" in x["properties"]}))
        elif s == ".html":
            p = HTMLParser(); p.feed(f.read_text()); e = []; extra = f.read_text().count("layer +")
        else: continue
        print(f"{f}: {'OK' if not e else e[:3]} {extra}")
