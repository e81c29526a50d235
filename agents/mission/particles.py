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


def read_particles(path: str | Path, time: str | None = None) -> Particles:
    """The active particles of the trajectory file ``path`` at ``time`` (ISO 8601, UTC; one of
    the file's times to the second; default its last time)."""
    file = Path(path)
    if not file.is_file() or file.suffix.lower() not in (".nc", ".nc4"):
        raise ConfigError(FIELD, str(path), "an existing NetCDF (.nc) trajectory file")
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
        when: str | None = None
        if tdim is not None:
            axis = lon_v.dims.index(tdim)
            lon, lat = np.moveaxis(lon, axis, -1), np.moveaxis(lat, axis, -1)
            times = ds[tdim].values if tdim in ds.coords else None
            k = lon.shape[-1] - 1
            if time is not None:
                if times is None or not np.issubdtype(times.dtype, np.datetime64):
                    raise ConfigError("particles_time", time, "null: the file has no CF times")
                from poc_env.theory.fields import epoch_seconds

                want_s = epoch_seconds([time], "particles_time", time)[0]
                have = epoch_seconds(times, f"{file} {tdim}", str(file))
                hits = np.flatnonzero(np.abs(have - want_s) < 0.5)
                if not len(hits):
                    raise ConfigError(
                        "particles_time",
                        time,
                        f"one of the file's {len(have)} times, "
                        f"{np.datetime_as_string(times[0], 's')} to "
                        f"{np.datetime_as_string(times[-1], 's')}",
                    )
                k = int(hits[0])
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
            f"{file} {names['lat']}",
            "values beyond 90 degrees",
            "WGS84 degrees (lat, lon swapped?)",
        )
    lon_a = np.where(lon[active] > 180.0, lon[active] - 360.0, lon[active])
    return Particles(lon_a, lat[active], when, int(lon.size), int((~active).sum()))
