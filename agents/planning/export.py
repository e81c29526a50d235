"""Mission export: a plan (``plan.json``, schema 2) as GeoJSON, KML or QGroundControl missions.

Projection
----------
Plans are in local metres; a coordinate reference system (CRS) places them on the WGS84
ellipsoid. Every projection goes through pyproj (PROJ) Transformers with ``always_xy=True``
(so every call is (lon, lat) <-> (easting, northing); :func:`to_geographic` and
:func:`to_local` keep the (lat, lon) order of their callers):

- ``aeqd`` (default): the azimuthal equidistant projection centred on the map's (0, 0),
  ``+proj=aeqd +lat_0=LAT +lon_0=LON +datum=WGS84 +units=m +no_defs``. Distances and bearings
  from the origin are exact; elsewhere the scale across the radius is about
  ``1 + rho**2 / (6 R**2)``, below 0.04 % within 300 km of the origin. Measured against the
  ellipsoid (``pyproj.Geod``, tests/planning/test_export.py, numbers in docs/EXPORT.md): over the
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

``plan.json`` (schema 2; schema-1 files still load) holds: ``schema``, ``scenario``, ``seed``,
``map_source``, ``optimizer`` {``name``, ``settings``}, ``runtime_s``, ``posc``,
``upper_bound`` and ``uavs``: a list of {``id``, ``rectangle`` {``center_m`` [x, y],
``length_m``, ``width_m``, ``theta_deg``} (the optimiser's decision rectangle; ``null`` in a
schema-2 route plan such as the allocation planner's), ``spacing_m``, ``takeoff_m``,
``landing_m``, ``waypoints_m`` [[x, y], ...], ``track_length_m``, ``flight_time_s``, ``pod``,
``poc``, ``pos``, ``feasible``}. ``waypoints_m`` are the search pattern only: the route flown is
take-off field, transit to ``waypoints_m[0]``, the search from ``waypoints_m[0]`` to
``waypoints_m[-1]``, transit to the landing field. **``waypoints_m`` is what the time model
flies**; the rectangles are for people.

Schema 2 adds (all optional, checked when present):

- per UAV ``flown_rectangle`` {``center_m``, ``line_length_m``, ``strip_width_m``,
  ``lines_theta_rad``, ``rule``}: the strip the lines actually sweep
  (:func:`poc_env.agents.planning.objective.flown_rectangle`). :data:`RECTANGLE_RULE` (also written
  as the top-level ``rectangle_rule``) says how to fly it: lines along ``lines_theta_rad`` at
  spacing ``spacing_m``, ``d/2`` inside each long edge, ``strip_width_m / spacing_m`` lines.
  Re-flying it by that rule (or by the usual ``ceil(E/d)`` lawnmower, which coincides on it)
  gives the plan's own eq. 17 flight time; re-flying the decision rectangle the usual way does
  not (issue 12), so every export draws the flown strip, not the decision rectangle.
- per UAV ``areas_m``: polygons the UAV searches (a route plan's regions), drawn as search areas.
- ``bounds`` {``honest``, ``reach``}: :func:`poc_env.theory.bound.honest_optimum` and the
  reach-aware :func:`poc_env.theory.bound.reach_bound` of the plan's prior, the bounds no policy
  beats in the environment (``upper_bound`` stays the optimiser's same-effort bound).

Optional fields of both schemas (a plan without them is read as before):

- ``crs``: {``kind``: ``aeqd`` | ``utm`` | ``epsg`` | ``proj``, ``origin_deg`` [lat, lon],
  ``proj`` (a PROJ string; required unless ``kind`` is ``epsg``), ``epsg`` (an integer; required
  for ``epsg``)}, as written by :func:`make_crs`. With it, export needs no ``--origin``; an
  ``--origin`` given anyway must equal ``crs.origin_deg``. Without it, ``--origin`` is required
  and the default ``aeqd`` CRS at that origin is used.
- ``flight``: {``cruise_speed_mps`` (v_b, the flight home), ``search_speed_mps`` (v_s, on the
  route after the first waypoint), ``transit_speed_mps`` (out to the first waypoint; default
  v_b), ``altitude_m``, ``max_altitude_m``} of the scenario's UAV (default the paper's 220 km/h,
  180 km/h, 220 km/h, 1,000 m, 4,000 m). The allocation planner's ``--speed max`` plans record
  v_max as the search and transit speeds.
- ``operating_area_m``: the operating area (eq. 20's boundary) as a polygon [[x, y], ...]; the
  QGC geofence's inclusion polygon. Without it the inclusion fence is left empty.
- ``no_fly_zones_m``: a list of polygons; exclusion fences.
- ``airfields``: [{``name``, ``position_m``}]; names in KML/GeoJSON.

:func:`load_plan` checks every field an export reads before anything is written: finite numbers
in documented ranges (points within :data:`MAX_EXTENT_M` of the origin, probabilities in
[0, 1]), the right shapes, a known CRS kind that pyproj accepts as a projected CRS in metres,
and UAV ids of 1-64 ``A-Z a-z 0-9 _ -`` (they become file names), so no NaN, no out-of-range
latitude and no path outside ``--out`` can reach a mission file.
"""

from __future__ import annotations

import functools
import json
import math
import os
import re
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape

import numpy as np
from pyproj import CRS, Transformer
from pyproj.exceptions import CRSError, ProjError

from poc_env.errors import ConfigError, as_number
from poc_env.io import write_bytes_atomic, write_text_atomic

SCHEMA = 2
#: The schemas :func:`load_plan` reads.
READ_SCHEMAS = (1, 2)
#: How a plan's ``flown_rectangle`` is flown (module docstring).
RECTANGLE_RULE = (
    "flown_rectangle: lines along lines_theta_rad at spacing spacing_m, the first and last d/2 "
    "inside the strip's long edges, strip_width_m / spacing_m lines, boustrophedon; this is "
    "the track waypoints_m flies and flight_time_s times"
)
FORMATS = ("geojson", "kml", "qgc", "html")
CRS_KINDS = ("aeqd", "utm", "epsg", "proj")
ALTITUDE_REFS = ("home", "amsl")

