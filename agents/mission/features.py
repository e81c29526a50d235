"""What every map format draws, computed once: altitudes, landing approaches, fences, fields.

GeoJSON, KML, the QGroundControl missions and the HTML map report read these so that they
show the same numbers: the cruise altitude and ground level in the chosen altitude reference
(:func:`altitudes`), each UAV's fixed-wing landing approach (:func:`approach_point`), and the
airfields, operating area and no-fly zones (:func:`overlays`).
"""

from __future__ import annotations

import itertools
from typing import Any, cast

import numpy as np

from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.plan import (
    APPROACH_APART_M,
    APPROACH_DISTANCE_M,
    APPROACH_HEIGHT_M,
    APPROACH_KIND,
    CLIMB_KIND,
    DESCENT_KIND,
    Plan,
    approach_point,
    approach_sides,
    flight,
    route,
)
from poc_env.agents.mission.terrain import departure_heading_deg, from_record, plan_profiles
from poc_env.crs import densify_ring
from poc_env.errors import ConfigError, as_number
from poc_env.geometry import zone_label

#: Altitude references: ``home`` (above the take-off field) or ``amsl`` (above mean sea level).
ALTITUDE_REFS = ("home", "amsl")


def check_altitude_ref(altitude_ref: str) -> str:
    """``altitude_ref`` if it is one of :data:`ALTITUDE_REFS`, else ConfigError."""
    if altitude_ref not in ALTITUDE_REFS:
        raise ConfigError("altitude_ref", altitude_ref, "home or amsl")
    return altitude_ref


def altitudes(
    plan: Plan, altitude_m: float | None, altitude_ref: str, field_elevation_m: float
) -> tuple[float, float]:
    """(cruise altitude, ground level) in the reference ``altitude_ref``, checked.

    Parameters
    ----------
    plan : Plan
        Its ``flight.altitude_m`` (above the field) is the default altitude and its
        ``flight.max_altitude_m`` the ceiling.
    altitude_m : float or None
        The altitude in the reference ``altitude_ref``; None: the plan's.
    altitude_ref : {"home", "amsl"}
    field_elevation_m : float
        The fields' height above mean sea level (``amsl`` only).

    Raises
    ------
    ConfigError
        An altitude at or below the ground or above the UAV's ceiling.
    """
    check_altitude_ref(altitude_ref)
    fl = flight(plan)
    ground = 0.0
    if altitude_ref == "amsl":
        ground = as_number("field_elevation_m", field_elevation_m, -500.0, 9000.0)
    alt = fl["altitude_m"] + ground if altitude_m is None else altitude_m
    as_number("altitude_m", alt, -1e9, 1e9)
    top = fl["max_altitude_m"]
    if not alt > ground:
        above = "home (> 0)" if altitude_ref == "home" else f"the field elevation {ground:g} m"
        raise ConfigError("altitude_m", alt, f"above {above} and at most the ceiling {top:g} m")
    if alt - ground > top:
        raise ConfigError("altitude_m", alt, f"at most the UAV ceiling {top:g} m above the field")
    return float(alt), ground


#: How an export orders the UAVs into altitude layers (:func:`with_layers`): ``field``, by
#: index among the UAVs of one take-off field (field-mates share the take-off and homeward
#: legs); ``fleet``, by index among all the UAVs exported.
LAYER_ORDERS = ("field", "fleet")
#: The largest ``separation_m`` an export takes (metres; more is a typo, not a layer).
MAX_SEPARATION_M = 1000.0


#: The smallest non-zero ``separation_m`` (metres): less is no separation (the exports write
#: altitudes to 0.1 m, and 1e-9 wrote every ``layer_m`` as 0.0; i24-smallfix).
MIN_SEPARATION_M = 1.0


def check_separation(separation_m: Any, layer_by: Any) -> float:
    """``separation_m`` (metres: 0, off, or :data:`MIN_SEPARATION_M` to
    :data:`MAX_SEPARATION_M`) as a float if it and ``layer_by`` (one of :data:`LAYER_ORDERS`)
    are valid, else ConfigError naming the field."""
    if layer_by not in LAYER_ORDERS:
        raise ConfigError("layer_by", layer_by, "one of " + ", ".join(LAYER_ORDERS))
    s = as_number("separation_m", separation_m, 0.0, MAX_SEPARATION_M)
    if 0 < s < MIN_SEPARATION_M:
        raise ConfigError(
            "separation_m", separation_m,
            f"0 (no layers) or {MIN_SEPARATION_M:g} to {MAX_SEPARATION_M:g} m: less is no "
            "separation between the layers",
        )  # fmt: skip
    return s


