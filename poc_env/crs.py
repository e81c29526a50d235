"""The coordinate reference system of a plan: local metres <-> latitude/longitude (pyproj).

Plans are in local metres; a coordinate reference system (CRS) places them on the WGS84
ellipsoid. Every projection goes through pyproj (PROJ) Transformers with ``always_xy=True``
(so every call is (lon, lat) <-> (easting, northing); :func:`to_geographic` and
:func:`to_local` keep the (lat, lon) order of their callers):

- ``aeqd`` (default): the azimuthal equidistant projection centred on the map's (0, 0),
  ``+proj=aeqd +lat_0=LAT +lon_0=LON +datum=WGS84 +units=m +no_defs``. Distances and bearings
  from the origin are exact; elsewhere the scale across the radius is about
  ``1 + rho**2 / (6 R**2)``, below 0.04 % within 300 km of the origin. Measured against the
  ellipsoid (``pyproj.Geod``, tests/mission/test_export.py, numbers in docs/EXPORT.md): over the
  paper_6_2 extent with its 20 km margin (x in [-20, 220] km, y in [-80, 170] km) local
  distances agree with geodesic ones within 0.024 % (UTM: 0.040 %; the test asserts 0.1 %);
  round trips return the same metres within 4e-9 m out to +-300 km (the test asserts 1e-3 m).
- ``utm``: Universal Transverse Mercator on WGS84, the zone chosen from the origin
  (``floor((lon + 180) / 6) + 1``, south when lat < 0; the Norway/Svalbard exceptions are not
  applied) or given. Local metres are UTM metres shifted so that the origin is (0, 0).
- ``epsg`` / ``proj``: any projected CRS in metres given as an EPSG code or a PROJ string,
  shifted the same way.

In every case ``local = projected(lon, lat) - projected(origin)``; for ``aeqd`` the shift is 0.
The hand-written tangent plane used before put a 200 km east-west line at y = 150 km on the
ground 195.116 km long (2.44 % short: its longitude scale was fixed at the origin's latitude);
it is now 199.982 km (0.009 % short; UTM 200.055 km, 0.027 % long), and the test keeps that case.

A plan's ``crs`` record (:func:`make_crs`, checked by :func:`check_crs`): {``kind``: ``aeqd`` |
``utm`` | ``epsg`` | ``proj``, ``origin_deg`` [lat, lon], ``proj`` (a PROJ string; required
unless ``kind`` is ``epsg``), ``epsg`` (an integer; required for ``epsg``)}.
"""

from __future__ import annotations

import functools
import math
import re
from typing import Any

import numpy as np
from pyproj import CRS, Transformer
from pyproj.exceptions import CRSError, ProjError

from poc_env.errors import ConfigError, as_number

CRS_KINDS = ("aeqd", "utm", "epsg", "proj")


def parse_origin(text: str) -> tuple[float, float]:
    """``"LAT,LON"`` in degrees -> (lat, lon).

    Raises
    ------
    ConfigError
        Outside [-89.9, 89.9] x [-180, 180], or not two numbers.
    """
    try:
        lat, lon = (float(v) for v in str(text).split(","))
    except ValueError:
        raise ConfigError("origin", text, "LAT,LON in degrees, e.g. 45.5,126.6") from None
    if not (-90 <= lat <= 90 and -180 <= lon <= 180) or abs(lat) > 89.9:
        raise ConfigError("origin", text, "latitude in [-89.9, 89.9], longitude in [-180, 180]")
    return lat, lon


def check_origin(origin: Any) -> tuple[float, float]:
    """A ``"LAT,LON"`` text or a (lat, lon) pair, checked as :func:`parse_origin` does."""
    if isinstance(origin, str):
        return parse_origin(origin)
    try:
        lat, lon = (float(v) for v in origin)
    except (TypeError, ValueError):
        raise ConfigError("origin", origin, "(lat, lon) in degrees") from None
    return parse_origin(f"{lat!r},{lon!r}")


