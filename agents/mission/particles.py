"""Particle files in: an OpenDrift output (or any CF ``trajectory`` NetCDF) as a prior.

A drift model run from a last-known position (OpenDrift's Leeway or OceanDrift, SAROPS-like
tools) writes ``N`` particles x ``T`` times: variables ``lon(trajectory, time)`` and
``lat(trajectory, time)`` in WGS84 degrees, CF ``featureType = "trajectory"``, a CF time
coordinate, and NaN (masked) positions where a particle is not active (not yet seeded,
stranded, deactivated). :func:`read_particles` takes the positions at one time (by default the
last: the search starts where the drift run ends) and :mod:`poc_env.agents.mission.geoimport`
bins them onto the scenario's cells as the prior (``poc-env scenario import --particles``);
each active particle carries the same mass.

Refused with a :class:`~poc_env.errors.ConfigError` naming the file and what is wrong: a
file that is not readable NetCDF, a ``featureType`` other than trajectory, no longitude /
latitude variables (particle files without coordinates), coordinates in another CRS (x/y, a
``grid_mapping`` not on WGS84, units other than degrees), a time outside the run, no active
particle at that time, latitudes beyond 90 degrees.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.errors import ConfigError, require_extra

FIELD = "particles"


@dataclass(frozen=True)
class Particles:
    """The active particles of a file at one time: ``lon, lat (n,)`` degrees (WGS84), the
    ``time`` (ISO 8601, or None for an undated file), how many particles the file has and how
    many were inactive (NaN) then."""

    lon: np.ndarray
    lat: np.ndarray
    time: str | None
    total: int
    inactive: int


def _coord(ds: Any, which: str) -> str | None:
    """The name of the longitude (``which = "lon"``) or latitude variable, or None."""
    std = "longitude" if which == "lon" else "latitude"
    names = ("lon", "longitude") if which == "lon" else ("lat", "latitude")
    for k in ds.variables:
        if str(ds[k].attrs.get("standard_name", "")).strip() == std:
            return str(k)
    for k in names:
        if k in ds.variables:
            return k
    return None


def _wgs84_mapping(ds: Any, var: Any, file: Path) -> None:
    gm = var.attrs.get("grid_mapping")
    if not gm or str(gm) not in ds.variables:
        return
    from pyproj import CRS
    from pyproj.exceptions import CRSError

    try:
        crs = CRS.from_cf(dict(ds[str(gm)].attrs))
    except CRSError as err:
        raise ConfigError(f"{file} grid_mapping", str(gm), f"a CF grid mapping ({err})") from None
    e = crs.ellipsoid
    if (
        not crs.is_geographic
        or e is None
        or abs(e.semi_major_metre - 6378137.0) > 1e-3
        or abs(e.inverse_flattening - 298.257223563) > 1e-6
    ):
        raise ConfigError(
            f"{file} grid_mapping",
            _describe(crs),
            "longitude/latitude on WGS84 (as OpenDrift writes them); reproject the particles",
        )


def _describe(crs: Any) -> str:
    """A CRS's name and ellipsoid, for messages (a CF grid mapping often has no name)."""
    e = crs.ellipsoid
    ell = f"ellipsoid a = {e.semi_major_metre:.1f} m, 1/f = {e.inverse_flattening:.4f}" if e else ""
    return f"{crs.name} ({ell})" if ell else str(crs.name)


