"""The next sortie (issue 24, deliverable 4): ``poc-env replan``.

A search that ends without finding the target leaves a belief: the prior less what the flights
searched. :func:`searched_belief` sweeps the flown paths over the prior's sample points and
updates it by eq. 14 (:func:`poc_env.theory.search_theory.sweep_track`, the environment's
detection law and cut-off, the one implementation of the update); :func:`next_sortie` plans
the next sortie on what is left (the allocation planner by default). The flown paths are
either the previous plan's routes (take-off, waypoints, landing: what the plan said would be
flown) or the tracks actually flown -- GeoJSON LineStrings (RFC 7946), KML LineStrings or
``gx:Track`` (also in KMZ), GPX 1.1 track segments, all WGS 84 longitude/latitude -- put into
the map's metres with its frame (:func:`map_frame`: the scenario's CRS, else the last plan's,
else ``--origin``) (:func:`read_tracks`). A plan made in another frame (the area re-imported
with another origin) is carried into the map's metres through longitude/latitude.

The belief is not renormalised: the next plan's POS is then a share of the original prior, and
the sorties' POS add up to the cumulative POS (eq. 13) -- ``searched_pos`` plus the next
plan's ``sortie_posc``, its routes swept over the sample points' belief the flights left (the
planner plans on cells and scores its ``posc`` on each cell's belief spread evenly).

A track that leaves the operating area (the map grown to its airfields, eq. 20's boundary) is
cut to it, with a warning, and its part inside swept (:func:`clip_tracks`); a GeoJSON ``crs``
member of the 2008 specification (UTM, Web Mercator) is reprojected
(:func:`poc_env.crs.geojson_crs_to_lonlat`).

Bad input is a :class:`~poc_env.errors.ConfigError` naming the field: a track with no point
inside the operating area or one more than 1,000 km from it, a track point NaN or out of range,
a GeoJSON ``crs`` member pyproj cannot read, a geometry that is not a LineString, nesting deeper
than the JSON reader's limit or :data:`MAX_XML_DEPTH`, a DTD or entity in KML/GPX (the XML is
parsed with no entity resolution and no network), a file above :data:`MAX_TRACK_BYTES`, a plan
of another scenario's map. Nothing is written then.
"""

from __future__ import annotations

import os
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.config import Scenario
from poc_env.crs import geojson_crs_to_lonlat
from poc_env.errors import ConfigError, say_warning
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import sweep_track


def check_paths(
    sc: Scenario, paths, names, crs: Any = None, margin_m: float = 0.0
) -> list[np.ndarray]:
    """``paths`` as (k, 2) arrays, each point inside the operating area (or, with
    ``margin_m``, within that many metres beyond its edges); else a ConfigError naming
    ``names[i]`` and the point's index. With ``crs`` (the tracks were read in
    longitude/latitude, :func:`read_tracks`) the error gives the point as read, its distance
    from the area, and whether reading it as (lat, lon) would put it inside (a slip of order)."""
    from poc_env.sim.core import operating_area

    x0, y0, x1, y1 = operating_area(sc)  # eq. 20's boundary: the map grown to hold its fields
    tol = 1e-6 * max(x1 - x0, y1 - y0) + margin_m
    where = f"within {margin_m / 1e3:g} km of " if margin_m else "inside "

    def inside(p: np.ndarray) -> np.ndarray:
        return (
            np.isfinite(p).all(axis=1)
            & (p[:, 0] >= x0 - tol)
            & (p[:, 0] <= x1 + tol)
            & (p[:, 1] >= y0 - tol)
            & (p[:, 1] <= y1 + tol)
        )

    out = []
    for i, path in enumerate(paths):
        pts = np.asarray(path, dtype=float).reshape(-1, 2)
        bad = ~inside(pts)
        if bad.any():
            j = int(np.argmax(bad))
            text = (
                f"a point in metres {where}the operating area x {x0:g}..{x1:g}, y "
                f"{y0:g}..{y1:g} of scenario {sc.name!r} (the map and its airfields)"
            )
            if crs is None or not np.isfinite(pts[j]).all():
                got = [round(float(v), 1) for v in pts[j]]
                raise ConfigError(f"{names[i]}[{j}]", got, text)
            area = (text.replace(" in metres", ""), (x0, y0), (x1, y1))
            raise ConfigError(f"{names[i]}[{j}]", *_off_area(pts[j], crs, area, inside))
        out.append(pts)
    return out


