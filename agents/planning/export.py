"""Mission export: a plan (``plan.json``, schema 1) as GeoJSON, KML or QGroundControl missions.

Local metres are placed at a geographic origin (the map's (0, 0)) by a local tangent-plane
projection on the WGS84 ellipsoid: ``lat = lat0 + y / M(lat0)``, ``lon = lon0 + x / (N(lat0)
cos lat0)`` with the meridional and prime-vertical radii of curvature M and N at the origin.
Within 200 km of the origin its distances are within about 0.1 % of the geodesic ones -- the
scale of the paper's 150 x 200 km areas -- and it inverts exactly, so exported files parse back
to the same waypoints. For continental areas use a proper projection (e.g. pyproj's azimuthal
equidistant) before exporting.

``plan.json`` (schema 1) holds: ``schema``, ``scenario``, ``seed``, ``map_source``,
``optimizer`` {``name``, ``settings``}, ``runtime_s``, ``posc``, ``upper_bound`` and
``uavs``: a list of {``id``, ``rectangle`` {``center_m`` [x, y], ``length_m``, ``width_m``,
``theta_deg``}, ``spacing_m``, ``takeoff_m``, ``landing_m``, ``waypoints_m`` [[x, y], ...],
``track_length_m``, ``flight_time_s``, ``pod``, ``poc``, ``pos``, ``feasible``}.

:func:`load_plan` checks every field an export reads before anything is written: finite numbers
in documented ranges (points within :data:`MAX_EXTENT_M` of the origin, probabilities in
[0, 1]), the right shapes, and UAV ids of 1-64 ``A-Z a-z 0-9 _ -`` (they become file names), so
no NaN, no out-of-range latitude and no path outside ``--out`` can reach a mission file.
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape

from poc_env.errors import ConfigError
from poc_env.io import write_text_atomic

SCHEMA = 1
FORMATS = ("geojson", "kml", "qgc")
_A = 6378137.0  # WGS84 semi-major axis, m
_F = 1 / 298.257223563
_E2 = _F * (2 - _F)

PLAN_KEYS = {
    "schema", "scenario", "seed", "map_source", "optimizer", "runtime_s", "posc",
    "upper_bound", "uavs",
}  # fmt: skip
UAV_KEYS = {
    "id", "rectangle", "spacing_m", "takeoff_m", "landing_m", "waypoints_m", "track_length_m",
    "flight_time_s", "pod", "poc", "pos", "feasible",
}  # fmt: skip


def parse_origin(text: str) -> tuple[float, float]:
    """``"LAT,LON"`` in degrees -> (lat, lon); ConfigError outside [-90, 90] x [-180, 180]."""
    try:
        lat, lon = (float(v) for v in str(text).split(","))
    except ValueError:
        raise ConfigError("origin", text, "LAT,LON in degrees, e.g. 45.5,126.6") from None
    if not (-90 <= lat <= 90 and -180 <= lon <= 180) or abs(lat) > 89.9:
        raise ConfigError("origin", text, "latitude in [-89.9, 89.9], longitude in [-180, 180]")
    return lat, lon


def _radii(lat0: float) -> tuple[float, float]:
    s = math.sin(math.radians(lat0))
    w = math.sqrt(1 - _E2 * s * s)
    return _A * (1 - _E2) / w**3, _A / w  # M, N


def to_geographic(xy, origin: tuple[float, float]) -> list[tuple[float, float]]:
    """Local metres [[x, y], ...] -> [(lat, lon), ...] degrees (see the module docstring)."""
    lat0, lon0 = origin
    m, n = _radii(lat0)
    c = math.cos(math.radians(lat0))
    out = []
    for x, y in xy:
        lat = lat0 + math.degrees(y / m)
        lon = lon0 + math.degrees(x / (n * c))
        if not -180.0 <= lon <= 180.0:  # across the antimeridian
            lon = (lon + 180.0) % 360.0 - 180.0
        if not (math.isfinite(lat) and math.isfinite(lon) and -90.0 <= lat <= 90.0):
            raise ConfigError(
                "waypoints", [x, y], f"points whose latitude from origin {origin} is within +-90"
            )
        out.append((lat, lon))
    return out


def to_local(latlon, origin: tuple[float, float]) -> list[tuple[float, float]]:
    """The exact inverse of :func:`to_geographic`."""
    lat0, lon0 = origin
    m, n = _radii(lat0)
    c = math.cos(math.radians(lat0))
    return [(math.radians(lon - lon0) * n * c, math.radians(lat - lat0) * m) for lat, lon in latlon]


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
    if plan.get("schema") != SCHEMA:
        raise ConfigError("plan.schema", plan.get("schema"), f"{SCHEMA}")
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
        r = u["rectangle"]
        if not isinstance(r, dict) or sorted(r) != ["center_m", "length_m", "theta_deg", "width_m"]:
            raise ConfigError(
                f"{where}.rectangle", r, "a mapping of center_m, length_m, width_m, theta_deg"
            )
        _point(f"{where}.rectangle.center_m", r["center_m"])
        for key in ("length_m", "width_m"):
            _number(f"{where}.rectangle.{key}", r[key], 0.0, MAX_EXTENT_M)
        _number(f"{where}.rectangle.theta_deg", r["theta_deg"], -360.0, 360.0)
        for key in ("spacing_m", "track_length_m"):
            _number(f"{where}.{key}", u[key], 0.0, 100 * MAX_EXTENT_M)
        _number(f"{where}.flight_time_s", u["flight_time_s"], 0.0, 1e7)
        for key in ("pod", "poc", "pos"):
            _number(f"{where}.{key}", u[key], 0.0, 1.0)
        if not isinstance(u["feasible"], bool):
            raise ConfigError(f"{where}.feasible", u["feasible"], "true or false")
    return plan


#: Largest |x| or |y| of a plan point, metres: 2,000 km from the map origin, far beyond a
#: regional search (the projection is accurate to about 0.1 % within 200 km).
MAX_EXTENT_M = 2.0e6
_SAFE_ID = re.compile(r"[A-Za-z0-9_-]{1,64}")


def _number(field: str, value: Any, lo: float, hi: float) -> float:
    """``value`` as a float if it is a finite JSON number in [lo, hi], else ConfigError."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(field, value, f"a number in [{lo:g}, {hi:g}]")
    x = float(value)
    if not (math.isfinite(x) and lo <= x <= hi):
        raise ConfigError(field, value, f"a finite number in [{lo:g}, {hi:g}]")
    return x


