"""The plan model: ``plan.json`` (schema 2; schema-1 files still load), read and written here only.

A plan is a JSON object; :class:`Plan` and the classes below type it (``TypedDict``: at run
time a plan is the plain ``dict`` the file holds, so a plan loads and rewrites byte for byte).
:func:`load_plan` reads and checks one, :func:`write_plan` writes one; nothing else in the
project opens a plan.json.

Fields
------
``schema``, ``scenario``, ``seed``, ``map_source``, ``optimizer`` {``name``, ``settings``},
``runtime_s``, ``posc``, ``upper_bound`` and ``uavs``: a list of {``id``, ``rectangle``
{``center_m`` [x, y], ``length_m``, ``width_m``, ``theta_deg``} (the optimiser's decision
rectangle; ``null`` in a schema-2 route plan such as the allocation planner's), ``spacing_m``,
``takeoff_m``, ``landing_m``, ``waypoints_m`` [[x, y], ...], ``track_length_m``,
``flight_time_s``, ``pod``, ``poc``, ``pos``, ``feasible``}. ``waypoints_m`` are the search
pattern only: the route flown is take-off field, transit to ``waypoints_m[0]``, the search from
``waypoints_m[0]`` to ``waypoints_m[-1]``, transit to the landing field. **``waypoints_m`` is
what the time model flies**; the rectangles are for people.

Schema 2 adds (all optional, checked when present):

- per UAV ``flown_rectangle`` {``center_m``, ``line_length_m``, ``strip_width_m``,
  ``lines_theta_rad``, ``rule``}: the strip the lines actually sweep
  (:func:`poc_env.agents.planning.objective.flown_rectangle`). :data:`RECTANGLE_RULE` (also
  written as the top-level ``rectangle_rule``) says how to fly it: lines along
  ``lines_theta_rad`` at spacing ``spacing_m``, ``d/2`` inside each long edge,
  ``strip_width_m / spacing_m`` lines. Re-flying it by that rule (or by the usual ``ceil(E/d)``
  lawnmower, which coincides on it) gives the plan's own eq. 17 flight time; re-flying the
  decision rectangle the usual way does not (issue 12), so every export draws the flown strip,
  not the decision rectangle.
- per UAV ``areas_m``: polygons the UAV searches (a route plan's regions), drawn as search areas.
- ``bounds`` {``honest``, ``reach``}: :func:`poc_env.theory.bound.honest_optimum` and the
  reach-aware :func:`poc_env.theory.bound.reach_bound` of the plan's prior, the bounds no policy
  beats in the environment (``upper_bound`` stays the optimiser's same-effort bound).

Optional fields of both schemas (a plan without them is read as before):

- ``crs``: the :func:`poc_env.agents.mission.crs.make_crs` record {``kind``: ``aeqd`` | ``utm``
  | ``epsg`` | ``proj``, ``origin_deg`` [lat, lon], ``proj``, ``epsg``}. With it, export needs
  no ``--origin``; an ``--origin`` given anyway must equal ``crs.origin_deg``. Without it,
  ``--origin`` is required and the default ``aeqd`` CRS at that origin is used.
- ``flight``: {``cruise_speed_mps`` (v_b, the flight home), ``search_speed_mps`` (v_s, on the
  route after the first waypoint), ``transit_speed_mps`` (out to the first waypoint; default
  v_b), ``altitude_m``, ``max_altitude_m``} of the scenario's UAV (default the paper's 220 km/h,
  180 km/h, 220 km/h, 1,000 m, 4,000 m). The allocation planner's ``--speed max`` plans record
  v_max as the search and transit speeds.
- ``operating_area_m``: the operating area (eq. 20's boundary) as a polygon [[x, y], ...]; the
  QGC geofence's inclusion polygon. Without it the inclusion fence is left empty.
- ``no_fly_zones_m``: a list of polygons; exclusion fences.
- ``no_fly_zone_names``: one name per zone (from ``map.no_fly_names``); messages name zone
  ``i`` as ``no-fly zone i ('name')``, counted from 0 (:func:`poc_env.geometry.zone_label`).
- ``airfields``: [{``name``, ``position_m``}]; names in KML/GeoJSON.
- ``terrain``: the scenario's DEM resampled onto a grid over the operating area and the
  clearance rules (:func:`poc_env.agents.mission.terrain.terrain_record`: ``origin_m``,
  ``cell_m``, ``ground_m`` and ``ground_max_m`` rows from the south in metres AMSL, ``fields``
  [{``name``, ``position_m``, ``elevation_m``}], ``min_clearance_m``, ``search_height_m``,
  ``ceiling_m``, ``max_pitch_deg``, ``source``; optional ``max_climb_rate_mps`` and
  ``max_sink_rate_mps``, the aircraft's vertical rates, recorded only when the scenario gives
  them). With it every export flies AMSL altitudes
  that clear the ground (:func:`poc_env.agents.mission.terrain.profile`).

Planners add fields of their own (``objective``, ``history``, ``x``, ``planner``, ...); they are
kept as written and not read by any export.

:func:`load_plan` checks every field an export reads before anything is written: finite numbers
in documented ranges (points within :data:`MAX_EXTENT_M` of the origin, probabilities in
[0, 1]), the right shapes, a known CRS kind that pyproj accepts as a projected CRS in metres,
and UAV ids of 1-64 ``A-Z a-z 0-9 _ -`` (they become file names), so no NaN, no out-of-range
latitude and no path outside ``--out`` can reach a mission file.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any, NoReturn, TypedDict

from poc_env.agents.mission.crs import check_crs
from poc_env.errors import ConfigError, as_number, check_name, check_text
from poc_env.io import read_json, write_text_atomic
from poc_env.limits import MAX_AIRFIELD_NAME, MAX_ZONE_NAME

SCHEMA = 2
#: The schemas :func:`load_plan` reads.
READ_SCHEMAS = (1, 2)
#: How a plan's ``flown_rectangle`` is flown (module docstring).
RECTANGLE_RULE = (
    "flown_rectangle: lines along lines_theta_rad at spacing spacing_m, the first and last d/2 "
    "inside the strip's long edges, strip_width_m / spacing_m lines, boustrophedon; this is "
    "the track waypoints_m flies and flight_time_s times"
)

#: The top-level fields every schema has.
PLAN_KEYS = {
    "schema", "scenario", "seed", "map_source", "optimizer", "runtime_s", "posc",
    "upper_bound", "uavs",
}  # fmt: skip
#: The per-UAV fields every schema has.
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

#: Largest |x| or |y| of a plan point, metres: 2,000 km from the map origin, far beyond a
#: regional search (the projections are documented and measured within 300 km).
MAX_EXTENT_M = 2.0e6
#: Largest speed (m/s) and altitude (m) a plan's ``flight`` section may hold.
MAX_SPEED_MPS = 1000.0
MAX_ALTITUDE_M = 30_000.0
#: Largest terrain grid (cells) a scenario may resample onto or a plan may record.
MAX_TERRAIN_CELLS = 1_000_000
#: Highest and (negated) lowest ground height (m AMSL) a DEM, a scenario or a plan may hold:
#: the Earth's surface lies within about +-11 km of sea level.
MAX_GROUND_M = 12_000.0
_SAFE_ID = re.compile(r"[A-Za-z0-9_-]{1,64}")

#: Fixed-wing landing pattern: the approach waypoint lies this far from the landing field, on
#: the side the UAV comes from, this high above the field (a 4.3 degree glide slope).
APPROACH_DISTANCE_M = 4000.0
APPROACH_HEIGHT_M = 300.0
#: The final glide's gradient, approach waypoint -> landing field (300 m over 4 km, 4.29 deg):
#: PX4 refuses a mission whose last leg to NAV_LAND is steeper than its FW_LND_ANG (default
#: 5 deg) + 0.1 deg (navigator's FeasibilityChecker), so no export glides steeper unless a
#: terrain clearance needs it (:func:`poc_env.agents.mission.terrain.profile` warns then).
LANDING_GLIDE = APPROACH_HEIGHT_M / APPROACH_DISTANCE_M
#: With altitude layers, field-mates landing at one field keep their approach points at least
#: this far apart (metres; eq. 21's safe distance d_s of the paper's UAV): one glide path flown
#: by two UAVs cannot be layered (a common glide slope puts both at one altitude over each
#: point), so the later UAV's approach is turned round the field, 15 deg steps (1.04 km at
#: :data:`APPROACH_DISTANCE_M`), nearest first (i24-missionfix).
APPROACH_APART_M = 1000.0
#: The ``kind`` (GeoJSON property, KML style id) of the landing approach drawn beside each
#: route: not a second flight (``replan --tracks`` skips it, the route already flies to the field).
APPROACH_KIND = "landing_approach"
#: The ``kind`` (GeoJSON property) of the climb spiral over the take-off field drawn beside a
#: route whose straight climb meets the ground
#: (:func:`poc_env.agents.mission.terrain.climb_spiral`): flown (KML draws it in the route's
#: style, ``replan --tracks`` reads it as flown).
CLIMB_KIND = "climb_spiral"
#: The ``kind`` (GeoJSON property) of the descent orbit at the landing approach point drawn
#: beside a route whose straight final glide meets the ground
#: (:func:`poc_env.agents.mission.terrain.descent_orbit`): flown, like :data:`CLIMB_KIND`
#: (the orbit kinds' one home, i24-missionfix; it was defined in the terrain module).
DESCENT_KIND = "descent_orbit"


class Rectangle(TypedDict):
    """The optimiser's decision rectangle of a UAV (metres, degrees)."""

    center_m: list[float]
    length_m: float
    width_m: float
    theta_deg: float


