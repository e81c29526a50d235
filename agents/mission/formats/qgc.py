"""QGroundControl missions: one ``.plan`` per UAV (fixed wing, PX4), with its geofence.

A mission that would breach its own geofence (a point outside the operating area, a leg
through a no-fly zone) is refused before anything is written (:func:`check_fences`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.features import (
    APPROACH_HEIGHT_M,
    approach_altitude,
    approach_point,
    check_altitude_ref,
    drawn_ring,
    layer_of,
)
from poc_env.agents.mission.job import ExportJob
from poc_env.agents.mission.plan import DEFAULT_FLIGHT, Plan, UavPlan, flight, route
from poc_env.errors import ConfigError
from poc_env.geometry import zone_crossed
from poc_env.io import write_text_atomic

# MAVLink ids (https://mavlink.io/en/messages/common.html): MAV_CMD and MAV_FRAME.
MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_LAND = 21
MAV_CMD_NAV_TAKEOFF = 22
#: Loiter at a point until an altitude is reached (MAVLink common.xml; params: heading
#: required (1: leave heading for the next waypoint), radius (m, positive clockwise), empty,
#: exit xtrack (1: straight from the exit point to the next waypoint)); the climb spiral over
#: the take-off field (:func:`poc_env.agents.mission.terrain.climb_spiral`) and the descent
#: orbit at the landing approach point (:func:`poc_env.agents.mission.terrain.descent_orbit`).
MAV_CMD_NAV_LOITER_TO_ALT = 31
MAV_CMD_DO_CHANGE_SPEED = 178
MAV_CMD_DO_LAND_START = 189
MAV_FRAME_GLOBAL = 0
MAV_FRAME_MISSION = 2
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
#: MAVLink's MISSION_COUNT ``count`` is a uint16: no mission protocol upload holds more.
MAVLINK_MAX_ITEMS = 65535
#: How many mission items autopilots hold (docs/EXPORT.md, "Mission size", with the sources):
#: a mission beyond the smallest is warned, one beyond the largest refused.
MISSION_ITEM_LIMITS: dict[str, int] = {
    # PX4 dataman, NUM_MISSIONS_SUPPORTED on NuttX boards: 2000 until PX4-Autopilot PR
    # #18827 (2021, the RAM backend), 500 since; PR #24252 (2025) keeps 500 on boards defined
    # RAM_CONSTRAINED_SYSTEM and allows 1000 on the others
    "PX4 on RAM-constrained boards": 500,
    # ArduPilot AP_Mission in the Pixhawk's storage: about 700 commands (ArduPilot issues
    # #2391 and #7254; more with the mission on the SD card)
    "ArduPilot on Pixhawk-class storage": 700,
    "PX4 on other NuttX boards (since 2025)": 1000,
    # PX4 on POSIX (SITL): UINT16_MAX - 1, allocated as needed
    "PX4 SITL": 65534,
}
#: altitude reference -> (MAV_FRAME, QGC AltitudeMode (1 relative, 2 absolute))
ALTITUDE_FRAMES = {
    "home": (MAV_FRAME_GLOBAL_RELATIVE_ALT, 1),
    "amsl": (MAV_FRAME_GLOBAL, 2),
}


def _nav(command: int, lat: float, lon: float, alt: float, ref: str, p4=(0, 0, 0, None)) -> dict:
    frame, mode = ALTITUDE_FRAMES[ref]
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


def qgc_plan(
    u: UavPlan,
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
    profile: Any = None,
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
    field elevation; ``home_amsl_m`` is the planned home position's AMSL altitude. The UAV's
    altitude layer (``layer_m``, :func:`~poc_env.agents.mission.features.with_layers`) is added
    to the take-off and every waypoint's altitude, not to the approach's.

    ``profile`` (a :class:`poc_env.agents.mission.terrain.Profile`, for a plan with terrain):
    every altitude is AMSL (MAV_FRAME_GLOBAL) from the profile, which clears the DEM; the
    take-off climbs to the profile's first altitude over the field, the profile's intermediate
    points become waypoints, the approach waypoint is its last point, NAV_LAND and the planned
    home position are at the fields' DEM elevations. Where the straight climb meets the ground
    (the profile's ``climb`` spiral), the take-off climbs to the spiral's first altitude and
    NAV_LOITER_TO_ALT (31) at the field, clockwise at the spiral's radius, climbs to its last
    before the transit; where that take-off departs on a heading of its own (the spiral's
    ``depart_m``, :func:`poc_env.agents.mission.terrain.departure_spiral`), the take-off item
    stands where its climb reaches the orbit's first altitude, on that heading (PX4's
    fixed-wing mission take-off climbs out on the course from the launch point towards it).
    Where no straight final glide clears the ground (the profile's
    ``descent``, :func:`poc_env.agents.mission.terrain.landing_profile`), the approach
    waypoint is followed by NAV_LOITER_TO_ALT at it down to the glide's entry altitude (PX4's
    fixed-wing landing pattern: DO_LAND_START, the orbit, NAV_LAND; its feasibility check
    reads the glide from the orbit's tangent exit).
    """
    if profile is not None:
        return _terrain_plan(
            u, crs, profile, cruise_speed_mps, search_speed_mps, transit_speed_mps,
            operating_area_m, no_fly_zones_m,
        )  # fmt: skip
    ref = check_altitude_ref(altitude_ref)
    wps = [list(w) for w in u["waypoints_m"]]
    start, end = list(u["takeoff_m"]), list(u["landing_m"])
    approach = approach_point(u, no_fly_zones_m)
    ll = to_geographic([start, *wps, approach, end], crs)
    t_ll, w_ll, a_ll, l_ll = ll[0], ll[1:-2], ll[-2], ll[-1]
    app_alt = approach_altitude(altitude_m, ground_m)
    alt = altitude_m + layer_of(u)  # the UAV's layer (with_layers): take-off to approach
    items = [_nav(MAV_CMD_NAV_TAKEOFF, *t_ll, alt, ref, (15, 0, 0, None))]
    if w_ll:
        items.append(_speed(cruise_speed_mps if transit_speed_mps is None else transit_speed_mps))
        items.append(_nav(MAV_CMD_NAV_WAYPOINT, *w_ll[0], alt, ref))
        items.append(_speed(search_speed_mps))
        items += [_nav(MAV_CMD_NAV_WAYPOINT, lat, lon, alt, ref) for lat, lon in w_ll[1:]]
    items.append(_speed(cruise_speed_mps))
    items.append(_do(MAV_CMD_DO_LAND_START, [0, 0, 0, 0, 0, 0, 0]))
    items.append(_nav(MAV_CMD_NAV_WAYPOINT, *a_ll, app_alt, ref))
    items.append(_nav(MAV_CMD_NAV_LAND, *l_ll, ground_m, ref))
    return _document(
        items, u, crs, ref, cruise_speed_mps, t_ll, home_amsl_m, operating_area_m, no_fly_zones_m
    )