def _point(field: str, value: Any) -> None:
    """An [x, y] point in metres within :data:`MAX_EXTENT_M` of the origin."""
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ConfigError(field, value, "[x, y] in metres")
    for v in value:
        _number(field, v, -MAX_EXTENT_M, MAX_EXTENT_M)


def _route(u: dict) -> list[list[float]]:
    return [list(u["takeoff_m"]), *u["waypoints_m"], list(u["landing_m"])]


def geojson(plan: dict, origin: tuple[float, float]) -> dict:
    """A FeatureCollection: per UAV the route (LineString) and its search rectangle (Polygon)."""
    feats = []
    for u in plan["uavs"]:
        route = [[lon, lat] for lat, lon in to_geographic(_route(u), origin)]
        props = {k: u[k] for k in ("id", "spacing_m", "track_length_m", "pod", "poc", "pos")}
        feats.append(
            {
                "type": "Feature",
                "geometry": {"type": "LineString", "coordinates": route},
                "properties": {**props, "kind": "route"},
            }
        )
        r = u["rectangle"]
        from poc_env.geometry import rectangle_corners

        corners = rectangle_corners(
            r["center_m"], r["length_m"], r["width_m"], math.radians(r["theta_deg"])
        ).tolist()
        ring = [[lon, lat] for lat, lon in to_geographic([*corners, corners[0]], origin)]
        feats.append(
            {
                "type": "Feature",
                "geometry": {"type": "Polygon", "coordinates": [ring]},
                "properties": {"id": u["id"], "kind": "search_rectangle"},
            }
        )
    return {
        "type": "FeatureCollection",
        "features": feats,
        "properties": {"scenario": plan["scenario"], "posc": plan["posc"]},
    }


