"""The campaign's ``datafiles`` target: the data files issue 25 and 24 added (issue 27's rule).

Four kinds of hostile file, each written small in the case's temporary folder:

* **velocity fields** for ``target.field_file`` (CF NetCDF written by xarray, ``.csv``,
  ``.npy``; :mod:`poc_env.theory.fields`): NaN cells, wrong or missing units, wrong shapes,
  not covering the map or the episode's time span, missing coordinates, another datum, huge
  speeds, truncated and binary files, odd ``target.field_start`` values. Oracle: a clear
  ConfigError naming a ``target.`` field, or a valid env whose belief mass is conserved by
  every predict step (``mass + mass_out = 1`` within 1e-9);
* **particle files** for ``scenario import --particles`` (:mod:`poc_env.agents.mission.particles`):
  no lon/lat, another CRS, wrong units, a time not in the run, no active particle, NaN
  positions, a file whose declared size is refused before it is read;
* **DEMs** for ``scenario import --dem`` (rasterio GeoTIFF; :mod:`poc_env.agents.mission.terrain`):
  no CRS, not covering, nodata, NaN, absurd heights, truncated files. A valid DEM is planned
  on and exported to QGC, and every mission must clear the DEM's own pixels by the clearance
  (:func:`poc_env.agents.mission.terrain.qgc_clearance`);
* **flown tracks and plans** for ``poc-env replan`` (``--tracks`` GeoJSON, ``--plan``): outside
  the map, another CRS, not LineStrings, NaN/huge coordinates, a plan of another scenario,
  deep nesting.

For the last three an error must leave the output folder empty (nothing written).
"""

from __future__ import annotations

import functools
import json
import math
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.agents.testing.hostile import check, hostile_scalars
from poc_env.errors import ConfigError, PocEnvError

# ------------------------------------------------------------------------ velocity fields
_FIELD_ORIGIN = [45.0, -60.0]  # (lat, lon) of the small scenario's (0, 0): 40 x 40 km
_T0 = np.datetime64("2024-05-01T00:00:00", "ns")
#: Field variants: how the file differs from a valid CF current covering map and episode.
FIELD_VARIANTS = [
    "good", "good", "good", "uniform_csv", "lattice_csv", "npy", "npy_frames",
    "nan_cell", "nan_all", "units", "no_units", "speed", "small", "short", "no_coords",
    "datum", "depth", "wind", "wind_named", "truncated", "binary", "npy_shape", "npy_nan",
    "npz_as_npy",
    "csv_nan", "csv_binary", "csv_header", "time_desc", "xy_km",
]  # fmt: skip
#: A CF grid mapping on the Clarke 1866 ellipsoid (NAD27): another datum than WGS84.
NAD27 = {"grid_mapping_name": "latitude_longitude", "semi_major_axis": 6378206.4,
         "inverse_flattening": 294.9786982}  # fmt: skip
_UNITS = ["m s-1", "cm s-1", "knots", "km h-1", "", "m", "furlongs", "m s-1 ", "M S-1"]
_STARTS = [
    None, None, None, "2024-05-01T00:00:00", "2024-05-01T00:30", "2024-05-01T02:00:00",
    "2024-04-30T23:00", "noon", "", "2024-13-01", "2024-05-01T00:00:00+09:00", "1e308",
]  # fmt: skip


def _current(
    times: int = 4,
    lon: tuple[float, float] = (-60.5, -59.0),
    lat: tuple[float, float] = (44.8, 45.6),
    units: Any = "m s-1",
    value: float | None = None,
) -> Any:
    """A small CF current in lon/lat (lats descending, as many models write them)."""
    import xarray as xr

    lons = np.linspace(lon[0], lon[1], 7)
    lats = np.linspace(lat[0], lat[1], 6)[::-1]
    t = _T0 + np.arange(times) * np.timedelta64(3600, "s")
    la, lo = np.meshgrid(lats, lons, indexing="ij")
    h = np.arange(times, dtype=float)[:, None, None]
    u = 0.2 + 0.1 * (lo[None] + 60) + 0.05 * h
    v = -0.1 + 0.2 * (la[None] - 45) + 0 * h
    if value is not None:
        u = np.full_like(u, value)
    attrs_u = {"standard_name": "eastward_sea_water_velocity", "units": units}
    attrs_v = {"standard_name": "northward_sea_water_velocity", "units": units}
    return xr.Dataset(
        {
            "uo": (("time", "latitude", "longitude"), u, attrs_u),
            "vo": (("time", "latitude", "longitude"), v, attrs_v),
        },
        coords={
            "time": ("time", t),
            "latitude": ("latitude", lats, {"standard_name": "latitude", "units": "degrees_north"}),
            "longitude": ("longitude", lons,
                          {"standard_name": "longitude", "units": "degrees_east"}),
        },
        attrs={"Conventions": "CF-1.8"},
    )  # fmt: skip


