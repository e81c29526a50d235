"""replan-audit probes: track files as real tools write them, read as `poc-env replan` reads them.

Usage: python results/audit/replan/probes.py PLAN.json OUTDIR > probes.log
Writes each probe file into OUTDIR, then reads it with read_tracks -> check_paths ->
searched_belief (what replan does before planning) and prints one line per probe:
name, outcome (tracks read and POS they found, or the ConfigError), seconds, peak MB.
"""

import json
import sys
import time
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np

from poc_env.agents.planning.replan import check_paths, plan_paths, read_tracks, searched_belief
from poc_env.config import load_scenario
from poc_env.crs import to_geographic
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import build_prior

plan = json.loads(Path(sys.argv[1]).read_text())
out = Path(sys.argv[2])
out.mkdir(parents=True, exist_ok=True)
crs = plan["crs"]
sc = load_scenario(plan["scenario"])
prior = build_prior(sc.map)
routes = plan_paths(plan)
ll = [np.array([(lon, lat) for lat, lon in to_geographic(r, crs)]) for r in routes]


def dense(lonlat, n):
    """n points evenly along the polyline (a 1 Hz logger)."""
    seg = np.hypot(*np.diff(lonlat, axis=0).T)
    s = np.concatenate([[0], np.cumsum(seg)])
    t = np.linspace(0, s[-1], n)
    return np.stack([np.interp(t, s, lonlat[:, 0]), np.interp(t, s, lonlat[:, 1])], axis=1)


T0 = "2026-11-28T08:00:00Z"


def trkpts(pts, ele=True, time_=True, ext=False, back=False):
    rows = []
    for j, (lon, lat) in enumerate(pts):
        sec = (len(pts) - j) if back else j
        body = f"<ele>{1000 + j % 7}</ele>" if ele else ""
        if time_:
            hms = f"{8 + sec // 3600:02d}:{sec // 60 % 60:02d}:{sec % 60:02d}"
            body += f"<time>2026-11-28T{hms}Z</time>"
        if ext:
            body += (
                "<extensions><gpxtpx:TrackPointExtension><gpxtpx:atemp>-3</gpxtpx:atemp>"
                "<gpxtpx:hr>0</gpxtpx:hr></gpxtpx:TrackPointExtension></extensions>"
            )
        rows.append(f'<trkpt lat="{lat:.7f}" lon="{lon:.7f}">{body}</trkpt>')
    return "".join(rows)


GPX10 = "http://www.topografix.com/GPX/1/0"


def gpx(body, ns="http://www.topografix.com/GPX/1/1", extra="", version="1.1"):
    return (
        f'<?xml version="1.0" encoding="UTF-8"?>\n<gpx version="{version}" creator="probe" '
        f'xmlns="{ns}" {extra}>{body}</gpx>'
    )


GARMIN = (
    'xmlns:gpxtpx="http://www.garmin.com/xmlschemas/TrackPointExtension/v1" '
    'xmlns:gpxx="http://www.garmin.com/xmlschemas/GpxExtensions/v3" '
    'xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
    'xsi:schemaLocation="http://www.topografix.com/GPX/1/1 '
    'http://www.topografix.com/GPX/1/1/gpx.xsd"'
)


def segs(pts, k):
    """pts cut into k segments that share their end points (a logger paused and resumed)."""
    idx = np.linspace(0, len(pts) - 1, k + 1).astype(int)
    return [pts[idx[i] : idx[i + 1] + 1] for i in range(k)]


def kml(body, extra=""):
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<kml xmlns="http://www.opengis.net/kml/2.2" '
        f'xmlns:gx="http://www.google.com/kml/ext/2.2" {extra}><Document>{body}</Document></kml>'
    )


def coords(pts, alt=True):
    return " ".join(f"{lon:.7f},{lat:.7f}" + (",1000" if alt else "") for lon, lat in pts)


def fc(geoms, **extra):
    feats = [
        {"type": "Feature", "properties": {"name": f"UAV {i + 1}"}, "geometry": g}
        for i, g in enumerate(geoms)
    ]
    return json.dumps({"type": "FeatureCollection", "features": feats, **extra})


def line(pts, z=False):
    return {
        "type": "LineString",
        "coordinates": [[lon, lat, 1000.0] if z else [lon, lat] for lon, lat in pts],
    }


ground = np.repeat(ll[0][:1], 600, axis=0)  # 10 min at the field, engine running
far = np.array(to_geographic([[20000.0, 200000.0]], crs))[0][::-1]  # 200 km north
lo, la = np.array(to_geographic([[-19000.0, 59000.0]], crs))[0][::-1]  # in the area's corner