class FlownRectangle(TypedDict):
    """The strip a UAV's lines sweep and the rule that flies it (:data:`RECTANGLE_RULE`)."""

    center_m: list[float]
    line_length_m: float
    strip_width_m: float
    lines_theta_rad: float
    rule: str


class _UavRequired(TypedDict):
    id: int | str
    rectangle: Rectangle | None
    spacing_m: float
    takeoff_m: list[float]
    landing_m: list[float]
    waypoints_m: list[list[float]]
    track_length_m: float
    flight_time_s: float
    pod: float
    poc: float
    pos: float
    feasible: bool


class UavPlan(_UavRequired, total=False):
    """One UAV of a plan (module docstring); schema 2's members are optional."""

    flown_rectangle: FlownRectangle | None
    areas_m: list[list[list[float]]] | None
    #: set by an export only (:func:`poc_env.agents.mission.features.with_layers`): the UAV's
    #: altitude layer above the plan's altitude, metres
    layer_m: float
    #: set by an export's layers only (with_layers): the landing approach point, local metres,
    #: turned from the default side to keep field-mates' approaches apart
    approach_m: list[float]


class Airfield(TypedDict):
    """A named airfield in local metres."""

    name: str
    position_m: list[float]


class Bounds(TypedDict):
    """The environment's two bounds of the plan's prior."""

    honest: float
    reach: float