PLAN_KEYS = {
    "schema", "scenario", "seed", "map_source", "optimizer", "runtime_s", "posc",
    "upper_bound", "uavs",
}  # fmt: skip
UAV_KEYS = {
    "id", "rectangle", "spacing_m", "takeoff_m", "landing_m", "waypoints_m", "track_length_m",
    "flight_time_s", "pod", "poc", "pos", "feasible",
}  # fmt: skip

#: The paper's UAV (§6.2) for plans that record no ``flight`` section.
DEFAULT_FLIGHT = {
    "cruise_speed_mps": 220 / 3.6,
    "search_speed_mps": 180 / 3.6,
    "transit_speed_mps": 220 / 3.6,
    "altitude_m": 1000.0,
    "max_altitude_m": 4000.0,
}

# MAVLink ids (https://mavlink.io/en/messages/common.html): MAV_CMD and MAV_FRAME.
MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_LAND = 21
MAV_CMD_NAV_TAKEOFF = 22
MAV_CMD_DO_CHANGE_SPEED = 178
MAV_CMD_DO_LAND_START = 189
MAV_FRAME_GLOBAL = 0
MAV_FRAME_MISSION = 2
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
#: altitude reference -> (MAV_FRAME, QGC AltitudeMode (1 relative, 2 absolute), KML altitudeMode)
_ALT_REF = {
    "home": (MAV_FRAME_GLOBAL_RELATIVE_ALT, 1, "relativeToGround"),
    "amsl": (MAV_FRAME_GLOBAL, 2, "absolute"),
}


def parse_origin(text: str) -> tuple[float, float]:
    """``"LAT,LON"`` in degrees -> (lat, lon); ConfigError outside [-90, 90] x [-180, 180]."""
    try:
        lat, lon = (float(v) for v in str(text).split(","))
    except ValueError:
        raise ConfigError("origin", text, "LAT,LON in degrees, e.g. 45.5,126.6") from None
    if not (-90 <= lat <= 90 and -180 <= lon <= 180) or abs(lat) > 89.9:
        raise ConfigError("origin", text, "latitude in [-89.9, 89.9], longitude in [-180, 180]")
    return lat, lon


def _origin(origin: Any) -> tuple[float, float]:
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


def make_crs(
    kind: str = "aeqd",
    origin: Any = None,
    *,
    zone: int | None = None,
    epsg: int | None = None,
    proj: str | None = None,
) -> dict[str, Any]:
    """The ``crs`` record of a plan (see the module docstring), checked by pyproj.

    ``aeqd``: azimuthal equidistant centred on ``origin`` (lat, lon); ``utm``: UTM zone
    ``zone`` (default: the origin's, south when lat < 0); ``epsg``/``proj``: a projected CRS in
    metres, with ``origin`` the point that becomes local (0, 0).
    """
    lat, lon = _origin(origin)
    if kind == "aeqd":
        text = f"+proj=aeqd +lat_0={lat!r} +lon_0={lon!r} +datum=WGS84 +units=m +no_defs"
        rec: dict[str, Any] = {"kind": kind, "proj": text}
    elif kind == "utm":
        z = utm_zone((lat, lon)) if zone is None else zone
        if isinstance(z, bool) or not isinstance(z, int) or not 1 <= z <= 60:
            raise ConfigError("crs.zone", z, "a UTM zone 1-60")
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
    _check_crs("crs", rec)
    return rec


def _crs_text(rec: dict[str, Any]) -> str:
    return f"EPSG:{rec['epsg']}" if rec["kind"] == "epsg" else str(rec["proj"])


def _check_crs(field: str, rec: Any) -> dict[str, Any]:
    """A plan's ``crs`` record, validated: known kind, a projected CRS in metres, an origin."""
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
    _number(f"{field}.origin_deg", o[0], -89.9, 89.9)
    _number(f"{field}.origin_deg", o[1], -180.0, 180.0)
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
        crs = CRS.from_user_input(_crs_text(rec))
    except CRSError as err:
        raise ConfigError(f"{field}.{key}", rec.get(key), f"a CRS pyproj accepts ({err})") from None
    units = {a.unit_name for a in crs.axis_info}
    if not crs.is_projected or units != {"metre"}:
        raise ConfigError(f"{field}.{key}", rec.get(key), "a projected CRS in metres")
    if kind in ("aeqd", "utm") and not re.search(rf"\+proj={kind}(\s|$)", str(rec["proj"])):
        raise ConfigError(f"{field}.proj", rec.get("proj"), f"+proj={kind} ... for kind {kind}")
    return rec


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
        lat, lon = _origin(crs)
        rec = {
            "kind": "aeqd",
            "proj": f"+proj=aeqd +lat_0={lat!r} +lon_0={lon!r} +datum=WGS84 +units=m +no_defs",
            "origin_deg": [lat, lon],
        }
    lat0, lon0 = (float(v) for v in rec["origin_deg"])
    return _transformers(_crs_text(rec), lat0, lon0)