def _terrain_plan(
    u: UavPlan,
    crs: Any,
    prof: Any,
    cruise_speed_mps: float,
    search_speed_mps: float,
    transit_speed_mps: float | None,
    operating_area_m: list | None,
    no_fly_zones_m: list | None,
) -> dict:
    """:func:`qgc_plan` of a plan with terrain (its docstring)."""
    n_wps = len(u["waypoints_m"])
    pts = prof.points_m.tolist()
    ll = to_geographic([*pts, list(u["landing_m"])], crs)
    ref = "amsl"
    z = [round(float(v), 1) for v in prof.amsl_m]
    sp = prof.climb
    up = z[0] if sp is None else round(float(sp.from_m), 1)
    at = ll[0]  # the take-off item: at the field, or where a departure of its own tops out
    if sp is not None and sp.depart_m > 0.0:  # (PX4 climbs out on the course towards it)
        at = to_geographic([list(sp.depart_xy)], crs)[0]
    items = [_nav(MAV_CMD_NAV_TAKEOFF, *at, up, ref, (15, 0, 0, None))]
    items.append(_speed(cruise_speed_mps if transit_speed_mps is None else transit_speed_mps))
    if sp is not None:  # orbit the field up to where the straight climb clears the ground
        orbit = (1, round(float(sp.radius_m), 1), 0, 1)  # leave it heading for the next point
        items.append(_nav(MAV_CMD_NAV_LOITER_TO_ALT, *ll[0], round(float(sp.to_m), 1), ref, orbit))
    last = len(pts) - 1  # the approach point
    for k in range(1, last):
        items.append(_nav(MAV_CMD_NAV_WAYPOINT, *ll[k], z[k], ref))
        v = int(prof.vertex[k])
        if v == 1:
            items.append(_speed(search_speed_mps))
        if v == n_wps:
            items.append(_speed(cruise_speed_mps))
    if n_wps == 0:
        items.append(_speed(cruise_speed_mps))
    items.append(_do(MAV_CMD_DO_LAND_START, [0, 0, 0, 0, 0, 0, 0]))
    items.append(_nav(MAV_CMD_NAV_WAYPOINT, *ll[last], z[last], ref))
    if prof.descent is not None:  # orbit the approach point down to the glide (PX4's pattern)
        o = prof.descent.orbit
        orbit = (1, round(float(o.radius_m), 1), 0, 1)  # leave it heading for the field
        down = round(float(o.to_m), 1)
        items.append(_nav(MAV_CMD_NAV_LOITER_TO_ALT, *ll[last], down, ref, orbit))
    items.append(_nav(MAV_CMD_NAV_LAND, *ll[-1], round(prof.landing_field_m, 1), ref))
    return _document(
        items, u, crs, ref, cruise_speed_mps, ll[0], round(prof.field_m, 1), operating_area_m,
        no_fly_zones_m, landing_above_home_m=prof.landing_field_m - prof.field_m,
    )  # fmt: skip