class Flight(TypedDict, total=False):
    """The UAV's speeds and altitudes (:data:`DEFAULT_FLIGHT` fills what is missing)."""

    cruise_speed_mps: float
    search_speed_mps: float
    transit_speed_mps: float
    altitude_m: float
    max_altitude_m: float


class _PlanRequired(TypedDict):
    schema: int
    scenario: str
    seed: int
    map_source: str
    optimizer: dict[str, Any]
    runtime_s: float
    posc: float
    upper_bound: float
    uavs: list[UavPlan]


class Plan(_PlanRequired, total=False):
    """A plan.json (module docstring): the schema-1 fields, schema 2's and the optional ones."""

    rectangle_rule: str | None
    bounds: Bounds | None
    crs: dict[str, Any] | None
    flight: Flight | None
    operating_area_m: list[list[float]] | None
    no_fly_zones_m: list[list[list[float]]] | None
    no_fly_zone_names: list[str] | None
    airfields: list[Airfield] | None
    terrain: dict[str, Any] | None
    #: set by an export only (:func:`poc_env.agents.mission.features.with_layers`):
    #: ``{separation_m, layer_by}``
    altitude_layers: dict[str, Any] | None


def write_plan(plan: Any, path: str | os.PathLike[str]) -> Path:
    """Write ``plan`` (a :class:`Plan`, with any extra fields of its planner) as plan.json.

    Atomically (:func:`poc_env.io.write_text_atomic`), as ``json.dumps(plan, indent=1)``: a plan
    read by :func:`load_plan` rewrites to the same bytes.
    """
    return write_text_atomic(path, json.dumps(plan, indent=1))