def trks(fn, name=False):
    """One GPX ``trk`` per UAV route, its segments from ``fn(lonlat)``."""
    head = (lambda i: f"<name>UAV {i + 1}</name>") if name else (lambda i: "")
    return "".join(f"<trk>{head(i)}{fn(q)}</trk>" for i, q in enumerate(ll))


def seg(pts, **kw):
    return f"<trkseg>{trkpts(pts, **kw)}</trkseg>"


def rte(q):
    return "<rte>" + "".join(f'<rtept lat="{b:.7f}" lon="{a:.7f}"/>' for a, b in q) + "</rte>"


def marks(fn):
    """One KML Placemark per UAV route, its body from ``fn(i, lonlat)``."""
    return "".join(f"<Placemark>{fn(i, q)}</Placemark>" for i, q in enumerate(ll))


def ls(q, alt=True, extra=""):
    return f"<LineString>{extra}<coordinates>{coords(q, alt)}</coordinates></LineString>"


def gx_track(q):
    d = dense(q, 300)
    when = "".join(f"<when>{T0}</when>" for _ in d)
    xyz = "".join(f"<gx:coord>{a:.7f} {b:.7f} 1000</gx:coord>" for a, b in d)
    return f"<gx:MultiTrack><gx:Track>{when}{xyz}</gx:Track></gx:MultiTrack>"


ALT = "<extrude>1</extrude><tessellate>1</tessellate><altitudeMode>absolute</altitudeMode>"
EXT = "<extensions><gpxx:TrackExtension><gpxx:DisplayColor>Red</gpxx:DisplayColor>"
EXT += "</gpxx:TrackExtension></extensions>"
AREA = "<Polygon><outerBoundaryIs><LinearRing><coordinates>"
AREA += f"{coords(ll[0][:4])} {coords(ll[0][:1])}</coordinates></LinearRing></outerBoundaryIs>"
AREA += "</Polygon>"
NULL = {"type": "Feature", "properties": {"note": "UAV 4 did not fly"}, "geometry": None}
POINT = {"type": "Point", "coordinates": [float(v) for v in ll[0][0]]}
M3857 = [[879430.0 + 100 * j, 5860000.0 + 50 * j] for j in range(5)]


def named(name):
    return {"type": "name", "properties": {"name": name}}


def swapped(q):
    return {"type": "LineString", "coordinates": [[float(b), float(a)] for a, b in q]}


def mixed(q):
    cs = [[float(a), float(b)] + ([1000.0] if j % 2 else []) for j, (a, b) in enumerate(q)]
    return {"type": "LineString", "coordinates": cs}


def lines_of(q):
    return [[float(v) for v in r] for r in q]


