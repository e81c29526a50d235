"""Independent checks of poc-env exports against the target tools' own definitions.

Run with the scratch venv (/tmp/export-audit/venv: lxml, html5lib, shapely, geojson, pyproj,
jsonschema; no project code imported). Usage: check.py PLAN.json OUTDIR
"""

import glob
import itertools
import json
import math
import re
import sys
from pathlib import Path

import geojson as gj
import html5lib
import pyproj
from lxml import etree
from shapely.geometry import LineString, Polygon

KML_XSD = "/tmp/export-audit/venv/lib/python3.11/site-packages/pykml/schemas/ogckml22.xsd"
NS = {"k": "http://www.opengis.net/kml/2.2"}
problems: list[str] = []


def bad(msg):
    problems.append(msg)


def reject_constant(c):
    raise ValueError(f"non-JSON constant {c}")


plan = json.loads(Path(sys.argv[1]).read_text(encoding="utf-8"))
out = Path(sys.argv[2])
crs = plan["crs"]
proj = pyproj.Transformer.from_crs(
    pyproj.CRS.from_user_input(crs.get("proj") or f"EPSG:{crs['epsg']}"),
    "EPSG:4326",
    always_xy=True,
)
if crs["kind"] != "aeqd":
    x0, y0 = pyproj.Transformer.from_crs("EPSG:4326", proj.source_crs, always_xy=True).transform(
        crs["origin_deg"][1], crs["origin_deg"][0]
    )
else:
    x0 = y0 = 0.0


def ll(p):
    lon, lat = proj.transform(p[0] + x0, p[1] + y0)
    return lat, lon


terrain = plan.get("terrain")
field_elev = {f["name"]: f["elevation_m"] for f in (terrain or {}).get("fields", [])}
geod = pyproj.Geod(ellps="WGS84")


def dist(a, b):  # (lat, lon)
    return geod.inv(a[1], a[0], b[1], b[0])[2]


# ------------------------------------------------------------------ QGC
def nullable_num(v):
    return v is None or (isinstance(v, (int, float)) and not isinstance(v, bool))