def to_geographic(xy, origin: Any) -> list[tuple[float, float]]:
    """Local metres [[x, y], ...] -> [(lat, lon), ...] degrees.

    ``origin``: the (lat, lon) of the map's (0, 0) (the default ``aeqd`` CRS there) or a plan's
    ``crs`` record (see the module docstring).
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


def load_plan(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read and check a plan.json; errors name the missing or wrong field."""
    p = Path(path)
    if not p.is_file():
        raise ConfigError("plan", str(p), "an existing plan.json written by `poc-env plan`")
    try:
        plan = json.loads(p.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise ConfigError("plan", str(p), f"valid JSON ({err})") from None
    if not isinstance(plan, dict):
        raise ConfigError("plan", type(plan).__name__, "a JSON object")
    schema = plan.get("schema")
    if isinstance(schema, bool) or schema not in READ_SCHEMAS:
        raise ConfigError("plan.schema", schema, " or ".join(map(str, READ_SCHEMAS)))
    missing = sorted(PLAN_KEYS - set(plan))
    if missing:
        raise ConfigError(f"plan.{missing[0]}", None, "present (schema 1 field)")
    if not isinstance(plan["uavs"], list) or not plan["uavs"]:
        raise ConfigError("plan.uavs", plan["uavs"], "a non-empty list of UAV plans")
    _number("plan.posc", plan["posc"], 0.0, 1.0)
    ids: set[str] = set()
    for k, u in enumerate(plan["uavs"]):
        where = f"plan.uavs[{k}]"
        miss = sorted(UAV_KEYS - set(u)) if isinstance(u, dict) else ["id"]
        if miss:
            raise ConfigError(f"{where}.{miss[0]}", None, "present (schema 1 field)")
        uid = u["id"]
        if (
            isinstance(uid, bool)
            or not isinstance(uid, (int, str))
            or not _SAFE_ID.fullmatch(str(uid))
        ):
            raise ConfigError(f"{where}.id", uid, "an integer >= 0 or 1-64 of A-Z a-z 0-9 _ -")
        if str(uid) in ids:
            raise ConfigError(f"{where}.id", uid, "unique among the plan's UAVs")
        ids.add(str(uid))
        _point(f"{where}.takeoff_m", u["takeoff_m"])
        _point(f"{where}.landing_m", u["landing_m"])
        wps = u["waypoints_m"]
        if not isinstance(wps, list):
            raise ConfigError(f"{where}.waypoints_m", wps, "a list of [x, y] points in metres")
        for i, w in enumerate(wps):
            _point(f"{where}.waypoints_m[{i}]", w)
        _check_rectangles(where, u, schema)
        for key in ("spacing_m", "track_length_m"):
            _number(f"{where}.{key}", u[key], 0.0, 100 * MAX_EXTENT_M)
        _number(f"{where}.flight_time_s", u["flight_time_s"], 0.0, 1e7)
        for key in ("pod", "poc", "pos"):
            _number(f"{where}.{key}", u[key], 0.0, 1.0)
        if not isinstance(u["feasible"], bool):
            raise ConfigError(f"{where}.feasible", u["feasible"], "true or false")
    _check_optional(plan)
    return plan


def _check_rectangles(where: str, u: dict[str, Any], schema: int) -> None:
    """``rectangle`` (null allowed from schema 2), ``flown_rectangle`` and ``areas_m``."""
    r = u["rectangle"]
    if r is not None or schema < 2:
        keys = ["center_m", "length_m", "theta_deg", "width_m"]
        if not isinstance(r, dict) or sorted(r) != keys:
            allowed = "a mapping of center_m, length_m, width_m, theta_deg"
            raise ConfigError(f"{where}.rectangle", r, allowed + (" or null" if schema > 1 else ""))
        _point(f"{where}.rectangle.center_m", r["center_m"])
        for key in ("length_m", "width_m"):
            _number(f"{where}.rectangle.{key}", r[key], 0.0, MAX_EXTENT_M)
        _number(f"{where}.rectangle.theta_deg", r["theta_deg"], -360.0, 360.0)
    fr = u.get("flown_rectangle")
    if fr is not None:
        keys = ["center_m", "line_length_m", "lines_theta_rad", "rule", "strip_width_m"]
        if not isinstance(fr, dict) or sorted(fr) != keys:
            raise ConfigError(f"{where}.flown_rectangle", fr, "a mapping of " + ", ".join(keys))
        _point(f"{where}.flown_rectangle.center_m", fr["center_m"])
        for key in ("line_length_m", "strip_width_m"):
            _number(f"{where}.flown_rectangle.{key}", fr[key], 0.0, MAX_EXTENT_M)
        _number(f"{where}.flown_rectangle.lines_theta_rad", fr["lines_theta_rad"], -7.0, 7.0)
        if not isinstance(fr["rule"], str) or len(fr["rule"]) > 500:
            raise ConfigError(f"{where}.flown_rectangle.rule", fr["rule"], "a text of <= 500")
    areas = u.get("areas_m")
    if areas is not None:
        if not isinstance(areas, list):
            raise ConfigError(f"{where}.areas_m", areas, "a list of polygons")
        for i, a in enumerate(areas):
            _polygon(f"{where}.areas_m[{i}]", a)


def search_rings(u: dict[str, Any]) -> list[tuple[str, list[list[float]], dict[str, Any]]]:
    """What a UAV searches, as closed rings in local metres: ``(kind, ring, properties)``.

    The flown strip when the plan has one (``search_strip``: what the lines sweep, see
    :data:`RECTANGLE_RULE`), else the decision rectangle (``search_rectangle``; schema 1),
    then every ``areas_m`` polygon (``search_area``). Properties in km and degrees. One
    implementation for GeoJSON, KML and the figures.
    """
    from poc_env.geometry import rectangle_corners

    out: list[tuple[str, list[list[float]], dict[str, Any]]] = []
    fr, r = u.get("flown_rectangle"), u.get("rectangle")
    if fr is not None:
        c = rectangle_corners(
            fr["center_m"], fr["line_length_m"], fr["strip_width_m"], fr["lines_theta_rad"]
        ).tolist()
        props = {
            "line_length_km": round(fr["line_length_m"] / 1e3, 3),
            "strip_width_km": round(fr["strip_width_m"] / 1e3, 3),
            "lines_heading_deg": round(math.degrees(fr["lines_theta_rad"]) % 360.0, 2),
            "spacing_km": round(u["spacing_m"] / 1e3, 3),
            "rule": fr["rule"],
        }
        out.append(("search_strip", [*c, c[0]], props))
    elif r is not None:
        c = rectangle_corners(
            r["center_m"], r["length_m"], r["width_m"], math.radians(r["theta_deg"])
        ).tolist()
        props = {
            "length_km": round(r["length_m"] / 1e3, 3),
            "width_km": round(r["width_m"] / 1e3, 3),
            "theta_deg": round(r["theta_deg"], 2),
        }
        out.append(("search_rectangle", [*c, c[0]], props))
    for a in u.get("areas_m") or []:
        ring = [[float(x), float(y)] for x, y in a]
        if ring[0] != ring[-1]:
            ring.append(ring[0])
        out.append(("search_area", ring, {"spacing_km": round(u["spacing_m"] / 1e3, 3)}))
    return out


def _check_optional(plan: dict[str, Any]) -> None:
    """The optional fields (module docstring): absent or null is fine, anything else checked."""
    if plan.get("crs") is not None:
        _check_crs("plan.crs", plan["crs"])
    b = plan.get("bounds")
    if b is not None:
        if not isinstance(b, dict) or sorted(b) != ["honest", "reach"]:
            raise ConfigError("plan.bounds", b, "a mapping of honest, reach")
        for key in ("honest", "reach"):
            _number(f"plan.bounds.{key}", b[key], 0.0, 1.0)
    rule = plan.get("rectangle_rule")
    if rule is not None and (not isinstance(rule, str) or len(rule) > 1000):
        raise ConfigError("plan.rectangle_rule", rule, "a text of <= 1000 characters")
    fl = plan.get("flight")
    if fl is not None:
        if not isinstance(fl, dict) or not set(fl) <= set(DEFAULT_FLIGHT):
            raise ConfigError("plan.flight", fl, "a mapping of " + ", ".join(DEFAULT_FLIGHT))
        for key in ("cruise_speed_mps", "search_speed_mps", "transit_speed_mps"):
            if key in fl:
                _number(f"plan.flight.{key}", fl[key], 1e-3, MAX_SPEED_MPS)
        for key in ("altitude_m", "max_altitude_m"):
            if key in fl:
                _number(f"plan.flight.{key}", fl[key], 1e-3, MAX_ALTITUDE_M)
    if plan.get("operating_area_m") is not None:
        _polygon("plan.operating_area_m", plan["operating_area_m"])
    zones = plan.get("no_fly_zones_m")
    if zones is not None:
        if not isinstance(zones, list):
            raise ConfigError("plan.no_fly_zones_m", zones, "a list of polygons")
        for i, z in enumerate(zones):
            _polygon(f"plan.no_fly_zones_m[{i}]", z)
    fields = plan.get("airfields")
    if fields is not None:
        if not isinstance(fields, list):
            raise ConfigError("plan.airfields", fields, "a list of {name, position_m}")
        for i, a in enumerate(fields):
            if not isinstance(a, dict) or sorted(a) != ["name", "position_m"]:
                raise ConfigError(f"plan.airfields[{i}]", a, "a mapping of name, position_m")
            if not isinstance(a["name"], str) or not 1 <= len(a["name"]) <= 64:
                raise ConfigError(f"plan.airfields[{i}].name", a["name"], "1-64 characters")
            _point(f"plan.airfields[{i}].position_m", a["position_m"])


#: Largest |x| or |y| of a plan point, metres: 2,000 km from the map origin, far beyond a
#: regional search (the projections are documented and measured within 300 km).
MAX_EXTENT_M = 2.0e6
#: Largest speed (m/s) and altitude (m) a plan's ``flight`` section may hold.
MAX_SPEED_MPS = 1000.0
MAX_ALTITUDE_M = 30_000.0
_SAFE_ID = re.compile(r"[A-Za-z0-9_-]{1,64}")


def _number(field: str, value: Any, lo: float, hi: float) -> float:
    """``value`` as a float if it is a finite JSON number in [lo, hi], else ConfigError (the
    project's one coercion, :func:`poc_env.errors.as_number`)."""
    return as_number(field, value, lo, hi)


def _point(field: str, value: Any) -> None:
    """An [x, y] point in metres within :data:`MAX_EXTENT_M` of the origin."""
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ConfigError(field, value, "[x, y] in metres")
    for v in value:
        _number(field, v, -MAX_EXTENT_M, MAX_EXTENT_M)


def _polygon(field: str, value: Any) -> None:
    """A polygon: a list of at least 3 [x, y] points in metres."""
    if not isinstance(value, list) or len(value) < 3:
        raise ConfigError(field, value, "a list of at least 3 [x, y] points in metres")
    for i, v in enumerate(value):
        _point(f"{field}[{i}]", v)


def _route(u: dict) -> list[list[float]]:
    return [list(u["takeoff_m"]), *u["waypoints_m"], list(u["landing_m"])]


def _flight(plan: dict) -> dict[str, float]:
    return {**DEFAULT_FLIGHT, **(plan.get("flight") or {})}


def _altitudes(
    plan: dict, altitude_m: float | None, altitude_ref: str, field_elevation_m: float
) -> tuple[float, float]:
    """(cruise altitude, ground level) in the reference ``altitude_ref``, checked."""
    if altitude_ref not in _ALT_REF:
        raise ConfigError("altitude_ref", altitude_ref, "home or amsl")
    fl = _flight(plan)
    ground = 0.0
    if altitude_ref == "amsl":
        ground = _number("field_elevation_m", field_elevation_m, -500.0, 9000.0)
    alt = fl["altitude_m"] + ground if altitude_m is None else altitude_m
    _number("altitude_m", alt, -1e9, 1e9)
    top = fl["max_altitude_m"]
    if not alt > ground:
        above = "home (> 0)" if altitude_ref == "home" else f"the field elevation {ground:g} m"
        raise ConfigError("altitude_m", alt, f"above {above} and at most the ceiling {top:g} m")
    if alt - ground > top:
        raise ConfigError("altitude_m", alt, f"at most the UAV ceiling {top:g} m above the field")
    return float(alt), ground


def _plan_crs(plan: dict, origin: Any, projection: str, zone: int | None) -> dict[str, Any]:
    """The plan's CRS; ``origin`` must agree with it (or is needed when it has none)."""
    rec = plan.get("crs")
    if rec is not None:
        if origin is not None:
            lat, lon = _origin(origin)
            lat0, lon0 = rec["origin_deg"]
            if max(abs(lat - lat0), abs(lon - lon0)) > 1e-7:
                raise ConfigError(
                    "origin", origin, f"{lat0!r},{lon0!r} (the plan's crs.origin_deg) or omitted"
                )
        return dict(rec)
    if origin is None:
        raise ConfigError("origin", None, "LAT,LON of the map's (0, 0): the plan records no crs")
    return make_crs(projection, origin, zone=zone)


def _ll(points, crs: dict) -> list[tuple[float, float]]:
    return to_geographic(points, crs)


def _r6(v: float) -> float:
    """Degrees rounded to 1e-6 (about 0.1 m)."""
    return round(float(v), 6)


def geojson(
    plan: dict,
    crs: Any,
    altitude_m: float | None = None,
    altitude_ref: str = "home",
    field_elevation_m: float = 0.0,
) -> dict:
    """A FeatureCollection: per UAV the route (LineString) and its search rectangle (Polygon).

    Coordinates [lon, lat, z] rounded to 1e-6 degrees (about 0.1 m); z is the altitude in the
    reference ``altitude_ref`` (the same numbers as the QGC mission and the KML); properties in
    km, minutes, km/h and %.
    """
    alt, ground = _altitudes(plan, altitude_m, altitude_ref, field_elevation_m)
    fl = _flight(plan)
    feats = []
    for u in plan["uavs"]:
        pts = _ll(_route(u), crs)
        zs = [ground, *[alt] * (len(pts) - 2), ground]
        route = [[_r6(lon), _r6(lat), z] for (lat, lon), z in zip(pts, zs)]
        props = {
            "id": u["id"],
            "kind": "route",
            "spacing_km": round(u["spacing_m"] / 1e3, 3),
            "track_km": round(u["track_length_m"] / 1e3, 3),
            "flight_time_min": round(u["flight_time_s"] / 60, 1),
            "pod_pct": round(100 * u["pod"], 2),
            "poc_pct": round(100 * u["poc"], 2),
            "pos_pct": round(100 * u["pos"], 2),
            "feasible": u["feasible"],
            "altitude_m": round(alt, 1),
            "altitude_ref": altitude_ref,
            "cruise_speed_kmh": round(fl["cruise_speed_mps"] * 3.6, 1),
            "search_speed_kmh": round(fl["search_speed_mps"] * 3.6, 1),
            "transit_speed_kmh": round(fl["transit_speed_mps"] * 3.6, 1),
        }
        feats.append(
            {
                "type": "Feature",
                "geometry": {"type": "LineString", "coordinates": route},
                "properties": props,
            }
        )
        for kind, ring_m, props in search_rings(u):
            ring = [[_r6(lon), _r6(lat)] for lat, lon in _ll(ring_m, crs)]
            feats.append(
                {
                    "type": "Feature",
                    "geometry": {"type": "Polygon", "coordinates": [ring]},
                    "properties": {"id": u["id"], "kind": kind, **props},
                }
            )
    for o in _overlays(plan, crs, alt, ground):
        if o["geometry"] == "Polygon":
            coords: Any = [[[_r6(lon), _r6(lat)] for lat, lon in o["latlon"]]]
        else:
            coords = [[_r6(lon), _r6(lat), z] for (lat, lon), z in zip(o["latlon"], o["z"])]
            coords = coords[0] if o["geometry"] == "Point" else coords
        feats.append(
            {
                "type": "Feature",
                "geometry": {"type": o["geometry"], "coordinates": coords},
                "properties": o["properties"],
            }
        )
    return {
        "type": "FeatureCollection",
        "features": feats,
        "properties": {
            "scenario": plan["scenario"],
            "posc_pct": round(100 * plan["posc"], 2),
            "local_crs": _crs_text(crs) if isinstance(crs, dict) else None,
            "altitude_ref": altitude_ref,
        },
    }


def kml(
    plan: dict,
    crs: Any,
    altitude_m: float | None = None,
    altitude_ref: str = "home",
    field_elevation_m: float = 0.0,
    ground_overlay: dict[str, Any] | None = None,
) -> str:
    """KML with one Placemark (LineString route) per UAV.

    ``altitude_ref`` ``home`` -> ``relativeToGround``, ``amsl`` -> ``absolute``; z as in
    :func:`geojson` and the QGC mission (see docs/EXPORT.md for the caveat on home vs ground).
    ``ground_overlay`` {``href``, ``box`` (south, west, north, east) degrees, ``note``}: the
    prior as a GroundOverlay (an image evenly spaced in latitude and longitude, see
    :func:`poc_env.agents.planning.report.warp_prior`) in its own folder under everything else;
    without one, ``note`` (if any) becomes the document's description.
    """
    alt, ground = _altitudes(plan, altitude_m, altitude_ref, field_elevation_m)
    mode = _ALT_REF[altitude_ref][2]
    fl = _flight(plan)
    overlays = _overlays(plan, crs, alt, ground)
    folders = []
    for u in plan["uavs"]:
        pts = _ll(_route(u), crs)
        zs = [ground, *[alt] * (len(pts) - 2), ground]
        uid = escape(str(u["id"]))
        route = (
            f"<Placemark><name>UAV {uid} route</name><styleUrl>#route</styleUrl>"
            f"<description>POS {100 * u['pos']:.2f} %, track {u['track_length_m'] / 1000:.1f} km"
            f", {u['flight_time_s'] / 60:.0f} min, {alt:g} m ({altitude_ref}); out "
            f"{3.6 * fl['transit_speed_mps']:.0f} km/h, search {3.6 * fl['search_speed_mps']:.0f}"
            f" km/h, home {3.6 * fl['cruise_speed_mps']:.0f} km/h</description>"
            f"<LineString><altitudeMode>{mode}</altitudeMode>"
            f"<coordinates>{_kml_coords(pts, zs)}</coordinates></LineString></Placemark>"
        )
        rect = "".join(
            f"<Placemark><name>UAV {uid} {kind.replace('_', ' ')}</name>"
            f"<styleUrl>#rectangle</styleUrl><description>{escape(_kml_props(props))}"
            "</description><Polygon><outerBoundaryIs><LinearRing><coordinates>"
            f"{_kml_coords(_ll(ring_m, crs))}</coordinates></LinearRing></outerBoundaryIs>"
            "</Polygon></Placemark>"
            for kind, ring_m, props in search_rings(u)
        )
        mine = [o for o in overlays if o["properties"].get("id") == u["id"]]
        extra = "".join(_kml_placemark(o, mode) for o in mine)
        folders.append(f"<Folder><name>UAV {uid}</name>{route}{rect}{extra}</Folder>")
    others = "".join(_kml_placemark(o, mode) for o in overlays if "id" not in o["properties"])
    name = escape(str(plan["scenario"]))
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        f"<name>{name}</name>{_kml_ground_overlay(ground_overlay)}{_KML_STYLES}{''.join(folders)}"
        f"<Folder><name>Area, airfields, no-fly zones</name>{others}</Folder></Document></kml>\n"
    )