def utm_zone(origin: tuple[float, float]) -> int:
    """The UTM zone (1-60) of a (lat, lon) origin: ``floor((lon + 180) / 6) + 1``."""
    return min(math.floor((origin[1] + 180.0) / 6.0) + 1, 60)


#: Largest longitude difference (degrees) between a UTM zone's central meridian and the origin:
#: the zone's own half width (3) plus the usual one-zone overlap (6). A zone farther off puts
#: the map where the projection's scale error is large (about 19 % short at 180 degrees).
UTM_MAX_OFFSET_DEG = 9.0
#: Points (airfields, no-fly vertices, CSV rows, flown tracks) farther than this from the
#: search area are refused: no aircraft of this planner flies so far, and the local
#: projection's scale error grows with the distance.
MAX_DISTANCE_KM = 1000.0


def utm_zones_near(lon: float) -> list[int]:
    """The UTM zones whose central meridian (``6 z - 183``) is within
    :data:`UTM_MAX_OFFSET_DEG` of longitude ``lon`` (wrapping at the antimeridian)."""
    return [z for z in range(1, 61) if _lon_gap(6.0 * z - 183.0, lon) <= UTM_MAX_OFFSET_DEG]


def check_utm_zone(field: str, zone: int, origin: tuple[float, float], value: Any = None) -> None:
    """Refuse a UTM ``zone`` whose central meridian is more than :data:`UTM_MAX_OFFSET_DEG`
    from the origin's longitude (``value``: what the error shows, default the zone).

    Raises
    ------
    ConfigError
        Naming ``field``, the zone and the zones allowed at the origin.
    """
    near = utm_zones_near(float(origin[1]))
    if zone not in near:
        gap = _lon_gap(6.0 * zone - 183.0, float(origin[1]))
        raise ConfigError(
            field,
            zone if value is None else value,
            f"a UTM zone whose central meridian is within {UTM_MAX_OFFSET_DEG:g} degrees of the "
            f"origin's longitude {origin[1]:g} (zone {zone} is {gap:.1f} degrees away): one of "
            + ", ".join(map(str, near)),
        )


def _lon_gap(a: float, b: float) -> float:
    """The longitude difference |a - b| in degrees, wrapped to [0, 180]."""
    return abs((a - b + 180.0) % 360.0 - 180.0)


def make_crs(
    kind: str = "aeqd",
    origin: Any = None,
    *,
    zone: int | None = None,
    epsg: int | None = None,
    proj: str | None = None,
) -> dict[str, Any]:
    """The ``crs`` record of a plan (see the module docstring), checked by pyproj.

    Parameters
    ----------
    kind : {"aeqd", "utm", "epsg", "proj"}
        ``aeqd``: azimuthal equidistant centred on ``origin``; ``utm``: UTM zone ``zone``
        (default: the origin's, south when lat < 0); ``epsg``/``proj``: a projected CRS in
        metres, with ``origin`` the point that becomes local (0, 0).
    origin : str or (float, float)
        (lat, lon) degrees of the map's (0, 0).
    zone, epsg, proj
        The UTM zone, EPSG code or PROJ string of the kinds that take one.

    Returns
    -------
    dict
        ``kind``, ``proj`` and/or ``epsg``, ``origin_deg``.
    """
    lat, lon = check_origin(origin)
    if kind == "aeqd":
        text = f"+proj=aeqd +lat_0={lat!r} +lon_0={lon!r} +datum=WGS84 +units=m +no_defs"
        rec: dict[str, Any] = {"kind": kind, "proj": text}
    elif kind == "utm":
        z = utm_zone((lat, lon)) if zone is None else zone
        if isinstance(z, bool) or not isinstance(z, int) or not 1 <= z <= 60:
            raise ConfigError("crs.zone", z, "a UTM zone 1-60")
        check_utm_zone("crs.zone", z, (lat, lon))
        south = " +south" if lat < 0 else ""
        text = f"+proj=utm +zone={z}{south} +datum=WGS84 +units=m +no_defs"
        rec = {"kind": kind, "proj": text, "epsg": (32700 if south else 32600) + z}
    elif kind == "epsg":
        rec = {"kind": kind, "epsg": epsg}
    elif kind == "proj":
        rec = {"kind": kind, "proj": proj}
    else:
        raise ConfigError("crs.kind", kind, "one of " + ", ".join(CRS_KINDS))
    rec["origin_deg"] = [lat, lon]
    check_crs("crs", rec)
    return rec