def with_layers(plan: Plan, separation_m: float, layer_by: str = "field") -> Plan:
    """The plan with each UAV of a search route given its altitude layer (``layer_m``).

    UAV k is flown ``k' x separation_m`` above the plan's altitude (a flat map) or its terrain
    profile's wanted height (:func:`~poc_env.agents.mission.terrain.profile`, which keeps the
    clearance and the ceiling), ``k'`` its index among the UAVs with a route of its take-off
    field (``layer_by="field"``) or of the whole plan (``"fleet"``). The take-off climb,
    transit, search and homeward legs fly the layer; the landing approach point keeps the
    plan's approach height (the glide to the field is the landing's, one per field), so
    field-mates landing at one field are kept on approaches
    :data:`~poc_env.agents.mission.plan.APPROACH_APART_M` apart instead (``approach_m``,
    :func:`_approaches_apart`). The plan
    records ``altitude_layers`` (``separation_m``, ``layer_by``) for the formats' metadata.
    ``separation_m = 0`` returns ``plan`` itself: every export as without layers. ``layer_m``,
    ``approach_m`` and ``altitude_layers`` are an export's own: a plan.json carrying them
    (written by hand, or a plan exported in memory) has them dropped first, so only
    ``separation_m`` decides.
    """
    own = ("layer_m", "approach_m")
    if "altitude_layers" in plan or any(k in u for u in plan["uavs"] for k in own):
        kept = {k: v for k, v in plan.items() if k != "altitude_layers"}
        plan = cast(Plan, {**kept, "uavs": [{k: v for k, v in u.items() if k not in own}
                                            for u in plan["uavs"]]})  # fmt: skip
    if separation_m == 0:
        return plan
    count: dict[Any, int] = {}
    uavs = []
    for u in plan["uavs"]:
        if not u["waypoints_m"]:  # not exported (export.searching_uavs): no layer used
            uavs.append(u)
            continue
        key = tuple(u["takeoff_m"]) if layer_by == "field" else None
        count[key] = count.get(key, -1) + 1
        uavs.append({**u, "layer_m": count[key] * float(separation_m)})
    layers = {"separation_m": float(separation_m), "layer_by": layer_by}
    return {**plan, "uavs": _approaches_apart(uavs, plan.get("no_fly_zones_m")),
            "altitude_layers": layers}  # fmt: skip


def _apart(p: np.ndarray, others: list[np.ndarray]) -> bool:
    """Whether ``p`` is at least :data:`~poc_env.agents.mission.plan.APPROACH_APART_M` from
    every point of ``others``."""
    return all(float(np.hypot(*(p - q))) >= APPROACH_APART_M - 1e-6 for q in others)


def _approaches_apart(uavs: list[Any], zones: Any) -> list[Any]:
    """Field-mates landing at one field with approach points closer than
    :data:`~poc_env.agents.mission.plan.APPROACH_APART_M` (leftover g of i24-missionfix: on
    the day audit's swall2 and s150land two UAVs glided down one path, 0.11 km apart at one
    altitude, whatever their layers): each UAV in turn keeps its approach side if it is that
    far from every earlier mate's, else takes the nearest side round the field
    (:func:`~poc_env.agents.mission.plan.approach_sides`, clear of the ``zones``) that is,
    recorded as its ``approach_m``. None that is: its own side, as before."""
    taken: dict[tuple, list[np.ndarray]] = {}
    out = []
    for u in uavs:
        if not u["waypoints_m"]:
            out.append(u)
            continue
        mates = taken.setdefault(tuple(u["landing_m"]), [])
        first = np.asarray(approach_point(u, zones))
        sides = (np.asarray(p) for p in approach_sides(u, zones or ()))  # only if needed
        pick = next((p for p in itertools.chain([first], sides) if _apart(p, mates)), first)
        if pick is not first:
            u = {**u, "approach_m": [float(v) for v in pick]}
        mates.append(pick)
        out.append(u)
    return out


def layer_of(u: Any) -> float:
    """A UAV's altitude layer above the plan's altitude (metres; 0 without layers)."""
    return float(u.get("layer_m", 0.0))