#: KML styles (colours aabbggrr): routes orange, approaches white, search rectangles and the
#: operating area outlined, no-fly zones filled red, airfields as the default pin.
_KML_STYLES = (
    '<Style id="route"><LineStyle><color>ff00a5ff</color><width>2</width></LineStyle></Style>'
    '<Style id="landing_approach"><LineStyle><color>ffffffff</color><width>2</width></LineStyle>'
    "</Style>"
    '<Style id="rectangle"><LineStyle><color>ffffff00</color><width>1.5</width></LineStyle>'
    "<PolyStyle><fill>0</fill></PolyStyle></Style>"
    '<Style id="operating_area"><LineStyle><color>ff00ffff</color><width>1.5</width></LineStyle>'
    "<PolyStyle><fill>0</fill></PolyStyle></Style>"
    '<Style id="no_fly_zone"><LineStyle><color>ff0000ff</color><width>1.5</width></LineStyle>'
    "<PolyStyle><color>660000ff</color></PolyStyle></Style>"
    '<Style id="airfield"><IconStyle><scale>1.1</scale></IconStyle></Style>'
)


def _kml_ground_overlay(g: dict[str, Any] | None) -> str:
    """The prior's GroundOverlay folder (or the note why there is none) of :func:`kml`."""
    if g is None:
        return ""
    note = f"<description>{escape(str(g.get('note', '')))}</description>"
    if not g.get("href"):
        return note
    s, w, n, e = (f"{v:.8f}" for v in g["box"])
    return (
        f"{note}<Folder><name>Prior probability of containment</name><GroundOverlay>"
        f"<name>prior POC per cell</name><description>{escape(str(g.get('note', '')))}"
        f"</description><drawOrder>0</drawOrder><Icon><href>{escape(str(g['href']))}</href>"
        f"</Icon><LatLonBox><north>{n}</north><south>{s}</south><east>{e}</east><west>{w}</west>"
        "</LatLonBox></GroundOverlay></Folder>"
    )