def _off_area(xy: np.ndarray, crs: Any, area: tuple[str, Any, Any], inside: Any) -> tuple[str, str]:
    """The (value, allowed) of :func:`check_paths`'s error for a track point ``xy`` (map
    metres) read in longitude/latitude and projected by ``crs``: the point as read, how far it
    lies from the area (``area``: its text and its (x0, y0) and (x1, y1) corners), and a hint
    when its two numbers swapped would lie inside."""
    from poc_env.agents.mission.crs import to_geographic, to_local

    text, lo, hi = area
    ((lat, lon),) = to_geographic([xy], crs)
    off = np.hypot(*np.maximum(np.maximum(np.subtract(lo, xy), np.subtract(xy, hi)), 0.0))
    allowed = f"{text}; it maps to x {xy[0]:.0f}, y {xy[1]:.0f} m, {off / 1e3:.0f} km from it"
    try:
        flipped = np.array(to_local([(lon, lat)], crs)) if abs(lon) <= 90 else None
    except ConfigError:
        flipped = None
    if flipped is not None and inside(flipped).all():
        allowed += (
            f"; read as lat {lon:.5f}, lon {lat:.5f} it would lie inside: are the file's "
            "coordinates in lat, lon order? (GeoJSON and KML write lon, lat)"
        )
    return f"lon {lon:.5f}, lat {lat:.5f}", allowed


def clip_tracks(
    sc: Scenario, tracks: list[tuple[str, np.ndarray]], crs: Any
) -> list[tuple[str, np.ndarray]]:
    """The flown ``tracks`` (map metres, each with its field) cut to the operating area: a
    UAV that diverted to a field outside it, or flew its approach over the sea beside it, has
    its part inside swept (each stretch inside one flight) and a warning printed naming the
    track and how much of it was outside; what was flown outside searched nothing on the map.

    Refused (:func:`check_paths`'s error, naming the track's first such point): a track with a
    point more than :data:`~poc_env.crs.MAX_DISTANCE_KM` from the area
    (the wrong side of the globe, a sign or lat/lon slip: no aircraft of this planner flies so
    far), or none of it inside (another area's log)."""
    from poc_env.agents.mission.crs import MAX_DISTANCE_KM
    from poc_env.sim.core import operating_area

    x0, y0, x1, y1 = operating_area(sc)
    tol = 1e-6 * max(x1 - x0, y1 - y0)  # check_paths's: points on the edge stay whole
    lo, hi = np.array([x0 - tol, y0 - tol]), np.array([x1 + tol, y1 + tol])
    out = []
    for field, pts in tracks:
        off = np.hypot(*np.maximum(np.maximum([x0, y0] - pts, pts - [x1, y1]), 0.0).T)
        if off.max() <= tol:
            out.append((field, pts))
            continue
        check_paths(sc, [pts], [field], crs, MAX_DISTANCE_KM * 1e3)  # raises for a far point
        parts = _inside_stretches(pts, lo, hi)
        if not parts:
            check_paths(sc, [pts], [field], crs)  # raises: none of it inside
        total = float(np.sum(np.hypot(*np.diff(pts, axis=0).T)))
        kept = sum(float(np.sum(np.hypot(*np.diff(q, axis=0).T))) for q in parts)
        say_warning(
            f"{field}: {(total - kept) / 1e3:.1f} of {total / 1e3:.1f} km flown "
            f"outside the operating area (up to {off.max() / 1e3:.1f} km from it); the "
            f"{len(parts)} stretch(es) inside are swept"
        )
        out += [(field, q) for q in parts]
    return out


def _inside_stretches(pts: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> list[np.ndarray]:
    """The stretches of the polyline ``pts`` inside the box ``lo``-``hi``, in flight order:
    each leg clipped to the box (Liang-Barsky), consecutive clipped legs that meet joined into
    one stretch; stretches of no length dropped."""
    out: list[list[np.ndarray]] = []
    joined = False  # the previous leg reached its end inside: this one continues its stretch
    for a, b in pairwise(pts):
        d = b - a
        t0, t1 = 0.0, 1.0
        for k in range(2):
            if d[k] == 0.0:
                if not lo[k] <= a[k] <= hi[k]:
                    t0, t1 = 1.0, 0.0
            else:
                ta, tb = sorted(((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]))
                t0, t1 = max(t0, ta), min(t1, tb)
        if t0 > t1:
            joined = False
            continue
        p, q = np.clip(a + t0 * d, lo, hi), np.clip(a + t1 * d, lo, hi)  # no ulp outside
        if joined and t0 == 0.0:
            out[-1].append(q)
        else:
            out.append([p, q])
        joined = t1 == 1.0
    return [np.array(s) for s in out if np.sum(np.hypot(*np.diff(np.array(s), axis=0).T)) > 0]


def plan_paths(plan: dict[str, Any]) -> list[np.ndarray]:
    """The flights a plan says: per UAV take-off, waypoints, landing (UAVs without waypoints
    did not fly)."""
    out = []
    for u in plan["uavs"]:
        if u["waypoints_m"]:
            out.append(np.array([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]], dtype=float))
    return out