def kml(plan: dict, origin: tuple[float, float], altitude_m: float = 1000.0) -> str:
    """KML with one Placemark (LineString route) per UAV."""
    marks = []
    for u in plan["uavs"]:
        coords = " ".join(
            f"{lon:.8f},{lat:.8f},{altitude_m:g}" for lat, lon in to_geographic(_route(u), origin)
        )
        marks.append(
            f"<Placemark><name>UAV {escape(str(u['id']))}</name>"
            f"<description>POS {u['pos']:.4f}, track {u['track_length_m'] / 1000:.1f} km"
            f"</description><LineString><altitudeMode>relativeToGround</altitudeMode>"
            f"<coordinates>{coords}</coordinates></LineString></Placemark>"
        )
    name = escape(str(plan["scenario"]))
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        f"<name>{name}</name>{''.join(marks)}</Document></kml>\n"
    )


def _item(seq: int, command: int, lat: float, lon: float, alt: float, params4=(0, 0, 0, None)):
    return {
        "type": "SimpleItem", "autoContinue": True, "command": command, "doJumpId": seq,
        "frame": 3, "params": [*params4, lat, lon, alt], "Altitude": alt, "AltitudeMode": 1,
        "AMSLAltAboveTerrain": None,
    }  # fmt: skip


def qgc_plan(
    u: dict, origin: tuple[float, float], altitude_m: float = 1000.0, cruise_speed_mps: float = 61.1
) -> dict:
    """A QGroundControl ``.plan`` (fixed wing): take-off, the waypoints, land."""
    pts = to_geographic(_route(u), origin)
    items = [_item(1, 22, *pts[0], altitude_m, (15, 0, 0, None))]  # MAV_CMD_NAV_TAKEOFF
    items += [_item(k + 2, 16, lat, lon, altitude_m) for k, (lat, lon) in enumerate(pts[1:-1])]
    items.append(_item(len(pts), 21, *pts[-1], 0.0))  # MAV_CMD_NAV_LAND
    return {
        "fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
        "mission": {
            "version": 2, "firmwareType": 12, "vehicleType": 1,
            "cruiseSpeed": cruise_speed_mps, "hoverSpeed": 5,
            "plannedHomePosition": [pts[0][0], pts[0][1], 0], "items": items,
        },
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "rallyPoints": {"points": [], "version": 2},
    }  # fmt: skip


def export_plan(
    plan_path: str | os.PathLike[str],
    fmt: str,
    origin: str | tuple[float, float],
    out_dir: str | os.PathLike[str] | None = None,
) -> list[Path]:
    """Write ``fmt`` files next to the plan (or into ``out_dir``); return their paths."""
    if fmt not in FORMATS:
        raise ConfigError("format", fmt, "one of " + ", ".join(FORMATS))
    org = (
        parse_origin(origin)
        if isinstance(origin, str)
        else parse_origin(f"{origin[0]},{origin[1]}")
    )
    plan = load_plan(plan_path)
    out = Path(out_dir) if out_dir else Path(plan_path).parent
    stem = Path(plan_path).stem
    if fmt == "geojson":
        return [
            write_text_atomic(
                out / f"{stem}.geojson", json.dumps(geojson(plan, org), indent=1, allow_nan=False)
            )
        ]
    if fmt == "kml":
        return [write_text_atomic(out / f"{stem}.kml", kml(plan, org))]
    return [
        write_text_atomic(
            out / f"{stem}_uav{u['id']}.plan",
            json.dumps(qgc_plan(u, org), indent=1, allow_nan=False),
        )
        for u in plan["uavs"]
    ]