def layer_text(u: Any) -> str:
    """``, layer +L m`` for a UAV given a layer by :func:`with_layers` (even ``+0``: the lowest
    of its field), else empty: the words KML and the map report add to its altitude."""
    return f", layer +{layer_of(u):g} m" if "layer_m" in u else ""


def layers_note(plan: Plan) -> str:
    """One sentence on the export's altitude layers (:func:`with_layers`), or empty."""
    a = plan.get("altitude_layers")
    if not a:
        return ""
    per = "take-off field" if a["layer_by"] == "field" else "fleet"
    return (
        f"Altitude layers: {a['separation_m']:g} m apart, counted per {per} (the landing "
        "approach at the plan's height; no time separation)."
    )


def check_layers(plan: Plan, altitude_m: float, ground_m: float) -> None:
    """ConfigError, naming ``plan.uavs[k]`` (UAV id), its altitude and the ceiling, if a UAV's
    layer (:func:`with_layers`) puts its cruise altitude ``altitude_m + layer`` more than the
    ceiling ``flight.max_altitude_m`` above the field ``ground_m`` (a flat map; over terrain
    the profile refuses it)."""
    top = flight(plan)["max_altitude_m"]
    for k, u in enumerate(plan["uavs"]):
        z = altitude_m + layer_of(u)
        if z - ground_m > top + 1e-9:
            raise ConfigError(
                f"plan.uavs[{k}] (UAV {u['id']})",
                f"altitude {z:g} m ({altitude_m:g} m + layer {layer_of(u):g} m)",
                f"at most the UAV ceiling flight.max_altitude_m = {top:g} m above the field: "
                "a smaller separation_m, layer_by=field, or a lower altitude_m",
            )  # fmt: skip


def approach_altitude(altitude_m: float, ground_m: float) -> float:
    """:data:`APPROACH_HEIGHT_M` above the field (lower if the cruise altitude is lower)."""
    return ground_m + min(APPROACH_HEIGHT_M, altitude_m - ground_m)


def clockwise(ring_xy: list) -> list:
    """The ring in clockwise order (QGC geofence polygons; x east, y north)."""
    a = np.asarray(ring_xy, dtype=float)
    area2 = float(np.sum(a[:, 0] * np.roll(a[:, 1], -1) - np.roll(a[:, 0], -1) * a[:, 1]))
    return list(ring_xy[::-1]) if area2 > 0 else list(ring_xy)


def drawn_ring(ring_xy: list, crs: Any, *, clockwise_order: bool) -> list:
    """The planner's polygon ``ring_xy`` (map metres, edges straight there; not closed) as
    every export hands it to a reader that joins vertices straight in latitude/longitude (a
    GIS, Google Earth, QGroundControl and the autopilot's geofence): clockwise (QGC) or
    counter-clockwise (GeoJSON, RFC 7946), long edges given points along them so that each
    piece stays within :data:`poc_env.crs.EDGE_TOLERANCE_M` of the planner's edge
    (:func:`poc_env.crs.densify_ring`), as ``(lat, lon)`` pairs, not closed."""
    ring = clockwise(ring_xy) if clockwise_order else clockwise(ring_xy)[::-1]
    return to_geographic(densify_ring(ring, crs, straight_in="local").tolist(), crs)