#: Track files larger than this are refused before they are parsed (a day of 1 Hz GPS fixes
#: from 24 aircraft is about 60 MB of GPX).
MAX_TRACK_BYTES = 128 * 1024 * 1024
#: Element nesting deeper than this in a KML or GPX file is refused (GPX 1.1 needs 4 levels,
#: KML Documents in Folders a few more).
MAX_XML_DEPTH = 64
TRACK_SUFFIXES = (".geojson", ".json", ".kml", ".kmz", ".gpx")
GPX_NAMESPACES = ("http://www.topografix.com/GPX/1/1", "http://www.topografix.com/GPX/1/0")
KML_NAMESPACES = ("http://www.opengis.net/kml/2.2", "http://www.opengis.net/kml/2.3",
                  "http://earth.google.com/kml/2.2", "http://earth.google.com/kml/2.1")  # fmt: skip


def read_tracks(
    path: str | os.PathLike[str], crs: Any, skipped: list[str] | None = None
) -> list[tuple[str, np.ndarray]]:
    """The flown tracks of a GeoJSON (LineString / MultiLineString), KML (``LineString`` and
    ``gx:Track`` placemarks) or GPX 1.1 (``trk/trkseg/trkpt``) file, in WGS 84 longitude/
    latitude, put into map metres by ``crs`` (a plan's CRS record or a (lat, lon) origin,
    :func:`poc_env.agents.mission.crs.to_local`); each with the field that holds its points
    (``tracks.features[1].geometry.coordinates``, ``tracks.Placemark[0].LineString``,
    ``tracks.trk[0].trkseg[1]``). The format is the file's suffix.

    The landing approaches ``poc-env export`` draws beside each route (GeoJSON ``kind``, KML
    ``styleUrl`` :data:`~poc_env.agents.mission.plan.APPROACH_KIND`) are not read: the
    route already flies to the field (over terrain its last leg is that approach), so they are
    no second flight; their fields are appended to ``skipped`` when it is given."""
    file = Path(path)
    suffix = file.suffix.lower()
    if suffix not in TRACK_SUFFIXES:
        raise ConfigError("tracks", os.fspath(path), "a " + " / ".join(TRACK_SUFFIXES) + " file")
    try:
        size = file.stat().st_size
        if size > MAX_TRACK_BYTES:
            raise ConfigError("tracks", f"{os.fspath(path)} ({size} bytes)",
                              f"a track file of at most {MAX_TRACK_BYTES} bytes")  # fmt: skip
        raw = file.read_bytes()
    except OSError as err:
        raise ConfigError("tracks", os.fspath(path), f"a readable track file ({err})") from None
    parts: list[tuple[str, np.ndarray | None]]
    if suffix == ".kmz":
        parts = _kml_tracks(_kmz_kml(raw, path), path)
    elif suffix == ".kml":
        parts = _kml_tracks(raw, path)
    elif suffix == ".gpx":
        parts = list(_gpx_tracks(raw, path))
    else:
        parts = _geojson_tracks(raw, path)
    approaches = [f for f, arr in parts if arr is None]
    if skipped is not None:
        skipped += approaches
    lines = [(f, _to_map(f, arr, crs)) for f, arr in parts if arr is not None]
    if not lines:
        raise ConfigError("tracks", os.fspath(path), "at least one track of 2 or more points")
    return lines


def _kmz_kml(raw: bytes, path: Any) -> bytes:
    """The KML of a KMZ archive (a zip; KML 2.2 section 15: ``doc.kml``, else the first
    ``.kml`` file in it), at most :data:`MAX_TRACK_BYTES` unpacked (read so, whatever the
    archive's directory claims)."""
    import io
    import zipfile

    allowed = "a KMZ file: a zip archive holding a .kml file (doc.kml)"
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as z:
            names = [n for n in z.namelist() if n.lower().endswith(".kml")]
            if not names:
                raise ConfigError("tracks", os.fspath(path), allowed)
            name = "doc.kml" if "doc.kml" in names else names[0]
            with z.open(name) as f:
                kml = f.read(MAX_TRACK_BYTES + 1)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, OSError) as err:
        raise ConfigError("tracks", os.fspath(path), f"{allowed} ({err})") from None
    if len(kml) > MAX_TRACK_BYTES:
        raise ConfigError("tracks", f"{os.fspath(path)}: {name} unpacks to more than "
                          f"{MAX_TRACK_BYTES} bytes", allowed)  # fmt: skip
    return kml


