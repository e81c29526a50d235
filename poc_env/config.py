"""Typed, validated, immutable scenario configuration.

A scenario is one YAML file in ``configs/`` (or any path). YAML is only the serialisation of the
frozen dataclasses below: every key is known (an unknown key is an error that lists the allowed
ones), every value is checked when the object is built, and every error names the dotted field,
the value and what is allowed.

Units: SI inside (metres, seconds, radians, metres per second). Where a YAML key is in another
unit, the unit is in its name (``width_km``, ``search_speed_kmh``, ``endurance_h``,
``max_turn_deg``) and it is converted once, here, at load. ``Scenario.to_dict()`` writes the same
keys back, so a resolved config can be saved beside a run and loaded again.
"""

from __future__ import annotations

import copy
import dataclasses
import datetime
import functools
import importlib.resources
import math
import os
import types
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

import poc_env.limits as limits
from poc_env._kernels.sensing import LAW_CODES
from poc_env.errors import ConfigError, as_bool, as_int, as_number, check_name, describe_range
from poc_env.io import write_text_atomic

KM = 1000.0
KMH = 1000.0 / 3600.0
HOUR = 3600.0
DEG = math.pi / 180.0
#: Largest distance of any configured point (origin, airfields, zones, peaks, means) from the
#: map origin, in metres (:data:`poc_env.limits.MAX_COORD_KM`).
MAX_COORD_M = limits.MAX_COORD_KM * KM
#: Largest swarm.
MAX_UAVS = 64

#: Folder of the built-in scenarios, region plans and topologies: package data, read through
#: ``importlib.resources`` so that a wheel, an editable install and a Ray worker all find it.
#: In the source tree ``poc_env/configs`` is a link to the top-level ``configs/`` (the one copy).
CONFIG_DIR = Path(str(importlib.resources.files("poc_env").joinpath("configs")))


def _f(
    key: str | None = None,
    scale: float = 1.0,
    default: Any = dataclasses.MISSING,
    *,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    **kw: Any,
):
    """A dataclass field whose YAML key is ``key`` and whose YAML value times ``scale`` is SI.

    ``lo``/``hi`` (``lo_open``: ``lo`` excluded) bound a number or integer field, in the YAML
    key's unit; :func:`_coerce` applies them, with the type, to every section when it is built.
    """
    meta = {"key": key, "scale": scale, "lo": lo, "hi": hi, "lo_open": lo_open}
    if default is dataclasses.MISSING:
        return field(metadata=meta, **kw)
    return field(default=default, metadata=meta, **kw)


# --------------------------------------------------------------------------- helpers


@functools.cache
def _field_types(cls: type) -> tuple[tuple[dataclasses.Field, Any, bool], ...]:
    """(field, type without Optional, optional?) of a section, resolved once."""
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        tp = hints[f.name]
        out.append((f, _strip_optional(tp), _strip_optional(tp) is not tp))
    return tuple(out)


def _coerce(obj: Any) -> None:
    """The one type-and-range check of every scalar field of a section, by its annotation.

    Numbers (``float``) become finite floats, integers (``int``) ints (integral floats and numpy
    integers accepted), flags (``bool``) must be true/false, text (``str``) a string; each within
    its field's ``lo``/``hi`` in YAML units. Errors name the YAML key and show the value in the
    key's unit. Vectors and polygons are checked by the section itself.
    """
    for f, tp, optional in _field_types(type(obj)):  # type: ignore[arg-type]
        value = getattr(obj, f.name)
        if value is None and optional:
            continue
        meta = f.metadata
        key = meta.get("key") or f.name
        scale = meta.get("scale", 1.0)
        lo, hi, lo_open = meta.get("lo"), meta.get("hi"), meta.get("lo_open", False)
        if tp is bool:
            object.__setattr__(obj, f.name, as_bool(key, value))
        elif tp is int:
            object.__setattr__(obj, f.name, as_int(key, value, _int_or(lo), _int_or(hi)))
        elif tp is float:
            allowed = describe_range(lo, hi, lo_open=lo_open)
            si = as_number(key, value, allowed=allowed)
            as_number(key, si / scale, lo, hi, lo_open=lo_open)  # the range, in YAML units
            object.__setattr__(obj, f.name, si)
        elif tp is str and not isinstance(value, str):
            raise ConfigError(key, value, "a string")


def _int_or(x: float | None) -> int | None:
    return None if x is None else int(x)