def antimeridian_parts(latlon: Any, *, ring: bool = False) -> list[list[list[float]]]:
    """A line or a polygon's ring, ``[(lat, lon, *more), ...]`` (``more``: a z, interpolated
    where the line is cut), cut at the 180th meridian into the parts on each side, as RFC 7946
    section 3.1.9 asks of GeoJSON (a GIS joins vertices straight in longitude, so a line from
    179.9 to -179.9 is drawn across the globe). Longitudes are first made continuous along the
    line (np.unwrap); each part is then shifted into [-180, 180], the cut points at exactly 180
    or -180. A geometry that does not cross it is returned whole, unchanged (one part).

    ``ring``: ``latlon`` is a polygon's ring (closed or not); its parts are the rings of the
    polygon cut by the meridian (shapely), each closed, without z.

    >>> antimeridian_parts([(0.0, 179.0, 5.0), (2.0, -179.0, 7.0)])
    [[[0.0, 179.0, 5.0], [1.0, 180.0, 6.0]], [[1.0, -180.0, 6.0], [2.0, -179.0, 7.0]]]
    """
    lon = np.array([p[1] for p in latlon], dtype=float)
    if np.all(np.abs(np.diff(lon)) <= 180.0):
        return [[list(p) for p in latlon]]  # as given, numbers untouched
    pts = np.asarray(latlon, dtype=float)
    pts[:, 1] = np.unwrap(pts[:, 1], period=360.0)
    turn = np.floor((pts[:, 1] + 180.0) / 360.0)  # which copy of [-180, 180) each point is in
    if ring:
        from shapely.geometry import Polygon, box

        poly = Polygon(pts[:, 1::-1])  # (lon, lat)
        out = []
        for k in range(int(turn.min()), int(turn.max()) + 1):
            piece = poly.intersection(box(360.0 * k - 180.0, -90.0, 360.0 * k + 180.0, 90.0))
            for g in getattr(piece, "geoms", [piece]):
                if g.geom_type == "Polygon" and not g.is_empty:
                    out.append([[lat, lon - 360.0 * k] for lon, lat in g.exterior.coords])
        return out
    parts = [[pts[0].tolist()]]
    for i in range(1, len(pts)):
        p, q = pts[i - 1], pts[i]
        for k in range(int(turn[i - 1]), int(turn[i]), 1 if turn[i] > turn[i - 1] else -1):
            b = 360.0 * k + (180.0 if turn[i] > turn[i - 1] else -180.0)  # the meridian crossed
            x = p + (b - p[1]) / (q[1] - p[1]) * (q - p)
            x[1] = b
            parts[-1].append(x.tolist())
            parts.append([x.tolist()])
        parts[-1].append(q.tolist())
    # a vertex exactly on the meridian leaves a part of no length there: dropped
    parts = [q for q in parts if len({(v[0], v[1]) for v in q}) > 1] or parts[:1]
    for part in parts:  # into [-180, 180]: the turn its points' mean is in (one copy each)
        turns = float(np.floor((np.mean([v[1] for v in part]) + 180.0) / 360.0))
        for v in part:
            v[1] -= 360.0 * turns
    return parts


def r6(v: float) -> float:
    """Degrees rounded to 1e-6 (about 0.1 m)."""
    return round(float(v), 6)


def routes_3d(plan: Plan, alt: float, ground: float) -> list[tuple[list[list[float]], list[float]]]:
    """Each UAV's route as flown, ``(points in local metres, altitudes)``: one implementation
    for GeoJSON and KML.

    Without terrain: take-off field, ``waypoints_m``, landing field at ``alt`` plus the UAV's
    layer (:func:`with_layers`; fields at ``ground``). With the plan's ``terrain``: the
    take-off field on the ground, the :func:`~poc_env.agents.mission.terrain.profile` points
    (the climb over the field, the waypoints and the points the clearance needs, the landing
    approach point) at their AMSL altitudes (the layer in them), the landing field on the
    ground. Where the UAV lands on a descent orbit (the profile's ``descent``), the route's
    last leg is the glide it flies from the orbit's tangent exit (at the glide's altitude) to
    the field, after the leg out from the approach point (the orbit's centre) to the exit,
    which stands for the way out to the orbit (the orbit itself is its own line, read as
    flown by ``replan --tracks``); before (i24-missionfix), the route ran straight from the
    approach point to the field, where the aircraft flew the orbit and a glide 18 deg off
    that line.
    """
    profs = plan_profiles(plan)
    out = []
    for k, u in enumerate(plan["uavs"]):
        if profs is None:
            pts = route(u)
            out.append((pts, [ground, *[alt + layer_of(u)] * (len(pts) - 2), ground]))
            continue
        p = profs[k]
        pts = [list(u["takeoff_m"]), *p.points_m.tolist()]
        zs = [p.field_m, *p.amsl_m.tolist()]
        if p.descent is not None:  # the glide flown from the orbit's exit, not from its centre
            pts.append(list(p.descent.exit_m))
            zs.append(float(p.descent.orbit.to_m))
        out.append(([*pts, list(u["landing_m"])], [*zs, p.landing_field_m]))
    return out


def _orbit_line(
    u: Any, kind: str, what: str, xy: np.ndarray, zs: np.ndarray, crs: Any, **props: Any
) -> dict[str, Any]:
    """An orbit flown over a field (a climb spiral, a descent orbit) as an overlay line: its
    points at their AMSL altitudes, ``kind`` and ``props`` in its properties."""
    return {
        "geometry": "LineString",
        "latlon": to_geographic(xy.tolist(), crs),
        "z": [round(float(v), 1) for v in zs],
        "properties": {"id": u["id"], "kind": kind, "name": f"UAV {u['id']} {what}", **props},
    }