def _to_map(field: str, arr: np.ndarray, crs: Any) -> np.ndarray:
    """(n, 2) lon/lat (checked: finite, in range, 2 or more points) -> map metres."""
    from poc_env.agents.mission.crs import to_local

    if arr.ndim != 2 or arr.shape[1] < 2 or len(arr) < 2:
        raise ConfigError(field, arr.tolist() if arr.size < 6 else "array", "2 or more [lon, lat]")
    lon, lat = arr[:, 0], arr[:, 1]
    ok = np.isfinite(arr[:, :2]).all(axis=1) & (np.abs(lat) <= 90) & (np.abs(lon) <= 180)
    if not ok.all():
        j = int(np.argmin(ok))
        raise ConfigError(f"{field}[{j}]", arr[j, :2].tolist(), "[lon, lat] in WGS 84 degrees")
    return np.array(to_local(np.stack([lat, lon], axis=1), crs))


#: GeoJSON geometries a collection of tracks may hold beside its lines (skipped).
GEOJSON_OTHER = ("Point", "MultiPoint", "Polygon", "MultiPolygon")


def _geojson_tracks(raw: bytes, path: Any) -> list[tuple[str, np.ndarray | None]]:
    """The lines of a GeoJSON object; an exported landing approach as ``(field, None)``."""
    from poc_env.agents.mission.plan import APPROACH_KIND
    from poc_env.io import loads_json

    where = "tracks"
    data = loads_json(raw, where, os.fspath(path))  # NaN, Infinity, deep nesting refused
    if not isinstance(data, dict):
        raise ConfigError(where, type(data).__name__, "a GeoJSON object")
    out: list[tuple[str, np.ndarray | None]] = []
    # a 2008-style crs member (UTM, Web Mercator...): reprojected; one pyproj cannot read: refused
    reproject = geojson_crs_to_lonlat(data.get("crs"), f"{where}.crs") if "crs" in data else None
    if data.get("type") == "FeatureCollection":
        feats = data.get("features")
        if not isinstance(feats, list):
            raise ConfigError(f"{where}.features", feats, "a list of features")
        geoms = []
        for i, f in enumerate(feats):
            field = f"{where}.features[{i}].geometry"
            props = f.get("properties") if isinstance(f, dict) else None
            if isinstance(props, dict) and props.get("kind") == APPROACH_KIND:
                out.append((field, None))  # drawn beside the route: not a second flight
                continue
            geoms.append((field, f.get("geometry") if isinstance(f, dict) else f))
    elif data.get("type") == "Feature":
        geoms = [(f"{where}.geometry", data.get("geometry"))]
    else:
        geoms = [(where, data)]
    lines = ("LineString", "MultiLineString")
    flat: list[tuple[str, Any]] = []  # a GeometryCollection's members (RFC 7946 3.1.8)
    for field, g in geoms:
        members = None
        if isinstance(g, dict) and g.get("type") == "GeometryCollection":
            members = g.get("geometries")
        if isinstance(members, list):
            flat += [(f"{field}.geometries[{k}]", m) for k, m in enumerate(members)]
        else:
            flat.append((field, g))
    geoms = flat
    # a collection's points and areas (a logger's waypoints, the search area drawn beside the
    # tracks) and null geometries (RFC 7946 3.2: an unlocated feature, a UAV that did not
    # fly) sweep no line: skipped, as KML's other placemarks and GPX's waypoints are; a
    # collection without a line is refused, as a lone geometry of another type is
    skip = len(geoms) > 1 and any(isinstance(g, dict) and g.get("type") in lines for _, g in geoms)
    for field, g in geoms:
        if skip and (g is None or (isinstance(g, dict) and g.get("type") in GEOJSON_OTHER)):
            continue
        if not isinstance(g, dict) or g.get("type") not in lines:
            kind = g.get("type") if isinstance(g, dict) else g
            raise ConfigError(f"{field}.type", kind, "LineString or MultiLineString")
        parts = [g.get("coordinates")] if g["type"] == "LineString" else g.get("coordinates")
        for p, coords in enumerate(parts or []):
            f = f"{field}.coordinates" + (f"[{p}]" if g["type"] == "MultiLineString" else "")
            xy = _positions(coords, f)
            out.append((f, xy if reproject is None or not len(xy) else reproject(xy)))
    return out


def _positions(coords: Any, field: str) -> np.ndarray:
    """A GeoJSON line's positions (RFC 7946 3.1.1: 2 or more numbers each, 3 with an altitude,
    mixed as a logger writes them) as an (n, 2) lon/lat array; else a ConfigError naming the
    first position that is not numbers."""
    if not isinstance(coords, list):
        shown = coords if len(str(coords)) < 200 else type(coords).__name__
        raise ConfigError(field, shown, "a list of [lon, lat] or [lon, lat, altitude] positions")
    rows = []
    for j, c in enumerate(coords):
        ok = isinstance(c, list) and len(c) >= 2
        ok = ok and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in c)
        try:
            rows.append([float(c[0]), float(c[1])] if ok else None)
        except OverflowError:  # 10**400 is a JSON integer
            ok = False
        if not ok:
            shown = c if len(str(c)) < 200 else "array"
            raise ConfigError(f"{field}[{j}]", shown, "a position [lon, lat] or [lon, lat, "
                              "altitude] of numbers")  # fmt: skip
    return np.array(rows, dtype=float).reshape(-1, 2)