for f in sorted(glob.glob(str(out / "*.plan"))):
    name = Path(f).name
    doc = json.loads(Path(f).read_text(encoding="utf-8"), parse_constant=reject_constant)
    if doc.get("fileType") != "Plan" or doc.get("version") != 1:
        bad(f"{name}: fileType/version")
    if not isinstance(doc.get("groundStation"), str):
        bad(f"{name}: groundStation")
    for k in ("mission", "geoFence", "rallyPoints"):
        if not isinstance(doc.get(k), dict):
            bad(f"{name}: {k} not object")
    m = doc["mission"]
    for k, t in (("plannedHomePosition", list), ("items", list)):
        if not isinstance(m.get(k), t):
            bad(f"{name}: mission.{k}")
    if not isinstance(m.get("firmwareType"), (int, float)):
        bad(f"{name}: firmwareType")
    for k in ("vehicleType", "cruiseSpeed", "hoverSpeed", "globalPlanAltitudeMode"):
        if k in m and not nullable_num(m[k]):
            bad(f"{name}: {k} type")
    if m.get("globalPlanAltitudeMode") not in (None, 1, 2, 4):
        bad(
            f"{name}: globalPlanAltitudeMode {m.get('globalPlanAltitudeMode')}"
            " (0/3/5 changed meaning)"
        )
    home = m["plannedHomePosition"]
    if len(home) != 3 or not all(isinstance(v, (int, float)) for v in home):
        bad(f"{name}: plannedHomePosition {home}")
    if not (-90 <= home[0] <= 90 and -180 <= home[1] <= 180):
        bad(f"{name}: home off the globe {home}")
    ids = []
    uid = re.search(r"_uav(.+)\.plan$", name).group(1)
    u = next(x for x in plan["uavs"] if str(x["id"]) == uid)
    for i, it in enumerate(m["items"]):
        where = f"{name} item {i}"
        if it.get("type") != "SimpleItem":
            bad(f"{where}: type")
        for k in ("frame", "command"):
            if not isinstance(it.get(k), (int, float)):
                bad(f"{where}: {k}")
        if not isinstance(it.get("autoContinue"), bool):
            bad(f"{where}: autoContinue")
        p = it.get("params")
        if not isinstance(p, list) or len(p) != 7 or not all(nullable_num(v) for v in p):
            bad(f"{where}: params {p}")
        ids.append(it.get("doJumpId"))
        alt_keys = [k for k in ("AltitudeMode", "Altitude", "AMSLAltAboveTerrain") if k in it]
        if alt_keys and len(alt_keys) != 3:
            bad(f"{where}: partial altitude keys {alt_keys}")
        if it["command"] in (16, 21, 22):
            if it["frame"] not in (0, 3, 10):
                bad(f"{where}: nav frame {it['frame']}")
            mode = {3: 1, 0: 2, 10: 4}[it["frame"]]
            if it.get("AltitudeMode") != mode:
                bad(f"{where}: AltitudeMode {it.get('AltitudeMode')} vs frame {it['frame']}")
            if it.get("Altitude") != p[6]:
                bad(f"{where}: Altitude {it.get('Altitude')} != param7 {p[6]}")
            if not (-90 <= p[4] <= 90 and -180 <= p[5] <= 180):
                bad(f"{where}: lat/lon {p[4:6]}")
        elif it["frame"] != 2:
            bad(f"{where}: DO item frame {it['frame']}")
        if it["command"] == 178 and (p[0] not in (0, 1) or not p[1] > 0 or p[2] != -1):
            bad(f"{where}: DO_CHANGE_SPEED params {p}")
    if ids != sorted(set(ids)) or any(not isinstance(v, int) for v in ids):
        bad(f"{name}: doJumpId {ids}")
    items = m["items"]
    nav = [it for it in items if it["command"] in (16, 21, 22)]
    # take-off and landing where the plan says
    t_ll, l_ll = ll(u["takeoff_m"]), ll(u["landing_m"])
    if nav[0]["command"] != 22 or dist(t_ll, nav[0]["params"][4:6]) > 0.01:
        bad(f"{name}: take-off not at the take-off field")
    if nav[-1]["command"] != 21 or dist(l_ll, nav[-1]["params"][4:6]) > 0.01:
        bad(f"{name}: landing not at the landing field")
    if dist(t_ll, home[:2]) > 0.01:
        bad(f"{name}: home not at the take-off field")
    # the plan's waypoints are among the mission's (in order)
    wll = [ll(w) for w in u["waypoints_m"]]
    navll = [tuple(it["params"][4:6]) for it in nav]
    j = 0
    for w in wll:
        while j < len(navll) and dist(w, navll[j]) > 0.01:
            j += 1
        if j == len(navll):
            bad(f"{name}: waypoint {w} missing or out of order")
            break
    # heights above the ground at each field
    frame = nav[0]["frame"]
    home_amsl = home[2]
    land = nav[-1]
    land_amsl = land["params"][6] + (home_amsl if frame == 3 else 0)
    if terrain:
        names = {tuple(a["position_m"]): a["name"] for a in plan.get("airfields", [])}
        lname = names.get(tuple(u["landing_m"]))
        if lname in field_elev and abs(land_amsl - field_elev[lname]) > 0.5:
            bad(f"{name}: NAV_LAND {land_amsl} AMSL vs field {field_elev[lname]}")
    # landing approach: the nav point before NAV_LAND, its glide slope
    app = nav[-2]
    app_amsl = app["params"][6] + (home_amsl if app["frame"] == 3 else 0)
    d = dist(app["params"][4:6], land["params"][4:6])
    slope = math.degrees(math.atan2(app_amsl - land_amsl, d))
    print(f"  {name}: items {len(items)}, approach {d / 1e3:.2f} km, glide {slope:.2f} deg")
    # geofence
    gf = doc["geoFence"]
    if gf.get("version") != 2 or not isinstance(gf.get("circles"), list):
        bad(f"{name}: geoFence version/circles")
    for k, poly in enumerate(gf.get("polygons", [])):
        if poly.get("version") != 1 or not isinstance(poly.get("inclusion"), bool):
            bad(f"{name}: fence {k} version/inclusion")
        pts = poly["polygon"]
        if len(pts) < 3 or any(len(q) != 2 for q in pts):
            bad(f"{name}: fence {k} points")
        if not Polygon([(q[1], q[0]) for q in pts]).is_valid:
            bad(f"{name}: fence {k} not a simple polygon")
    # rally points: QGC sends them as MAV_FRAME_GLOBAL_RELATIVE_ALT (RallyPointManager.cc)
    rp = doc["rallyPoints"]
    if rp.get("version") != 2:
        bad(f"{name}: rally version")
    for q in rp["points"]:
        if len(q) != 3:
            bad(f"{name}: rally point {q}")
        if terrain:
            near = min(plan["airfields"], key=lambda a: dist(ll(a["position_m"]), q[:2]))
            ground = field_elev.get(near["name"])
            amsl = home_amsl + q[2]
            if ground is not None and amsl - ground < 100:
                bad(
                    f"{name}: rally point at {near['name']!r} {amsl:.0f} m AMSL"
                    f" (home {home_amsl:.0f} + {q[2]:.0f}) is {amsl - ground:.0f} m above"
                    f" its ground {ground:.0f} m"
                )