def crs_text(rec: dict[str, Any]) -> str:
    """What pyproj reads for a ``crs`` record: ``EPSG:<code>`` or its PROJ string."""
    return f"EPSG:{rec['epsg']}" if rec["kind"] == "epsg" else str(rec["proj"])


def check_crs(field: str, rec: Any) -> dict[str, Any]:
    """A plan's ``crs`` record, validated: known kind, a projected CRS in metres, an origin.

    Raises
    ------
    ConfigError
        Naming ``field`` and the member that is wrong.
    """
    if not isinstance(rec, dict):
        raise ConfigError(field, rec, "a mapping with kind, origin_deg and proj or epsg")
    kind = rec.get("kind")
    if kind not in CRS_KINDS:
        raise ConfigError(f"{field}.kind", kind, "one of " + ", ".join(CRS_KINDS))
    allowed = {"kind", "origin_deg", "proj", "epsg"}
    extra = sorted(set(rec) - allowed)
    if extra:
        raise ConfigError(f"{field}.{extra[0]}", rec[extra[0]], "one of " + ", ".join(allowed))
    o = rec.get("origin_deg")
    if not isinstance(o, (list, tuple)) or len(o) != 2:
        raise ConfigError(f"{field}.origin_deg", o, "[lat, lon] in degrees")
    as_number(f"{field}.origin_deg", o[0], -89.9, 89.9)
    as_number(f"{field}.origin_deg", o[1], -180.0, 180.0)
    if kind == "epsg":
        code = rec.get("epsg")
        if isinstance(code, bool) or not isinstance(code, int) or not 1024 <= code <= 999999:
            raise ConfigError(f"{field}.epsg", code, "an EPSG code (integer) of a projected CRS")
    else:
        text = rec.get("proj")
        if not isinstance(text, str) or not text.strip() or len(text) > 1000:
            raise ConfigError(f"{field}.proj", text, "a PROJ string, e.g. '+proj=aeqd ...'")
    key = "epsg" if kind == "epsg" else "proj"
    try:
        crs = CRS.from_user_input(crs_text(rec))
    except CRSError as err:
        raise ConfigError(f"{field}.{key}", rec.get(key), f"a CRS pyproj accepts ({err})") from None
    units = {a.unit_name for a in crs.axis_info}
    if not crs.is_projected or units != {"metre"}:
        raise ConfigError(f"{field}.{key}", rec.get(key), "a projected CRS in metres")
    if kind in ("aeqd", "utm") and not re.search(rf"\+proj={kind}(\s|$)", str(rec["proj"])):
        raise ConfigError(f"{field}.proj", rec.get("proj"), f"+proj={kind} ... for kind {kind}")
    zone = _utm_zone_of(crs)
    if zone is not None:
        check_utm_zone(f"{field}.{key}", zone, (float(o[0]), float(o[1])), rec.get(key))
    return rec


def _utm_zone_of(crs: CRS) -> int | None:
    """The zone of a UTM CRS (a ``+proj=utm`` string or an EPSG 326xx/327xx code), else None."""
    m = re.match(r"(\d+)", crs.utm_zone or "")
    return int(m.group(1)) if m else None


@functools.lru_cache(maxsize=64)
def _transformers(
    text: str, lat0: float, lon0: float
) -> tuple[Transformer, Transformer, float, float]:
    """(lon/lat -> projected, projected -> lon/lat, x0, y0) of a CRS; cached per CRS and origin."""
    fwd = Transformer.from_crs("EPSG:4326", text, always_xy=True)
    inv = Transformer.from_crs(text, "EPSG:4326", always_xy=True)
    x0, y0 = fwd.transform(lon0, lat0, errcheck=True)
    return fwd, inv, float(x0), float(y0)