def _xml_root(raw: bytes, path: Any, kind: str, namespaces: tuple[str, ...]) -> Any:
    """The root element of a KML or GPX document, parsed safely: no DTD (so no entity of any
    kind), no network, no huge-tree mode, nesting at most :data:`MAX_XML_DEPTH`; and a root in
    one of ``namespaces``."""
    from lxml import etree

    where = "tracks"
    if b"<!DOCTYPE" in raw or b"<!ENTITY" in raw:
        raise ConfigError(where, "a DOCTYPE/ENTITY declaration", f"plain {kind} (no DTD)")
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False,
                             huge_tree=False, remove_comments=True)  # fmt: skip
    try:
        root = etree.fromstring(raw, parser)
    except etree.XMLSyntaxError as err:
        raise ConfigError(where, f"{os.fspath(path)}: not XML ({err})", f"a {kind} file") from None
    depth = max((sum(1 for _ in e.iterancestors()) for e in root.iter()), default=0) + 1
    if depth > MAX_XML_DEPTH:
        raise ConfigError(where, f"elements nested {depth} deep",
                          f"{kind} nested at most {MAX_XML_DEPTH} levels deep")  # fmt: skip
    ns = etree.QName(root).namespace
    if ns not in namespaces:
        allowed = f"a {kind} root element in namespace " + " or ".join(namespaces)
        raise ConfigError(f"{where}.{etree.QName(root).localname}", ns or "(no namespace)", allowed)
    return root


def _number(text: str | None, field: str) -> float:
    try:
        return float(text)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ConfigError(field, text, "a number (decimal degrees, WGS 84)") from None


def _kml_tracks(raw: bytes, path: Any) -> list[tuple[str, np.ndarray | None]]:
    """Every ``LineString`` (its ``coordinates``: ``lon,lat[,alt]`` tuples) and ``gx:Track``
    (its ``gx:coord``: ``lon lat alt``) of every Placemark. KML is WGS 84 longitude/latitude by
    definition (OGC KML 2.2, section 6.2). An exported landing approach (``styleUrl``
    ``#landing_approach``) as ``(field, None)``."""
    from poc_env.agents.mission.plan import APPROACH_KIND

    root = _xml_root(raw, path, "KML", KML_NAMESPACES)
    out: list[tuple[str, np.ndarray | None]] = []
    placemarks = [e for e in root.iter() if isinstance(e.tag, str) and e.tag.endswith("}Placemark")]
    seen = 0  # LineStrings and gx:Tracks read, kept or not
    for i, pm in enumerate(placemarks):
        style = next((x for x in pm if str(x.tag).endswith("}styleUrl")), None)
        if style is not None and (style.text or "").strip() == "#" + APPROACH_KIND:
            out.append((f"tracks.Placemark[{i}]", None))  # drawn beside the route
            seen += 1
            continue
        n = 0
        for e in pm.iter():
            if not isinstance(e.tag, str):
                continue
            name = e.tag.rsplit("}", 1)[-1]
            if name == "LineString":
                field = f"tracks.Placemark[{i}].LineString" + (f"[{n}]" if n else "")
                c = next((x for x in e if str(x.tag).endswith("}coordinates")), None)
                toks = (c.text or "").split() if c is not None else []
                rows = [[_number(v, f"{field}.coordinates[{j}]") for v in tok.split(",")[:2]]
                        for j, tok in enumerate(toks)]  # fmt: skip
            elif name == "Track":
                field = f"tracks.Placemark[{i}].Track" + (f"[{n}]" if n else "")
                coords = [x for x in e if str(x.tag).endswith("}coord")]
                rows = [[_number(v, f"{field}.coord[{j}]") for v in (x.text or "").split()[:2]]
                        for j, x in enumerate(coords)]  # fmt: skip
            else:
                continue
            n += 1
            seen += 1
            if any(len(r) != 2 for r in rows):
                j = next(k for k, r in enumerate(rows) if len(r) != 2)
                raise ConfigError(f"{field}[{j}]", rows[j], "lon,lat[,alt]")
            if name == "Track" and len(rows) < 2:  # one fix sweeps no line (as a GPX segment)
                continue
            out.append((field, np.array(rows, dtype=float).reshape(-1, 2)))
    if not seen:
        raise ConfigError("tracks", os.fspath(path), "a KML file with LineString placemarks")
    return out


