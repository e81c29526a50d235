"""Velocity fields from files, onto the scenario's map cells and episode time (issue 25).

``target.field_file`` of a ``drift`` scenario (:class:`~poc_env.config.TargetConfig`) names a
current, read by :func:`read_field` and interpolated by :func:`regrid` onto the centre of every
map cell and the episode's time span; the result is a :class:`~poc_env.theory.motion.
VelocityField` that the filter's predict step and the hidden target both use.

Formats (by suffix):

``.npy``
    Already on the map's cells: ``(2, ny, nx)`` or ``(T, 2, ny, nx)`` m/s, east then north,
    frames ``target.field_dt_s`` apart from the episode's start
    (:func:`poc_env.theory.motion.load_field`).
``.csv``
    A header row; ``u_mps`` and ``v_mps`` (east, north; m/s), optionally a time column
    (``time``: ISO 8601 dates, or ``t_s``: seconds from the episode's start) and optionally a
    position (``x_m``, ``y_m``: the scenario's local metres, or ``lon``, ``lat``: WGS84
    degrees). Without a position the field is uniform; with one, the rows must form a full
    lattice (every time x every y x every x once).
``.nc``
    CF-convention NetCDF as ocean models and OpenDrift readers write it (netCDF4/HDF5 through
    ``h5netcdf``, netCDF3 through scipy; the ``ocean`` extra). The current is the variable pair
    with ``standard_name`` ``eastward_sea_water_velocity`` / ``northward_sea_water_velocity``
    (or ``surface_...``, ``x_sea_water_velocity`` / ``y_sea_water_velocity``), else variables
    named ``u``/``v``, ``uo``/``vo`` or ``water_u``/``water_v``. Units must be given (``m s-1``
    and its spellings, ``cm s-1``, ``knots`` are converted). Horizontal coordinates are 1-D:
    longitude/latitude (``standard_name`` or ``units`` ``degrees_east``/``degrees_north``;
    WGS84, or a ``grid_mapping`` on the WGS84 ellipsoid) or projected ``x``/``y`` in m or km
    (``projection_x_coordinate``/``projection_y_coordinate``, ``axis`` X/Y) with a CF
    ``grid_mapping`` giving their CRS (without one they are the scenario's local metres). The
    time coordinate is CF (``seconds since ...``); a dimension of size one (a single depth) is
    dropped. ``x_wind``/``y_wind`` are recognised and refused for ``drift``: a wind is not a
    current.

The same reader reads the 10 m wind of a ``leeway`` target (``target.wind_file``,
``target.wind_start``; kind ``"wind"`` of :func:`read_field`, errors naming those keys): the
pair with ``standard_name`` ``eastward_wind`` / ``northward_wind`` (or ``x_wind`` /
``y_wind``), else variables ``u10``/``v10``, ``uwnd``/``vwnd`` or ``u``/``v``; the same units,
coordinates and checks, speeds up to :data:`~poc_env.theory.motion.MAX_WIND_MPS`; a current
given as the wind is refused.

Interpolation: bilinear in space at each cell centre (projected to the file's coordinates by
pyproj, :mod:`poc_env.crs`, through the map's ``origin_deg`` and
``projection``), linear in time between the file's own times (kept, not resampled). The
episode starts at ``target.field_start`` (ISO 8601, UTC) or, by default, at the file's first
time; undated times (``t_s``) start at 0.

Refused, with a :class:`~poc_env.errors.ConfigError` naming ``target.field_file`` (or the
key at fault) and nothing written: an unreadable file or one without the needed variables,
units or coordinates; curvilinear (2-D) coordinates; a geographic datum other than WGS84;
a field that does not cover every cell centre or the episode's time span (no extrapolation);
NaN (land, missing values) at a cell centre; speeds above
:data:`~poc_env.theory.motion.MAX_FIELD_MPS` (a unit error); a lon/lat or projected file for a
map without ``origin_deg``.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.errors import ConfigError, require_extra

#: (east, north) standard names of a current, in order of preference.
CURRENT_STANDARD_NAMES = (
    ("eastward_sea_water_velocity", "northward_sea_water_velocity"),
    ("surface_eastward_sea_water_velocity", "surface_northward_sea_water_velocity"),
    ("x_sea_water_velocity", "y_sea_water_velocity"),
)
#: standard names of a wind: recognised to refuse a wind file given as a current.
WIND_STANDARD_NAMES = (("x_wind", "y_wind"), ("eastward_wind", "northward_wind"))
#: variable names used when no standard name matches.
CURRENT_VARIABLES = (("u", "v"), ("uo", "vo"), ("water_u", "water_v"))
#: accepted units of a velocity and their factor to m/s.
SPEED_UNITS = {
    "m s-1": 1.0, "m/s": 1.0, "m s**-1": 1.0, "m s^-1": 1.0, "m.s-1": 1.0, "m.s**-1": 1.0,
    "meter second-1": 1.0, "meters second-1": 1.0, "metre second-1": 1.0,
    "meter/second": 1.0, "meters/second": 1.0, "ms-1": 1.0,
    "cm s-1": 0.01, "cm/s": 0.01, "cm.s-1": 0.01,
    "knots": 1852.0 / 3600.0, "knot": 1852.0 / 3600.0, "kt": 1852.0 / 3600.0,
}  # fmt: skip
LENGTH_UNITS = {"m": 1.0, "meter": 1.0, "meters": 1.0, "metre": 1.0, "metres": 1.0, "km": 1e3}
FIELD = "target.field_file"
#: the kinds of field a file may hold: (file key, start key, what it is) of the scenario; one
#: reader for both (:func:`read_field`), told apart by their standard names.
KINDS = {
    "current": ("target.field_file", "target.field_start", "a current"),
    "wind": ("target.wind_file", "target.wind_start", "a 10 m wind"),
}
#: (east, north) variable names of a wind when no standard name matches (ERA5, NCEP, generic).
WIND_VARIABLES = (("u10", "v10"), ("uwnd", "vwnd"), ("u", "v"))


def _kind(kind: str) -> tuple[str, str, str]:
    if kind not in KINDS:
        raise ValueError(f"field kind {kind!r}: one of {tuple(KINDS)}")
    return KINDS[kind]


@dataclass(frozen=True)
class RawField:
    """A velocity field as read from a file, before regridding.

    ``u, v (T, NY, NX)`` m/s on the lattice ``ys (NY,)`` x ``xs (NX,)`` (ascending) in the
    coordinates ``frame``: ``"local"`` (the scenario's metres), ``"lonlat"`` (WGS84 degrees) or
    ``"projected"`` (metres of ``crs``, a pyproj CRS); ``xs, ys`` None for a uniform field
    (``NY = NX = 1``). ``times (T,)`` seconds (since 1970 when ``dated``, else from the
    episode's start) or None for a stationary field (``T = 1``).
    """

    u: np.ndarray
    v: np.ndarray
    xs: np.ndarray | None
    ys: np.ndarray | None
    frame: str
    crs: Any
    times: np.ndarray | None
    dated: bool
    path: str
    #: ``"current"`` or ``"wind"`` (:data:`KINDS`): which scenario keys its errors name
    kind: str = "current"


# ------------------------------------------------------------------------------ reading
def read_field(path: str, kind: str = "current") -> RawField:
    """Read the ``.csv`` or ``.nc`` velocity field ``path`` (module docstring) holding a
    ``kind`` of field (:data:`KINDS`: a ``"current"`` or a ``"wind"``); errors name the
    scenario key of that kind."""
    field = _kind(kind)[0]
    p = Path(path)
    if not p.is_file():
        raise ConfigError(field, path, "an existing .npy, .csv or .nc file")
    if p.suffix.lower() == ".csv":
        return _read_csv(p, kind)
    if p.suffix.lower() in (".nc", ".nc4", ".netcdf"):
        return _read_netcdf(p, kind)
    raise ConfigError(field, path, "a .npy, .csv or .nc (CF NetCDF) velocity field")


def epoch_seconds(values: Any, field: str, shown: Any) -> np.ndarray:
    """datetime64 values (or ISO 8601 texts) -> float seconds since 1970-01-01 (UTC)."""
    vals = np.asarray(values)
    if vals.dtype.kind in "UO":  # texts: UTC only ('Z' or '+00:00' accepted and dropped)
        texts = [str(v).strip() for v in vals.ravel()]
        texts = [t[:-1] if t.endswith(("Z", "z")) else t for t in texts]
        texts = [t[:-6] if t.endswith(("+00:00", "-00:00")) else t for t in texts]
        vals = np.array(texts)
    try:
        t = np.asarray(vals, dtype="datetime64[ns]")
    except (ValueError, TypeError) as err:
        raise ConfigError(field, shown, f"ISO 8601 dates, e.g. 2024-05-01T06:00 ({err})") from None
    if np.isnat(t).any():
        raise ConfigError(field, shown, "dates without missing values")
    return t.astype("int64").astype(float) / 1e9


def _read_csv(p: Path, kind: str = "current") -> RawField:
    FIELD = _kind(kind)[0]
    try:
        with p.open(newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise ConfigError(FIELD, str(p), f"a readable UTF-8 CSV file ({err})") from None
    if len(rows) < 2:
        raise ConfigError(FIELD, str(p), "a CSV with a header row and at least one data row")
    head = [h.strip() for h in rows[0]]
    missing = [c for c in ("u_mps", "v_mps") if c not in head]
    if missing:
        raise ConfigError(
            f"{FIELD} header",
            head,
            "columns u_mps, v_mps (m/s, east and north); optional time (ISO 8601) or t_s, "
            f"and x_m, y_m (local metres) or lon, lat (missing: {missing})",
        )
    col = {h: k for k, h in enumerate(head)}
    pos = ("x_m", "y_m") if "x_m" in col else ("lon", "lat") if "lon" in col else None
    if pos is not None and pos[1] not in col:
        raise ConfigError(f"{FIELD} header", head, f"both {pos[0]} and {pos[1]}")
    tcol = "time" if "time" in col else "t_s" if "t_s" in col else None
    data = rows[1:]

    def numbers(name: str) -> np.ndarray:
        out = np.empty(len(data))
        for k, r in enumerate(data):
            try:
                out[k] = float(r[col[name]])
            except (ValueError, IndexError):
                raise ConfigError(
                    f"{FIELD} line {k + 2} {name}",
                    r[col[name]] if col[name] < len(r) else None,
                    "a finite number",
                ) from None
            if not math.isfinite(out[k]):
                raise ConfigError(f"{FIELD} line {k + 2} {name}", out[k], "a finite number")
        return out

    u, v = numbers("u_mps"), numbers("v_mps")
    if tcol == "time":
        t = epoch_seconds([r[col["time"]] for r in data], f"{FIELD} time", str(p))
    elif tcol == "t_s":
        t = numbers("t_s")
    else:
        t = np.zeros(len(data))
    x = numbers(pos[0]) if pos else np.zeros(len(data))
    y = numbers(pos[1]) if pos else np.zeros(len(data))
    ts, ti = np.unique(t, return_inverse=True)
    xs, xi = np.unique(x, return_inverse=True)
    ys, yi = np.unique(y, return_inverse=True)
    shape = (len(ts), len(ys), len(xs))
    flat = np.ravel_multi_index((ti, yi, xi), shape)
    if len(flat) != math.prod(shape) or len(np.unique(flat)) != len(flat):
        raise ConfigError(
            FIELD,
            f"{p}: {len(flat)} rows on {len(ts)} times x {len(ys)} y x {len(xs)} x",
            "a full lattice: every (time, y, x) combination exactly once",
        )
    uu, vv = np.empty(shape), np.empty(shape)
    uu.ravel()[flat] = u
    vv.ravel()[flat] = v
    return RawField(
        u=uu,
        v=vv,
        xs=xs if pos else None,
        ys=ys if pos else None,
        frame="local" if pos == ("x_m", "y_m") else "lonlat",
        crs=None,
        times=ts if tcol else None,
        dated=tcol == "time",
        path=str(p),
        kind=kind,
    )


def _std(var: Any) -> str:
    return str(var.attrs.get("standard_name", "")).strip()


def _find_pair(ds: Any, p: Path, kind: str = "current") -> tuple[str, str]:
    """The (east, north) variables of a ``kind`` of field: by standard name, else by variable
    name unless a standard name says the other kind; a file of the other kind is refused."""
    FIELD = _kind(kind)[0]
    names = {_std(ds[k]): k for k in ds.data_vars}
    mine, other = (
        (CURRENT_STANDARD_NAMES, WIND_STANDARD_NAMES)
        if kind == "current"
        else (WIND_STANDARD_NAMES, CURRENT_STANDARD_NAMES)
    )
    for east, north in mine:
        if east in names and north in names:
            return names[east], names[north]
    theirs = {n for pair in other for n in pair}
    for east, north in CURRENT_VARIABLES if kind == "current" else WIND_VARIABLES:
        # by name, unless the standard name says the other kind
        pair = (east in ds.data_vars) and (north in ds.data_vars)
        if pair and not {_std(ds[east]), _std(ds[north])} & theirs:
            return east, north
    for east, north in other:
        if east in names and north in names:
            if kind == "current":
                raise ConfigError(
                    FIELD,
                    f"{p} (a wind: {east}/{north})",
                    "a current (eastward_sea_water_velocity / northward_sea_water_velocity): "
                    "target.model drift is advected by the current; a wind drives the leeway "
                    "model (target.wind_file)",
                )
            raise ConfigError(
                FIELD,
                f"{p} (a current: {east}/{north})",
                "a 10 m wind (eastward_wind / northward_wind or x_wind / y_wind): the leeway "
                "is driven by the wind; a current goes in target.field_file",
            )
    if kind == "current":
        want = (
            "a pair with standard_name eastward_sea_water_velocity / "
            "northward_sea_water_velocity (or variables u/v, uo/vo, water_u/water_v)"
        )
    else:
        want = (
            "a pair with standard_name eastward_wind / northward_wind or x_wind / y_wind "
            "(or variables u10/v10, uwnd/vwnd, u/v)"
        )
    raise ConfigError(FIELD, f"{p} with variables {sorted(map(str, ds.data_vars))}", want)


def _units(var: Any, name: str, p: Path, FIELD: str = FIELD) -> float:
    units = str(var.attrs.get("units", "")).strip()
    factor = SPEED_UNITS.get(units) or SPEED_UNITS.get(units.lower())
    if factor is None:
        raise ConfigError(
            f"{FIELD} {name}.units",
            units or None,
            "a speed unit: m s-1 (m/s), cm s-1 or knots",
        )
    return factor


def _axis_kind(ds: Any, dim: str) -> str | None:
    """``"time"``, ``"lon"``, ``"lat"``, ``"x"``, ``"y"`` or None for a dimension."""
    if dim not in ds.coords:
        return None
    c = ds.coords[dim]
    std = _std(c)
    units = str(c.attrs.get("units", "")).strip().lower()
    axis = str(c.attrs.get("axis", "")).upper()
    name = str(dim).lower()
    if np.issubdtype(c.dtype, np.datetime64) or std == "time" or axis == "T":
        return "time"
    if std == "longitude" or units in ("degrees_east", "degree_east", "degrees_e"):
        return "lon"
    if std == "latitude" or units in ("degrees_north", "degree_north", "degrees_n"):
        return "lat"
    if std == "projection_x_coordinate" or axis == "X" or name in ("x", "xc"):
        return "x"
    if std == "projection_y_coordinate" or axis == "Y" or name in ("y", "yc"):
        return "y"
    if name in ("lon", "longitude"):
        return "lon"
    if name in ("lat", "latitude"):
        return "lat"
    return None


def _grid_crs(ds: Any, var: Any, p: Path, FIELD: str = FIELD) -> Any:
    """The pyproj CRS of ``var``'s CF ``grid_mapping``, or None."""
    gm = var.attrs.get("grid_mapping")
    if not gm:
        return None
    gm = str(gm).split(":")[0].strip()
    if gm not in ds.variables:
        raise ConfigError(f"{FIELD} grid_mapping", gm, f"a variable of {p.name}")
    from pyproj import CRS
    from pyproj.exceptions import CRSError

    try:
        return CRS.from_cf(dict(ds[gm].attrs))
    except CRSError as err:
        raise ConfigError(
            f"{FIELD} grid_mapping", gm, f"a CF grid mapping pyproj understands ({err})"
        ) from None


def _read_netcdf(p: Path, kind: str = "current") -> RawField:
    FIELD = _kind(kind)[0]
    require_extra("ocean", f"{FIELD} {p.name} (NetCDF)", "xarray", "h5netcdf")
    import xarray as xr

    try:
        ds = xr.open_dataset(p, decode_times=True)
    except Exception as err:
        raise ConfigError(FIELD, str(p), f"a readable CF NetCDF file ({err})") from None
    with ds:
        ue, vn = _find_pair(ds, p, kind)
        u, v = ds[ue], ds[vn]
        if u.dims != v.dims:
            raise ConfigError(FIELD, f"{p}: {ue}{u.dims}, {vn}{v.dims}", "the same dimensions")
        fu, fv = _units(u, ue, p, FIELD), _units(v, vn, p, FIELD)
        kinds: dict[str, str] = {}
        for d in u.dims:
            k = _axis_kind(ds, str(d))
            if k is None:
                if ds.sizes[d] == 1:
                    continue
                raise ConfigError(
                    f"{FIELD} {ue}",
                    f"dimension {d!r} of size {ds.sizes[d]}"
                    + ("" if d in ds.coords else " without a coordinate variable"),
                    "dimensions time, latitude/longitude or y/x with CF coordinates (a depth "
                    "or ensemble dimension must have size 1: select the surface level)",
                )
            if k in kinds.values():
                raise ConfigError(f"{FIELD} {ue}", f"two {k} dimensions {u.dims}", "one each")
            kinds[str(d)] = k
        horiz = set(kinds.values()) - {"time"}
        if not horiz:
            for c in ("lon", "lat", "longitude", "latitude"):
                if c in ds.coords and ds.coords[c].ndim == 2:
                    raise ConfigError(
                        FIELD,
                        f"{p}: 2-D (curvilinear) {c}",
                        "a rectilinear grid: 1-D longitude/latitude or x/y coordinates",
                    )
        elif horiz not in ({"lon", "lat"}, {"x", "y"}):
            raise ConfigError(
                f"{FIELD} {ue}",
                f"horizontal coordinates {sorted(horiz)}",
                "1-D longitude and latitude, or projection x and y",
            )
        order = [d for d in u.dims if d in kinds]
        tdim = next((d for d, k in kinds.items() if k == "time"), None)
        xdim = next((d for d, k in kinds.items() if k in ("lon", "x")), None)
        ydim = next((d for d, k in kinds.items() if k in ("lat", "y")), None)
        want = [d for d in (tdim, ydim, xdim) if d is not None]
        from poc_env.limits import check_memory

        # a file's declared size, before its data are read (a chunked file of a few kB can
        # declare terabytes): the pair in float64 plus the interpolation's copies
        check_memory(FIELD, str(p), 4 * 8.0 * u.size, "velocity field (u and v)")
        uu = np.asarray(u.squeeze([d for d in u.dims if d not in kinds]).transpose(*want))
        vv = np.asarray(v.squeeze([d for d in v.dims if d not in kinds]).transpose(*want))
        del order
        shape = tuple(1 if d is None else ds.sizes[d] for d in (tdim, ydim, xdim))
        uu = uu.reshape(shape).astype(float) * fu
        vv = vv.reshape(shape).astype(float) * fv
        times = None
        dated = False
        if tdim is not None:
            tc = ds.coords[tdim]
            if not np.issubdtype(tc.dtype, np.datetime64):
                raise ConfigError(
                    f"{FIELD} {tdim}",
                    str(tc.attrs.get("units", None)),
                    "a CF time coordinate with units, e.g. 'seconds since 2024-05-01 00:00'",
                )
            times = epoch_seconds(tc.values, f"{FIELD} {tdim}", str(p))
            dated = True
        xs = ys = None
        frame, crs = "local", None
        if xdim is not None and ydim is not None:
            xs = np.array(ds.coords[xdim].values, dtype=float)
            ys = np.array(ds.coords[ydim].values, dtype=float)
            gcrs = _grid_crs(ds, u, p, FIELD)
            if kinds[xdim] == "lon":
                frame = "lonlat"
                if gcrs is not None and not _wgs84(gcrs):
                    e = gcrs.ellipsoid
                    raise ConfigError(
                        f"{FIELD} grid_mapping",
                        f"{gcrs.name} (ellipsoid a = {e.semi_major_metre:.1f} m)"
                        if e
                        else gcrs.name,
                        "longitude/latitude on WGS84 (reproject the file, e.g. with cdo/gdal)",
                    )
            else:
                for d, arr in ((xdim, xs), (ydim, ys)):
                    lu = str(ds.coords[d].attrs.get("units", "m")).strip().lower()
                    if lu not in LENGTH_UNITS:
                        raise ConfigError(f"{FIELD} {d}.units", lu, "m or km")
                    arr *= LENGTH_UNITS[lu]
                frame, crs = ("projected", gcrs) if gcrs is not None else ("local", None)
                if gcrs is not None and not gcrs.is_projected:
                    raise ConfigError(
                        f"{FIELD} grid_mapping", gcrs.name, "a projected CRS for x/y in metres"
                    )
    for name, coord in (("x", xs), ("y", ys), ("time", times)):
        if coord is not None and not np.all(np.isfinite(coord)):
            raise ConfigError(f"{FIELD} {name}", f"{p}: NaN coordinates", "finite coordinates")
    # ascending axes
    if xs is not None and ys is not None:
        for axis, arr in ((2, xs), (1, ys)):
            if len(arr) > 1 and arr[0] > arr[-1]:
                arr[:] = arr[::-1].copy()
                uu, vv = np.flip(uu, axis), np.flip(vv, axis)
            if np.any(np.diff(arr) <= 0):
                raise ConfigError(FIELD, f"{p}: coordinates not monotonic", "a monotonic grid")
    if times is not None and np.any(np.diff(times) <= 0):
        raise ConfigError(FIELD, f"{p}: times not increasing", "strictly increasing times")
    return RawField(uu, vv, xs, ys, frame, crs, times, dated, str(p), kind)


def _wgs84(crs: Any) -> bool:
    """True when ``crs``'s ellipsoid is WGS84's (to 1 mm and 1e-6 in inverse flattening)."""
    e = crs.ellipsoid
    return (
        e is not None
        and abs(e.semi_major_metre - 6378137.0) < 1e-3
        and (abs(e.inverse_flattening - 298.257223563) < 1e-6)
    )


# ---------------------------------------------------------------------------- regridding
def cell_centres(map_cfg: Any, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Local metres (x, y) ``(ny, nx)`` of every map cell's centre (row 0 at the south)."""
    ny, nx = shape
    x0, y0 = map_cfg.origin_m
    c = map_cfg.cell_m
    y, x = np.mgrid[:ny, :nx]
    return x0 + (x + 0.5) * c, y0 + (y + 0.5) * c


def _map_crs(map_cfg: Any, why: str) -> dict[str, Any]:
    if map_cfg is None or map_cfg.origin_deg is None:
        raise ConfigError(
            "map.origin_deg",
            None,
            f"[lat, lon] of the map's (0, 0) to place {why} (or give the field in local x_m, y_m)",
        )
    from poc_env.crs import make_crs

    return make_crs(map_cfg.projection, map_cfg.origin_deg, zone=map_cfg.utm_zone)


def _to_file_frame(raw: RawField, x: np.ndarray, y: np.ndarray, map_cfg: Any) -> tuple:
    """The cell centres ``x, y`` in the file's coordinates."""
    if raw.frame == "local":
        return x, y
    from poc_env.crs import to_geographic

    rec = _map_crs(map_cfg, f"the {raw.frame} field {raw.path}")
    latlon = np.asarray(to_geographic(np.column_stack([x.ravel(), y.ravel()]), rec))
    lat, lon = latlon[:, 0].reshape(x.shape), latlon[:, 1].reshape(x.shape)
    if raw.frame == "lonlat":
        assert raw.xs is not None
        if raw.xs.max() > 180.0:  # a 0-360 longitude axis
            lon = np.mod(lon, 360.0)
        return lon, lat
    from pyproj import Transformer

    tr = Transformer.from_crs("EPSG:4326", raw.crs, always_xy=True)
    fx, fy = tr.transform(lon, lat)
    return np.asarray(fx, dtype=float), np.asarray(fy, dtype=float)


def _bilinear(xs: np.ndarray, ys: np.ndarray, f: np.ndarray, px: np.ndarray, py: np.ndarray):
    """``f (T, NY, NX)`` on the lattice at the points ``px, py`` (inside it): (T, *px.shape)."""

    def weights(axis: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if len(axis) == 1:
            return np.zeros(p.shape, dtype=int), np.zeros(p.shape)
        i = np.clip(np.searchsorted(axis, p, side="right") - 1, 0, len(axis) - 2)
        return i, (p - axis[i]) / (axis[i + 1] - axis[i])

    i, wx = weights(xs, px)
    j, wy = weights(ys, py)
    i1 = np.minimum(i + 1, len(xs) - 1)
    j1 = np.minimum(j + 1, len(ys) - 1)
    return (1 - wy) * ((1 - wx) * f[:, j, i] + wx * f[:, j, i1]) + wy * (
        (1 - wx) * f[:, j1, i] + wx * f[:, j1, i1]
    )


def parse_start(text: Any, field: str = "target.field_start") -> float:
    """``target.field_start`` (or ``field``; ISO 8601, UTC) -> seconds since 1970."""
    return float(epoch_seconds([str(text)], field, text)[0])


def regrid(
    raw: RawField, map_cfg: Any, shape: tuple[int, int], span_s: float, start: Any = None
) -> tuple[np.ndarray, np.ndarray | None]:
    """``(frames (T, 2, ny, nx) m/s on the map's cells, times_s (T,) from the episode's start
    or None)`` of ``raw`` over an episode of ``span_s`` seconds starting at ``start`` (ISO 8601;
    default the file's first time). ConfigError for a field not covering the map or the span,
    NaN at a cell centre, or ``start`` with an undated field (module docstring)."""
    FIELD, START, _ = _kind(raw.kind)
    x, y = cell_centres(map_cfg, shape)
    if raw.xs is None or raw.ys is None:
        frames_u = np.broadcast_to(raw.u[:, :1, :1], (len(raw.u), *shape))
        frames_v = np.broadcast_to(raw.v[:, :1, :1], (len(raw.v), *shape))
    else:
        fx, fy = _to_file_frame(raw, x, y, map_cfg)
        outside = (
            ((fx < raw.xs[0]) | (fx > raw.xs[-1]) | (fy < raw.ys[0]) | (fy > raw.ys[-1]))
            | ~np.isfinite(fx)
            | ~np.isfinite(fy)
        )
        if outside.any():
            j, i = np.argwhere(outside)[0]
            names = {"lonlat": ("lon", "lat"), "local": ("x_m", "y_m")}.get(raw.frame, ("x", "y"))
            raise ConfigError(
                FIELD,
                f"{raw.path} covering {names[0]} [{raw.xs[0]:g}, {raw.xs[-1]:g}], {names[1]} "
                f"[{raw.ys[0]:g}, {raw.ys[-1]:g}]",
                f"a field covering every cell centre of the map ({int(outside.sum())} of "
                f"{outside.size} outside, e.g. the cell in column {i}, row {j} (row 0 south) "
                f"at {names[0]} {fx[j, i]:.6g}, {names[1]} {fy[j, i]:.6g})",
            )
        frames_u = _bilinear(raw.xs, raw.ys, raw.u, fx, fy)
        frames_v = _bilinear(raw.xs, raw.ys, raw.v, fx, fy)
    times = None
    if raw.times is not None and len(raw.times) > 1:
        if start is not None and not raw.dated:
            raise ConfigError(START, start, "null for a field timed in t_s")
        t0 = parse_start(start, START) if start is not None else float(raw.times[0])
        rel = raw.times - t0
        if rel[0] > 0 or rel[-1] < span_s:
            raise ConfigError(
                FIELD,
                f"{raw.path} times from {rel[0]:g} s to {rel[-1]:g} s of the episode's start",
                f"times covering the episode: 0 to {span_s:g} s ({START})",
            )
        first = max(int(np.searchsorted(rel, 0.0, side="right")) - 1, 0)
        last = min(int(np.searchsorted(rel, span_s, side="left")), len(rel) - 1)
        keep = slice(first, last + 1)
        frames_u, frames_v, times = frames_u[keep], frames_v[keep], rel[keep]
    elif (
        start is not None
        and raw.times is not None
        and raw.dated
        and (parse_start(start, START) != float(raw.times[0]))
    ):
        raise ConfigError(START, start, "the single time of a one-frame field, or null")
    frames = np.stack([frames_u, frames_v], axis=1).astype(float)
    bad = ~np.isfinite(frames)
    if bad.any():
        k, c, j, i = np.argwhere(bad)[0]
        raise ConfigError(
            FIELD,
            f"{raw.path} with NaN at {int(bad[:, 0].any(axis=0).sum())} map cell(s), e.g. "
            f"the cell in column {i}, row {j}, frame {k} ({'uv'[c]})",
            "finite velocities at every cell centre (land or missing values near the map?)",
        )
    return np.ascontiguousarray(frames), times