probes: dict[str, str | bytes] = {
    # GPX
    "gpx11_multiseg.gpx": gpx(trks(lambda q: "".join(seg(t) for t in segs(dense(q, 300), 3)), 1)),
    "gpx_garmin_ext.gpx": gpx(trks(lambda q: EXT + seg(dense(q, 300), ext=True), 1), extra=GARMIN),
    "gpx10.gpx": gpx(trks(lambda q: seg(dense(q, 300)), 1), ns=GPX10, version="1.0"),
    "gpx_rte_only.gpx": gpx("".join(rte(q) for q in ll)),
    "gpx_wpt_only.gpx": gpx("".join(f'<wpt lat="{b:.7f}" lon="{a:.7f}"/>' for a, b in ll[0])),
    "gpx_rte_and_trk.gpx": gpx("".join(rte(q) for q in ll) + trks(lambda q: seg(dense(q, 300)))),
    "gpx_50k.gpx": gpx(trks(lambda q: seg(dense(q, 50000 // 3)))),
    "gpx_duplicates.gpx": gpx(trks(lambda q: seg(np.repeat(dense(q, 300), 3, axis=0)))),
    "gpx_ground_start.gpx": gpx(trks(lambda q: seg(np.concatenate([ground, dense(q, 300)])))),
    "gpx_landed_elsewhere_in_area.gpx": gpx(
        trks(lambda q: seg(np.concatenate([dense(q, 300)[:-1], [[lo, la]]])))
    ),
    "gpx_landed_200km_away.gpx": gpx(
        trks(lambda q: seg(np.concatenate([dense(q, 300)[:-1], [far]])))
    ),
    "gpx_time_backwards.gpx": gpx(trks(lambda q: seg(dense(q, 300), back=True))),
    "gpx_no_ele_no_time.gpx": gpx(trks(lambda q: seg(dense(q, 300), ele=False, time_=False))),
    # KML
    "kml_gx_track.kml": kml(marks(lambda i, q: f"<name>UAV {i + 1}</name>{gx_track(q)}")),
    "kml_multigeometry.kml": kml(
        marks(
            lambda i, q: (
                f"<name>UAV {i + 1}</name><MultiGeometry>"
                + "".join(ls(t) for t in segs(q, 2))
                + f"<Point><coordinates>{coords(q[:1])}</coordinates></Point></MultiGeometry>"
            )
        )
    ),
    "kml_altitudemode.kml": kml(
        marks(
            lambda i, q: (
                f"<name>UAV {i + 1}</name><LineString>{ALT}<coordinates>\n\t\t"
                f"{coords(q)}\n\t</coordinates></LineString>"
            )
        )
    ),
    "kml_folders.kml": kml(
        "<Folder><name>day</name>"
        + "".join(
            f"<Folder><name>UAV {i + 1}</name><Folder><Placemark><name>track</name>"
            f"{ls(q, alt=False)}</Placemark></Folder></Folder>"
            for i, q in enumerate(ll)
        )
        + "</Folder>"
    ),
    "kml_same_names.kml": kml(marks(lambda i, q: f"<name>track</name>{ls(q)}")),
    "kml_points_polygon_beside.kml": kml(
        f"<Placemark><name>area</name>{AREA}</Placemark>"
        + "".join(
            f"<Placemark><name>wp</name><Point><coordinates>{coords(q[:1])}</coordinates>"
            f"</Point></Placemark><Placemark>{ls(q)}</Placemark>"
            for q in ll
        )
    ),
    "kml_lat_lon_swapped.kml": kml(
        marks(
            lambda i, q: (
                "<LineString><coordinates>"
                + " ".join(f"{b:.7f},{a:.7f}" for a, b in q)
                + "</coordinates></LineString>"
            )
        )
    ),
    # GeoJSON
    "gj_multilinestring.geojson": json.dumps(
        {
            "type": "Feature",
            "properties": {},
            "geometry": {"type": "MultiLineString", "coordinates": [lines_of(q) for q in ll]},
        }
    ),
    "gj_null_geometry.geojson": json.dumps(
        {
            "type": "FeatureCollection",
            "features": [*json.loads(fc([line(q) for q in ll]))["features"], NULL],
        }
    ),
    "gj_points_mixed.geojson": fc([*[line(q) for q in ll], POINT]),
    "gj_3d.geojson": fc([line(q, z=True) for q in ll]),
    "gj_geometrycollection.geojson": json.dumps(
        {"type": "GeometryCollection", "geometries": [line(q) for q in ll]}
    ),
    "gj_crs_3857.geojson": fc([line(q) for q in ll], crs=named("urn:ogc:def:crs:EPSG::3857")),
    "gj_crs_utm32.geojson": fc([line(q) for q in ll], crs=named("EPSG:32632")),
    "gj_crs_on_feature_3857_metres.geojson": json.dumps(
        {
            "type": "Feature",
            "crs": named("EPSG:3857"),
            "properties": {},
            "geometry": {"type": "LineString", "coordinates": M3857},
        }
    ),
    "gj_lat_lon_swapped.geojson": fc([swapped(q) for q in ll]),
    "gj_partly_outside_area.geojson": fc([line(np.concatenate([q, [far]])) for q in ll]),
    "gj_outside_map_inside_area.geojson": fc([line(np.array([[lo, la], ll[0][0]]))]),
    "gj_longer_than_endurance.geojson": fc([line(np.concatenate([q, q, q])) for q in ll]),
    "gj_mixed_2d_3d.geojson": fc([mixed(q) for q in ll]),
}
(out / "kmz_src.kml").write_text(probes["kml_altitudemode.kml"])
buf = out / "tracks.kmz"
with zipfile.ZipFile(buf, "w") as z:
    z.writestr("doc.kml", probes["kml_altitudemode.kml"])
names = [*probes, "tracks.kmz"]
for name, text in probes.items():
    (out / name).write_text(text) if isinstance(text, str) else (out / name).write_bytes(text)

_, ref = searched_belief(sc, prior, check_paths(sc, routes, ["route"] * len(routes)))
print(f"reference: the plan's routes swept find {ref:.6f} (plan posc {plan['posc']:.6f})")
for name in names:
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        tr = read_tracks(out / name, crs)
        paths = check_paths(sc, [t for _, t in tr], [f for f, _ in tr])
        _, found = searched_belief(sc, prior, paths)
        n = sum(len(t) for _, t in tr)
        res = f"OK {len(tr)} tracks, {n} points, found {found:.6f} ({found - ref:+.6f} vs routes)"
    except ConfigError as err:
        res = f"REFUSED {err}"
    except Exception as err:  # a crash is a finding
        res = f"CRASH {type(err).__name__}: {err}"
    dt = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    size = (out / name).stat().st_size / 2**20
    print(f"{name:40s} {res}  [{dt:.2f} s, peak {peak:.0f} MB, file {size:.1f} MB]")
