"""Plane geometry shared by regions, patterns, constraints and the planner.

One rotation (eq. 5 and its inverse eq. 6), one polygon validator, one rectangle builder.
Coordinates are metres, angles radians unless a name says ``_deg``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from shapely.geometry import Point, Polygon
from shapely.validation import explain_validity

from poc_env.errors import GeometryError

ArrayLike = np.ndarray | Sequence[Sequence[float]]


def rotate_ccw(points: ArrayLike, theta: float) -> np.ndarray:
    """Rotate ``points`` (..., 2) counter-clockwise by ``theta`` about the origin (eq. 5).

    ``p_hat = [[cos, -sin], [sin, cos]] p``.
    """
    p = np.asarray(points, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * p[..., 0] - s * p[..., 1], s * p[..., 0] + c * p[..., 1]], axis=-1)


def rotate_cw(points: ArrayLike, theta: float) -> np.ndarray:
    """Rotate ``points`` clockwise by ``theta`` (eq. 6), the inverse of :func:`rotate_ccw`.

    ``q = [[cos, sin], [-sin, cos]] q_hat``.
    """
    return rotate_ccw(points, -theta)


#: What :func:`validate_polygon` accepts, as its errors say it.
POLYGON_ALLOWED = (
    "at least 3 finite [x, y] vertices forming a simple ring (no self-intersection) with "
    "positive area; each hole likewise, inside it"
)


def _ring(vertices: ArrayLike, name: str) -> np.ndarray:
    try:
        pts = np.asarray(vertices, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise GeometryError(
            f"{name}: vertices that are not [x, y] number pairs; allowed: {POLYGON_ALLOWED}"
        ) from None
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 3:
        raise GeometryError(
            f"{name}: {len(pts) if pts.ndim else 0} vertices of shape {pts.shape}; "
            f"allowed: {POLYGON_ALLOWED}"
        )
    if not np.all(np.isfinite(pts)):
        raise GeometryError(
            f"{name}: vertices that are NaN or infinite; allowed: {POLYGON_ALLOWED}"
        )
    return pts


def validate_polygon(
    vertices: ArrayLike, name: str = "polygon", holes: Sequence[ArrayLike] = ()
) -> Polygon:
    """Return a valid shapely polygon or raise :class:`GeometryError` naming ``name``.

    Rejects fewer than three vertices (in the outer ring or a hole), non-finite coordinates,
    self-intersection (a "bow-tie", reported as such) and zero area.
    """
    pts = _ring(vertices, name)
    hole_arrays = [_ring(h, f"{name} hole {k}") for k, h in enumerate(holes)]
    poly = Polygon(pts, hole_arrays)
    if Polygon(pts).convex_hull.area <= 0:
        raise GeometryError(
            f"{name}: zero area (the vertices lie on a line); allowed: {POLYGON_ALLOWED}"
        )
    if not poly.is_valid:
        raise GeometryError(
            f"{name}: invalid polygon ({explain_validity(poly)}); allowed: {POLYGON_ALLOWED}"
        )
    if poly.area <= 0:
        raise GeometryError(f"{name}: zero area; allowed: {POLYGON_ALLOWED}")
    return poly


def as_polygon(region: Polygon | ArrayLike, name: str = "polygon") -> Polygon:
    """A shapely polygon from a polygon or a vertex array, validated."""
    if isinstance(region, Polygon):
        if region.is_empty or region.area <= 0:
            raise GeometryError(f"{name}: degenerate polygon (zero area)")
        if not region.is_valid:
            raise GeometryError(f"{name}: invalid polygon ({explain_validity(region)})")
        return region
    return validate_polygon(region, name)


def point_in_polygon(point: Sequence[float], vertices: ArrayLike) -> bool:
    """True when ``point`` lies inside or on the polygon ``vertices``."""
    poly = Polygon(np.asarray(vertices, dtype=float))
    return bool(poly.covers(Point(float(point[0]), float(point[1]))))


def rectangle_corners(
    center: Sequence[float], length: float, width: float, theta: float
) -> np.ndarray:
    """Corners (4, 2) of the rectangle Q(x_c, y_c, l, w, theta) of §3.1.6.

    ``length`` runs along direction ``theta`` (radians from the x axis), ``width`` across it.
    """
    hl, hw = 0.5 * length, 0.5 * width
    local = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])
    return rotate_ccw(local, theta) + np.asarray(center, dtype=float)


def rectangle_polygon(center: Sequence[float], length: float, width: float, theta: float):
    """The rectangle Q as a shapely polygon."""
    return Polygon(rectangle_corners(center, length, width, theta))


def polyline_length(waypoints: ArrayLike) -> float:
    """Length of the polyline through ``waypoints`` (k, 2)."""
    w = np.asarray(waypoints, dtype=float)
    if len(w) < 2:
        return 0.0
    return float(np.sum(np.hypot(*np.diff(w, axis=0).T)))


def covers_points(geom, points: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """Boolean mask: which of ``points`` (k, 2) lie in ``geom`` buffered by ``tol`` metres."""
    g = geom.buffer(tol) if tol > 0 else geom
    return shapely.covers(g, shapely.points(np.asarray(points, dtype=float)))


def zone_label(i: int, names: Sequence[str] = ()) -> str:
    """How every message names no-fly zone ``i``: counted from 0 (as ``no_fly_zones_km[i]``
    and import errors count), with its name when it has one: ``no-fly zone 0 ('range R-12')``."""
    name = names[i] if 0 <= i < len(names) and names[i] else ""
    return f"no-fly zone {i}" + (f" ({name!r})" if name else "")


def check_zones_leave_room(
    zones: Sequence[Sequence[Sequence[float]]], names: Sequence[str], region: Polygon, what: str
) -> None:
    """Refuse no-fly ``zones`` (point lists, the map's metres) that together cover ``region``
    (the search area: the map's rectangle, or an imported area polygon): nothing would be
    left to fly over it. One zone or several side by side alike.

    Raises
    ------
    ConfigError
        Naming ``no_fly_zones_km[i, j, ...]`` (the zones that meet ``region``), their labels
        (:func:`zone_label`) and ``what`` the region is.
    """
    from poc_env.errors import ConfigError

    polys = [Polygon(z) for z in zones]
    valid = [p for p in polys if p.is_valid]
    if not valid or not shapely.union_all(valid).covers(region):
        return
    one = [i for i, p in enumerate(polys) if p.is_valid and p.covers(region)]
    if one:  # a zone alone: named alone
        idx, allowed = one[:1], f"a zone that leaves part of {what} flyable (it covers all of it)"
    else:
        idx = [i for i, p in enumerate(polys) if p.is_valid and p.intersection(region).area > 0]
        allowed = f"zones that leave part of {what} flyable (together they cover all of it)"
    raise ConfigError(
        f"no_fly_zones_km[{', '.join(str(i) for i in idx)}]",
        ", ".join(zone_label(i, names) for i in idx),
        allowed,
    )


def zone_crossed(pts: ArrayLike, zones: list) -> int | None:
    """The index of the first of the shapely polygons ``zones`` that the polyline ``pts`` flies
    through (more than 1 m of it inside), else None: the QGC export's geofence rule
    (:func:`poc_env.agents.mission.formats.qgc.check_fences`), also the planners' orbit fit's."""
    line = shapely.LineString(pts)
    for i, z in enumerate(zones):
        if z.is_valid and line.intersection(z).length > 1.0:
            return i
    return None