def _open_tracks(file: Path) -> tuple[np.ndarray, np.ndarray, Any, str | None, str]:
    """``(lon, lat, times, tdim, lat name)`` of the trajectory file: ``lon, lat`` with the time
    axis last (``(N, T)``, or ``(N,)`` without one), ``times`` the time coordinate's values (or
    None); every check of the module docstring but the time's."""
    if not file.is_file() or file.suffix.lower() not in (".nc", ".nc4"):
        raise ConfigError(FIELD, str(file), "an existing NetCDF (.nc) trajectory file")
    require_extra("ocean", f"particles {file.name} (NetCDF)", "xarray", "h5netcdf")
    import xarray as xr

    try:
        ds = xr.open_dataset(file, decode_times=True)
    except Exception as err:
        raise ConfigError(str(file), f"unreadable ({err})", "a CF NetCDF trajectory file") from None
    with ds:
        ftype = str(ds.attrs.get("featureType", "trajectory")).strip()
        if ftype.lower() != "trajectory":
            raise ConfigError(
                f"{file} featureType", ftype, "trajectory (particles x times, as OpenDrift writes)"
            )
        names = {w: _coord(ds, w) for w in ("lon", "lat")}
        if names["lon"] is None or names["lat"] is None:
            has_xy = [k for k in ("x", "y") if k in ds.variables]
            raise ConfigError(
                str(file),
                f"variables {sorted(map(str, ds.variables))}",
                "particle longitude and latitude variables (standard_name longitude / latitude, "
                "WGS84 degrees)"
                + (": x/y in another CRS are not read, reproject to lon/lat" if has_xy else ""),
            )
        lon_v, lat_v = ds[names["lon"]], ds[names["lat"]]
        for v, want in ((lon_v, "degrees_east"), (lat_v, "degrees_north")):
            units = str(v.attrs.get("units", want)).strip().lower()
            if units not in (want, want.replace("degrees", "degree"), "degrees", "degree"):
                raise ConfigError(f"{file} {v.name}.units", units, f"{want} (WGS84 degrees)")
            _wgs84_mapping(ds, v, file)
        if lon_v.dims != lat_v.dims or lon_v.ndim not in (1, 2):
            raise ConfigError(
                str(file),
                f"{names['lon']}{lon_v.dims}, {names['lat']}{lat_v.dims}",
                "lon and lat of the same dimensions (trajectory, time)",
            )
        tdim = next(
            (d for d in lon_v.dims if d in ds.coords and np.issubdtype(ds[d].dtype, np.datetime64)),
            None,
        )
        if tdim is None and "time" in lon_v.dims:
            tdim = "time"
        from poc_env import limits

        # the declared size, before the data are read (a chunked file of a few kB can
        # declare terabytes): lon and lat in float64
        limits.check_memory(FIELD, str(file), 2 * 8.0 * lon_v.size, "particle positions")
        lon = np.asarray(lon_v.values, dtype=float)
        lat = np.asarray(lat_v.values, dtype=float)
        times = None
        if tdim is not None:
            axis = lon_v.dims.index(tdim)
            lon, lat = np.moveaxis(lon, axis, -1), np.moveaxis(lat, axis, -1)
            times = ds[tdim].values if tdim in ds.coords else None
            if lon.ndim == 1:  # one particle: (T,) -> (1, T)
                lon, lat = lon[None], lat[None]
    return lon, lat, times, None if tdim is None else str(tdim), str(names["lat"])


def _time_index(file: Path, times: Any, tdim: str | None, time: str, field: str) -> int:
    """The index of ``time`` (ISO 8601) among the file's ``times`` (to the second)."""
    if times is None or not np.issubdtype(times.dtype, np.datetime64):
        raise ConfigError(field, time, "null: the file has no CF times")
    from poc_env.theory.fields import epoch_seconds

    want_s = epoch_seconds([time], field, time)[0]
    have = epoch_seconds(times, f"{file} {tdim}", str(file))
    hits = np.flatnonzero(np.abs(have - want_s) < 0.5)
    if not len(hits):
        raise ConfigError(
            field,
            time,
            f"one of the file's {len(have)} times, {np.datetime_as_string(times[0], 's')} to "
            f"{np.datetime_as_string(times[-1], 's')}",
        )
    return int(hits[0])