def _vec2(
    name: str,
    value: Any,
    bound: float = MAX_COORD_M,
    allowed: str = "a pair of finite numbers [x, y]",
) -> tuple[float, float]:
    """A pair of finite numbers, each within ``bound`` in magnitude (``allowed``: what the
    error says is allowed)."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ConfigError(name, value, allowed)
    x, y = (as_number(name, v, allowed=allowed) for v in value)
    if max(abs(x), abs(y)) > bound:
        raise ConfigError(name, value, f"{allowed}, each within +-{bound:g} in magnitude")
    return (x, y)


def _polygon(name: str, value: Any) -> tuple[tuple[float, float], ...]:
    from poc_env.geometry import validate_polygon

    if not isinstance(value, (list, tuple)) or len(value) < 3:
        raise ConfigError(name, value, "a list of at least 3 [x, y] vertices")
    pts = tuple(_vec2(f"{name}[{i}]", v) for i, v in enumerate(value))
    validate_polygon(pts, name)
    return pts


def _choice(name: str, value: Any, allowed: tuple[str, ...]) -> str:
    if not isinstance(value, str) or value not in allowed:
        raise ConfigError(name, value, "one of " + ", ".join(repr(a) for a in allowed))
    return str(value)


# --------------------------------------------------------------------------- sections

_KM_MAX = limits.MAX_EXTENT_KM
_RANGE_MAX = limits.MAX_RANGE_KM


@dataclass(frozen=True)
class GaussianComponent:
    """One component of a Gaussian-mixture prior (axes rotated by ``rotation``)."""

    mean_m: tuple[float, float] = _f("mean_km", KM)
    sigma_m: tuple[float, float] = _f("sigma_km", KM)
    #: relative weight (the mixture is normalised; any positive scale will do).
    weight: float = _f(default=1.0, lo=limits.MIN_POSITIVE)
    rotation_rad: float = _f("rotation_deg", DEG, default=0.0, lo=-3600.0, hi=3600.0)

    def __post_init__(self) -> None:
        _coerce(self)
        object.__setattr__(self, "mean_m", _vec2("mean_km", self.mean_m))
        sx, sy = _vec2("sigma_km", self.sigma_m)
        for sig in (sx, sy):
            as_number("sigma_km", sig / KM, limits.MIN_POSITIVE, _KM_MAX)
        object.__setattr__(self, "sigma_m", (sx, sy))


@dataclass(frozen=True)
class PriorConfig:
    """Where the prior POC map comes from.

    ``kind: gaussian_mixture`` builds it from ``components`` plus a uniform ``background`` share
    (the fraction of the mass spread evenly over the map); ``kind: file`` reads ``file`` (.npy or
    .csv, shape ``(ny, nx)``, row 0 at the south edge; a relative path is read from the
    scenario YAML's folder).
    """

    kind: str = _f(default="gaussian_mixture")
    components: tuple[GaussianComponent, ...] = _f(default=())
    background: float = _f(default=0.02, lo=0.0, hi=1.0)
    file: str | None = _f(default=None)

    def __post_init__(self) -> None:
        _coerce(self)
        _choice("kind", self.kind, ("gaussian_mixture", "file"))
        if self.kind == "gaussian_mixture" and not self.components and self.background <= 0:
            raise ConfigError("components", [], "at least one component, or background > 0")
        if self.kind == "file" and not self.file:
            raise ConfigError("file", self.file, "a path to a .npy or .csv map when kind is file")


@dataclass(frozen=True)
class ThreatPeak:
    """A terrain threat peak of eq. 22: f = exp(-lambda * ((x - x_p)^2 + (y - y_p)^2))."""

    center_m: tuple[float, float] = _f("center_km", KM)
    #: decay rate lambda in 1/m^2 (YAML: ``lambda_per_km2``).
    lambda_per_m2: float = _f("lambda_per_km2", 1e-6, lo=limits.MIN_POSITIVE, hi=1e6)

    def __post_init__(self) -> None:
        _coerce(self)
        object.__setattr__(self, "center_m", _vec2("center_km", self.center_m))


@dataclass(frozen=True)
class MapConfig:
    """The search area: a ``width x height`` rectangle from ``origin`` cut into square cells.

    Sides up to :data:`poc_env.limits.MAX_EXTENT_KM`, cells down to
    :data:`poc_env.limits.MIN_CELL_KM`, and no more cells than the memory guard allows.
    """

    width_m: float = _f("width_km", KM, lo=limits.MIN_POSITIVE, hi=_KM_MAX)
    height_m: float = _f("height_km", KM, lo=limits.MIN_POSITIVE, hi=_KM_MAX)
    cell_m: float = _f("cell_km", KM, lo=limits.MIN_CELL_KM, hi=_KM_MAX)
    origin_m: tuple[float, float] = _f("origin_km", KM, default=(0.0, 0.0))
    prior: PriorConfig = _f(default_factory=PriorConfig)
    no_fly_zones_m: tuple[tuple[tuple[float, float], ...], ...] = _f(
        "no_fly_zones_km", KM, default=()
    )
    #: the zones' names (``scenario import`` keeps each feature's ``name``), one per zone or
    #: none; messages name zone ``i`` as ``no-fly zone i ('name')`` (counted from 0).
    no_fly_names: tuple[str, ...] = _f(default=())
    threat_peaks: tuple[ThreatPeak, ...] = _f(default=())
    #: eq. 23 threshold Th_s on the peak threat f.
    threat_threshold: float = _f(default=0.5, lo=0.0, hi=1.0)
    #: Optional geography: (lat, lon) in degrees of the local (0, 0), and the projection
    #: between local metres and lat/lon (``aeqd``: azimuthal equidistant at that point;
    #: ``utm``: UTM zone ``utm_zone`` or the origin's). With it, ``poc-env plan`` records the
    #: plan's CRS without ``--origin`` (poc_env.agents.mission.crs.make_crs).
    origin_deg: tuple[float, float] | None = None
    projection: str = "aeqd"
    utm_zone: int | None = _f(default=None, lo=1, hi=60)

    def __post_init__(self) -> None:
        _coerce(self)
        object.__setattr__(self, "origin_m", _vec2("origin_km", self.origin_m))
        if self.origin_deg is not None:
            lat, lon = _vec2("origin_deg", self.origin_deg)
            if not (-89.9 <= lat <= 89.9 and -180.0 <= lon <= 180.0):
                raise ConfigError(
                    "origin_deg", self.origin_deg, "[lat, lon] in degrees, |lat| <= 89.9, "
                    "|lon| <= 180 (latitude first)",
                )  # fmt: skip
            object.__setattr__(self, "origin_deg", (lat, lon))
        if self.projection not in ("aeqd", "utm"):
            raise ConfigError("projection", self.projection, "aeqd or utm")
        if self.utm_zone is not None and self.projection != "utm":
            raise ConfigError("utm_zone", self.utm_zone, "null unless projection is utm")
        if self.origin_deg is None and (self.projection != "aeqd" or self.utm_zone is not None):
            raise ConfigError("origin_deg", None, "[lat, lon] when a projection is given")
        for name, size in (("width_km", self.width_m), ("height_km", self.height_m)):
            n = size / self.cell_m
            if abs(n - round(n)) > 1e-6 or round(n) < 1:
                raise ConfigError(
                    name, size / KM, f"a whole multiple of cell_km = {self.cell_m / KM:g}"
                )
        limits.check_memory(
            "cell_km",
            self.cell_m / KM,
            limits.map_bytes(self.nx * self.ny),
            f"{self.nx} x {self.ny} cell map",
        )
        if not isinstance(self.no_fly_zones_m, (list, tuple)):
            raise ConfigError("no_fly_zones_km", self.no_fly_zones_m, "a list of polygons")
        zones = tuple(
            _polygon(f"no_fly_zones_km[{i}]", z) for i, z in enumerate(self.no_fly_zones_m)
        )
        object.__setattr__(self, "no_fly_zones_m", zones)
        names = self.no_fly_names
        if not isinstance(names, (list, tuple)) or not all(isinstance(n, str) for n in names):
            raise ConfigError("no_fly_names", names, "a list of strings")
        if names and len(names) != len(zones):
            raise ConfigError(
                "no_fly_names", list(names), f"one name per no-fly zone ({len(zones)})"
            )
        for i, name in enumerate(names):
            check_name(f"no_fly_names[{i}]", name, limits.MAX_ZONE_NAME, empty=True)
        object.__setattr__(self, "no_fly_names", tuple(names))
        if zones:
            from shapely.geometry import box

            from poc_env.geometry import check_zones_leave_room

            area = box(self.origin_m[0], self.origin_m[1], self.origin_m[0] + self.width_m,
                       self.origin_m[1] + self.height_m)  # fmt: skip
            check_zones_leave_room(zones, self.no_fly_names, area, "the search area")

    def zone_label(self, i: int) -> str:
        """How messages name no-fly zone ``i`` (:func:`poc_env.geometry.zone_label`)."""
        from poc_env.geometry import zone_label

        return zone_label(i, self.no_fly_names)

    @property
    def nx(self) -> int:
        return round(self.width_m / self.cell_m)

    @property
    def ny(self) -> int:
        return round(self.height_m / self.cell_m)


_SPEED: dict[str, Any] = {"lo": limits.MIN_POSITIVE, "hi": limits.MAX_SPEED_KMH}
_RATE: dict[str, Any] = {"lo": limits.MIN_POSITIVE, "hi": limits.MAX_RATE_DEG_S}
_ALT: dict[str, Any] = {"lo": limits.MIN_POSITIVE, "hi": limits.MAX_ALTITUDE_M}
_VERTICAL: dict[str, Any] = {"lo": 0.0, "lo_open": True, "hi": limits.MAX_VERTICAL_RATE_MPS}


@dataclass(frozen=True)
class UAVConfig:
    """One UAV type (the swarm is homogeneous). Defaults are the paper's §6 values."""

    #: maximum endurance T (eq. 18).
    endurance_s: float = _f(
        "endurance_h", HOUR, default=3 * HOUR, lo=limits.MIN_ENDURANCE_H, hi=limits.MAX_ENDURANCE_H
    )
    #: share of T usable for the plan: t_i <= 0.85 T (eq. 18).
    usable_fraction: float = _f(default=0.85, lo=0.01, hi=1.0)
    #: cruise (transit) speed v_b (eq. 17).
    cruise_speed_mps: float = _f("cruise_speed_kmh", KMH, default=220 * KMH, **_SPEED)
    #: search speed v_s (eq. 17).
    search_speed_mps: float = _f("search_speed_kmh", KMH, default=180 * KMH, **_SPEED)
    #: speed bounds of the eq. 19 point mass.
    min_speed_mps: float = _f("min_speed_kmh", KMH, default=100 * KMH, **_SPEED)
    max_speed_mps: float = _f("max_speed_kmh", KMH, default=240 * KMH, **_SPEED)
    #: per-step limits of the eq. 19 increments (dv, d alpha, d beta).
    max_accel_mps2: float = _f(
        "max_accel_mps2", 1.0, default=0.5, lo=limits.MIN_POSITIVE, hi=limits.MAX_ACCEL_MPS2
    )
    max_turn_rate_rad_s: float = _f("max_turn_rate_deg_s", DEG, default=3.0 * DEG, **_RATE)
    max_pitch_rate_rad_s: float = _f("max_pitch_rate_deg_s", DEG, default=1.0 * DEG, **_RATE)
    max_pitch_rad: float = _f(
        "max_pitch_deg", DEG, default=15.0 * DEG, lo=limits.MIN_POSITIVE, hi=limits.MAX_PITCH_DEG
    )
    #: search altitude (z of eq. 19) and the ceiling.
    cruise_altitude_m: float = _f("cruise_altitude_m", 1.0, default=1000.0, **_ALT)
    max_altitude_m: float = _f("max_altitude_m", 1.0, default=4000.0, **_ALT)
    #: the aircraft's vertical rate limits (m/s) for its exported missions over terrain: the
    #: most it climbs (PX4 ``FW_T_CLMB_MAX``, ArduPlane ``TECS_CLMB_MAX``; both default 5 m/s)
    #: and sinks (``FW_T_SINK_MAX``, ``TECS_SINK_MAX``; 5 m/s). Null (the default): eq. 19's
    #: pitch bound alone, as the environment flies. Read only by the mission's terrain profile
    #: (:mod:`poc_env.agents.mission.terrain`), never by the environment's tasks.
    max_climb_rate_mps: float | None = _f("max_climb_rate_mps", 1.0, default=None, **_VERTICAL)
    max_sink_rate_mps: float | None = _f("max_sink_rate_mps", 1.0, default=None, **_VERTICAL)

    def __post_init__(self) -> None:
        _coerce(self)
        if self.min_speed_mps > self.max_speed_mps:
            raise ConfigError("min_speed_kmh", self.min_speed_mps / KMH, "at most max_speed_kmh")
        for name in ("cruise_speed_mps", "search_speed_mps"):
            v = getattr(self, name)
            if not (self.min_speed_mps - 1e-9 <= v <= self.max_speed_mps + 1e-9):
                raise ConfigError(
                    _yaml_key(UAVConfig, name),
                    v / KMH,
                    f"within [min_speed_kmh, max_speed_kmh] = [{self.min_speed_mps / KMH:g}, "
                    f"{self.max_speed_mps / KMH:g}]",
                )
        if self.cruise_altitude_m > self.max_altitude_m:
            raise ConfigError("cruise_altitude_m", self.cruise_altitude_m, "<= max_altitude_m")

    @property
    def usable_endurance_s(self) -> float:
        """0.85 T of eq. 18 (with the configured fraction)."""
        return self.usable_fraction * self.endurance_s


#: ``sensor.sweep_width_km``'s default, the paper's §6 W = 5 km (metres).
DEFAULT_SWEEP_WIDTH_M = 5 * KM


@dataclass(frozen=True)
class SensorConfig:
    """The downward sensor: sweep width W and the detection law.

    ``law`` is a name of the table of laws (:mod:`poc_env.theory.detection`), validated against
    the names of their compiled branches (:data:`poc_env._kernels.sensing.LAW_CODES`), which
    the table checks it covers.
    """

    #: W; not given (None): :data:`DEFAULT_SWEEP_WIDTH_M` for ``fixed``, the model's W for
    #: ``camera``. Whether it was given is kept (``width_given``): a width given beside a
    #: model that computes it is refused unless it is the model's own (terrain follow-up: a
    #: given 5 km, the default's value, was silently replaced).
    sweep_width_m: float = _f(
        "sweep_width_km",
        KM,
        default=None,
        lo=limits.MIN_POSITIVE,
        hi=limits.MAX_SWEEP_WIDTH_KM,
    )
    #: ``inverse_cube`` (Koopman, composes to eq. 10), ``exponential`` (random search) or
    #: ``definite_range`` (cookie cutter).
    law: str = _f(default="inverse_cube")
    #: target positions sampled per cell side (s x s points per cell) for cell averages. The
    #: default 2 keeps a lawnmower at S = W within 1.4 % of eq. 10 through step() at twice the
    #: speed of 4 (measured by `poc-env bench env`; see the README).
    samples_per_cell: int = _f(default=2, lo=1, hi=16)
    #: lateral cut-off of the inverse-cube tail, in sweep widths (see sensing.cutoff_error).
    cutoff_sweep_widths: float = _f(default=4.0, lo=0.5, hi=100.0)
    #: where W comes from (:meth:`sweep_width_at`): ``fixed`` (``sweep_width_km``, the
    #: paper's; default) or ``camera`` (the footprint of a downward camera of cross-track field
    #: of view ``fov_deg`` at the search height ``uav.cruise_altitude_m`` above ground, times
    #: ``detection_factor``). With ``camera`` the scenario's ``sweep_width_km`` is the model's
    #: value, resolved once when the scenario loads, so the planner, the bounds and the
    #: environment all read the same W.
    model: str = _f(default="fixed")
    fov_deg: float = _f(default=60.0, lo=0.1, hi=170.0)
    detection_factor: float = _f(default=1.0, lo=limits.MIN_POSITIVE, hi=1.0)

    def __post_init__(self) -> None:
        given = self.sweep_width_m is not None
        object.__setattr__(self, "width_given", given)  # not a field: no YAML key, no compare
        if not given:
            object.__setattr__(self, "sweep_width_m", DEFAULT_SWEEP_WIDTH_M)
        _coerce(self)
        _choice("law", self.law, tuple(LAW_CODES))
        _choice("model", self.model, SENSOR_MODELS)

    def sweep_width_at(self, height_m: float) -> float:
        """The sweep width W (m) at ``height_m`` above the ground: the sensor model (issue 24),
        the one implementation (:meth:`Scenario._resolve_sweep_width` reads it once at load).

        ``fixed``: ``sweep_width_km`` whatever the height (the paper's §6, W = 5 km; the
        default, which every registered task keeps). ``camera``: a nadir sensor of cross-track
        field of view ``fov`` sees a footprint ``2 h tan(fov / 2)`` wide at height ``h``; the
        effective sweep width is ``W = k 2 h tan(fov / 2)``, ``k = detection_factor`` in
        (0, 1] the share of the footprint over which the target class is detected as the
        detection law assumes (1: all of it; less for small targets or poor resolution at the
        edges). ``h`` is ``uav.cruise_altitude_m``: over a DEM the missions fly that height
        above the ground where eq. 19's climb limit allows, higher over ridges (the footprint
        is wider there; :mod:`poc_env.agents.mission.terrain`).
        """
        if self.model == "fixed":
            return float(self.sweep_width_m)
        if not height_m > 0:
            raise ConfigError("uav.cruise_altitude_m", height_m, "a height > 0 m")
        return self.detection_factor * 2.0 * height_m * math.tan(math.radians(self.fov_deg) / 2)


#: The sensor models of ``sensor.model`` (:meth:`SensorConfig.sweep_width_at`).
SENSOR_MODELS = ("fixed", "camera")


@dataclass(frozen=True)
class TerrainConfig:
    """The ground under the operating area (issue 24): a DEM, or none (the paper's flat map).

    ``dem``: a GeoTIFF of ground heights above mean sea level in metres, in any CRS rasterio
    reads (a relative path is read from the scenario YAML's folder); it is resampled onto a
    grid of ``cell_km`` cells (default the map's cell, at most 1 km) aligned with the map and
    covering eq. 20's operating area, by
    :func:`poc_env.agents.mission.terrain.load_terrain` (the scenario needs
    ``map.origin_deg``). ``elevation_m``: the same grid given directly, rows from the south,
    ``[ny][nx]`` metres AMSL, its south-west corner at ``origin_km`` (default the operating
    area's) in ``cell_km`` cells. Missions fly ``uav.cruise_altitude_m`` above the ground where
    the climb limit of eq. 19 allows, never less than ``min_clearance_m`` above it, never above
    ``uav.max_altitude_m`` (read as AMSL when a DEM is given).
    """

    dem: str | None = _f(default=None)
    elevation_m: tuple[tuple[float, ...], ...] | None = _f(default=None)
    origin_m: tuple[float, float] | None = _f("origin_km", KM, default=None)
    cell_m: float | None = _f("cell_km", KM, default=None, lo=0.01, hi=_KM_MAX)
    #: least height above the highest ground near any point of a mission (not the take-off
    #: climb or the final glide to the field, flown by the airfield's procedures).
    min_clearance_m: float = _f(default=150.0, lo=0.0, hi=limits.MAX_ALTITUDE_M)

    def __post_init__(self) -> None:
        _coerce(self)
        if self.dem is not None and self.elevation_m is not None:
            raise ConfigError("dem", self.dem, "null when elevation_m is given (one source)")
        if self.origin_m is not None:
            object.__setattr__(self, "origin_m", _vec2("origin_km", self.origin_m))
        if self.elevation_m is not None:
            rows = self.elevation_m
            allowed = "a list of equal rows of finite heights in metres (at least 2 x 2)"
            if not isinstance(rows, (list, tuple)) or len(rows) < 2:
                raise ConfigError("elevation_m", rows, allowed)
            try:
                arr = np.asarray(rows, dtype=float)
            except (TypeError, ValueError):
                raise ConfigError("elevation_m", "ragged or non-numeric rows", allowed) from None
            if arr.ndim != 2 or arr.shape[1] < 2:
                raise ConfigError("elevation_m", f"shape {arr.shape}", allowed)
            bad = ~np.isfinite(arr) | (np.abs(arr) > 12_000.0)
            if bad.any():
                i, j = (int(v) for v in np.argwhere(bad)[0])
                raise ConfigError(
                    f"elevation_m[{i}][{j}]", rows[i][j], "a finite height in [-12000, 12000] m"
                )
            limits.check_memory("elevation_m", arr.shape, arr.nbytes, "terrain grid")
            object.__setattr__(self, "elevation_m", tuple(tuple(map(float, r)) for r in arr))

    @property
    def given(self) -> bool:
        """A DEM or an elevation grid is given."""
        return self.dem is not None or self.elevation_m is not None


@dataclass(frozen=True)
class Airfield:
    """A take-off / landing field, in map coordinates (it may lie outside the search area)."""

    name: str = _f()
    position_m: tuple[float, float] = _f("position_km", KM)

    def __post_init__(self) -> None:
        check_name("name", self.name, limits.MAX_AIRFIELD_NAME)  # what every export carries
        object.__setattr__(self, "position_m", _vec2("position_km", self.position_m))


@dataclass(frozen=True)
class FleetGroup:
    """``count`` UAVs that take off from ``takeoff`` and land at ``landing`` (default: same)."""

    takeoff: str = _f()
    count: int = _f(default=1, lo=0, hi=64)
    landing: str | None = _f(default=None)

    def __post_init__(self) -> None:
        _coerce(self)
        if self.landing is None:
            object.__setattr__(self, "landing", self.takeoff)


@dataclass(frozen=True)
class CommsConfig:
    """Communication constraint (eq. 24) and topology switching (§3.2.5)."""

    range_m: float = _f("range_km", KM, default=150 * KM, lo=limits.MIN_POSITIVE, hi=_RANGE_MAX)
    #: every UAV needs at least this many others within range (the paper: two).
    min_neighbours: int = _f(default=2, lo=0, hi=63)
    #: ``table2`` (the paper's five-UAV switching table) or ``auto`` (any N).
    topology: str = _f(default="auto")
    #: probability per step that a link in range drops anyway.
    link_failure_prob: float = _f(default=0.0, lo=0.0, hi=1.0)
    #: ``global`` (the paper: one shared belief) or ``comms`` (merge only through links).
    belief_sharing: str = _f(default="global")

    def __post_init__(self) -> None:
        _coerce(self)
        _choice("topology", self.topology, ("auto", "table2"))
        _choice("belief_sharing", self.belief_sharing, ("global", "comms"))


@dataclass(frozen=True)
class ConstraintsConfig:
    """Safety constraints (§3.2.3) and how a violation is handled."""

    #: minimum separation d_s between UAVs (eq. 21).
    safety_distance_m: float = _f(
        "safety_distance_km", KM, default=1 * KM, lo=limits.MIN_POSITIVE, hi=_RANGE_MAX
    )
    #: ``penalize`` (report and subtract a penalty), ``terminate`` (the agent ends) or
    #: ``shield`` (the action is modified to stay safe).
    violation: str = _f(default="penalize")

    def __post_init__(self) -> None:
        _coerce(self)
        _choice("violation", self.violation, ("penalize", "terminate", "shield"))


_WEIGHT: dict[str, Any] = {"lo": 0.0, "hi": limits.MAX_WEIGHT}


@dataclass(frozen=True)
class RewardConfig:
    """Weights of the reward: alpha * POS - beta * time share (eq. 25) - penalties."""

    alpha: float = _f(default=1.0, **_WEIGHT)
    beta: float = _f(default=0.0, **_WEIGHT)
    #: ``team`` (every agent gets the swarm's POS) or ``individual`` (own POS only).
    credit: str = _f(default="team")
    #: per step and agent, for each step with a safety or communication violation.
    violation_penalty: float = _f(default=0.01, **_WEIGHT)
    #: per step and agent flying beyond 0.85 T (eq. 18).
    overtime_penalty: float = _f(default=0.01, **_WEIGHT)
    #: once, when an agent crashes (ground, endurance, or a violation in ``terminate`` mode).
    crash_penalty: float = _f(default=0.1, **_WEIGHT)

    def __post_init__(self) -> None:
        _coerce(self)
        _choice("credit", self.credit, ("team", "individual"))


@dataclass(frozen=True)
class EpisodeConfig:
    """Time stepping of the environment."""

    dt_s: float = _f("dt_s", 1.0, default=60.0, lo=limits.MIN_POSITIVE, hi=limits.MAX_DT_S)
    #: truncation horizon in steps (default: endurance T / dt, rounded up).
    horizon_steps: int | None = _f(default=None, lo=1, hi=limits.MAX_STEPS)
    detection_ends_episode: bool = _f(default=False)
    #: landing rule: within this horizontal distance of the landing field ...
    landing_radius_m: float = _f(
        "landing_radius_km", KM, default=3 * KM, lo=limits.MIN_POSITIVE, hi=_KM_MAX
    )
    #: ... at or below this altitude (default above the cruise altitude: no descent needed) ...
    landing_max_altitude_m: float = _f("landing_max_altitude_m", 1.0, default=1500.0, **_ALT)
    #: ... and at or below this speed (an approach: the UAV must slow down to land).
    landing_max_speed_mps: float = _f("landing_max_speed_kmh", KMH, default=130 * KMH, **_SPEED)
    #: the operating area (eq. 20's boundary) is the bounding box of the grid and the
    #: airfields, grown by this margin on every side.
    boundary_margin_m: float = _f("boundary_margin_km", KM, default=20 * KM, lo=0.0, hi=_KM_MAX)

    def __post_init__(self) -> None:
        _coerce(self)


#: What ``target.current_kmh`` and ``target.wind_kmh`` allow: a velocity, pointing where the
#: water or air goes (oceanographic; a weather report gives the wind's "from" direction).
VELOCITY_ALLOWED = (
    "a pair of finite numbers [east, north] km/h: the velocity, toward where the water or air "
    "goes (a wind from the west is [+speed, 0])"
)


@dataclass(frozen=True)
class TargetConfig:
    """How the lost target moves (issue 25): a model of the table in
    :mod:`poc_env.theory.motion` and its coefficients.

    ``model`` ``static`` (the paper, default: nothing moves), ``diffusion`` (a random walk of
    coefficient ``diffusion_m2_s``), ``drift`` (advection by the current plus diffusion) or
    ``leeway`` (current plus the leeway of ``leeway_class`` in the 10 m wind ``wind_kmh`` or
    the gridded wind of ``wind_file``, plus diffusion). The current is ``current_kmh`` (east,
    north; toward where the water goes, as ``wind_kmh`` is toward where the air goes), plus at
    each reset one of speed ``U(0, random_current_kmh)`` in a uniform direction
    drawn from the env's generator, plus (``drift``, ``leeway``) the gridded field of
    ``field_file`` (a ``.npy`` of m/s, ``(2, ny, nx)`` or ``(T, 2, ny, nx)`` frames
    ``field_dt_s`` apart, or a ``.csv`` / CF NetCDF ``.nc`` current interpolated onto the
    cells and the episode from ``field_start``, :mod:`poc_env.theory.fields`; a relative path
    is read from the scenario's folder). The
    model name and the leeway class are checked against their tables when the scenario loads
    (the class whatever the model: a scenario switched to ``leeway`` later must not meet a typo
    then); the field against the map when the dynamics are built
    (:func:`poc_env.theory.motion.check`).
    """

    model: str = _f(default="static")
    diffusion_m2_s: float = _f(default=0.0, lo=0.0, hi=1e7)
    current_kmh: tuple[float, float] = _f(default=(0.0, 0.0))
    random_current_kmh: float = _f(default=0.0, lo=0.0, hi=100.0)
    wind_kmh: tuple[float, float] = _f(default=(0.0, 0.0))
    leeway_class: str = _f(default="person_in_water")
    field_file: str | None = _f(default=None)
    field_dt_s: float | None = _f(default=None, lo=limits.MIN_POSITIVE, lo_open=False, hi=1e9)
    #: the episode's start on a dated ``.csv``/``.nc`` field's time axis (ISO 8601, UTC);
    #: default the file's first time (:mod:`poc_env.theory.fields`)
    field_start: str | None = _f(default=None)
    #: (``leeway``) a gridded, time-varying 10 m wind instead of ``wind_kmh``: a ``.npy`` of m/s
    #: on the map's cells (frames ``wind_dt_s`` apart) or a ``.csv`` / CF ``.nc`` wind
    #: (``eastward_wind``/``northward_wind``), read as ``field_file`` is; its episode start
    #: ``wind_start``
    wind_file: str | None = _f(default=None)
    wind_dt_s: float | None = _f(default=None, lo=limits.MIN_POSITIVE, lo_open=False, hi=1e9)
    wind_start: str | None = _f(default=None)
    #: (``particles``) the ``.npz`` of particle tracks that move the belief and the target
    #: (:mod:`poc_env.theory.particles`; ``poc-env scenario import --particle-motion``)
    particles_file: str | None = _f(default=None)

    def __post_init__(self) -> None:
        for key in ("field_start", "wind_start"):
            t = getattr(self, key)
            if isinstance(t, (datetime.date, datetime.datetime)):
                # YAML reads an unquoted ISO 8601 time as a datetime: back to UTC text
                if isinstance(t, datetime.datetime) and t.tzinfo is not None:
                    t = t.astimezone(datetime.timezone.utc).replace(tzinfo=None)
                object.__setattr__(self, key, t.isoformat())
        _coerce(self)
        _choice("model", self.model, MOTION_MODEL_NAMES)  # a typo is refused at load
        _choice("leeway_class", self.leeway_class, LEEWAY_CLASS_NAMES)  # whatever the model
        for key in ("current_kmh", "wind_kmh"):
            u, v = _vec2(key, getattr(self, key), bound=400.0, allowed=VELOCITY_ALLOWED)
            object.__setattr__(self, key, (u, v))
        if self.field_file is not None and self.model not in ("drift", "leeway"):
            raise ConfigError(
                "field_file", self.field_file, "null unless model is 'drift' or 'leeway'"
            )
        if self.wind_file is not None and self.model != "leeway":
            raise ConfigError("wind_file", self.wind_file, "null unless model is 'leeway'")
        if (self.particles_file is None) == (self.model == "particles"):
            raise ConfigError(
                "particles_file",
                self.particles_file,
                "the .npz of particle tracks with model 'particles' (poc-env scenario import "
                "--particle-motion), null otherwise",
            )

    @property
    def moves(self) -> bool:
        """The target moves (any model but ``static``)."""
        return self.model != "static"


#: Names of the target motion models (``target.model``), checked when a scenario loads; the
#: table of what each does is :data:`poc_env.theory.motion.MODELS`, which checks at import
#: that it names exactly these (as the detection laws check ``LAW_CODES``).
MOTION_MODEL_NAMES = ("static", "diffusion", "drift", "leeway", "particles")

#: Names of the leeway classes (``target.leeway_class``), checked when a scenario loads; the
#: classes' coefficients are :data:`poc_env.theory.motion.LEEWAY_CLASSES`, which checks at
#: import that it names exactly these.
LEEWAY_CLASS_NAMES = (
    "person_in_water",
    "piw_vertical_pfd",
    "life_raft_deep_ballast",
    "life_raft_no_ballast",
    "skiff",
    "fishing_vessel",
)


@dataclass(frozen=True)
class PlannerConfig:
    """The §6.2 planner: adaptive DE settings (§6: NP = 100, G = 300, F0 = 0.2, CR = 0.1), the
    weights of eq. 25 and the penalty factor M of eq. 26.

    ``alpha`` and ``beta`` are the planner's own, apart from ``reward.alpha`` / ``reward.beta``
    of the RL reward, so that a training override (``reward.alpha=100``) never changes a plan.
    Their defaults, POS only and time free, are the time-limited search of §6.2: as much POS as
    the usable endurance allows.
    """

    population: int = _f(default=100, lo=4, hi=limits.POPSIZE_MAX)
    generations: int = _f(default=300, lo=1, hi=limits.MAXITER_MAX)
    f0: float = _f(default=0.2, lo=0.0, hi=2.0)
    cr: float = _f(default=0.1, lo=0.0, hi=1.0)
    penalty_m: float = _f(default=1000.0, **_WEIGHT)
    #: eq. 25 weight of the plan's cumulative POS (POS_C).
    alpha: float = _f(default=1.0, **_WEIGHT)
    #: eq. 25 weight of the UAVs' mean flight-time share t_i / (0.85 T) (a cost).
    beta: float = _f(default=0.0, **_WEIGHT)

    def __post_init__(self) -> None:
        _coerce(self)


@dataclass(frozen=True)
class Scenario:
    """A whole scenario: map, UAVs, sensor, airfields, fleet, comms, constraints, reward."""

    name: str = _f()
    map: MapConfig = _f()
    description: str = _f(default="")
    uav: UAVConfig = _f(default_factory=UAVConfig)
    sensor: SensorConfig = _f(default_factory=SensorConfig)
    airfields: tuple[Airfield, ...] = _f(default=())
    fleet: tuple[FleetGroup, ...] = _f(default=())
    comms: CommsConfig = _f(default_factory=CommsConfig)
    constraints: ConstraintsConfig = _f(default_factory=ConstraintsConfig)
    reward: RewardConfig = _f(default_factory=RewardConfig)
    episode: EpisodeConfig = _f(default_factory=EpisodeConfig)
    planner: PlannerConfig = _f(default_factory=PlannerConfig)
    target: TargetConfig = _f(default_factory=TargetConfig)
    terrain: TerrainConfig = _f(default_factory=TerrainConfig)

    def __post_init__(self) -> None:
        _coerce(self)
        self._resolve_sweep_width()
        if not self.airfields:
            raise ConfigError("airfields", [], "at least one airfield")
        names = [a.name for a in self.airfields]
        if len(set(names)) != len(names):
            raise ConfigError("airfields", names, "distinct airfield names")
        for i, g in enumerate(self.fleet):
            for key in ("takeoff", "landing"):
                if getattr(g, key) not in names:
                    raise ConfigError(f"fleet[{i}].{key}", getattr(g, key), f"one of {names}")
        if not 1 <= self.n_uavs <= MAX_UAVS:
            raise ConfigError(
                "fleet", [dataclasses.asdict(g) for g in self.fleet], f"1 to {MAX_UAVS} UAVs"
            )
        c, d_s = self.comms, self.constraints.safety_distance_m
        if self.n_uavs > 1 and c.min_neighbours > 0 and c.range_m < d_s:
            raise ConfigError(
                "comms.range_km", c.range_m / KM,
                f"at least constraints.safety_distance_km = {d_s / KM:g} while "
                f"comms.min_neighbours is {c.min_neighbours} (eq. 24's neighbours in range "
                "and eq. 21's separation cannot both hold: every step would be a violation), "
                "or comms.min_neighbours: 0",
            )  # fmt: skip
        if self.episode.dt_s > self.uav.endurance_s:
            raise ConfigError(
                "episode.dt_s", self.episode.dt_s,
                f"at most the endurance, uav.endurance_h x 3600 = {self.uav.endurance_s:g} s (UAVs "
                "fly whole steps: "
                "with a longer step each one flies and senses past its endurance in its first "
                "step and crashes, whatever it does)",
            )  # fmt: skip
        self._check_filter_work()
        steps = self.horizon_steps
        if steps > limits.MAX_STEPS:
            raise ConfigError(
                "episode.dt_s",
                self.episode.dt_s,
                f"a step for which endurance_h / dt_s is at most {limits.MAX_STEPS} steps "
                f"(it gives {steps:.3g})",
            )
        from poc_env.geometry import point_in_polygon

        for a in self.airfields:
            for k, zone in enumerate(self.map.no_fly_zones_m):
                if point_in_polygon(a.position_m, zone):
                    raise ConfigError(
                        f"airfields[{a.name}].position_km",
                        [c / KM for c in a.position_m],
                        f"a point outside {self.map.zone_label(k)}",
                    )

    def _check_filter_work(self) -> None:
        """A moving target's predict step within :data:`poc_env.limits.MAX_FILTER_SUBSTEPS`
        sub-steps (the one stability rule, ``poc_env._kernels.motion.substeps``, which
        :func:`poc_env.theory.motion.substeps` wraps; at the largest uniform current a reset
        can draw) and :data:`~poc_env.limits.
        MAX_FILTER_UPDATES` sub-steps times the filter's sub-cells (``cell_km /
        samples_per_cell``); ConfigError naming the diffusion (or the current) otherwise."""
        t = self.target
        if not t.moves or t.model == "particles":
            return
        from poc_env._kernels.motion import substeps  # the stability rule's one kernel

        s = self.sensor.samples_per_cell
        h, dt, d = self.map.cell_m / s, self.episode.dt_s, t.diffusion_m2_s
        rand = t.random_current_kmh * KMH
        u, v = abs(t.current_kmh[0]) * KMH + rand, abs(t.current_kmh[1]) * KMH + rand
        cells = self.map.nx * self.map.ny * s * s
        n = int(substeps(float(u), float(v), float(d), float(dt), float(h)))
        if n * cells <= limits.MAX_FILTER_UPDATES and n <= limits.MAX_FILTER_SUBSTEPS:
            return
        most = min(math.floor(limits.MAX_FILTER_UPDATES / cells), limits.MAX_FILTER_SUBSTEPS)
        d_max = (most / dt - (u + v) / h) * h * h / 4.0
        where = (
            f"on {self.map.nx * s} x {self.map.ny * s} filter sub-cells of {h:g} m at dt "
            f"{dt:g} s (its predict step is at most {limits.MAX_FILTER_SUBSTEPS} stability "
            f"sub-steps and {limits.MAX_FILTER_UPDATES:g} cell updates; raise map.cell_km or "
            "lower episode.dt_s)"
        )
        if d_max > 0:
            raise ConfigError("target.diffusion_m2_s", d, f"at most {d_max:.3g} m^2/s {where}")
        raise ConfigError(
            "target.current_kmh", list(t.current_kmh),
            f"a current (with random_current_kmh) slow enough {where}",
        )  # fmt: skip

    def _resolve_sweep_width(self) -> None:
        """``sensor.sweep_width_m`` from ``sensor.model`` (:meth:`SensorConfig.sweep_width_at`)
        at the search height: the one W the planner, the bounds and the environment read."""
        s = self.sensor
        if s.model == "fixed":
            return
        w = s.sweep_width_at(self.uav.cruise_altitude_m)
        given = s.sweep_width_m
        if getattr(s, "width_given", True) and abs(given - w) > 1e-6 * max(w, 1.0):
            raise ConfigError(
                "sensor.sweep_width_km", given / KM,
                f"absent when sensor.model is {s.model!r} (the model gives {w / KM:.6g} km at "
                f"cruise_altitude_m {self.uav.cruise_altitude_m:g} m)",
            )  # fmt: skip
        if not limits.MIN_POSITIVE <= w / KM <= limits.MAX_SWEEP_WIDTH_KM:
            raise ConfigError(
                "sensor.model", s.model,
                f"a model giving a sweep width in (0, {limits.MAX_SWEEP_WIDTH_KM:g}] km (it "
                f"gives {w / KM:.6g} km)",
            )  # fmt: skip
        object.__setattr__(self, "sensor", dataclasses.replace(s, sweep_width_m=w))

    # -- derived ---------------------------------------------------------------------------
    @property
    def horizon_steps(self) -> int:
        """Steps of an episode: ``episode.horizon_steps``, else endurance T / dt rounded up."""
        return self.episode.horizon_steps or math.ceil(self.uav.endurance_s / self.episode.dt_s)

    @property
    def n_uavs(self) -> int:
        return sum(g.count for g in self.fleet)

    def airfield(self, name: str) -> Airfield:
        for a in self.airfields:
            if a.name == name:
                return a
        raise ConfigError("airfield", name, f"one of {[a.name for a in self.airfields]}")

    @property
    def takeoff_m(self) -> tuple[tuple[float, float], ...]:
        """Take-off position of each UAV, in fleet order."""
        return tuple(
            self.airfield(g.takeoff).position_m for g in self.fleet for _ in range(g.count)
        )

    @property
    def landing_m(self) -> tuple[tuple[float, float], ...]:
        """Landing position of each UAV, in fleet order."""
        return tuple(
            self.airfield(g.landing).position_m  # type: ignore[arg-type]
            for g in self.fleet
            for _ in range(g.count)
        )

    def with_uavs(self, n: int) -> Scenario:
        """The same scenario with ``n`` UAVs, the fleet's own take-off/landing pairs first.

        The fleet's UAVs are taken one from each group in turn (round-robin over ``fleet``, a
        group left out once its own count is used): ``n`` up to the fleet's size are the first
        ``n`` of that order, so ``n`` equal to the fleet's size is the fleet itself and each
        UAV lands where its group lands (i24-smallfix, F4: before, every UAV was spread over
        the airfields and landed where it took off, the fleet's landing fields dropped). Beyond
        the fleet's size, UAV ``j`` (from 0) takes off from airfield ``j mod A`` (the
        scenario's ``A`` airfields in order) and lands there, as before. Where the fleet spreads
        evenly over the airfields in their order and lands where it took off (every built-in
        scenario's fleet), the fleets are the same as before for every ``n``.

        Parameters
        ----------
        n : int
            The number of UAVs, 1 to ``MAX_UAVS``.

        Returns
        -------
        Scenario
            The scenario with ``fleet`` replaced: the fleet's groups in its order with their
            new counts, the UAVs beyond the fleet added to the group that takes off from and
            lands at their airfield, else in a new group after them (empty groups left out).
        """
        n = as_int("uavs", n, 1, MAX_UAVS)
        left = [g.count for g in self.fleet]
        order: list[int] = []  # group of each UAV of the fleet, round-robin over the groups
        while any(left):
            for i, c in enumerate(left):
                if c:
                    order.append(i)
                    left[i] -= 1
        own = [0] * len(self.fleet)
        for i in order[:n]:
            own[i] += 1
        more = [0] * len(self.airfields)
        for j in range(len(order), n):
            more[j % len(self.airfields)] += 1
        fleet = [dataclasses.replace(g, count=c) for g, c in zip(self.fleet, own, strict=True)]
        for a, c in zip(self.airfields, more, strict=True):  # into the field's own group if any
            at = next((i for i, g in enumerate(fleet) if g.takeoff == g.landing == a.name), None)
            if at is None:
                fleet.append(FleetGroup(takeoff=a.name, count=c))
            else:
                fleet[at] = dataclasses.replace(fleet[at], count=fleet[at].count + c)
        return dataclasses.replace(self, fleet=tuple(g for g in fleet if g.count))

    def to_dict(self) -> dict[str, Any]:
        """The YAML mapping (keys with units) that loads back to this scenario."""
        return _to_mapping(self)


# --------------------------------------------------------------------------- (de)serialise


def _yaml_key(cls: type, name: str) -> str:
    for f in dataclasses.fields(cls):
        if f.name == name:
            return f.metadata.get("key") or f.name
    return name


def _resolve_hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _strip_optional(tp: Any) -> Any:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0]
    return tp