def _document(
    items: list,
    u: UavPlan,
    crs: Any,
    ref: str,
    cruise_speed_mps: float,
    t_ll: Any,
    home_amsl_m: float,
    operating_area_m: list | None,
    no_fly_zones_m: list | None,
    landing_above_home_m: float = 0.0,
) -> dict:
    """The ``.plan`` document around mission ``items``: jump ids, geofence, rally points.

    Rally points stand :data:`APPROACH_HEIGHT_M` above the take-off and the landing field; QGC
    sends them in MAV_FRAME_GLOBAL_RELATIVE_ALT (``RallyPointManager.cc``), so their altitude
    is above home (the take-off field): the landing field's is ``landing_above_home_m`` (its
    elevation less home's; 0 on a flat map) + :data:`APPROACH_HEIGHT_M`.
    """
    start, end = list(u["takeoff_m"]), list(u["landing_m"])
    for k, it in enumerate(items):
        it["doJumpId"] = k + 1
    polygons = []
    fences = [(True, operating_area_m)] if operating_area_m else []
    for inclusion, ring_m in [*fences, *((False, z) for z in no_fly_zones_m or [])]:
        ring = drawn_ring(ring_m, crs, clockwise_order=True)  # QGC joins vertices in lat/lon
        polygons.append(
            {"inclusion": inclusion, "polygon": [[lat, lon] for lat, lon in ring], "version": 1}
        )
    fields = [start] if start == end else [start, end]
    above = [0.0, round(float(landing_above_home_m), 1)]
    rally = [
        [lat, lon, h + APPROACH_HEIGHT_M]
        for (lat, lon), h in zip(to_geographic(fields, crs), above)
    ]
    return {
        "fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
        "mission": {
            "version": 2, "firmwareType": 12, "vehicleType": 1,
            "globalPlanAltitudeMode": ALTITUDE_FRAMES[ref][1],
            "cruiseSpeed": cruise_speed_mps, "hoverSpeed": 5,
            "plannedHomePosition": [t_ll[0], t_ll[1], home_amsl_m], "items": items,
        },
        "geoFence": {"circles": [], "polygons": polygons, "version": 2},
        "rallyPoints": {"points": rally, "version": 2},
    }  # fmt: skip


def check_fences(plan: Plan, area: list | None) -> None:
    """ConfigError if a UAV's mission (route and landing approach) leaves the inclusion fence
    ``area`` (by more than 1 m) or flies through a no-fly zone (more than 1 m of a leg)."""
    from shapely.geometry import Point, Polygon

    from poc_env.agents.mission.terrain import approaches
    from poc_env.geometry import zone_label

    inc = Polygon(area).buffer(1.0) if area else None
    zones = [Polygon(z) for z in plan.get("no_fly_zones_m") or []]
    for k, (u, app) in enumerate(zip(plan["uavs"], approaches(plan))):
        pts = [*route(u)[:-1], app, list(u["landing_m"])]
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
        i = zone_crossed(pts, zones)
        if i is not None:
            raise ConfigError(
                f"plan.uavs[{k}]", u["id"],
                f"a mission outside {zone_label(i, plan.get('no_fly_zone_names') or ())}"
                " (an exclusion geofence): re-plan",
            )  # fmt: skip


def check_mission_size(where: str, items: int, limit: int | None = None) -> None:
    """Warn (UserWarning) when a mission of ``items`` items is more than the smallest
    autopilot of :data:`MISSION_ITEM_LIMITS` holds (its upload is refused there, PX4 and
    ArduPilot answering MAV_MISSION_NO_SPACE), naming ``where`` (the UAV), the count and the
    limits it passes; refuse it beyond ``limit`` (the officer's autopilot, ``max_mission_items``)
    or, without one, beyond every autopilot's (:data:`MISSION_ITEM_LIMITS`' largest).

    Raises
    ------
    ConfigError
        ``where`` named: more items than ``limit`` (or any autopilot) holds.
    """
    largest = max(MISSION_ITEM_LIMITS.values())
    top = largest if limit is None else limit
    if items > top:
        whose = f"max_mission_items = {limit}" if limit is not None else "any autopilot"
        raise ConfigError(
            where, f"a QGC mission of {items} items",
            f"at most {top} items ({whose} holds; autopilots: {_limits_text()}): re-plan with "
            "a wider sweep (fewer turns), fewer or more UAVs, or split the search",
        )  # fmt: skip
    passed = [f"{name} ({n})" for name, n in MISSION_ITEM_LIMITS.items() if items > n]
    if passed:
        import warnings

        warnings.warn(
            f"{where}: a QGC mission of {items} items, more than "
            f"{', '.join(passed)} hold{'s' if len(passed) == 1 else ''} (the upload is "
            "refused there: MAV_MISSION_NO_SPACE); check your autopilot's limit, or export "
            "with max_mission_items (--max-mission-items N) to refuse missions above it",
            UserWarning,
            stacklevel=3,
        )