def _kml_props(props: dict[str, Any]) -> str:
    """A search area's properties as one line of text (KML descriptions)."""
    return "; ".join(f"{k.replace('_', ' ')}: {v}" for k, v in props.items())


def _kml_coords(latlon, zs=None) -> str:
    if zs is None:
        return " ".join(f"{lon:.8f},{lat:.8f}" for lat, lon in latlon)
    return " ".join(f"{lon:.8f},{lat:.8f},{z:g}" for (lat, lon), z in zip(latlon, zs))


def _kml_placemark(o: dict, mode: str) -> str:
    name = escape(str(o["properties"]["name"]))
    head = f"<Placemark><name>{name}</name><styleUrl>#{o['properties']['kind']}</styleUrl>"
    if o["geometry"] == "Polygon":
        geom = (
            f"<Polygon><outerBoundaryIs><LinearRing><coordinates>{_kml_coords(o['latlon'])}"
            "</coordinates></LinearRing></outerBoundaryIs></Polygon>"
        )
    else:
        tag = o["geometry"]
        geom = (
            f"<{tag}><altitudeMode>{mode}</altitudeMode><coordinates>"
            f"{_kml_coords(o['latlon'], o['z'])}</coordinates></{tag}>"
        )
    return f"{head}{geom}</Placemark>"