def overlays(plan: Plan, crs: Any, alt: float, ground: float) -> list[dict[str, Any]]:
    """What GeoJSON, KML and the map report draw beside the routes and search areas.

    Per UAV the landing approach (as flown by the QGC mission), the airfields, the operating
    area and the no-fly zones (polygons counter-clockwise, closed).

    Returns
    -------
    list of dict
        Each: ``geometry`` (GeoJSON type), ``latlon``, ``z`` (None for polygons, drawn on the
        ground) and ``properties``.
    """
    out: list[dict[str, Any]] = []
    profs = plan_profiles(plan)
    rec = plan.get("terrain")
    terrain = from_record(rec) if rec is not None else None
    for k, u in enumerate(plan["uavs"]):
        app_z = [approach_altitude(alt, ground), ground]
        app = approach_point(u, plan.get("no_fly_zones_m"))
        pk = profs[k] if profs is not None else None
        dsc = pk.descent if pk is not None else None
        if pk is not None:  # from the terrain profile's last point to the field
            app_z = [float(pk.amsl_m[-1]), pk.landing_field_m]
            turned = pk.points_m[-1]  # turned round the field where the glide needs it
            if float(np.hypot(*(turned - np.asarray(app)))) > 1.0:
                app = turned.tolist()
            if dsc is not None:  # the glide from the descent orbit's exit
                app, app_z = list(dsc.exit_m), [float(dsc.orbit.to_m), pk.landing_field_m]
        out.append(
            {
                "geometry": "LineString",
                "latlon": to_geographic([app, u["landing_m"]], crs),
                "z": app_z,
                "properties": {
                    "id": u["id"],
                    "kind": APPROACH_KIND,
                    "name": f"UAV {u['id']} landing approach",
                    "approach_km": APPROACH_DISTANCE_M / 1e3,
                    "approach_height_m": round(app_z[0] - app_z[1], 1),  # as drawn
                },
            }
        )
        if dsc is not None:  # the descent orbit at the approach point (terrain.descent_orbit)
            o = dsc.orbit
            out.append(_orbit_line(
                u, DESCENT_KIND, "descent orbit at the landing approach point", *dsc.points(),
                crs, radius_km=round(o.radius_m / 1e3, 3), from_m=round(o.from_m, 1),
                to_m=round(o.to_m, 1), minutes=round(dsc.time_s / 60.0, 1),
            ))  # fmt: skip
        sp = profs[k].climb if profs is not None else None
        if sp is not None:  # the climb spiral over the take-off field (terrain.climb_spiral)
            xy, zs = sp.points()
            extra = {}
            if sp.depart_m > 0.0:  # a take-off on a heading of its own: drawn before the orbit
                dxy, dz = sp.departure(profs[k].field_m)  # type: ignore[index]
                xy, zs = np.concatenate([dxy, xy[1:]]), np.concatenate([dz, zs[1:]])
                extra = {"departure_heading_deg": round(departure_heading_deg(sp), 1),
                         "departure_km": round(sp.depart_m / 1e3, 3)}  # fmt: skip
            out.append(_orbit_line(
                u, CLIMB_KIND, "climb spiral over the take-off field", xy, zs, crs,
                radius_km=round(sp.radius_m / 1e3, 3), turns=round(sp.turns, 2),
                from_m=round(sp.from_m, 1), to_m=round(sp.to_m, 1),
                minutes=round(sp.time_s / 60.0, 1), **extra,
            ))  # fmt: skip
    for a in plan.get("airfields") or []:
        out.append(
            {
                "geometry": "Point",
                "latlon": to_geographic([a["position_m"]], crs),
                "z": [ground if terrain is None else terrain.field_elevation(a["position_m"])],
                "properties": {"kind": "airfield", "name": a["name"]},
            }
        )
    polys = []
    area = plan.get("operating_area_m")
    if area:
        polys.append(("operating_area", "operating area (eq. 20)", area))
    znames = plan.get("no_fly_zone_names") or ()
    for i, z in enumerate(plan.get("no_fly_zones_m") or []):
        polys.append(("no_fly_zone", zone_label(i, znames), z))
    for kind, name, ring in polys:
        ccw = drawn_ring(ring, crs, clockwise_order=False)
        out.append(
            {
                "geometry": "Polygon",
                "latlon": [*ccw, ccw[0]],
                "z": None,
                "properties": {"kind": kind, "name": name},
            }
        )
    return out