def _write_field(root: Path, variant: str, units: Any, value: Any) -> Path:
    """The file of ``variant`` in ``root``."""
    nc = root / "cur.nc"
    if variant in ("good", "truncated"):
        _current().to_netcdf(nc, engine="h5netcdf")
        if variant == "truncated":
            data = nc.read_bytes()
            nc.write_bytes(data[: len(data) // 2])
        return nc
    if variant == "binary":
        nc.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 4)
        return nc
    if variant in ("nan_cell", "nan_all"):
        ds = _current()
        if variant == "nan_all":
            ds["uo"][:] = np.nan
        else:
            ds["uo"][1, 2:4, 2:5] = np.nan
    elif variant == "units":
        ds = _current(units=units)
    elif variant == "no_units":
        ds = _current()
        del ds["vo"].attrs["units"]
    elif variant == "speed":
        ds = _current(value=_finite_or(value, 1e308))
    elif variant == "small":
        ds = _current(lon=(-59.9, -59.0))
    elif variant == "short":
        ds = _current(times=2)
    elif variant == "no_coords":
        ds = _current().drop_vars(["latitude", "longitude"])
    elif variant == "datum":
        ds = _current()
        ds["crs"] = ((), 0, NAD27)
        ds["uo"].attrs["grid_mapping"] = "crs"
        ds["vo"].attrs["grid_mapping"] = "crs"
    elif variant == "depth":
        ds = _current().expand_dims(depth=[0.0, 10.0], axis=1)
    elif variant in ("wind", "wind_named"):  # a wind, its variables renamed or named uo/vo
        ds = _current()
        ds["uo"].attrs["standard_name"] = "x_wind"
        ds["vo"].attrs["standard_name"] = "y_wind"
        if variant == "wind":
            ds = ds.rename({"uo": "uw", "vo": "vw"})
    elif variant == "time_desc":
        ds = _current().isel(time=slice(None, None, -1))
    elif variant == "xy_km":  # projected x/y in km, no grid mapping: the scenario's local metres
        import xarray as xr

        xs = np.linspace(-5.0, 45.0, 6)
        u = np.full((4, 6, 6), _finite_or(value, 0.3))
        ds = xr.Dataset(
            {"u": (("time", "y", "x"), u, {"units": units}),
             "v": (("time", "y", "x"), -u, {"units": units})},
            coords={"time": ("time", _T0 + np.arange(4) * np.timedelta64(3600, "s")),
                    "x": ("x", xs, {"axis": "X", "units": "km"}),
                    "y": ("y", xs, {"axis": "Y", "units": "km"})},
        )  # fmt: skip
    else:
        return _write_field_table(root, variant, value)
    ds.to_netcdf(nc, engine="h5netcdf")
    return nc


def _finite_or(value: Any, default: float) -> float:
    """``value`` as a float if it is a real number (NaN and infinities kept), else ``default``."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            return float(value)
        except OverflowError:
            return default
    return default


def _write_field_table(root: Path, variant: str, value: Any) -> Path:
    """``.csv`` and ``.npy`` variants (the map's 8 x 8 cells, m/s)."""
    v = _finite_or(value, 0.3)
    if variant == "uniform_csv":
        p = root / "cur.csv"
        p.write_text(f"t_s,u_mps,v_mps\n0,{v},0.1\n3600,0.2,{v}\n7200,0.1,0\n")
    elif variant == "lattice_csv":
        p = root / "cur.csv"
        rows = [f"{x},{y},{v},0.1" for y in (-5e3, 45e3) for x in (-5e3, 45e3)]
        p.write_text("x_m,y_m,u_mps,v_mps\n" + "\n".join(rows) + "\n")
    elif variant == "csv_nan":
        p = root / "cur.csv"
        p.write_text("u_mps,v_mps\nnan,0.1\n")
    elif variant == "csv_binary":
        p = root / "cur.csv"
        p.write_bytes(b"\x00\xff\xfe\x01" * 64)
    elif variant == "csv_header":
        p = root / "cur.csv"
        p.write_text("east,north\n0.1,0.2\n")
    elif variant in ("npy", "npy_frames", "npy_shape", "npy_nan"):
        p = root / "cur.npy"
        shape = {"npy": (2, 8, 8), "npy_frames": (3, 2, 8, 8), "npy_shape": (2, 7, 9),
                 "npy_nan": (2, 8, 8)}[variant]  # fmt: skip
        a = np.full(shape, v)
        if variant == "npy_nan":
            a[0, 3, 3] = np.nan
        np.save(p, a, allow_pickle=False)
    elif variant == "npz_as_npy":
        p = root / "cur.npy"
        with open(p, "wb") as fh:
            np.savez(fh, a=np.zeros((2, 8, 8)))
    else:  # pragma: no cover - a variant without a writer is a harness bug
        raise AssertionError(variant)
    return p


def _target_error(err: ConfigError, *prefixes: str) -> None:
    """Re-raise ``err`` as it is if it names a field starting with one of ``prefixes``; as an
    unclear error (no ``allowed:``) otherwise."""
    if not str(err.field).startswith(prefixes):
        raise PocEnvError(f"the error names {err.field!r}, not a {'/'.join(prefixes)} field")
    raise err


def run_field(variant: str, units: Any, value: Any, start: Any) -> None:
    """A drift scenario over the velocity field file: a ConfigError naming a ``target.``
    field, or an env whose predict steps conserve the belief's mass within 1e-9."""
    from poc_env.config import load_scenario
    from poc_env.sim import core as sim

    with tempfile.TemporaryDirectory() as d:
        path = _write_field(Path(d), variant, units, value)
        over = {
            "map.origin_deg": _FIELD_ORIGIN,
            "target.model": "drift",
            "target.field_file": str(path),
            "target.field_start": start,
            "episode.horizon_steps": 40,
        }
        try:
            sc = load_scenario("small", over)
            params = sim.make_params(sc)
        except ConfigError as err:
            _target_error(err, "target.")
        state = sim.initial(params, [np.random.default_rng(0)])
        before = state.belief.sum(axis=(1, 2)).copy()
        for _ in range(8):
            sim.predict(params, state)
            state.step += 1
        out = state.mass_out if state.mass_out is not None else 0.0
        total = state.belief.sum(axis=(1, 2)) + out
        check(bool(np.all(np.isfinite(state.belief))), "belief not finite after a predict step")
        check(bool(np.all(state.belief >= -1e-12)), "negative belief after a predict step")
        check(
            bool(np.all(np.abs(total - before) <= 1e-9)),
            f"mass not conserved: {total.tolist()} vs {before.tolist()}",
        )


# ------------------------------------------------------------------------ particle files
_AREA = [[126.2, 45.4], [126.5, 45.4], [126.5, 45.6], [126.2, 45.6], [126.2, 45.4]]
PARTICLE_VARIANTS = [
    "good", "good", "good", "some_nan", "all_nan", "no_lonlat", "units", "datum", "swapped",
    "lon360", "feature", "truncated", "binary", "huge", "one_d", "no_time", "outside",
]  # fmt: skip
_PTIMES = [None, None, None, "2024-05-01T02:00:00", "2024-05-01T00:00", "2030-01-01", "noon",
           "", "2024-05-01T02:00:00.4"]  # fmt: skip
#: Declared (trajectory, time) of the ``huge`` particle file: 8 GB of float64 a variable,
#: chunked and never written, so the file stays small.
HUGE_PARTICLES = (250_000, 4_000)


def _write_particles(root: Path, variant: str, units: Any) -> Path:
    import xarray as xr

    p = root / "drift.nc"
    if variant == "binary":
        p.write_bytes(b"CDF\x01" + bytes(range(256)) * 3)
        return p
    if variant == "huge":
        import h5netcdf

        with h5netcdf.File(p, "w") as f:
            f.dimensions = {"trajectory": HUGE_PARTICLES[0], "time": HUGE_PARTICLES[1]}
            f.attrs["featureType"] = "trajectory"
            for name, std, un in (("lon", "longitude", "degrees_east"),
                                  ("lat", "latitude", "degrees_north")):  # fmt: skip
                v = f.create_variable(name, ("trajectory", "time"), float, chunks=(1000, 100),
                                      fillvalue=np.nan)  # fmt: skip
                v.attrs["standard_name"] = std
                v.attrs["units"] = un
        return p
    rng = np.random.default_rng(5)
    n, nt = 12, 3
    lon = 126.35 + 0.05 * rng.standard_normal((n, nt))
    lat = 45.5 + 0.04 * rng.standard_normal((n, nt))
    if variant == "some_nan":
        lon[:5, -1] = np.nan
    elif variant == "all_nan":
        lon[:, -1] = np.nan
    elif variant == "swapped":
        lon, lat = lat, lon
    elif variant == "lon360":
        lon = lon % 360.0
    elif variant == "outside":
        lon = lon + 3.0
    lon_attrs = {"standard_name": "longitude", "units": "degrees_east"}
    lat_attrs = {"standard_name": "latitude", "units": "degrees_north"}
    if variant == "units":
        lon_attrs["units"] = units
    data = {"lon": (("trajectory", "time"), lon, lon_attrs),
            "lat": (("trajectory", "time"), lat, lat_attrs)}  # fmt: skip
    coords: dict[str, Any] = {"trajectory": np.arange(n)}
    if variant != "no_time":
        coords["time"] = _T0 + np.arange(nt) * np.timedelta64(3600, "s")
    ds = xr.Dataset(data, coords=coords, attrs={"featureType": "trajectory"})
    if variant == "no_lonlat":
        ds = ds.rename({"lon": "x", "lat": "y"})
        for k in ("x", "y"):
            ds[k].attrs = {"units": "m"}
    elif variant == "datum":
        ds["crs"] = ((), 0, NAD27)
        ds["lon"].attrs["grid_mapping"] = "crs"
    elif variant == "feature":
        ds.attrs["featureType"] = "timeSeries"
    elif variant == "one_d":
        ds = ds.isel(time=-1)
    ds.to_netcdf(p, engine="h5netcdf")
    if variant == "truncated":
        data_b = p.read_bytes()
        p.write_bytes(data_b[: len(data_b) // 3])
    return p


def _area_file(root: Path, ring: list) -> Path:
    p = root / "area.geojson"
    p.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {},
         "geometry": {"type": "Polygon", "coordinates": [ring]}}]}))  # fmt: skip
    return p


