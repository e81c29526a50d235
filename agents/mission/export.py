"""Mission export: a plan.json written in one of the registered formats.

``poc-env export plan.json --format NAME`` calls :func:`export_plan`: it checks every argument
and the plan (:func:`poc_env.agents.mission.plan.load_plan`) before anything is written,
settles the CRS (:func:`poc_env.agents.mission.crs.plan_crs`) and the altitudes
(:func:`poc_env.agents.mission.features.altitudes`), and hands an
:class:`~poc_env.agents.mission.job.ExportJob` to the format's writer in
:data:`poc_env.agents.mission.formats.FORMATS`.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Any

from poc_env.agents.mission.crs import check_origin, plan_crs
from poc_env.agents.mission.features import (
    altitudes,
    check_altitude_ref,
    check_layers,
    check_separation,
    with_layers,
)
from poc_env.agents.mission.formats import FORMATS
from poc_env.agents.mission.formats.qgc import check_fences
from poc_env.agents.mission.job import ExportJob
from poc_env.agents.mission.plan import load_plan
from poc_env.agents.mission.terrain import SteepGlideWarning, profiles_once
from poc_env.errors import ConfigError, as_number, say_warning


def export_plan(
    plan_path: str | os.PathLike[str],
    fmt: str,
    origin: str | tuple[float, float] | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    *,
    projection: str = "aeqd",
    zone: int | None = None,
    altitude_m: float | None = None,
    altitude_ref: str | None = None,
    field_elevation_m: float | None = None,
    geofence: bool = True,
    prior: Any = None,
    allow_infeasible: bool = False,
    max_mission_items: int | None = None,
    separation_m: float = 0.0,
    layer_by: str = "field",
) -> list[Path]:
    """Write ``fmt`` files next to the plan (or into ``out_dir``); return their paths.

    Parameters
    ----------
    plan_path : path
        A plan.json (:mod:`poc_env.agents.mission.plan`).
    fmt : str
        A name of :data:`~poc_env.agents.mission.formats.FORMATS`.
    origin : str or (float, float), optional
        (lat, lon) of the map's (0, 0). The CRS is the plan's ``crs`` (``origin``, if given,
        must agree) or, for a plan without one, ``projection`` (``aeqd`` or ``utm``, UTM zone
        ``zone`` or the origin's) at ``origin``.
    out_dir : path, optional
        The folder (default: the plan's).
    altitude_m : float, optional
        Default the plan's ``flight.altitude_m`` (above the field), in the reference
        ``altitude_ref`` (``home``, the default, or ``amsl``; ``field_elevation_m`` is the
        fields' AMSL height, default 0). A plan with ``terrain`` takes none of the three: it
        flies AMSL altitudes that clear its DEM
        (:func:`poc_env.agents.mission.terrain.plan_profiles`, checked here before anything
        is written) from fields at the DEM's elevations.
    geofence : bool
        QGC missions that would breach their own geofence (a point outside the operating area,
        a leg through a no-fly zone) are refused; ``geofence=False`` leaves the inclusion fence
        out.
    prior : None, array or path
        The prior overlay of ``kml`` and ``html`` (an array of the scenario grid's shape or a
        map file); by default the plan's scenario prior rebuilt by
        :func:`poc_env.agents.mission.overlay.plan_prior`.
    allow_infeasible : bool
        A UAV the plan marks infeasible (``feasible: false``: its flight beyond the usable
        endurance, eq. 18) is refused by the QGC export unless this is set; then, and in the
        viewing formats always, it is warned (:func:`check_endurance`).
    max_mission_items : int, optional
        QGC: refuse a mission of more items than this (the autopilot's limit; see
        :data:`~poc_env.agents.mission.formats.qgc.MISSION_ITEM_LIMITS`). Without it a mission
        beyond the smallest autopilot's limit is warned, and one beyond every autopilot's
        refused (:func:`~poc_env.agents.mission.formats.qgc.check_mission_size`).
    separation_m : float
        Vertical separation (metres, 0: off, the default): UAV ``k'`` flies ``k' x
        separation_m`` above the plan's altitude (a flat map) or its terrain profile's wanted
        height, ``k'`` its index among the exported UAVs of its take-off field (``layer_by``
        ``field``) or of the plan (``fleet``); the landing approach keeps the plan's
        (:func:`~poc_env.agents.mission.features.with_layers`). A layer above the ceiling is
        refused, naming the UAV, its altitude and the ceiling.
    layer_by : {"field", "fleet"}

    Returns
    -------
    list of Path
        The files written (atomically).

    Raises
    ------
    ConfigError
        A wrong argument or plan field, named; nothing is written then.
    """
    if fmt not in FORMATS:
        raise ConfigError("format", fmt, "one of " + ", ".join(FORMATS))
    if origin is not None:
        check_origin(origin)
    if projection not in ("aeqd", "utm"):
        raise ConfigError("projection", projection, "aeqd or utm")
    if altitude_ref is not None:
        check_altitude_ref(altitude_ref)
    separation_m = check_separation(separation_m, layer_by)
    with warnings.catch_warnings(), profiles_once():  # each UAV's terrain profile once
        if fmt != "qgc":  # the glide is PX4's check of the mission that flies: QGC's
            warnings.simplefilter("ignore", SteepGlideWarning)
        plan = with_layers(load_plan(plan_path), separation_m, layer_by)
        flown = searching_uavs(plan)  # a plan that reaches nothing: refused before any work
        if max_mission_items is not None:
            check_max_items(max_mission_items)
        crs = plan_crs(plan.get("crs"), origin, projection, zone)
        if plan.get("terrain") is not None:
            altitude_ref, field_elevation_m = _terrain_altitudes(
                plan, altitude_m, altitude_ref, field_elevation_m
            )
        altitude_ref = altitude_ref or "home"
        field_elevation_m = 0.0 if field_elevation_m is None else field_elevation_m
        alt, ground = altitudes(plan, altitude_m, altitude_ref, field_elevation_m)
        check_layers(plan, alt, ground)  # a layer above the ceiling: refused, the UAV named
        elevation = as_number("field_elevation_m", field_elevation_m, -500.0, 9000.0)
        # the whole plan checked, so a refusal names the UAV's index in the file
        area = plan.get("operating_area_m") if geofence or fmt != "qgc" else None
        warning = airspace_warning(plan, area)
        if fmt == "qgc" and warning is not None:
            check_fences(plan, area)  # QGC refuses such a plan (the error itself, raised)
        if warning is not None:  # the other formats show it, and say so
            say_warning(warning)
        check_endurance(plan, flown, refuse=fmt == "qgc" and not allow_infeasible)
        for line in (
            shared_orbits(plan, flown) + departures(plan, flown) + rate_warnings(plan, flown)
        ):
            say_warning(line)
        kept = {id(u) for u in flown}
        left = [f"plan.uavs[{k}] (UAV {u['id']})"
                for k, u in enumerate(plan["uavs"]) if id(u) not in kept]  # fmt: skip
        if left:  # one line, however many (a 64-UAV plan printed 49 lines: i24-dayaudit)
            more = f" and {len(left) - 6} more" if len(left) > 6 else ""
            say_warning(f"{', '.join(left[:6])}{more}: no search planned for "
                  f"{'it' if len(left) == 1 else 'them'} (no waypoints_m); left out of the "
                  "export")  # fmt: skip
        job = ExportJob(
            plan={**plan, "uavs": flown},
            plan_path=Path(plan_path),
            crs=crs,
            altitude_m=alt,
            ground_m=ground,
            altitude_ref=altitude_ref,
            field_elevation_m=elevation,
            geofence=geofence,
            prior=prior,
            out_dir=Path(out_dir) if out_dir else Path(plan_path).parent,
            warning=warning,
            indices=tuple(k for k, u in enumerate(plan["uavs"]) if id(u) in kept),
            max_mission_items=max_mission_items,
        )
        return FORMATS[fmt].write(job)


def check_endurance(plan: Any, flown: list[Any], *, refuse: bool) -> None:
    """Refuse (``refuse``: the QGC export, the missions that fly) or warn (UserWarning: the
    viewing formats, or QGC with ``allow_infeasible``) when a UAV exported, one of ``flown``,
    is marked infeasible by the plan (``feasible: false``: its flight time beyond the usable
    endurance 0.85 T, eq. 18, as the planner checked it). Each such UAV is named with its
    index in the file and its flight time; the HTML report's table says "NO" too.

    Raises
    ------
    ConfigError
        ``plan.uavs[k]`` (the first such UAV) with ``refuse``; nothing is written then.
    """
    kept = {id(u) for u in flown}
    bad = [(k, u) for k, u in enumerate(plan["uavs"]) if id(u) in kept and not u["feasible"]]
    if not bad:
        return
    names = ", ".join(
        f"plan.uavs[{k}] (UAV {u['id']}, {u['flight_time_s'] / 3600:.2f} h)" for k, u in bad[:6]
    )
    more = f" and {len(bad) - 6} more" if len(bad) > 6 else ""
    what = (
        f"{names}{more}: marked infeasible by the plan (feasible: false: a flight time beyond "
        "the usable endurance 0.85 T, eq. 18)"
    )
    if refuse:
        raise ConfigError(
            f"plan.uavs[{bad[0][0]}]",
            f"{len(bad)} of {len(flown)} missions marked infeasible by the plan",
            f"missions within the usable endurance: {what}; re-plan (raise --maxiter or "
            "--popsize, or --planner allocation), or export them anyway with "
            "allow_infeasible=True (--allow-infeasible: warned)",
        )
    warnings.warn(
        f"{what}: {len(bad)} of {len(flown)} missions exported anyway", UserWarning, stacklevel=3
    )


def check_max_items(value: Any) -> int:
    """``max_mission_items`` if it is an integer from 1 to MAVLink's uint16 count, else
    ConfigError."""
    from poc_env.agents.mission.formats.qgc import MAVLINK_MAX_ITEMS

    is_int = isinstance(value, int) and not isinstance(value, bool)
    if not is_int or not 1 <= value <= MAVLINK_MAX_ITEMS:
        raise ConfigError(
            "max_mission_items", value,
            f"an integer from 1 to {MAVLINK_MAX_ITEMS} (MAVLink's MISSION_COUNT is a uint16): "
            "your autopilot's mission size",
        )  # fmt: skip
    return value


def airspace_warning(plan: Any, area: list | None) -> str | None:
    """The QGC export's airspace refusal (:func:`~poc_env.agents.mission.formats.qgc.check_fences`:
    a mission point outside the inclusion fence ``area``, a leg through a no-fly zone) as text,
    or None: what the viewing formats (GeoJSON, KML, the HTML report) say about a plan, edited
    by hand, that QGC would not fly."""
    try:
        check_fences(plan, area)
    except ConfigError as err:
        return str(err)
    return None


def shared_orbits(plan: Any, flown: list[Any]) -> list[str]:
    """One sentence per orbit two or more exported UAVs (``flown``) fly on one circle: the
    climb spirals over one take-off field, or the descent orbits at one approach point, of a
    plan with terrain exported without altitude layers (``separation_m`` 0; with layers each
    UAV's orbit is its layer wider, :func:`~poc_env.agents.mission.terrain.orbit_radius`).
    The export schedules no launch times: the UAVs meet there unless launched apart."""
    from poc_env.agents.mission.terrain import plan_profiles

    if plan.get("altitude_layers") or plan.get("terrain") is None:
        return []
    profs = plan_profiles(plan)
    kept = {id(u) for u in flown}
    circles: dict[tuple, list[str]] = {}
    for u, p in zip(plan["uavs"], profs or ()):
        if id(u) not in kept:
            continue
        for what, o in (
            ("climb spiral over the take-off field", p.climb),
            ("descent orbit at the landing approach point", p.descent.orbit if p.descent else None),
        ):
            if o is not None:
                key = (what, round(o.center_m[0]), round(o.center_m[1]), round(o.radius_m))
                circles.setdefault(key, []).append(str(u["id"]))
    return [
        f"UAVs {', '.join(ids)} fly one {what} at ({x / 1e3:.1f}, {y / 1e3:.1f}) km, radius "
        f"{r / 1e3:.2f} km (no altitude layers): launch them apart in time, or export with "
        "--separation-m S to widen each UAV's orbit by its layer"
        for (what, x, y, r), ids in circles.items()
        if len(ids) > 1
    ]


def departures(plan: Any, flown: list[Any]) -> list[str]:
    """One sentence per exported UAV (``flown``) whose take-off climbs out on a heading of its
    own, away from its first waypoint (the climb towards it meets the ground:
    :func:`~poc_env.agents.mission.terrain.departure_spiral`): the heading to launch on (the
    QGC take-off item stands on it; firmware that climbs out in the launch direction needs
    the aircraft launched on it)."""
    from poc_env.agents.mission.terrain import departure_heading_deg, plan_profiles

    if plan.get("terrain") is None:
        return []
    kept = {id(u) for u in flown}
    return [
        f"plan.uavs[{k}] (UAV {u['id']}): its take-off climbs out on heading "
        f"{departure_heading_deg(p.climb):.0f} deg (grid north) for {p.climb.depart_m / 1e3:.1f}"
        f" km to {p.climb.from_m:.0f} m AMSL, then orbits the field up to {p.climb.to_m:.0f} m: "
        "the climb towards its first waypoint meets the rising ground; launch on that heading"
        for k, (u, p) in enumerate(zip(plan["uavs"], plan_profiles(plan) or ()))
        if id(u) in kept and p.climb is not None and p.climb.depart_m > 0.0
    ]


def rate_warnings(plan: Any, flown: list[Any]) -> list[str]:
    """One sentence per exported UAV (``flown``) of a plan with terrain whose mission needs a
    climb or sink faster than PX4's and ArduPlane's default limit
    (:data:`~poc_env.agents.mission.terrain.AUTOPILOT_DEFAULT_RATE_MPS`), for each of climb
    and sink whose rate the scenario left unset (``uav.max_climb_rate_mps`` /
    ``max_sink_rate_mps``: eq. 19's pitch alone bounds it): the phases and their rates
    (:func:`~poc_env.agents.mission.terrain.vertical_rates`). Files unchanged; at most six
    UAVs named, then a count."""
    from poc_env.agents.mission.plan import flight
    from poc_env.agents.mission.terrain import (
        AUTOPILOT_DEFAULT_RATE_MPS,
        from_record,
        plan_profiles,
        route_speed_mps,
        vertical_rates,
    )

    rec = plan.get("terrain")
    if rec is None:
        return []
    unset = {k for k in ("climb", "sink") if rec.get(f"max_{k}_rate_mps") is None}
    if not unset:
        return []
    t = from_record(rec)
    fl = flight(plan)
    kept = {id(u) for u in flown}
    slow = AUTOPILOT_DEFAULT_RATE_MPS
    lines = []
    for k, (u, p) in enumerate(zip(plan["uavs"], plan_profiles(plan) or ())):
        if id(u) not in kept:
            continue
        fast = [
            f"{kind} {rate:.1f} m/s on its {phase}" + (f" ({note})" if note else "")
            for phase, kind, rate, note in vertical_rates(
                t, p, fl["transit_speed_mps"], route_speed_mps(fl)
            )
            if kind in unset and rate > slow + 1e-9
        ]
        if fast:
            lines.append(f"plan.uavs[{k}] (UAV {u['id']}): {'; '.join(fast)}")
    if not lines:
        return []
    keys = " / ".join(f"uav.max_{k}_rate_mps" for k in ("climb", "sink") if k in unset)
    more = [f"and {len(lines) - 6} more UAVs"] if len(lines) > 6 else []
    return [
        *lines[:6],
        *more,
        f"these missions need a vertical rate above PX4's and ArduPlane's default {slow:g} m/s "
        "(FW_T_CLMB_MAX / FW_T_SINK_MAX, TECS_CLMB_MAX / TECS_SINK_MAX) and were planned at "
        f"eq. 19's pitch bound alone: set {keys} to the aircraft's rates in the scenario and "
        "plan again (the profile then climbs and sinks within them and the orbits' minutes are "
        "charged at them)",
    ]


def searching_uavs(plan: Any) -> list[Any]:
    """The plan's UAVs that have a search route (``waypoints_m`` not empty): what an export
    writes. A UAV without one (the allocation planner found no mass it could reach, or a
    teammate's route already covers it) would be a zero-length route in GeoJSON and KML and a
    take-off and landing on the spot in QGC; the export leaves it out and names it.

    Raises
    ------
    ConfigError
        ``plan.uavs``: no UAV has a search route (nothing to fly; the plan's ``reason`` said
        why), so nothing is written.
    """
    flown = [u for u in plan["uavs"] if u["waypoints_m"]]
    if not flown:
        why = f" (no search planned: {plan['reason']})" if plan.get("reason") else ""
        raise ConfigError(
            "plan.uavs", f"{len(plan['uavs'])} UAV(s), none with a search route{why}",
            "a plan with at least one UAV's search route (waypoints_m) to export: re-plan "
            "(another airfield, more endurance, or a prior with mass in reach)",
        )  # fmt: skip
    return flown


def _terrain_altitudes(
    plan: Any, altitude_m: float | None, altitude_ref: str | None, field_elevation_m: Any
) -> tuple[str, float]:
    """(``amsl``, the first take-off field's DEM elevation) for a plan with terrain, after
    refusing the flat-map options and checking every UAV's clearance (nothing written)."""
    from poc_env.agents.mission.terrain import from_record, plan_profiles

    why = "nothing: a plan with terrain flies AMSL altitudes that clear its DEM"
    if altitude_m is not None:
        raise ConfigError("altitude_m", altitude_m, why)
    if field_elevation_m is not None:
        raise ConfigError("field_elevation_m", field_elevation_m, why + " (fields from it)")
    if altitude_ref not in (None, "amsl"):
        raise ConfigError("altitude_ref", altitude_ref, "amsl (or nothing) for a plan with terrain")
    plan_profiles(plan)  # clearance impossible within the ceiling: refused, naming the UAV
    t = from_record(plan["terrain"])
    return "amsl", t.field_elevation(plan["uavs"][0]["takeoff_m"])