def _limits_text() -> str:
    return ", ".join(f"{name} {n}" for name, n in MISSION_ITEM_LIMITS.items())


def check_antimeridian(plan: Plan, area: list | None, crs: Any) -> None:
    """ConfigError if a fence polygon (the inclusion ``area``, a no-fly zone) crosses the 180th
    meridian. PX4 tests a point against a fence in latitude/longitude (navigator
    ``Geofence::insidePolygon``, PNPOLY, for polygons that do not intersect themselves): one
    whose longitudes jump from 180 to -180 is to it the rest of the globe, and QGC draws it so."""
    rings = [("plan.operating_area_m", area)] if area else []
    rings += [
        (f"plan.no_fly_zones_m[{i}]", z) for i, z in enumerate(plan.get("no_fly_zones_m") or [])
    ]
    for field, ring_m in rings:
        lon = np.array([q[1] for q in drawn_ring(ring_m, crs, clockwise_order=True)])
        if np.any(np.abs(np.diff(np.append(lon, lon[0]))) > 180.0):
            raise ConfigError(
                field, f"a polygon across the antimeridian (longitudes {lon.min():.3f} to "
                f"{lon.max():.3f})",
                "a geofence polygon on one side of the 180th meridian: PX4 and QGroundControl "
                "test fences in latitude/longitude, where this one is the rest of the globe "
                + ("(export without the inclusion fence: geofence=False / --no-geofence)"
                   if field == "plan.operating_area_m" else
                   "(move the zone off the meridian, or split it there into two zones)"),
            )  # fmt: skip


def write(job: ExportJob) -> list[Path]:
    """``<stem>_uav<ID>.plan`` per UAV, after :func:`check_fences` and
    :func:`check_antimeridian` (the operating area as the inclusion fence unless
    ``job.geofence`` is false)."""
    from poc_env.agents.mission.terrain import plan_profiles

    plan = job.plan
    fl = flight(plan)
    area = plan.get("operating_area_m") if job.geofence else None
    check_fences(plan, area)
    check_antimeridian(plan, area, job.crs)
    found = plan_profiles(plan)
    profiles: list[Any] = [None] * len(plan["uavs"]) if found is None else list(found)
    docs = [
        (
            u["id"],
            qgc_plan(
                u, job.crs, job.altitude_m, fl["cruise_speed_mps"],
                search_speed_mps=fl["search_speed_mps"],
                transit_speed_mps=fl["transit_speed_mps"], altitude_ref=job.altitude_ref,
                ground_m=job.ground_m, home_amsl_m=job.field_elevation_m,
                operating_area_m=area,
                no_fly_zones_m=plan.get("no_fly_zones_m"), profile=prof,
            ),
        )
        for u, prof in zip(plan["uavs"], profiles)
    ]  # fmt: skip
    for k, (_, doc) in enumerate(docs):  # every mission checked before any is written
        check_mission_size(job.where(k), len(doc["mission"]["items"]), job.max_mission_items)
    return [
        write_text_atomic(job.path(f"_uav{uid}.plan"), json.dumps(doc, indent=1, allow_nan=False))
        for uid, doc in docs
    ]


SCHEMA = Path(__file__).resolve().parents[1] / "assets" / "qgc_plan.schema.json"


def validate_qgc(doc: Any) -> list[str]:
    """The complaints of :data:`SCHEMA` (QGroundControl's documented ``.plan`` format, for the
    items this module writes) about a parsed ``.plan`` document, plus the one rule a schema
    cannot state: ``doJumpId`` numbered 1, 2, ... in item order. ``[]``: valid."""
    import jsonschema

    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    v = jsonschema.Draft202012Validator(schema)
    errs = [
        f"{'/'.join(map(str, e.absolute_path)) or '(root)'}: {e.message}"
        for e in sorted(v.iter_errors(doc), key=lambda e: list(map(str, e.absolute_path)))
    ]
    items = doc.get("mission", {}).get("items") if isinstance(doc, dict) else None
    if not errs and isinstance(items, list):
        ids = [it.get("doJumpId") for it in items]
        if ids != list(range(1, len(items) + 1)):
            errs.append(f"mission/items: doJumpId {ids}, not 1..{len(items)} in order")
    return errs