# ------------------------------------------------------------------ KML
schema = etree.XMLSchema(etree.parse(KML_XSD))
names_plan = {str(a["name"]) for a in plan.get("airfields", [])} | set(
    plan.get("no_fly_zone_names") or []
)
for f in sorted(glob.glob(str(out / "*.kml"))):
    name = Path(f).name
    doc = etree.parse(f)
    if not schema.validate(doc):
        bad(f"{name}: XSD {schema.error_log.last_error}")
    styles = {s.get("id") for s in doc.iterfind(".//k:Style", NS)}
    for su in doc.iterfind(".//k:styleUrl", NS):
        if su.text[1:] not in styles:
            bad(f"{name}: styleUrl {su.text} undefined")
    texts = {e.text for e in doc.iterfind(".//k:name", NS)} | {
        e.text for e in doc.iterfind(".//k:description", NS)
    }
    for n in names_plan:
        if not any(n in (t or "") for t in texts):
            bad(f"{name}: name {n!r} not carried intact")
    for c in doc.iterfind(".//k:coordinates", NS):
        tuples = [t.split(",") for t in c.text.split()]
        for t in tuples:
            lon, lat = float(t[0]), float(t[1])
            if not (-180 <= lon <= 180 and -90 <= lat <= 90):
                bad(f"{name}: coordinate {t}")
        parent = c.getparent()
        tag = etree.QName(parent).localname
        if tag == "LinearRing":
            if tuples[0] != tuples[-1] or len(tuples) < 4:
                bad(f"{name}: LinearRing not closed / < 4")
            ring = [(float(t[0]), float(t[1])) for t in tuples]
            a = sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in itertools.pairwise(ring))
            if a < 0:
                owner = parent.getparent().getparent().getparent()
                bad(f"{name}: LinearRing clockwise ({etree.QName(owner).localname})")
        else:
            mode = parent.find("k:altitudeMode", NS)
            if len(tuples[0]) == 3 and mode is None:
                bad(f"{name}: {tag} with z but no altitudeMode")

# ------------------------------------------------------------------ GeoJSON
for f in sorted(glob.glob(str(out / "*.geojson"))):
    name = Path(f).name
    text = Path(f).read_text(encoding="utf-8")
    doc = json.loads(text, parse_constant=reject_constant)
    if "crs" in doc:
        bad(f"{name}: crs member")
    obj = gj.loads(text)
    if not obj.is_valid:
        bad(f"{name}: geojson lib invalid {obj.errors()}")
    for k, ft in enumerate(doc["features"]):
        g = ft["geometry"]
        if "crs" in ft or "crs" in g:
            bad(f"{name}: crs member")
        json.dumps(ft["properties"], allow_nan=False)
        if g["type"] == "Polygon":
            for r, ring in enumerate(g["coordinates"]):
                if ring[0] != ring[-1] or len(ring) < 4:
                    bad(f"{name} f{k}: ring not closed")
                a = sum(p[0] * q[1] - q[0] * p[1] for p, q in itertools.pairwise(ring))
                if (a < 0) == (r == 0):
                    bad(f"{name} f{k} ({ft['properties'].get('kind')}): ring {r} winding")
            if not Polygon(g["coordinates"][0]).is_valid:
                bad(f"{name} f{k}: invalid polygon")
        if g["type"] == "LineString" and not LineString([p[:2] for p in g["coordinates"]]).is_valid:
            bad(f"{name} f{k}: invalid linestring")
        pos = g["coordinates"]
        flat = pos if g["type"] == "Point" else None
        for p in (
            [flat] if flat else (pos if g["type"] == "LineString" else [q for r in pos for q in r])
        ):
            if not (-180 <= p[0] <= 180 and -90 <= p[1] <= 90):
                bad(f"{name} f{k}: position {p}")
            if any(abs(v - round(v, 6)) > 1e-12 for v in p[:2]):
                bad(f"{name} f{k}: precision {p}")
    if "bbox" in doc:
        bad(f"{name}: bbox present (check it)")

# ------------------------------------------------------------------ HTML
for f in sorted(glob.glob(str(out / "*.html"))):
    name = Path(f).name
    raw = Path(f).read_text(encoding="utf-8")
    parser = html5lib.HTMLParser(strict=True, namespaceHTMLElements=False)
    try:
        tree = parser.parse(raw)
    except Exception as e:
        bad(f"{name}: html5lib strict: {e}")
        tree = html5lib.parse(raw, namespaceHTMLElements=False)
    for el in tree.iter():
        for attr in ("src", "href"):
            v = el.get(attr)
            if v and re.match(r"(?i)(https?:)?//", v):
                bad(f"{name}: external {attr} {v[:80]}")
    urls = set(re.findall(r"https?://[^\s\"'<>)]+", raw))
    print(f"  {name}: urls in page: {sorted(urls)[:6]}")
    scripts = [s for s in tree.iter("script")]
    body = " ".join(t for t in tree.itertext())
    for n in names_plan:
        # the name must reach the page as text (table or JSON), never as markup
        data = [json.loads(sc.text) for sc in tree.iter("script") if sc.get("id") == "plan-data"]

        def strings(o):
            if isinstance(o, str):
                yield o
            elif isinstance(o, dict):
                for v in o.values():
                    yield from strings(v)
            elif isinstance(o, list):
                for v in o:
                    yield from strings(v)

        if n not in body and not any(n in t for d in data for t in strings(d)):
            bad(f"{name}: name {n!r} absent")
    for el in tree.iter():
        if isinstance(el.tag, str) and el.tag.lower() in ("range", "hut", "a") and el.tag != "a":
            bad(f"{name}: injected element <{el.tag}>")

print(f"{sys.argv[1]}: {len(problems)} problems")
for p_ in problems:
    print("  -", p_)