def _resolve(crs: Any) -> tuple[Transformer, Transformer, float, float]:
    """A (lat, lon) origin (default aeqd there) or a plan's ``crs`` record -> transformers."""
    if isinstance(crs, dict):
        rec = crs
    else:
        lat, lon = check_origin(crs)
        rec = {
            "kind": "aeqd",
            "proj": f"+proj=aeqd +lat_0={lat!r} +lon_0={lon!r} +datum=WGS84 +units=m +no_defs",
            "origin_deg": [lat, lon],
        }
    lat0, lon0 = (float(v) for v in rec["origin_deg"])
    return _transformers(crs_text(rec), lat0, lon0)


def to_geographic(xy, origin: Any) -> list[tuple[float, float]]:
    """Local metres [[x, y], ...] -> [(lat, lon), ...] degrees.

    Parameters
    ----------
    xy : array_like, shape (n, 2)
        Local metres.
    origin : (float, float) or str or dict
        The (lat, lon) of the map's (0, 0) (the default ``aeqd`` CRS there) or a plan's
        ``crs`` record (see the module docstring).

    Raises
    ------
    ConfigError
        A point the projection does not map onto the globe.
    """
    pts = np.asarray(xy, dtype=float).reshape(-1, 2)
    if pts.size == 0:
        return []
    _, inv, x0, y0 = _resolve(origin)
    lon, lat = inv.transform(pts[:, 0] + x0, pts[:, 1] + y0)
    lon = np.atleast_1d(np.asarray(lon, dtype=float))
    lat = np.atleast_1d(np.asarray(lat, dtype=float))
    lon = np.where(np.abs(lon) <= 180.0, lon, (lon + 180.0) % 360.0 - 180.0)  # antimeridian
    bad = ~(np.isfinite(lat) & np.isfinite(lon) & (np.abs(lat) <= 90.0))
    if bad.any():
        k = int(np.argmax(bad))
        raise ConfigError(
            "waypoints", pts[k].tolist(), f"points the projection {origin} maps on the globe"
        )
    return [(float(a), float(b)) for a, b in zip(lat, lon)]


def continuous_lon(lon: Any, origin: Any) -> np.ndarray:
    """Longitudes ``lon`` (degrees) shifted by whole turns to lie within 180 degrees of the map
    origin's (``origin``: as :func:`to_geographic` takes it), so that a map drawn around the
    180th meridian is continuous (179.9 then 180.1, not -179.9): what Google Earth and Leaflet
    need to draw a line or polygon across it the short way (OGC 07-147r2 section 9.14.3.4 lets
    a ``LatLonBox`` extend beyond 180 for it). Away from the meridian nothing changes.

    >>> continuous_lon([179.9, -179.9, 10.0], (-16.5, 179.8)).tolist()
    [179.9, 180.1, 10.0]
    """
    lon0 = float(origin["origin_deg"][1]) if isinstance(origin, dict) else check_origin(origin)[1]
    a = np.asarray(lon, dtype=float)
    shift = 360.0 * np.round((a - lon0) / 360.0)
    return np.where(np.abs(a - lon0) <= 180.0, a, a - shift)


def to_local(latlon, origin: Any) -> list[tuple[float, float]]:
    """The inverse of :func:`to_geographic`: [(lat, lon), ...] degrees -> [(x, y), ...] m."""
    pts = np.asarray(latlon, dtype=float).reshape(-1, 2)
    if pts.size == 0:
        return []
    fwd, _, x0, y0 = _resolve(origin)
    try:
        x, y = fwd.transform(pts[:, 1], pts[:, 0], errcheck=True)
    except ProjError as err:
        raise ConfigError("latlon", pts.tolist()[:3], f"points on the globe ({err})") from None
    x = np.atleast_1d(np.asarray(x, dtype=float)) - x0
    y = np.atleast_1d(np.asarray(y, dtype=float)) - y0
    return [(float(a), float(b)) for a, b in zip(x, y)]