def load_plan(path: str | os.PathLike[str]) -> Plan:
    """Read and check a plan.json (module docstring).

    Raises
    ------
    ConfigError
        Naming the missing or wrong field (``plan.uavs[0].takeoff_m``, ...).
    """
    p = Path(path)
    if not p.is_file():
        raise ConfigError("plan", str(p), "an existing plan.json written by `poc-env plan`")
    # the one JSON reader: malformed text, NaN / Infinity and nesting too deep for the parser
    # are a ConfigError naming "plan", never a RecursionError
    try:
        plan = read_json(p, "plan")
    except ConfigError as err:
        _name_the_field(p, err)
    return check_plan(plan)


def _name_the_field(path: Path, err: ConfigError) -> NoReturn:
    """Raise the field-level error for a plan.json refused as JSON only for a NaN / Infinity
    (``plan.uavs[0].pod``, as the plan check names it); else ``err`` itself (a NaN in a field
    the check does not read, malformed text, nesting too deep)."""
    from poc_env.io import MAX_JSON_DEPTH, json_depth

    try:
        data = path.read_bytes()
        lenient = json.loads(data) if json_depth(data) <= MAX_JSON_DEPTH else None
    except (OSError, ValueError, RecursionError):
        lenient = None
    if lenient is not None:
        check_plan(lenient)  # raises naming the field that holds the NaN, when it reads it
    raise err


def check_plan(plan: Any) -> Plan:
    """``plan`` (parsed JSON) checked field by field and returned as is.

    Raises
    ------
    ConfigError
        Naming the missing or wrong field.
    """
    if not isinstance(plan, dict):
        raise ConfigError("plan", type(plan).__name__, "a JSON object")
    check_text("plan", plan)
    schema = plan.get("schema")
    if isinstance(schema, bool) or schema not in READ_SCHEMAS:
        raise ConfigError("plan.schema", schema, " or ".join(map(str, READ_SCHEMAS)))
    missing = sorted(PLAN_KEYS - set(plan))
    if missing:
        raise ConfigError(f"plan.{missing[0]}", None, "present (schema 1 field)")
    if not isinstance(plan["uavs"], list) or not plan["uavs"]:
        raise ConfigError("plan.uavs", plan["uavs"], "a non-empty list of UAV plans")
    as_number("plan.posc", plan["posc"], 0.0, 1.0)
    if "sortie_posc" in plan or "cumulative_posc" in plan:  # a replanned sortie's (replan)
        for key in ("sortie_posc", "cumulative_posc"):
            as_number(f"plan.{key}", plan.get(key), 0.0, 1.0)
    if not isinstance(plan["optimizer"], dict):  # the map report names its optimiser
        raise ConfigError("plan.optimizer", plan["optimizer"], "a mapping of name, settings")
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
            as_number(f"{where}.{key}", u[key], 0.0, 100 * MAX_EXTENT_M)
        as_number(f"{where}.flight_time_s", u["flight_time_s"], 0.0, 1e7)
        for key in ("pod", "poc", "pos"):
            as_number(f"{where}.{key}", u[key], 0.0, 1.0)
        if not isinstance(u["feasible"], bool):
            raise ConfigError(f"{where}.feasible", u["feasible"], "true or false")
    _check_optional(plan)
    return plan  # type: ignore[return-value]  # checked above, field by field


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
            as_number(f"{where}.rectangle.{key}", r[key], 0.0, MAX_EXTENT_M)
        as_number(f"{where}.rectangle.theta_deg", r["theta_deg"], -360.0, 360.0)
    fr = u.get("flown_rectangle")
    if fr is not None:
        keys = ["center_m", "line_length_m", "lines_theta_rad", "rule", "strip_width_m"]
        if not isinstance(fr, dict) or sorted(fr) != keys:
            raise ConfigError(f"{where}.flown_rectangle", fr, "a mapping of " + ", ".join(keys))
        _point(f"{where}.flown_rectangle.center_m", fr["center_m"])
        for key in ("line_length_m", "strip_width_m"):
            as_number(f"{where}.flown_rectangle.{key}", fr[key], 0.0, MAX_EXTENT_M)
        as_number(f"{where}.flown_rectangle.lines_theta_rad", fr["lines_theta_rad"], -7.0, 7.0)
        if not isinstance(fr["rule"], str) or len(fr["rule"]) > 500:
            raise ConfigError(f"{where}.flown_rectangle.rule", fr["rule"], "a text of <= 500")
    areas = u.get("areas_m")
    if areas is not None:
        if not isinstance(areas, list):
            raise ConfigError(f"{where}.areas_m", areas, "a list of polygons")
        for i, a in enumerate(areas):
            _polygon(f"{where}.areas_m[{i}]", a)