def _import_into(out: Path, **kwargs: Any) -> dict[str, Any]:
    """``scenario import`` into the empty folder ``out``; an error must leave it empty."""
    from poc_env.agents.mission.geoimport import import_scenario, write_imported

    out.mkdir()
    try:
        res = import_scenario(name="fuzz", **kwargs)
        write_imported(res, out / "fuzz.yaml")
    except PocEnvError:
        check(not any(out.iterdir()), f"an error left {sorted(p.name for p in out.iterdir())}")
        raise
    return res


def run_particles(variant: str, units: Any, when: Any) -> None:
    """``scenario import --particles``: a clear error with nothing written, or a scenario whose
    prior sums to 1 and holds the active particles inside the area."""
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import build_prior

    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        area = _area_file(root, _AREA)
        parts = _write_particles(root, variant, units)
        _import_into(
            root / "out", area=area, airfields=_fields_file(root), particles=parts,
            particles_time=when, cell_km=5.0,
        )  # fmt: skip
        sc = load_scenario(str(root / "out" / "fuzz.yaml"))
        prior = build_prior(sc.map)
        check(bool(np.all(np.isfinite(prior)) and np.all(prior >= 0)), "prior not finite")
        check(abs(float(prior.sum()) - 1.0) < 1e-9, f"prior sums to {prior.sum()!r}")