def _overlays(plan: dict, crs: Any, alt: float, ground: float) -> list[dict[str, Any]]:
    """What GeoJSON and KML draw beside the routes and rectangles, in one place: per UAV the
    landing approach (as flown by the QGC mission), the airfields, the operating area and the
    no-fly zones (polygons counter-clockwise, closed). Each: ``geometry`` (GeoJSON type),
    ``latlon``, ``z`` (None for polygons, drawn on the ground) and ``properties``."""
    out: list[dict[str, Any]] = []
    for u in plan["uavs"]:
        out.append(
            {
                "geometry": "LineString",
                "latlon": _ll([approach_point(u), u["landing_m"]], crs),
                "z": [_approach_altitude(alt, ground), ground],
                "properties": {
                    "id": u["id"],
                    "kind": "landing_approach",
                    "name": f"UAV {u['id']} landing approach",
                    "approach_km": APPROACH_DISTANCE_M / 1e3,
                    "approach_height_m": APPROACH_HEIGHT_M,
                },
            }
        )
    for a in plan.get("airfields") or []:
        out.append(
            {
                "geometry": "Point",
                "latlon": _ll([a["position_m"]], crs),
                "z": [ground],
                "properties": {"kind": "airfield", "name": a["name"]},
            }
        )
    polys = []
    if plan.get("operating_area_m"):
        polys.append(("operating_area", "operating area (eq. 20)", plan["operating_area_m"]))
    for i, z in enumerate(plan.get("no_fly_zones_m") or []):
        polys.append(("no_fly_zone", f"no-fly zone {i + 1}", z))
    for kind, name, ring in polys:
        ccw = _clockwise(ring)[::-1]
        out.append(
            {
                "geometry": "Polygon",
                "latlon": _ll([*ccw, ccw[0]], crs),
                "z": None,
                "properties": {"kind": kind, "name": name},
            }
        )
    return out


#: Fixed-wing landing pattern: the approach waypoint lies this far from the landing field, on
#: the side the UAV comes from, this high above the field (a 4.3 degree glide slope).
APPROACH_DISTANCE_M = 4000.0
APPROACH_HEIGHT_M = 300.0