def _check_optional(plan: dict[str, Any]) -> None:
    """The optional fields (module docstring): absent or null is fine, anything else checked."""
    if plan.get("crs") is not None:
        check_crs("plan.crs", plan["crs"])
    b = plan.get("bounds")
    if b is not None:
        if not isinstance(b, dict) or sorted(b) != ["honest", "reach"]:
            raise ConfigError("plan.bounds", b, "a mapping of honest, reach")
        for key in ("honest", "reach"):
            as_number(f"plan.bounds.{key}", b[key], 0.0, 1.0)
    rule = plan.get("rectangle_rule")
    if rule is not None and (not isinstance(rule, str) or len(rule) > 1000):
        raise ConfigError("plan.rectangle_rule", rule, "a text of <= 1000 characters")
    fl = plan.get("flight")
    if fl is not None:
        if not isinstance(fl, dict) or not set(fl) <= set(DEFAULT_FLIGHT):
            raise ConfigError("plan.flight", fl, "a mapping of " + ", ".join(DEFAULT_FLIGHT))
        for key in ("cruise_speed_mps", "search_speed_mps", "transit_speed_mps"):
            if key in fl:
                as_number(f"plan.flight.{key}", fl[key], 1e-3, MAX_SPEED_MPS)
        for key in ("altitude_m", "max_altitude_m"):
            if key in fl:
                as_number(f"plan.flight.{key}", fl[key], 1e-3, MAX_ALTITUDE_M)
    if plan.get("operating_area_m") is not None:
        _polygon("plan.operating_area_m", plan["operating_area_m"])
    zones = plan.get("no_fly_zones_m")
    if zones is not None:
        if not isinstance(zones, list):
            raise ConfigError("plan.no_fly_zones_m", zones, "a list of polygons")
        for i, z in enumerate(zones):
            _polygon(f"plan.no_fly_zones_m[{i}]", z)
    znames = plan.get("no_fly_zone_names")
    if znames is not None:
        n_z = len(zones or [])
        if not isinstance(znames, list) or len(znames) != n_z:
            raise ConfigError(
                "plan.no_fly_zone_names", znames, f"one name per no-fly zone ({n_z}), strings"
            )
        for i, zname in enumerate(znames):
            check_name(f"plan.no_fly_zone_names[{i}]", zname, MAX_ZONE_NAME, empty=True)
    if plan.get("terrain") is not None:
        _check_terrain("plan.terrain", plan["terrain"])
    fields = plan.get("airfields")
    if fields is not None:
        if not isinstance(fields, list):
            raise ConfigError("plan.airfields", fields, "a list of {name, position_m}")
        for i, a in enumerate(fields):
            if not isinstance(a, dict) or sorted(a) != ["name", "position_m"]:
                raise ConfigError(f"plan.airfields[{i}]", a, "a mapping of name, position_m")
            check_name(f"plan.airfields[{i}].name", a["name"], MAX_AIRFIELD_NAME)
            _point(f"plan.airfields[{i}].position_m", a["position_m"])


def _point(field: str, value: Any) -> None:
    """An [x, y] point in metres within :data:`MAX_EXTENT_M` of the origin."""
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ConfigError(field, value, "[x, y] in metres")
    for v in value:
        as_number(field, v, -MAX_EXTENT_M, MAX_EXTENT_M)


def _polygon(field: str, value: Any) -> None:
    """A polygon: a list of at least 3 [x, y] points in metres."""
    if not isinstance(value, list) or len(value) < 3:
        raise ConfigError(field, value, "a list of at least 3 [x, y] points in metres")
    for i, v in enumerate(value):
        _point(f"{field}[{i}]", v)