# ------------------------------------------------------------------------ DEMs
DEM_VARIANTS = [
    "good", "good", "no_crs", "small", "void", "nan", "absurd", "deep",
    "truncated", "binary", "utm", "int16",
]  # fmt: skip
_DEM_BOX = (125.8, 126.9, 45.1, 45.9)  # lon0, lon1, lat0, lat1: the operating area and more
_FIELD = [126.15, 45.5]  # the airfield, west of the area


def _write_dem(root: Path, variant: str, value: Any) -> Path:
    import rasterio
    from rasterio.transform import from_origin

    p = root / "dem.tif"
    if variant == "binary":
        p.write_bytes(b"II*\x00" + bytes(range(256)) * 4)
        return p
    lon0, lon1, lat0, lat1 = _DEM_BOX
    if variant == "small":
        lon1 = 126.3
    res = 0.02
    nx, ny = round((lon1 - lon0) / res), round((lat1 - lat0) / res)
    lons = lon0 + (np.arange(nx) + 0.5) * res
    lats = lat1 - (np.arange(ny) + 0.5) * res
    lo, la = np.meshgrid(lons, lats)
    z = 150.0 + 600.0 * np.exp(-(((lo - 126.35) / 0.05) ** 2 + ((la - 45.5) / 0.05) ** 2))
    dtype, nodata = "float64", -9999.0
    if variant == "void":
        z[10:14, 15:20] = nodata
    elif variant == "nan":
        z[10:14, 15:20] = np.nan
    elif variant == "absurd":
        z[12, 17] = _finite_or(value, 1e308)
    elif variant == "deep":
        z[12, 17] = -abs(_finite_or(value, 2e4)) if math.isfinite(_finite_or(value, 2e4)) else -2e4
    elif variant == "int16":
        dtype, nodata = "int16", -32768
    crs = None if variant == "no_crs" else "EPSG:4326"
    transform = from_origin(lon0, lat1, res, res)
    if variant == "utm":  # the same heights in UTM 51N metres
        from pyproj import Transformer

        crs = "EPSG:32651"
        fwd = Transformer.from_crs("EPSG:4326", crs, always_xy=True)
        (x0, x1), (y0, y1) = fwd.transform([lon0, lon1], [lat1, lat0])
        x0, y1 = fwd.transform(lon0 - 0.05, lat1 + 0.05)
        x1, y0 = fwd.transform(lon1 + 0.05, lat0 - 0.05)
        step = 1500.0
        nx, ny = int((x1 - x0) / step), int((y1 - y0) / step)
        xs = x0 + (np.arange(nx) + 0.5) * step
        ys = y1 - (np.arange(ny) + 0.5) * step
        back = Transformer.from_crs(crs, "EPSG:4326", always_xy=True)
        lo, la = back.transform(*np.meshgrid(xs, ys))
        z = 150.0 + 600.0 * np.exp(-(((lo - 126.35) / 0.05) ** 2 + ((la - 45.5) / 0.05) ** 2))
        transform = from_origin(x0, y1, step, step)
    kw = {"crs": crs} if crs else {}
    with rasterio.open(
        p, "w", driver="GTiff", width=z.shape[1], height=z.shape[0], count=1, dtype=dtype,
        transform=transform, nodata=nodata, **kw,
    ) as dst:  # fmt: skip
        dst.write(z.astype(dtype), 1)
    if variant == "truncated":
        data = p.read_bytes()
        p.write_bytes(data[: len(data) // 2])
    return p


def _fields_file(root: Path) -> Path:
    p = root / "fields.geojson"
    p.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"name": "west"},
         "geometry": {"type": "Point", "coordinates": _FIELD}}]}))  # fmt: skip
    return p