def plan_crs(
    rec: dict[str, Any] | None, origin: Any, projection: str, zone: int | None
) -> dict[str, Any]:
    """The CRS an export uses: the plan's record ``rec`` (``origin``, if given, must agree with
    its ``origin_deg``) or, for a plan without one, ``projection`` at ``origin``.

    Raises
    ------
    ConfigError
        ``origin`` disagrees with the plan's, or is missing when the plan records no CRS; a
        ``projection`` other than the default ``aeqd``, or a ``zone``, that disagrees with the
        plan's record (it would be ignored: the plan's CRS is the one its metres are in).
    """
    if rec is not None:
        kind = rec.get("kind")
        if projection != "aeqd" and projection != kind:
            raise ConfigError("projection", projection, f"{kind} (the plan's crs.kind) or "
                              "omitted: a plan's metres are in the crs it records")  # fmt: skip
        own_zone = rec["epsg"] % 100 if kind == "utm" and "epsg" in rec else None
        if zone is not None and zone != own_zone:
            shown = "no zone: its crs is " + str(kind) if own_zone is None else own_zone
            raise ConfigError("utm_zone", zone, f"omitted (the plan records its crs: {shown})")
        if origin is not None:
            lat, lon = check_origin(origin)
            lat0, lon0 = rec["origin_deg"]
            if max(abs(lat - lat0), abs(lon - lon0)) > 1e-7:
                raise ConfigError(
                    "origin", origin, f"{lat0!r},{lon0!r} (the plan's crs.origin_deg) or omitted"
                )
        return dict(rec)
    if origin is None:
        raise ConfigError("origin", None, "LAT,LON of the map's (0, 0): the plan records no crs")
    return make_crs(projection, origin, zone=zone)


#: GeoJSON ``crs`` member names (2008 GeoJSON spec) that mean WGS 84 longitude/latitude, the
#: RFC 7946 default, compared lower-case by :func:`is_wgs84_name`. One list for every GeoJSON
#: reader (``scenario import`` layers, ``replan --tracks``).
WGS84_NAMES = (
    "urn:ogc:def:crs:ogc:1.3:crs84",
    "urn:ogc:def:crs:ogc::crs84",
    "crs84",
    "epsg:4326",
    "urn:ogc:def:crs:epsg::4326",
    "urn:ogc:def:crs:epsg:6.6:4326",
    "http://www.opengis.net/def/crs/ogc/1.3/crs84",
    "http://www.opengis.net/def/crs/epsg/0/4326",
)


def is_wgs84_name(name: Any) -> bool:
    """Whether a GeoJSON ``crs`` member's name means WGS 84 longitude/latitude
    (:data:`WGS84_NAMES`, case and surrounding spaces ignored)."""
    return isinstance(name, str) and name.strip().lower() in WGS84_NAMES