def approach_point(u: dict) -> list[float]:
    """The fixed-wing approach waypoint of a UAV plan (metres): :data:`APPROACH_DISTANCE_M` from
    the landing field towards the last search point (east of the field if they coincide)."""
    end = np.asarray(u["landing_m"], dtype=float)
    wps = u["waypoints_m"]
    d = np.asarray(wps[-1] if wps else u["takeoff_m"], dtype=float) - end
    norm = float(np.hypot(*d))
    unit = d / norm if norm > 1.0 else np.array([1.0, 0.0])
    return [float(v) for v in end + APPROACH_DISTANCE_M * unit]


def _approach_altitude(altitude_m: float, ground_m: float) -> float:
    """:data:`APPROACH_HEIGHT_M` above the field (lower if the cruise altitude is lower)."""
    return ground_m + min(APPROACH_HEIGHT_M, altitude_m - ground_m)


def _nav(command: int, lat: float, lon: float, alt: float, ref: str, p4=(0, 0, 0, None)) -> dict:
    frame, mode, _ = _ALT_REF[ref]
    return {
        "AMSLAltAboveTerrain": None, "Altitude": alt, "AltitudeMode": mode, "autoContinue": True,
        "command": command, "doJumpId": 0, "frame": frame, "params": [*p4, lat, lon, alt],
        "type": "SimpleItem",
    }  # fmt: skip


def _do(command: int, params: list) -> dict:
    return {
        "autoContinue": True, "command": command, "doJumpId": 0, "frame": MAV_FRAME_MISSION,
        "params": params, "type": "SimpleItem",
    }  # fmt: skip


def _speed(v: float) -> dict:
    """MAV_CMD_DO_CHANGE_SPEED: airspeed (type 0) v m/s, throttle unchanged (-1), absolute."""
    return _do(MAV_CMD_DO_CHANGE_SPEED, [0, round(float(v), 3), -1, 0, 0, 0, 0])


def _clockwise(ring_xy: list) -> list:
    """The ring in clockwise order (QGC geofence polygons; x east, y north)."""
    a = np.asarray(ring_xy, dtype=float)
    area2 = float(np.sum(a[:, 0] * np.roll(a[:, 1], -1) - np.roll(a[:, 0], -1) * a[:, 1]))
    return list(ring_xy[::-1]) if area2 > 0 else list(ring_xy)


def qgc_plan(
    u: dict,
    crs: Any,
    altitude_m: float = 1000.0,
    cruise_speed_mps: float = DEFAULT_FLIGHT["cruise_speed_mps"],
    *,
    search_speed_mps: float = DEFAULT_FLIGHT["search_speed_mps"],
    transit_speed_mps: float | None = None,
    altitude_ref: str = "home",
    ground_m: float = 0.0,
    home_amsl_m: float = 0.0,
    operating_area_m: list | None = None,
    no_fly_zones_m: list | None = None,
) -> dict:
    """A QGroundControl ``.plan`` for a fixed-wing UAV (PX4, ``vehicleType`` 1).

    Items: NAV_TAKEOFF at the field; DO_CHANGE_SPEED to the transit speed (default v_b); the
    transit waypoint ``waypoints_m[0]``; DO_CHANGE_SPEED v_s; the search waypoints;
    DO_CHANGE_SPEED v_b;
    DO_LAND_START; an approach waypoint (:data:`APPROACH_DISTANCE_M` out,
    :data:`APPROACH_HEIGHT_M` up); NAV_LAND at the field. Geofence: the operating area as the
    inclusion polygon (empty without one) and the no-fly zones as exclusion polygons, clockwise;
    rally points at the take-off and landing fields. ``altitude_ref`` ``home`` writes
    MAV_FRAME_GLOBAL_RELATIVE_ALT (3), ``amsl`` MAV_FRAME_GLOBAL (0) with ``ground_m`` the
    field elevation; ``home_amsl_m`` is the planned home position's AMSL altitude.
    """
    ref = altitude_ref
    if ref not in _ALT_REF:
        raise ConfigError("altitude_ref", ref, "home or amsl")
    wps = [list(w) for w in u["waypoints_m"]]
    start, end = list(u["takeoff_m"]), list(u["landing_m"])
    approach = approach_point(u)
    ll = _ll([start, *wps, approach, end], crs)
    t_ll, w_ll, a_ll, l_ll = ll[0], ll[1:-2], ll[-2], ll[-1]
    app_alt = _approach_altitude(altitude_m, ground_m)
    items = [_nav(MAV_CMD_NAV_TAKEOFF, *t_ll, altitude_m, ref, (15, 0, 0, None))]
    if w_ll:
        items.append(_speed(cruise_speed_mps if transit_speed_mps is None else transit_speed_mps))
        items.append(_nav(MAV_CMD_NAV_WAYPOINT, *w_ll[0], altitude_m, ref))
        items.append(_speed(search_speed_mps))
        items += [_nav(MAV_CMD_NAV_WAYPOINT, lat, lon, altitude_m, ref) for lat, lon in w_ll[1:]]
    items.append(_speed(cruise_speed_mps))
    items.append(_do(MAV_CMD_DO_LAND_START, [0, 0, 0, 0, 0, 0, 0]))
    items.append(_nav(MAV_CMD_NAV_WAYPOINT, *a_ll, app_alt, ref))
    items.append(_nav(MAV_CMD_NAV_LAND, *l_ll, ground_m, ref))
    for k, it in enumerate(items):
        it["doJumpId"] = k + 1
    polygons = []
    if operating_area_m:
        ring = _ll(_clockwise(operating_area_m), crs)
        polygons.append(
            {"inclusion": True, "polygon": [[lat, lon] for lat, lon in ring], "version": 1}
        )
    for z in no_fly_zones_m or []:
        ring = _ll(_clockwise(z), crs)
        polygons.append(
            {"inclusion": False, "polygon": [[lat, lon] for lat, lon in ring], "version": 1}
        )
    fields = [start] if start == end else [start, end]
    rally = [[lat, lon, APPROACH_HEIGHT_M] for lat, lon in _ll(fields, crs)]
    return {
        "fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
        "mission": {
            "version": 2, "firmwareType": 12, "vehicleType": 1,
            "globalPlanAltitudeMode": _ALT_REF[ref][1],
            "cruiseSpeed": cruise_speed_mps, "hoverSpeed": 5,
            "plannedHomePosition": [t_ll[0], t_ll[1], home_amsl_m], "items": items,
        },
        "geoFence": {"circles": [], "polygons": polygons, "version": 2},
        "rallyPoints": {"points": rally, "version": 2},
    }  # fmt: skip