def run_dem(variant: str, value: Any, fmt: str) -> None:
    """``scenario import --dem``: a clear error with nothing written, or a scenario planned
    on and exported to QGC whose every mission clears the DEM's own pixels by the clearance."""
    from poc_env.agents.mission.export import export_plan
    from poc_env.agents.mission.formats.kml import validate_kml
    from poc_env.agents.mission.formats.qgc import validate_qgc
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.mission.terrain import qgc_clearance
    from poc_env.agents.planning.planner import make_plan
    from poc_env.config import load_scenario

    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        dem = _write_dem(root, variant, value)
        _import_into(
            root / "out", area=_area_file(root, _AREA), airfields=_fields_file(root), dem=dem,
            cell_km=5.0, base="small",
        )  # fmt: skip
        sc = load_scenario(str(root / "out" / "fuzz.yaml"))
        try:
            plan = make_plan(sc, planner="allocation", refine=0)
            write_plan(plan, root / "out" / "plan.json")  # beside its scenario (KML overlay)
            files = export_plan(root / "out" / "plan.json", fmt, out_dir=root / "x")
        except ConfigError as err:  # the import accepted ground a plan cannot record
            check(not str(err.field).startswith("plan.terrain"), f"imported, then {err}")
            raise
        clearance = float(sc.terrain.min_clearance_m)
        missions = 0
        for f in files:
            if f.suffix == ".kml":  # valid by the OGC KML 2.2 XSD
                check(validate_kml(f) == [], f"{f.name}: {validate_kml(f)[:2]}")
            if f.suffix != ".plan":
                continue
            doc = json.loads(f.read_text(encoding="utf-8"))
            check(validate_qgc(doc) == [], f"{f.name}: {validate_qgc(doc)[:2]}")
            least, legs = qgc_clearance(doc, dem)
            missions += legs > 0
            check(least >= clearance - 1e-6, f"{f.name} flies {least:.1f} m above the DEM")
        check(fmt != "qgc" or missions > 0, "no QGC mission to check")