def _gpx_tracks(raw: bytes, path: Any) -> list[tuple[str, np.ndarray]]:
    """Every track segment (``trk/trkseg/trkpt`` with ``lat`` and ``lon`` attributes) of a GPX
    1.1 (or 1.0) file; GPX is WGS 84 by definition. Routes (``rte``) and waypoints are not
    flown tracks and are ignored, and so are segments of fewer than two points (they sweep no
    line)."""
    from lxml import etree

    root = _xml_root(raw, path, "GPX", GPX_NAMESPACES)
    ns = etree.QName(root).namespace  # the root's, prefixed or not (checked by _xml_root)
    out = []
    segments = 0
    for i, trk in enumerate(root.findall(f"{{{ns}}}trk")):
        for k, seg in enumerate(trk.findall(f"{{{ns}}}trkseg")):
            segments += 1
            field = f"tracks.trk[{i}].trkseg[{k}]"
            pts = seg.findall(f"{{{ns}}}trkpt")
            if len(pts) < 2:  # an empty or one-fix segment (valid GPX: a logger's pause) sweeps
                continue  # no line; a file of nothing else is refused by read_tracks
            rows = [[_number(p.get("lon"), f"{field}.trkpt[{j}].lon"),
                     _number(p.get("lat"), f"{field}.trkpt[{j}].lat")]
                    for j, p in enumerate(pts)]  # fmt: skip
            out.append((f"{field}.trkpt", np.array(rows, dtype=float).reshape(-1, 2)))
    if not segments:
        raise ConfigError("tracks", os.fspath(path), "a GPX file with trk/trkseg/trkpt tracks")
    return out


def searched_belief(sc: Scenario, prior: np.ndarray, paths) -> tuple[np.ndarray, float]:
    """The prior less what ``paths`` (flights in map metres) searched, by eq. 14 on the sample
    points (:func:`sweep_points`), summed back to cells; and the POS the flights achieved
    (eq. 13: the sum of their POS)."""
    grid, s, belief, found = _swept(sc, prior, paths)
    return grid.coarsen(belief, s), found


def _swept(sc: Scenario, prior: np.ndarray, paths) -> tuple[Grid, int, np.ndarray, float]:
    """``(grid, samples per cell side, the sample points' belief after paths, the POS they
    achieved)``: the prior spread onto the sample points and ``paths`` swept over them
    (:func:`sweep_points`); what :func:`searched_belief` and :func:`next_sortie` both start
    from."""
    grid = Grid.from_config(sc.map)
    s = sc.sensor.samples_per_cell
    belief = np.ascontiguousarray(grid.refine(prior, s))
    return grid, s, belief, sweep_points(sc, belief, paths)


def sweep_points(sc: Scenario, belief_fine: np.ndarray, paths) -> float:
    """Sweep ``paths`` (flights in map metres, in order) over the sample points' belief
    ``belief_fine`` (updated in place by eq. 14,
    :func:`poc_env.theory.search_theory.sweep_track`, steps of at most a cell as the planner
    scores its routes); return the POS they achieve (eq. 13)."""
    grid = Grid.from_config(sc.map)
    w = sc.sensor.sweep_width_m
    cutoff = sc.sensor.cutoff_sweep_widths * w
    s = sc.sensor.samples_per_cell
    found = 0.0
    for path in paths:
        if len(path) >= 2:
            found += sweep_track(belief_fine, grid, s, path, w, sc.sensor.law, cutoff, grid.cell_m)
    return float(found)