def route(u: UavPlan) -> list[list[float]]:
    """The route a UAV flies: take-off field, ``waypoints_m``, landing field (metres)."""
    return [list(u["takeoff_m"]), *u["waypoints_m"], list(u["landing_m"])]


def flight(plan: Plan) -> dict[str, float]:
    """The plan's ``flight`` section with :data:`DEFAULT_FLIGHT` filling what it lacks."""
    given: dict[str, float] = dict(plan.get("flight") or {})  # type: ignore[arg-type]
    return {**DEFAULT_FLIGHT, **given}


def search_rings(u: UavPlan) -> list[tuple[str, list[list[float]], dict[str, Any]]]:
    """What a UAV searches, as closed rings in local metres: ``(kind, ring, properties)``.

    The flown strip when the plan has one (``search_strip``: what the lines sweep, see
    :data:`RECTANGLE_RULE`), else the decision rectangle (``search_rectangle``; schema 1),
    then every ``areas_m`` polygon (``search_area``). Properties in km and degrees. One
    implementation for GeoJSON, KML, the map report and the planner's figure.
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


def approach_point(u: UavPlan, zones: Any = ()) -> list[float]:
    """The fixed-wing approach waypoint of a UAV plan (metres): :data:`APPROACH_DISTANCE_M` from
    the landing field towards the last search point (east of the field if they coincide).

    ``zones``: the plan's ``no_fly_zones_m``. When the approach from that side would fly through
    one (more than 1 m of the legs last search point -> approach -> field, the QGC geofence's
    test), the side is turned in 15 degree steps, nearest first, to the first clear one (a
    field beside a zone, issue 24; :func:`approach_sides`); if none is clear, the first side
    (the geofence then names the zone)."""
    for p in approach_sides(u, zones, turn=bool(_valid_polygons(zones))):
        return p  # the first clear side: the later ones are not computed
    return next(approach_sides(u, (), turn=False))


def approach_sides(u: UavPlan, zones: Any = (), *, turn: bool = True) -> Iterator[list[float]]:
    """The approach waypoints :data:`APPROACH_DISTANCE_M` round the landing field a UAV may
    come in from, clear of the no-fly ``zones`` (:func:`approach_point`'s test): the side of
    the last search point first, then turned in 15 degree steps, nearest first (both ways, all
    24 sides; only the first without ``turn``), generated one by one; a UAV given its side by
    the export's layers (``approach_m``, :func:`~poc_env.agents.mission.features.with_layers`:
    field-mates' approaches apart) that side first. :func:`approach_point` takes the first;
    the terrain's final glide (:func:`poc_env.agents.mission.terrain.landing_profile`)
    searches them for one whose glide clears the ground."""
    import numpy as np

    end = np.asarray(u["landing_m"], dtype=float)
    wps = u["waypoints_m"]
    last = np.asarray(wps[-1] if wps else u["takeoff_m"], dtype=float)
    d = last - end
    first = math.atan2(d[1], d[0]) if float(np.hypot(*d)) > 1.0 else 0.0
    polys = _valid_polygons(zones)
    given = u.get("approach_m")  # an export's side for field-mates (features.with_layers)
    if given is not None:
        yield [float(v) for v in given]
    for step in (0, *(s * k for k in range(1, 13) for s in (1, -1))) if turn else (0,):
        a = first + math.radians(15.0 * step)
        p = end + APPROACH_DISTANCE_M * np.array([math.cos(a), math.sin(a)])
        if not polys or _clear([last, p, end], polys):
            yield [float(v) for v in p]


def _valid_polygons(zones: Any) -> list:
    from shapely.geometry import Polygon

    polys = [Polygon(z) for z in zones or ()]
    return [z for z in polys if z.is_valid]


def _clear(points: list, polys: list) -> bool:
    """The path through ``points`` flies at most 1 m inside each polygon of ``polys``."""
    from shapely.geometry import LineString

    line = LineString(points)
    return all(line.intersection(z).length <= 1.0 for z in polys)


def _check_terrain(field: str, rec: Any) -> None:
    """A plan's ``terrain`` record (:func:`poc_env.agents.mission.terrain.terrain_record`),
    checked field by field (ConfigError naming it)."""
    import numpy as np

    from poc_env import limits

    keys = sorted(
        ["origin_m", "cell_m", "ground_m", "ground_max_m", "fields", "min_clearance_m",
         "search_height_m", "ceiling_m", "max_pitch_deg", "source"]
    )  # fmt: skip
    # recorded since issue 24's F3; the vertical rates since i24-rates (only when given)
    optional = {"max_turn_rate_deg_s", "usable_endurance_s", "max_climb_rate_mps",
                "max_sink_rate_mps"}  # fmt: skip
    if not isinstance(rec, dict) or sorted(set(rec) - optional) != keys:
        raise ConfigError(
            field,
            rec if not isinstance(rec, dict) else sorted(rec),
            ", ".join(keys) + " (optional: " + ", ".join(sorted(optional)) + ")",
        )
    if "max_turn_rate_deg_s" in rec:
        as_number(
            f"{field}.max_turn_rate_deg_s", rec["max_turn_rate_deg_s"], limits.MIN_POSITIVE,
            limits.MAX_RATE_DEG_S,
        )  # fmt: skip
    if "usable_endurance_s" in rec:  # 0.85 T (eq. 18): at most the largest endurance
        as_number(
            f"{field}.usable_endurance_s", rec["usable_endurance_s"], limits.MIN_POSITIVE,
            limits.MAX_ENDURANCE_H * 3600.0,
        )  # fmt: skip
    for key in ("max_climb_rate_mps", "max_sink_rate_mps"):  # PX4's FW_T_CLMB_MAX/SINK_MAX
        if key in rec:
            as_number(f"{field}.{key}", rec[key], 0.0, limits.MAX_VERTICAL_RATE_MPS, lo_open=True)
    o = rec["origin_m"]
    if not isinstance(o, list) or len(o) != 2:
        raise ConfigError(f"{field}.origin_m", o, "[x, y] in metres")
    for v in o:
        as_number(f"{field}.origin_m", v, -2e6, 2e6)
    as_number(f"{field}.cell_m", rec["cell_m"], 1.0, 1e6)
    shape = None
    for key in ("ground_m", "ground_max_m"):
        g = rec[key]
        ok = isinstance(g, list) and len(g) >= 1 and all(isinstance(r, list) for r in g)
        arr = None
        if ok:
            try:
                arr = np.asarray(g, dtype=float)
            except (TypeError, ValueError):
                arr = None
        if arr is None or arr.ndim != 2 or arr.size > MAX_TERRAIN_CELLS:
            raise ConfigError(f"{field}.{key}", "not a grid", "equal rows of heights in metres")
        if not np.isfinite(arr).all() or np.abs(arr).max() > MAX_GROUND_M:
            raise ConfigError(
                f"{field}.{key}", f"a NaN or a height beyond {MAX_GROUND_M:g} m", "heights (m)"
            )
        if shape is not None and arr.shape != shape:
            raise ConfigError(f"{field}.{key}", list(arr.shape), f"the shape {list(shape)}")
        shape = arr.shape
    for key, hi in (("min_clearance_m", 30_000), ("search_height_m", 30_000),
                    ("ceiling_m", 30_000), ("max_pitch_deg", 89)):  # fmt: skip
        as_number(f"{field}.{key}", rec[key], 0.0, hi)
    if not isinstance(rec["source"], str) or len(rec["source"]) > 200:
        raise ConfigError(f"{field}.source", rec["source"], "a text of <= 200 characters")
    fl = rec["fields"]
    if not isinstance(fl, list):
        raise ConfigError(f"{field}.fields", fl, "a list of {name, position_m, elevation_m}")
    for i, f in enumerate(fl):
        if not isinstance(f, dict) or sorted(f) != ["elevation_m", "name", "position_m"]:
            raise ConfigError(f"{field}.fields[{i}]", f, "{name, position_m, elevation_m}")
        if not isinstance(f["name"], str) or len(f["name"]) > 64:
            raise ConfigError(f"{field}.fields[{i}].name", f["name"], "1-64 characters")
        p = f["position_m"]
        if not isinstance(p, list) or len(p) != 2:
            raise ConfigError(f"{field}.fields[{i}].position_m", p, "[x, y] in metres")
        for v in p:
            as_number(f"{field}.fields[{i}].position_m", v, -2e6, 2e6)
        as_number(f"{field}.fields[{i}].elevation_m", f["elevation_m"], -MAX_GROUND_M, MAX_GROUND_M)


def scenario_source(
    name: str, plan_path: str | os.PathLike[str], scenario_file: Any = None
) -> str | None:
    """Where the plan's scenario ``name`` is: a built-in name, the YAML file the plan records
    (``scenario_file``, written by ``poc-env plan --scenario FILE.yaml``: as recorded, else
    its file name beside the plan), or ``NAME.yaml`` beside the plan or in the current folder
    (plans without ``scenario_file``); None if none exists."""
    from poc_env.config import builtin_scenarios

    if name in builtin_scenarios():
        return name
    cands = _scenario_candidates(name, plan_path, {"scenario_file": scenario_file})
    return next((str(c) for c in cands if c.is_file()), None)


def scenario_not_found(name: str, plan_path: str | os.PathLike[str], plan: Any) -> str:
    """Why a plan's scenario ``name`` was not found, with every file tried (for messages:
    export's prior note, ``replan``'s error)."""
    looked = ", ".join(str(c) for c in _scenario_candidates(name, plan_path, plan))
    return (
        f"scenario {name!r} is not built in and no YAML file of it was found (looked for "
        f"{looked}): copy the scenario's YAML file beside the plan as {name}.yaml"
    )


def _scenario_candidates(name: str, plan_path: str | os.PathLike[str], plan: Any) -> list[Path]:
    """The YAML files :func:`scenario_source` tries, in order."""
    recorded = plan.get("scenario_file") if isinstance(plan, dict) else None
    cands = []
    if isinstance(recorded, str) and recorded:
        cands += [Path(recorded), Path(plan_path).parent / Path(recorded).name]
    if name.endswith((".yaml", ".yml")):
        cands.append(Path(name))
    for folder in (Path(plan_path).parent, Path.cwd()):
        cands += [folder / f"{name}.yaml", folder / f"{name}.yml"]
    return list(dict.fromkeys(cands))


def map_file_candidates(src: str, plan_path: str | os.PathLike[str]) -> list[Path]:
    """Where the prior file a plan records (``map_source``, the ``--map`` of ``poc-env plan``,
    as given then) may be: as recorded, else beside the plan (export's prior overlay,
    ``replan``'s prior)."""
    return list(dict.fromkeys([Path(src), Path(plan_path).parent / src]))


def with_scenario_file(plan: dict, scenario: object) -> dict:
    """``plan`` recording ``scenario_file`` (absolute) when the scenario came from a YAML file:
    export finds the prior's scenario by it (its ``name:`` may differ from the file name)."""
    if isinstance(scenario, str) and Path(scenario).is_file():
        return {**plan, "scenario_file": str(Path(scenario).resolve())}
    return plan


def check_map_option(sc: Any, map_file: Any) -> None:
    """``--map`` replaces a scenario's prior; over a scenario whose prior already is a file it
    would silently win over that file: refused, naming both."""
    prior = sc.map.prior
    if map_file is not None and prior.kind == "file":
        raise ConfigError(
            "map", os.fspath(map_file), f"no --map with scenario {sc.name!r}, whose prior is "
            f"the file {prior.file} (map.prior.file): change that key with --overrides "
            "map.prior.file=PATH, or leave --map out",
        )  # fmt: skip


def map_source(sc: Any, map_file: Any) -> str:
    """plan.json's ``map_source``: the ``--map`` file, else the scenario's prior file, else
    ``builtin`` (a prior computed from the scenario's components)."""
    if map_file is not None:
        return os.fspath(map_file)
    prior = sc.map.prior
    return str(prior.file) if prior.kind == "file" else "builtin"


def sortie_figures(plan: Any) -> dict[str, float]:
    """A replanned sortie's own figures (``poc-env replan``), ``{}`` for a first sortie.

    Its ``posc`` is the planner's model (each cell's belief spread evenly over the cell);
    ``sortie_posc`` is what its routes find on the belief the flights left, point by point, and
    ``cumulative_posc`` the search's POS with this sortie (eq. 14 over every flight): the two an
    officer reads in the exports."""
    if "sortie_posc" not in plan:
        return {}
    return {
        "sortie": int(plan.get("sortie", 0)),
        "sortie_posc": float(plan["sortie_posc"]),
        "cumulative_posc": float(plan["cumulative_posc"]),
    }