# ------------------------------------------------------------------------ replan tracks
TRACK_VARIANTS = [
    "good", "good", "good", "multi", "plan_only", "outside", "crs_other", "crs_string",
    "crs_props", "point", "polygon", "null_geometry", "bare_list", "nan", "huge", "inf_text",
    "short", "other_scenario", "deep", "binary", "empty", "lat_lon_swapped", "three_d",
    "plan_deep", "plan_nan",
]  # fmt: skip
_REPLAN_ORIGIN = "45.5,126.6"


@functools.lru_cache(maxsize=1)
def _first_plan() -> str:
    """The first sortie's plan.json of ``small`` (once per process; a JSON text)."""
    from poc_env.agents.mission.crs import make_crs
    from poc_env.agents.planning.planner import make_plan
    from poc_env.config import load_scenario

    sc = load_scenario("small")
    plan = make_plan(sc, planner="allocation")
    plan["crs"] = make_crs("aeqd", (45.5, 126.6))
    with tempfile.TemporaryDirectory() as d:
        from poc_env.agents.mission.plan import write_plan

        write_plan(plan, Path(d) / "p1.json")
        return (Path(d) / "p1.json").read_text(encoding="utf-8")


def _tracks_text(plan: dict[str, Any], variant: str, value: Any, where: int) -> str:
    from poc_env.agents.mission.crs import to_geographic

    lines = []
    for u in plan["uavs"]:
        pts = [u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]
        lines.append([[lon, lat] for lat, lon in to_geographic(pts, plan["crs"])])
    line = lines[0]
    k = where % len(line)
    geom: Any = {"type": "LineString", "coordinates": line}
    doc: dict[str, Any] = {"type": "FeatureCollection"}
    if variant == "multi":
        geom = {"type": "MultiLineString", "coordinates": lines}
    elif variant == "outside":
        line[k] = [line[k][0] + 2.0, line[k][1]]
    elif variant == "crs_other":
        doc["crs"] = {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::3857"}}
    elif variant == "crs_string":
        doc["crs"] = "EPSG:4326"
    elif variant == "crs_props":
        doc["crs"] = {"type": "name", "properties": value}
    elif variant == "point":
        geom = {"type": "Point", "coordinates": line[0]}
    elif variant == "polygon":
        geom = {"type": "Polygon", "coordinates": [[*line, line[0]]]}
    elif variant == "null_geometry":
        geom = None
    elif variant == "bare_list":
        return json.dumps(line)
    elif variant in ("nan", "huge"):
        line[k] = [line[k][0], value if variant == "nan" else 1e308]
    elif variant == "inf_text":
        text = json.dumps(line).replace(str(line[k][0]), "1e400", 1)
        geom = {"type": "LineString", "coordinates": "@@"}
        feature = {"type": "Feature", "properties": {}, "geometry": geom}
        return json.dumps({**doc, "features": [feature]}).replace('"@@"', text)
    elif variant == "short":
        geom = {"type": "LineString", "coordinates": line[:1]}
    elif variant == "deep":
        return '{"type": "FeatureCollection", "features": ' + "[" * 5000 + "]" * 5000 + "}"
    elif variant == "empty":
        doc["features"] = []
        return json.dumps(doc)
    elif variant == "lat_lon_swapped":
        geom = {"type": "LineString", "coordinates": [[b, a] for a, b in line]}
    elif variant == "three_d":
        geom = {"type": "LineString", "coordinates": [[*p, 120.0] for p in line]}
    doc["features"] = [{"type": "Feature", "properties": {}, "geometry": geom}]
    return json.dumps(doc, allow_nan=True)


def run_tracks(variant: str, value: Any, where: int) -> None:
    """``poc-env replan`` with hostile ``--tracks`` or ``--plan``: a clear error with nothing
    written, or a next plan whose POS figures are probabilities that add up (eq. 13)."""
    from types import SimpleNamespace

    from poc_env.agents.mission.plan import load_plan
    from poc_env.agents.planning.replan import cli_main

    plan = json.loads(_first_plan())
    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        p1 = root / "p1.json"
        if variant == "other_scenario":
            plan["scenario"] = "paper_6_2"
        p1.write_text(json.dumps(plan), encoding="utf-8")
        if variant == "plan_deep":
            p1.write_text('{"schema": 1, "uavs": ' + "[" * 3000 + "]" * 3000 + "}")
        elif variant == "plan_nan":
            plan["uavs"][0]["waypoints_m"][0] = [value, 1e308]
            p1.write_text(json.dumps(plan, allow_nan=True), encoding="utf-8")
        tracks = None
        if variant not in ("plan_only", "other_scenario", "plan_deep", "plan_nan"):
            tracks = root / "flown.geojson"
            if variant == "binary":
                tracks.write_bytes(b"\xff\xfe\x00{" * 100)
            else:
                tracks.write_text(_tracks_text(plan, variant, value, where), encoding="utf-8")
        out = root / "out"
        out.mkdir()
        args = SimpleNamespace(
            plan=[str(p1)], scenario="small" if variant == "other_scenario" else None,
            overrides=None, map_file=None, tracks=[str(tracks)] if tracks else None,
            origin=None, planner="allocation", seed=0, out=str(out / "p2.json"),
        )  # fmt: skip
        import contextlib
        import io

        try:
            with contextlib.redirect_stdout(io.StringIO()):
                cli_main(args)
        except PocEnvError:
            check(not any(out.iterdir()), f"an error left {sorted(p.name for p in out.iterdir())}")
            raise
        nxt: dict[str, Any] = dict(load_plan(out / "p2.json"))
        s, c, own = nxt["searched_pos"], nxt["cumulative_posc"], nxt["sortie_posc"]
        posc = nxt["posc"]
        check(
            all(0.0 <= v <= 1.0 for v in (s, c, own, posc)), f"POS out of [0, 1]: {s}, {c}, {own}"
        )
        # the sortie's own POS is its routes swept over the belief the flights left (replan-audit)
        check(abs(c - min(s + own, 1.0)) < 1e-9, "cumulative POS is not searched + sortie_posc")


# ------------------------------------------------------------------------ the target


def datafiles_strategy():
    from hypothesis import strategies as st

    value = st.one_of(
        st.sampled_from([0.3, -0.4, 2.0, 30.0, 1e308, -1e308, float("nan"), float("inf"), 0.0]),
        hostile_scalars(),
    )
    return st.one_of(
        st.tuples(st.just("field"), st.sampled_from(FIELD_VARIANTS), st.sampled_from(_UNITS),
                  value, st.one_of(st.sampled_from(_STARTS), hostile_scalars())),
        st.tuples(st.just("particles"), st.sampled_from(PARTICLE_VARIANTS),
                  st.sampled_from(_UNITS), st.sampled_from(_PTIMES)),
        st.tuples(st.just("dem"), st.sampled_from(DEM_VARIANTS), value,
                  st.sampled_from(["qgc", "qgc", "kml"])),
        st.tuples(st.just("tracks"), st.sampled_from(TRACK_VARIANTS), value,
                  st.integers(0, 50)),
    )  # fmt: skip


RUNNERS: dict[str, Callable[..., None]] = {
    "field": run_field,
    "particles": run_particles,
    "dem": run_dem,
    "tracks": run_tracks,
}


def run_datafiles(case: tuple) -> None:
    """One hostile data file (module docstring); see :data:`RUNNERS`."""
    kind, *rest = case
    RUNNERS[kind](*rest)


__all__ = ["datafiles_strategy", "run_datafiles"]