def _plain(value: Any) -> Any:
    """numpy scalars and arrays as the Python numbers and lists they hold (``np.int64(1)`` ->
    ``1``), so that unit scaling and validation treat them exactly like YAML values."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return type(value)(_plain(v) for v in value)
    return value


def _scale_value(value: Any, scale: float) -> Any:
    if scale == 1.0 or value is None:
        return value
    if isinstance(value, (list, tuple)):
        return tuple(_scale_value(v, scale) for v in value)
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)):
        try:
            return float(value) * scale
        except OverflowError:  # an int beyond the float range: validation names it
            return value
    return value  # leave it to validation to complain


def _from_mapping(cls: type, data: Any, where: str) -> Any:
    """Build dataclass ``cls`` from a YAML mapping, rejecting unknown keys."""
    if not isinstance(data, Mapping):
        raise ConfigError(where or cls.__name__, data, f"a mapping of {cls.__name__} keys")
    hints = _resolve_hints(cls)
    fields = {(f.metadata.get("key") or f.name): f for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        name = f"{where}.{unknown[0]}" if where else str(unknown[0])
        raise ConfigError(name, data[unknown[0]], "one of the keys " + ", ".join(sorted(fields)))
    kwargs: dict[str, Any] = {}
    for key, f in fields.items():
        if key not in data:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise ConfigError(f"{where}.{key}" if where else key, None, "a value (required)")
            continue
        value = _plain(data[key])
        sub = f"{where}.{key}" if where else key
        tp = _strip_optional(hints[f.name])
        if isinstance(tp, type) and dataclasses.is_dataclass(tp):
            kwargs[f.name] = _from_mapping(tp, value if value is not None else {}, sub)
            continue
        args = typing.get_args(tp)
        if (
            typing.get_origin(tp) is tuple
            and args
            and isinstance(args[0], type)
            and dataclasses.is_dataclass(args[0])
        ):
            if not isinstance(value, (list, tuple)):
                raise ConfigError(sub, value, f"a list of {args[0].__name__} mappings")
            kwargs[f.name] = tuple(
                _from_mapping(args[0], v, f"{sub}[{i}]") for i, v in enumerate(value)
            )
            continue
        kwargs[f.name] = _scale_value(value, f.metadata.get("scale", 1.0))
    try:
        return cls(**kwargs)
    except ConfigError as err:
        if err.field in data and err.field in fields:  # show the value as the user wrote it
            err = ConfigError(err.field, data[err.field], err.allowed)
        raise err.with_prefix(where) from None
    except TypeError as err:  # e.g. a list where a number belongs
        raise ConfigError(where or cls.__name__, dict(data), str(err)) from None


def _to_mapping(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj):
        out = {}
        for f in dataclasses.fields(obj):
            key = f.metadata.get("key") or f.name
            value = getattr(obj, f.name)
            scale = f.metadata.get("scale", 1.0)
            out[key] = _to_mapping(_scale_value(value, 1.0 / scale) if scale != 1.0 else value)
        return out
    if isinstance(obj, (list, tuple)):
        return [_to_mapping(v) for v in obj]
    if isinstance(obj, float):
        return float(f"{obj:.12g}")
    return obj


def _set_dotted(data: dict[str, Any], dotted: str, value: Any) -> None:
    parts = dotted.split(".")
    node = data
    for p in parts[:-1]:
        nxt = node.get(p)
        if nxt is None:
            nxt = node[p] = {}
        if not isinstance(nxt, dict):
            raise ConfigError(dotted, value, f"a key inside the mapping {p!r}")
        node = nxt
    node[parts[-1]] = value


def builtin_scenarios() -> list[str]:
    """Names of the scenarios shipped in ``configs/``."""
    return sorted(p.stem for p in CONFIG_DIR.glob("*.yaml"))


#: Most nodes a YAML document may expand to, with every alias (``*name``) counted as a copy of
#: what it names. The built-in scenarios have a few hundred; a "billion laughs" document of
#: under 1 kB nests aliases to expand to 10^9 nodes.
MAX_YAML_NODES = 100_000
#: Largest YAML file read, bytes (the built-in scenarios are about 2 kB).
MAX_YAML_BYTES = 4 * 2**20
#: Deepest nesting of YAML collections read (the built-in scenarios nest 4 deep); a deeper
#: document is refused before the parser's recursion could run out of stack.
MAX_YAML_DEPTH = 64


class _LimitedLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses documents expanding to more than MAX_YAML_NODES nodes
    (counted on the composed graph, before anything is built) or nesting collections more than
    MAX_YAML_DEPTH deep."""

    _depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise yaml.YAMLError(f"collections nested more than {MAX_YAML_DEPTH} deep")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def compose_document(self) -> Any:
        node = super().compose_document()
        sizes: dict[int, int] = {}

        def expanded(n: Any) -> int:
            if id(n) not in sizes:
                sizes[id(n)] = 0  # a recursive alias counts its cycle once
                kids: list[Any] = []
                if isinstance(n, yaml.SequenceNode):
                    kids = list(n.value)
                elif isinstance(n, yaml.MappingNode):
                    kids = [x for pair in n.value for x in pair]
                total = 1
                for k in kids:
                    total += expanded(k)
                    if total > MAX_YAML_NODES:
                        raise yaml.YAMLError(
                            f"the document expands to more than {MAX_YAML_NODES} nodes "
                            "through its aliases (*name)"
                        )
                sizes[id(n)] = total
            return sizes[id(n)]

        if node is not None:
            expanded(node)
        return node