def _check_fences(plan: dict, area: list | None) -> None:
    """ConfigError if a UAV's mission (route and landing approach) leaves the inclusion fence
    ``area`` (by more than 1 m) or flies through a no-fly zone (more than 1 m of a leg)."""
    from shapely.geometry import LineString, Point, Polygon

    inc = Polygon(area).buffer(1.0) if area else None
    zones = [Polygon(z) for z in plan.get("no_fly_zones_m") or []]
    for k, u in enumerate(plan["uavs"]):
        pts = [*_route(u)[:-1], approach_point(u), list(u["landing_m"])]
        names = [
            "takeoff_m", *(f"waypoints_m[{i}]" for i in range(len(pts) - 3)), "approach",
            "landing_m",
        ]  # fmt: skip
        if inc is not None:
            for name, pt in zip(names, pts):
                if not inc.covers(Point(pt)):
                    out = inc.exterior.distance(Point(pt)) / 1e3
                    raise ConfigError(
                        f"plan.uavs[{k}].{name}", pt,
                        f"inside the operating area, the mission's inclusion geofence ({out:.1f}"
                        " km outside): re-plan, or export without it (geofence=False)",
                    )  # fmt: skip
        line = LineString(pts)
        for i, z in enumerate(zones):
            if z.is_valid and line.intersection(z).length > 1.0:
                raise ConfigError(
                    f"plan.uavs[{k}]", u["id"],
                    f"a mission outside no-fly zone {i + 1} (an exclusion geofence): re-plan",
                )  # fmt: skip


def export_plan(
    plan_path: str | os.PathLike[str],
    fmt: str,
    origin: str | tuple[float, float] | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    *,
    projection: str = "aeqd",
    zone: int | None = None,
    altitude_m: float | None = None,
    altitude_ref: str = "home",
    field_elevation_m: float = 0.0,
    geofence: bool = True,
    prior: Any = None,
) -> list[Path]:
    """Write ``fmt`` files next to the plan (or into ``out_dir``); return their paths.

    The CRS is the plan's ``crs`` (``origin``, if given, must agree) or, for a plan without one,
    ``projection`` (``aeqd`` or ``utm``, UTM zone ``zone`` or the origin's) at ``origin``.
    ``altitude_m`` (default the plan's ``flight.altitude_m``, above the field) in the reference
    ``altitude_ref`` (``home`` or ``amsl``; ``field_elevation_m`` is the fields' AMSL height).
    QGC missions that would breach their own geofence (a point outside the operating area, a
    leg through a no-fly zone) are refused; ``geofence=False`` leaves the inclusion fence out.
    ``html`` writes the map report (:mod:`poc_env.agents.planning.report`); its prior overlay is
    ``prior`` (an array of the scenario grid's shape or a map file) or, by default, the plan's
    scenario prior rebuilt by :func:`poc_env.agents.planning.report.plan_prior`.
    """
    if fmt not in FORMATS:
        raise ConfigError("format", fmt, "one of " + ", ".join(FORMATS))
    if origin is not None:
        _origin(origin)
    if projection not in ("aeqd", "utm"):
        raise ConfigError("projection", projection, "aeqd or utm")
    if altitude_ref not in _ALT_REF:
        raise ConfigError("altitude_ref", altitude_ref, "home or amsl")
    plan = load_plan(plan_path)
    crs = _plan_crs(plan, origin, projection, zone)
    alt, ground = _altitudes(plan, altitude_m, altitude_ref, field_elevation_m)
    elevation = _number("field_elevation_m", field_elevation_m, -500.0, 9000.0)
    out = Path(out_dir) if out_dir else Path(plan_path).parent
    stem = Path(plan_path).stem
    if fmt == "geojson":
        doc = geojson(plan, crs, alt, altitude_ref, ground)
        return [
            write_text_atomic(out / f"{stem}.geojson", json.dumps(doc, indent=1, allow_nan=False))
        ]
    if fmt == "kml":
        from poc_env.agents.planning.report import plan_prior, png_bytes, warp_prior

        overlay, note = plan_prior(plan, plan_path, prior)
        written = []
        g: dict[str, Any] = {"note": note}
        if overlay is not None:  # the image first: the KML names it
            rgba, box = warp_prior(overlay, crs, "latitude")
            png = write_bytes_atomic(out / f"{stem}_prior.png", png_bytes(rgba))
            g.update(href=png.name, box=box)
            written.append(png)
        text = kml(plan, crs, alt, altitude_ref, ground, ground_overlay=g)
        return [write_text_atomic(out / f"{stem}.kml", text), *written]
    if fmt == "html":
        from poc_env.agents.planning.report import html_report, plan_prior

        overlay, note = plan_prior(plan, plan_path, prior)
        page = html_report(plan, crs, overlay, note, alt, altitude_ref, ground)
        return [write_text_atomic(out / f"{stem}.html", page)]
    fl = _flight(plan)
    area = plan.get("operating_area_m") if geofence else None
    _check_fences(plan, area)
    docs = [
        (
            u["id"],
            qgc_plan(
                u, crs, alt, fl["cruise_speed_mps"], search_speed_mps=fl["search_speed_mps"],
                transit_speed_mps=fl["transit_speed_mps"], altitude_ref=altitude_ref,
                ground_m=ground, home_amsl_m=elevation,
                operating_area_m=area,
                no_fly_zones_m=plan.get("no_fly_zones_m"),
            ),
        )
        for u in plan["uavs"]
    ]  # fmt: skip
    return [
        write_text_atomic(out / f"{stem}_uav{uid}.plan", json.dumps(doc, indent=1, allow_nan=False))
        for uid, doc in docs
    ]