def read_particles(path: str | Path, time: str | None = None) -> Particles:
    """The active particles of the trajectory file ``path`` at ``time`` (ISO 8601, UTC; one of
    the file's times to the second; default its last time)."""
    file = Path(path)
    lon, lat, times, tdim, lat_name = _open_tracks(file)
    when: str | None = None
    if tdim is not None:
        k = lon.shape[-1] - 1
        if time is not None:
            k = _time_index(file, times, tdim, time, "particles_time")
        lon, lat = lon[..., k], lat[..., k]
        if times is not None and np.issubdtype(times.dtype, np.datetime64):
            when = str(np.datetime_as_string(times[k], "s"))
    elif time is not None:
        raise ConfigError("particles_time", time, "null: the file has no time dimension")
    lon, lat = lon.ravel(), lat.ravel()
    active = np.isfinite(lon) & np.isfinite(lat)
    if not active.any():
        raise ConfigError(str(file), f"no active particle at {when}", "finite lon/lat positions")
    if np.any(np.abs(lat[active]) > 90.0) or np.any(np.abs(lon[active]) > 360.0):
        raise ConfigError(
            f"{file} {lat_name}",
            "values beyond 90 degrees",
            "WGS84 degrees (lat, lon swapped?)",
        )
    lon_a = np.where(lon[active] > 180.0, lon[active] - 360.0, lon[active])
    return Particles(lon_a, lat[active], when, int(lon.size), int((~active).sum()))


@dataclass(frozen=True)
class Tracks:
    """The trajectories of the particles active at ``start`` (ISO 8601): ``lon, lat (n, T)``
    degrees (WGS84; a particle deactivated later holds its last position), at ``t_s (T,)``
    seconds from ``start`` (from the last output time at or before it to the file's end)."""

    lon: np.ndarray
    lat: np.ndarray
    t_s: np.ndarray
    start: str
    total: int
    stranded: int


def read_tracks(path: str | Path, start: str | None = None) -> Tracks:
    """The trajectories of the file ``path`` from ``start`` (ISO 8601, UTC; one of the file's
    times; default its first), for the ``particles`` motion model
    (:mod:`poc_env.theory.particles`): ConfigError for a file without a CF time coordinate,
    no active particle at ``start`` and every check of :func:`read_particles`."""
    file = Path(path)
    lon, lat, times, tdim, lat_name = _open_tracks(file)
    if tdim is None or times is None or not np.issubdtype(times.dtype, np.datetime64):
        raise ConfigError(
            str(file),
            "no CF time coordinate",
            "trajectories over time (dimension time with units 'seconds since ...') to move "
            "the target",
        )
    k = 0 if start is None else _time_index(file, times, tdim, start, "particles_time")
    from poc_env.theory.fields import epoch_seconds

    secs = epoch_seconds(times, f"{file} {tdim}", str(file))
    if np.any(np.diff(secs) <= 0):
        raise ConfigError(f"{file} {tdim}", "times not increasing", "strictly increasing times")
    lon, lat = lon.reshape(-1, lon.shape[-1])[:, k:], lat.reshape(-1, lat.shape[-1])[:, k:]
    active = np.isfinite(lon[:, 0]) & np.isfinite(lat[:, 0])
    when = str(np.datetime_as_string(times[k], "s"))
    if not active.any():
        raise ConfigError(str(file), f"no active particle at {when}", "finite lon/lat positions")
    lon, lat = lon[active], lat[active]
    if np.any(np.abs(lat[np.isfinite(lat)]) > 90.0) or np.any(np.abs(lon[np.isfinite(lon)]) > 360):
        raise ConfigError(f"{file} {lat_name}", "values beyond 90 degrees", "WGS84 degrees")
    gone = ~(np.isfinite(lon) & np.isfinite(lat))
    stranded = int(gone.any(axis=1).sum())
    # a particle deactivated (stranded) later holds its last position: forward fill in time
    idx = np.where(~gone, np.arange(lon.shape[1])[None], 0)
    np.maximum.accumulate(idx, axis=1, out=idx)
    rows = np.arange(len(lon))[:, None]
    lon, lat = lon[rows, idx], lat[rows, idx]
    lon = np.where(lon > 180.0, lon - 360.0, lon)
    return Tracks(lon, lat, secs[k:] - secs[k], when, int(active.size), stranded)