def load_yaml_text(text: str) -> Any:
    """``yaml.safe_load`` that refuses alias bombs (raises ``yaml.YAMLError``)."""
    return yaml.load(text, Loader=_LimitedLoader)  # a SafeLoader subclass: safe types only


def read_yaml(path: str | os.PathLike[str], field: str = "scenario") -> dict[str, Any]:
    """Read a YAML mapping safely (:func:`load_yaml_text`: safe types only, no alias bombs, at
    most :data:`MAX_YAML_BYTES`); clear errors naming ``field`` (the option or key the path
    came from) for missing, unreadable, oversized or corrupt files."""
    from poc_env.io import read_text

    p = Path(path)
    if not p.is_file():
        raise ConfigError(field, str(p), "an existing YAML file or a built-in scenario name")
    if p.stat().st_size > MAX_YAML_BYTES:
        raise ConfigError(field, str(p), f"a YAML file of at most {MAX_YAML_BYTES} bytes")
    text = read_text(p, field, "a readable YAML file")  # a read error names no file
    try:
        data = load_yaml_text(text)
    except yaml.YAMLError as err:
        raise ConfigError(field, str(p), f"valid YAML ({err})") from None
    if not isinstance(data, dict):
        raise ConfigError(field, str(p), "a YAML mapping at the top level")
    return data