def geojson_crs_to_lonlat(member: Any, field: str) -> Any:
    """The reprojection a GeoJSON object's ``crs`` member asks for, or None.

    RFC 7946 (2016) removed ``crs``: positions are WGS 84 longitude/latitude. The 2008 GeoJSON
    specification allowed a named CRS (``{"type": "name", "properties": {"name":
    "urn:ogc:def:crs:EPSG::32632"}}``), positions then in its x, y (easting, northing) order,
    and older files (a logger's, a GIS's export) still carry one. Absent, or a name of
    :data:`WGS84_NAMES`: None (nothing to do). Any other name pyproj reads (UTM, Web Mercator,
    another datum's longitude/latitude): a function ``(n, 2) x, y -> (n, 2) lon, lat``.

    Raises
    ------
    ConfigError
        ``field`` (the member, e.g. ``tracks.crs``): not a named CRS, or a name pyproj cannot
        read.
    """
    if member is None:
        return None
    props = member.get("properties") if isinstance(member, dict) else None
    name = props.get("name") if isinstance(props, dict) else None
    if is_wgs84_name(name):
        return None
    allowed = (
        "no crs member (RFC 7946: WGS 84 longitude/latitude), or a named CRS that pyproj "
        'reads ({"type": "name", "properties": {"name": "EPSG:32632"}}, GeoJSON 2008)'
    )
    if not isinstance(name, str):
        raise ConfigError(field, member if len(str(member)) < 200 else "object", allowed)
    try:
        src = CRS.from_user_input(name.strip())
    except CRSError as err:
        raise ConfigError(field, name, f"{allowed}; pyproj: {err}") from None
    to_wgs = Transformer.from_crs(src, "EPSG:4326", always_xy=True)

    def lonlat(xy: np.ndarray) -> np.ndarray:
        lon, lat = to_wgs.transform(xy[:, 0], xy[:, 1])
        return np.stack([np.atleast_1d(lon), np.atleast_1d(lat)], axis=1).astype(float)

    return lonlat


#: Largest distance (m) allowed between a polygon edge, straight where it was drawn (in
#: longitude/latitude for a GeoJSON layer, in the map's metres for the planner's areas), and
#: the straight lines that stand for it once it is drawn in the other space
#: (:func:`densify_ring`).
EDGE_TOLERANCE_M = 10.0


def densify_ring(
    ring: Any, crs: Any, *, straight_in: str, tol_m: float = EDGE_TOLERANCE_M
) -> np.ndarray:
    """``ring`` ((n, 2), not closed) with points added along its long edges, so that joining
    its points with lines straight in the *other* space stays within ``tol_m`` metres of its
    edges as drawn.

    ``straight_in="lonlat"``: ``ring`` is (lon, lat), its edges straight in longitude/latitude
    (GeoJSON, RFC 7946 3.1.1), to be projected and joined straight in the map's metres (the
    import). ``straight_in="local"``: ``ring`` is in the map's metres, its edges straight there
    (the planner's operating area and zones), to be drawn by a GIS straight in lon/lat (the
    exports). An edge departs from its counterpart by about its length squared, so an edge
    departing ``d`` is cut evenly into ``ceil(sqrt(d / tol_m))`` pieces (at most 1,000): an edge
    under about 20 km at mid-latitudes keeps its two ends; a 500 km edge gets about 22 pieces.
    """
    a = np.asarray(ring, dtype=float).reshape(-1, 2)
    b = np.roll(a, -1, axis=0)
    t = np.linspace(0.0, 1.0, 9)[1:-1]
    mid = a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]  # evenly along, in ring space
    if straight_in == "lonlat":
        drawn = np.array(to_local(mid.reshape(-1, 2)[:, ::-1], crs)).reshape(mid.shape)
        ends = np.array(to_local(np.vstack([a, b])[:, ::-1], crs)).reshape(2, -1, 2)
        other = ends[0][:, None, :] + t[None, :, None] * (ends[1] - ends[0])[:, None, :]
    elif straight_in == "local":
        drawn = mid
        ll = np.array(to_geographic(np.vstack([a, b]), crs)).reshape(2, -1, 2)
        chord = ll[0][:, None, :] + t[None, :, None] * (ll[1] - ll[0])[:, None, :]
        other = np.array(to_local(chord.reshape(-1, 2), crs)).reshape(mid.shape)
    else:
        raise ValueError(f"straight_in: {straight_in!r}; allowed: lonlat or local")
    dev = np.max(np.hypot(*(drawn - other).transpose(2, 0, 1)), axis=1)
    pieces = np.clip(np.ceil(np.sqrt(np.maximum(dev, 0.0) / tol_m)).astype(int), 1, 1000)
    out = [p + (np.arange(m)[:, None] / m) * (q - p) for p, q, m in zip(a, b, pieces)]
    return np.vstack(out)