def map_frame(sc: Scenario, plans: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The ``crs`` of the map's metres: the scenario's own (``map.origin_deg``: every plan made
    on it records it), else the last plan's (a scenario without a place on the globe is put
    there by ``plan --origin``), else None."""
    from poc_env.agents.planning.geography import scenario_crs

    frame = scenario_crs(sc, None, sc.map.projection, None)
    return frame if frame is not None else (plans[-1].get("crs") if plans else None)


def _in_frame(paths: list[np.ndarray], crs: Any, frame: Any) -> list[np.ndarray]:
    """A plan's ``paths`` (metres of its own ``crs``) in the metres of ``frame``, through
    longitude/latitude when the two differ (replan-audit: a plan made before the area was
    re-imported with another origin was swept in the new map's metres, kilometres off)."""
    from poc_env.agents.mission.crs import to_geographic, to_local

    if same_frame(crs, frame):
        return paths
    return [np.array(to_local(to_geographic(p, crs), frame)) for p in paths]


def same_frame(crs: Any, frame: Any) -> bool:
    """Whether a plan's ``crs`` puts its metres where ``frame`` does (or either is unknown)."""
    from poc_env.crs import crs_text

    if crs is None or frame is None:
        return True
    return crs_text(crs) == crs_text(frame) and list(crs["origin_deg"]) == list(frame["origin_deg"])


def next_sortie(
    sc: Scenario,
    prior: np.ndarray,
    plans: list[dict[str, Any]],
    tracks: list[tuple[str, np.ndarray]] | None = None,
    *,
    planner: str = "allocation",
    seed: int = 0,
    refine: int | None = None,
    effort: str | None = None,
    gain_per_hour: float | None = None,
) -> dict[str, Any]:
    """The plan of the next sortie after ``plans`` (the sorties so far, in order: their routes,
    or the flown ``tracks`` of all of them when given) on ``prior``: eq. 14 along every flight
    (:func:`searched_belief`), then the planner on what is left. Extra fields: ``sortie``
    (``len(plans) + 1``), ``searched_pos`` (what the flights so far found, eq. 13),
    ``sortie_posc`` (what the new plan's routes find on the belief the flights left, swept
    point by point: the planner's own ``posc`` sees each cell's belief spread evenly over the
    cell) and ``cumulative_posc`` (their sum: eq. 14 over every flight, as sweeping them all
    from the prior). ``refine``: the allocation planner's refinement passes (``None``: its
    default); ``effort``: its effort level (``None``: the default;
    :meth:`poc_env.agents.planning.options.PlanOptions.preset`) and ``gain_per_hour`` its floor
    per flight hour (``None``: the level's; ``PlanOptions.gain_per_hour``), each refused with
    ``planner="de"`` as ``plan`` refuses it."""
    from poc_env.agents.planning.planner import make_plan

    names: list[str] = []
    flights: list[np.ndarray] = []
    frame = map_frame(sc, plans)
    for i, plan in enumerate(plans):
        where = f"plan[{i}]" if len(plans) > 1 else "plan"
        if plan.get("scenario") != sc.name:
            raise ConfigError(
                f"{where}.scenario", plan.get("scenario"), f"the scenario replanned, {sc.name!r} "
                "(the flights are in its map's metres)",
            )  # fmt: skip
        num = plan.get("sortie", 1)  # plans made by `plan` record none: they go anywhere
        if "sortie" in plan and num != i + 1:
            nth = {1: "st", 2: "nd", 3: "rd"}.get(num if num < 20 else num % 10, "th")
            raise ConfigError(
                f"{where}.sortie", num, f"a plan of sortie {num} as the {num}{nth} --plan, after "
                "the plans of the sorties it was planned after, in order (--plan p1.json --plan "
                "p2.json ...; replan swept only the flights of the plans given)",
            )  # fmt: skip
        uavs = enumerate(plan["uavs"])
        names += [f"{where}.uavs[{k}].waypoints_m" for k, u in uavs if u["waypoints_m"]]
        flights += _in_frame(plan_paths(plan), plan.get("crs"), frame)
    if tracks is not None:
        names, flights = [f for f, _ in tracks], [t for _, t in tracks]
    paths = check_paths(sc, flights, names)
    grid, s, fine, searched = _swept(sc, prior, paths)
    # the planner sees each cell's belief spread evenly over the cell (it plans on cells); the
    # flights left it uneven within cells, so the plan's POS is its routes swept over the
    # sample points' own belief (replan-audit: the Alps walkthrough's sortie 2 was scored
    # 0.1835 on the cells, 0.1463 on the points)
    nxt = make_plan(sc, prior=grid.coarsen(fine, s), planner=planner, seed=seed, refine=refine,
                    effort=effort, gain_per_hour=gain_per_hour)  # fmt: skip
    gain = sweep_points(sc, fine, plan_paths(nxt))
    if frame is not None:
        nxt["crs"] = frame  # the scenario's (make_plan's), else the last plan's: the same map
    nxt["sortie"] = len(plans) + 1
    nxt["searched_pos"] = searched
    nxt["sortie_posc"] = gain
    nxt["cumulative_posc"] = min(searched + gain, 1.0)
    return nxt


def swept_text(
    plans: list[str], files: list[str] | None, tracks: list | None, skipped: int = 0
) -> str:
    """What ``replan`` swept, in one line: the routes of the ``plans``, or the ``tracks`` read
    from ``files``, which stand for the flights of every plan (:func:`next_sortie`), and how
    many exported landing approaches :func:`read_tracks` ``skipped``."""
    routes = ", ".join(str(p) for p in plans)
    if not files or tracks is None:
        return f"swept: the routes of {routes}"
    n = len(tracks)
    text = (
        f"swept: {n} track{'s' if n != 1 else ''} from {', '.join(str(f) for f in files)}, "
        f"in place of the routes of {routes}"
    )
    if skipped:
        text += (
            f"; {skipped} landing-approach line{'s' if skipped != 1 else ''} skipped (drawn "
            "beside the routes by export: each route already flies to its field)"
        )
    return text


def sortie_text(nxt: dict[str, Any]) -> str:
    """The summary line of a :func:`next_sortie` plan: what the flights so far found, what this
    plan finds on the belief they left, the cumulative POS; and the planner's own score (on
    each cell's belief spread evenly over the cell) when it differs."""
    text = (
        f"sortie {nxt['sortie']}: the flights so far found {nxt['searched_pos']:.4f}; this plan "
        f"{nxt['sortie_posc']:.4f}; cumulative {nxt['cumulative_posc']:.4f}"
    )
    if abs(float(nxt["posc"]) - nxt["sortie_posc"]) >= 5e-5:
        text += (
            f" (this plan on the belief the flights left, point by point; the planner's POS_C "
            f"{float(nxt['posc']):.4f} sees each cell's belief spread evenly over the cell)"
        )
    return text


def cli_main(args: Any) -> int:
    """``poc-env replan``: read, check, plan, then write ``--out`` (nothing written on error)."""
    from poc_env.agents.mission.plan import (
        check_map_option,
        load_plan,
        map_file_candidates,
        map_source,
        scenario_not_found,
        scenario_source,
        with_scenario_file,
        write_plan,
    )
    from poc_env.agents.planning.planner import (
        effort_skip_note,
        lattice_warning,
        moving_target_warning,
        plan_table,
    )
    from poc_env.config import load_scenario, parse_overrides
    from poc_env.crs import plan_crs
    from poc_env.theory.probability_map import build_prior

    plans = [dict(load_plan(p)) for p in args.plan]
    # the scenario the first plan was made on: by name, or its recorded YAML file (plan
    # --scenario FILE.yaml records scenario_file; issue 24: replan looked for the name only)
    name = args.scenario or scenario_source(
        str(plans[0]["scenario"]), args.plan[0], plans[0].get("scenario_file")
    )
    if name is None:  # say where it looked, as export's prior note does
        why = scenario_not_found(str(plans[0]["scenario"]), args.plan[0], plans[0])
        raise ConfigError("scenario", plans[0]["scenario"], f"the plan's scenario ({why}), or "
                          "--scenario FILE.yaml")  # fmt: skip
    sc = load_scenario(name, parse_overrides(args.overrides or []))
    check_map_option(sc, args.map_file)
    # the prior the first plan was made on: its --map file (map_source), unless --map gives
    # another (new information); replan-audit: the built-in prior was swept silently
    map_file = args.map_file
    src = str(plans[0].get("map_source") or "builtin")
    if map_file is None and sc.map.prior.kind != "file" and src != "builtin":
        cands = map_file_candidates(src, args.plan[0])
        map_file = next((c for c in cands if c.is_file()), None)
        if map_file is None:
            raise ConfigError(
                "map", src, f"the prior file {args.plan[0]} was planned on (its map_source; "
                f"looked for {', '.join(str(c) for c in cands)}), or --map FILE",
            )  # fmt: skip
    prior = build_prior(sc.map, map_file)
    tracks = None
    skipped: list[str] = []  # exported landing approaches, not flights
    crs = map_frame(sc, plans)  # the tracks are put into this map's metres
    if crs is not None or args.origin is not None:  # --origin checked as export checks it
        crs = plan_crs(crs, args.origin, "aeqd", None)  # (replan-audit: it was ignored)
    if args.tracks:
        if crs is None:
            raise ConfigError(
                "origin", None, "LAT,LON of the map's (0, 0): the plan records no crs, and the "
                "tracks are in longitude/latitude",
            )  # fmt: skip
        tracks = []
        for t in args.tracks:
            tracks += read_tracks(t, crs, skipped)
        tracks = clip_tracks(sc, tracks, crs)  # the part inside counts; refusals in degrees
    nxt = next_sortie(
        sc, prior, plans, tracks, planner=args.planner, seed=args.seed,
        effort=getattr(args, "effort", None), gain_per_hour=getattr(args, "gain_per_hour", None),
    )  # fmt: skip
    nxt["map_source"] = map_source(sc, map_file)  # export draws this prior, replan sweeps it
    if crs is not None:
        nxt["crs"] = crs  # the plan's, or --origin's for a plan without one
    print(swept_text(args.plan, args.tracks, tracks, len(skipped)))
    for f, plan in zip(args.plan, plans, strict=True):
        rec: Any = plan.get("crs")
        if not args.tracks and crs is not None and not same_frame(rec, crs):
            print(
                f"note: {f} was made with its map's (0, 0) at {rec['origin_deg']}; its routes "
                f"are carried through longitude/latitude into this map's, at {crs['origin_deg']}"
            )
    print(plan_table(nxt))
    skipped_polish = effort_skip_note(nxt, getattr(args, "effort", None))
    if skipped_polish is not None:
        print(skipped_polish)
    for warning in (moving_target_warning(sc, replanned=True), lattice_warning(sc)):
        if warning is not None:
            say_warning(warning)
    print(sortie_text(nxt))
    write_plan(with_scenario_file(nxt, name), args.out)  # export finds the prior by it
    print(f"wrote {args.out}")
    return 0