def load_scenario(
    scenario: str | os.PathLike[str] | Mapping[str, Any] | Scenario = "paper_6_2",
    overrides: Mapping[str, Any] | None = None,
) -> Scenario:
    """Load a scenario by built-in name, YAML path, mapping, or pass a Scenario through.

    ``overrides`` maps dotted YAML keys to values, e.g. ``{"sensor.sweep_width_km": 4}``; they
    are validated like the file itself (an unknown key is an error).
    """
    if isinstance(scenario, Scenario) and not overrides:
        return scenario
    if isinstance(scenario, Scenario):
        data = scenario.to_dict()
    elif isinstance(scenario, Mapping):
        data = copy.deepcopy(dict(scenario))
    else:
        text = str(scenario)
        if text in builtin_scenarios():
            path = CONFIG_DIR / f"{text}.yaml"
        elif text.endswith((".yaml", ".yml")) or os.sep in text:
            path = Path(text)
        else:
            raise ConfigError(
                "scenario",
                text,
                "a built-in name (" + ", ".join(builtin_scenarios()) + ") or a path to a YAML file",
            )
        data = read_yaml(path)
        data.setdefault("name", Path(path).stem)
        _resolve_prior_file(data, Path(path).parent)
    over = dict(overrides or {})
    sensor = data.get("sensor")
    if (
        over.get("sensor.model", "fixed") != "fixed"
        and "sensor.sweep_width_km" not in over
        and isinstance(sensor, dict)
        and sensor.get("model", "fixed") == "fixed"
    ):  # the file's width is its fixed model's, which the override replaces; a width given
        # beside a model that computes W is refused (SensorConfig.width_given)
        data["sensor"] = {k: v for k, v in sensor.items() if k != "sweep_width_km"}
    for key, value in over.items():
        _set_dotted(data, key, value)
    return _from_mapping(Scenario, data, "")


def parse_overrides(items: Sequence[str]) -> dict[str, Any]:
    """``["a.b=1", ...]`` (the command line's ``--overrides``) -> ``{"a.b": 1}``; each value is
    parsed as YAML by :func:`load_yaml_text`."""
    if isinstance(items, str) or not isinstance(items, list | tuple):
        raise ConfigError("overrides", items, "a list of KEY=VALUE strings")
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = str(item).partition("=")
        if not sep or not key.strip():
            raise ConfigError("overrides", item, "KEY=VALUE, e.g. episode.horizon_steps=20")
        try:
            out[key.strip()] = load_yaml_text(value)
        except yaml.YAMLError as err:
            raise ConfigError("overrides", item, f"a YAML value after '=' ({err})") from None
    return out


def _resolve_prior_file(data: dict[str, Any], folder: Path) -> None:
    """A relative ``map.prior.file`` is read from the YAML file's folder, not the current one."""
    prior = (data.get("map") or {}).get("prior") if isinstance(data.get("map"), dict) else None
    if isinstance(prior, dict) and isinstance(prior.get("file"), str):
        f = Path(prior["file"])
        if not f.is_absolute():
            prior["file"] = str(folder / f)
    terrain = data.get("terrain")
    if isinstance(terrain, dict) and isinstance(terrain.get("dem"), str):
        f = Path(terrain["dem"])
        if not f.is_absolute():
            terrain["dem"] = str(folder / f)
    target = data.get("target")
    for key in ("field_file", "wind_file", "particles_file"):
        if isinstance(target, dict) and isinstance(target.get(key), str):
            f = Path(target[key])
            if not f.is_absolute():
                target[key] = str(folder / f)


def save_scenario(scenario: Scenario, path: str | os.PathLike[str]) -> Path:
    """Write the resolved scenario as YAML (atomically)."""
    return write_text_atomic(path, yaml.safe_dump(scenario.to_dict(), sort_keys=False))
