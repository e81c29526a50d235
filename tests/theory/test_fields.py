"""Velocity fields from .csv and CF NetCDF files (poc_env.theory.fields): interpolation onto the
map's cells and the episode's time, and every bad input named. Fixtures are small synthetic
files written by xarray."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.config import TargetConfig, load_scenario
from poc_env.errors import ConfigError
from poc_env.theory import fields, motion

xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")

ORIGIN = (45.0, -60.0)  # (lat, lon) of the map's (0, 0)
SHAPE = (8, 8)  # the small scenario: 40 km x 40 km of 5 km cells
SPAN = 3 * 3600.0
T0 = np.datetime64("2024-05-01T00:00:00", "ns")


def small_map(origin=ORIGIN, projection="aeqd"):
    return load_scenario(
        "small", {"map.origin_deg": list(origin) if origin else None, "map.projection": projection}
    ).map


def centres_lonlat(map_cfg):
    from poc_env.agents.mission.crs import make_crs, to_geographic

    x, y = fields.cell_centres(map_cfg, SHAPE)
    rec = make_crs(map_cfg.projection, map_cfg.origin_deg)
    ll = np.asarray(to_geographic(np.column_stack([x.ravel(), y.ravel()]), rec))
    return ll[:, 1].reshape(SHAPE), ll[:, 0].reshape(SHAPE)


def lonlat_dataset(times=4, lon=(-60.5, -59.0), lat=(44.8, 45.6), fn=None, units="m s-1"):
    """A current linear in lon, lat and time (so bilinear/linear interpolation is exact)."""
    lons = np.linspace(*lon, 31)
    lats = np.linspace(*lat, 25)[::-1]  # descending, as many models write it
    t = T0 + np.arange(times) * np.timedelta64(3600, "s")
    hours = np.arange(times, dtype=float)[:, None, None]
    la, lo = np.meshgrid(lats, lons, indexing="ij")
    fn = fn or (lambda h, lo, la: (0.2 + 0.1 * (lo + 60) + 0.05 * h, -0.1 + 0.2 * (la - 45)))
    u, v = fn(hours, lo[None], la[None])
    u = np.broadcast_to(u, (times, *lo.shape)).copy()
    v = np.broadcast_to(v, (times, *lo.shape)).copy()
    return xr.Dataset(
        {
            "uo": (("time", "latitude", "longitude"), u,
                   {"standard_name": "eastward_sea_water_velocity", "units": units}),
            "vo": (("time", "latitude", "longitude"), v,
                   {"standard_name": "northward_sea_water_velocity", "units": units}),
        },
        coords={
            "time": ("time", t),
            "latitude": ("latitude", lats,
                         {"standard_name": "latitude", "units": "degrees_north"}),
            "longitude": ("longitude", lons,
                          {"standard_name": "longitude", "units": "degrees_east"}),
        },
        attrs={"Conventions": "CF-1.8"},
    )  # fmt: skip


def write(ds, tmp_path, name="cur.nc", engine="h5netcdf"):
    path = tmp_path / name
    ds.to_netcdf(path, engine=engine)
    return str(path)


def check(path, map_cfg=None, start=None, span=SPAN):
    cfg = TargetConfig(model="drift", field_file=path, field_start=start)
    return motion.check(cfg, SHAPE, span, small_map() if map_cfg is None else map_cfg)


def test_a_cf_netcdf_current_in_lon_lat_is_interpolated_exactly_onto_the_cells(tmp_path):
    path = write(lonlat_dataset(), tmp_path)
    mo = check(path)
    lon, lat = centres_lonlat(small_map())
    f = mo.field
    assert f is not None and f.times_s is not None
    np.testing.assert_array_equal(f.times_s, [0.0, 3600.0, 7200.0, 10800.0])
    for t in (0.0, 1800.0, 5400.0, SPAN):
        h = t / 3600.0
        want_u = 0.2 + 0.1 * (lon + 60) + 0.05 * h
        want_v = -0.1 + 0.2 * (lat - 45)
        np.testing.assert_allclose(f.at(t)[0], want_u, atol=1e-12)
        np.testing.assert_allclose(f.at(t)[1], want_v, atol=1e-12)
    # a later start keeps only the frames the episode needs
    later = check(path, start="2024-05-01T00:30:00Z", span=3600.0).field
    assert later is not None and later.times_s is not None
    np.testing.assert_array_equal(later.times_s, [-1800.0, 1800.0, 5400.0])  # brackets [0, 1 h]
    np.testing.assert_allclose(later.at(0.0)[0], f.at(1800.0)[0], atol=1e-12)


def test_netcdf3_through_scipy_and_units_in_cm_per_second(tmp_path):
    ds = lonlat_dataset(fn=lambda h, lo, la: (20.0 + 0 * lo + 0 * h, -10.0 + 0 * la))
    for v in ("uo", "vo"):
        ds[v].attrs["units"] = "cm s-1"
    mo = check(write(ds, tmp_path, "c3.nc", engine="scipy"))
    assert mo.field is not None
    np.testing.assert_allclose(mo.field.at(100.0)[0], 0.2)
    np.testing.assert_allclose(mo.field.at(100.0)[1], -0.1)


def test_projected_x_y_with_a_grid_mapping_and_local_x_y_without_one(tmp_path):
    from pyproj import CRS, Transformer

    utm = CRS.from_epsg(32620)  # the origin's UTM zone (lon -60)
    tr = Transformer.from_crs("EPSG:4326", utm, always_xy=True)
    cx, cy = tr.transform(-59.8, 45.2)
    xs = cx + np.linspace(-60e3, 60e3, 13)
    ys = cy + np.linspace(-60e3, 60e3, 13)
    yy, xx = np.meshgrid(ys, xs, indexing="ij")
    u = 0.3 + 1e-6 * (xx - cx)  # linear in the file's x
    ds = xr.Dataset(
        {
            "u": (("y", "x"), u, {"units": "m/s", "grid_mapping": "crs"}),
            "v": (("y", "x"), np.full_like(u, 0.1), {"units": "m/s", "grid_mapping": "crs"}),
            "crs": ((), 0, utm.to_cf()),
        },
        coords={
            "x": ("x", xs / 1e3, {"standard_name": "projection_x_coordinate", "units": "km"}),
            "y": ("y", ys / 1e3, {"standard_name": "projection_y_coordinate", "units": "km"}),
        },
    )
    mo = check(write(ds, tmp_path, "utm.nc"))
    assert mo.field is not None and mo.field.frames.shape == (1, 2, *SHAPE)
    lon, lat = centres_lonlat(small_map())
    fx, _ = tr.transform(lon, lat)
    np.testing.assert_allclose(mo.field.at(0.0)[0], 0.3 + 1e-6 * (fx - cx), atol=1e-9)
    np.testing.assert_allclose(mo.field.at(0.0)[1], 0.1)
    # the same x/y without a grid mapping: the scenario's local metres (no origin needed)
    x = np.linspace(-5e3, 45e3, 11)
    yy, xx = np.meshgrid(x, x, indexing="ij")
    loc = xr.Dataset(
        {"u": (("y", "x"), 1e-5 * xx, {"units": "m s-1"}),
         "v": (("y", "x"), -1e-5 * yy, {"units": "m s-1"})},
        coords={"x": ("x", x, {"axis": "X", "units": "m"}),
                "y": ("y", x, {"axis": "Y", "units": "m"})},
    )  # fmt: skip
    mo = check(write(loc, tmp_path, "local.nc"), small_map(origin=None))
    cxm, cym = fields.cell_centres(small_map(origin=None), SHAPE)
    assert mo.field is not None
    np.testing.assert_allclose(mo.field.at(0.0)[0], 1e-5 * cxm, atol=1e-12)
    np.testing.assert_allclose(mo.field.at(0.0)[1], -1e-5 * cym, atol=1e-12)


def test_csv_uniform_time_varying_and_gridded(tmp_path):
    p = tmp_path / "u.csv"
    p.write_text("t_s,u_mps,v_mps\n0,0.0,1.0\n3600,1.0,1.0\n20000,1.0,0.0\n")
    mo = check(str(p), small_map(origin=None))
    assert mo.field is not None
    np.testing.assert_allclose(mo.field.at(1800.0)[0], 0.5)
    np.testing.assert_allclose(mo.field.at(1800.0)[1], 1.0)
    rows = ["x_m,y_m,u_mps,v_mps"]
    for y in (0.0, 40e3):
        for x in (0.0, 40e3):
            rows.append(f"{x},{y},{x / 1e5},{y / 1e5}")
    g = tmp_path / "g.csv"
    g.write_text("\n".join(rows) + "\n")
    mo = check(str(g), small_map(origin=None))
    cx, cy = fields.cell_centres(small_map(origin=None), SHAPE)
    assert mo.field is not None
    np.testing.assert_allclose(mo.field.at(0.0)[0], cx / 1e5, atol=1e-12)
    np.testing.assert_allclose(mo.field.at(0.0)[1], cy / 1e5, atol=1e-12)


def test_a_scenario_with_a_netcdf_current_runs_and_conserves_mass(tmp_path):
    from poc_env.sim import core as sim

    path = write(lonlat_dataset(times=3, lon=(-60.5, -59.0)), tmp_path)
    sc = load_scenario(
        "small",
        {"map.origin_deg": list(ORIGIN), "target.model": "drift", "target.field_file": path,
         "episode.horizon_steps": 100},
    )  # fmt: skip
    params = sim.make_params(sc)
    rngs = [np.random.default_rng(k) for k in range(2)]
    state = sim.initial(params, rngs)
    before = state.belief.sum(axis=(1, 2)).copy()
    for _ in range(5):
        sim.predict(params, state)
        state.step += 1
    assert state.mass_out is not None
    moved = np.abs(state.belief.sum(axis=(1, 2)) - before).max() > 0 or state.mass_out.max() > 0
    assert moved
    np.testing.assert_allclose(state.belief.sum(axis=(1, 2)) + state.mass_out, before, atol=1e-12)


def _bad(tmp_path, ds, name):
    return write(ds, tmp_path, f"{name}.nc")


def test_bad_fields_are_refused_naming_the_field(tmp_path):
    m = small_map()
    cases = {}
    ds = lonlat_dataset()
    ds["uo"][1, 10:14, 5:20] = np.nan
    cases["nan"] = ("target.field_file", _bad(tmp_path, ds, "nan"), "NaN")
    ds = lonlat_dataset(units="km h-1")
    cases["units"] = ("target.field_file uo.units", _bad(tmp_path, ds, "units"), "speed unit")
    ds = lonlat_dataset()
    del ds["uo"].attrs["units"]
    cases["no units"] = ("target.field_file uo.units", _bad(tmp_path, ds, "nounits"), "m s-1")
    ds = lonlat_dataset(fn=lambda h, lo, la: (30.0 + 0 * lo + 0 * h, 0 * la))
    cases["too fast"] = ("target.field_file", _bad(tmp_path, ds, "fast"), "km/h")
    cases["small"] = (
        "target.field_file", _bad(tmp_path, lonlat_dataset(lon=(-59.9, -59.0)), "small"),
        "covering every cell",
    )  # fmt: skip
    cases["short"] = ("target.field_file", _bad(tmp_path, lonlat_dataset(times=2), "short"), "0 to")
    ds = lonlat_dataset().drop_vars(["latitude", "longitude"])
    cases["no coords"] = ("target.field_file uo", _bad(tmp_path, ds, "nocoord"), "coordinates")
    ds = lonlat_dataset()
    clarke = {"grid_mapping_name": "latitude_longitude", "semi_major_axis": 6378206.4,
              "inverse_flattening": 294.9786982}  # fmt: skip
    ds["crs"] = ((), 0, clarke)
    ds["uo"].attrs["grid_mapping"] = "crs"
    cases["datum"] = ("target.field_file grid_mapping", _bad(tmp_path, ds, "nad27"), "WGS84")
    ds = lonlat_dataset()
    ds["uo"].attrs["standard_name"] = "x_wind"
    ds["vo"].attrs["standard_name"] = "y_wind"
    ds = ds.rename({"uo": "uw", "vo": "vw"})
    cases["wind"] = ("target.field_file", _bad(tmp_path, ds, "wind"), "a current")
    ds = lonlat_dataset().expand_dims(depth=[0.0, 10.0], axis=1)
    cases["depth"] = ("target.field_file uo", _bad(tmp_path, ds, "depth"), "size 1")
    for name, (field, path, text) in cases.items():
        with pytest.raises(ConfigError) as err:
            check(path, m)
            pytest.fail(name)
        assert err.value.field == field, name
        assert text in str(err.value), (name, str(err.value))
    good = write(lonlat_dataset(), tmp_path, "good.nc")
    with pytest.raises(ConfigError) as err:  # a lon/lat field on a map without geography
        check(good, small_map(origin=None))
    assert err.value.field == "map.origin_deg"
    with pytest.raises(ConfigError) as err:
        check(good, m, start="2024-05-01T02:00:00")  # the span then ends after the file
    assert err.value.field == "target.field_file"
    with pytest.raises(ConfigError) as err:
        check(good, m, start="noon")
    assert err.value.field == "target.field_start"
    with pytest.raises(ConfigError) as err:
        motion.check(TargetConfig(model="drift", field_file=good, field_dt_s=60.0), SHAPE, SPAN, m)
    assert err.value.field == "target.field_dt_s"
    p = tmp_path / "holes.csv"
    p.write_text("x_m,y_m,u_mps,v_mps\n0,0,0,0\n40000,0,0,0\n0,40000,0,0\n")
    with pytest.raises(ConfigError, match="full lattice"):
        check(str(p), m)
    p.write_text("x_m,y_m,u,v\n0,0,0,0\n")
    with pytest.raises(ConfigError) as err:
        check(str(p), m)
    assert err.value.field == "target.field_file header"
    with pytest.raises(ConfigError) as err:
        check(str(tmp_path / "missing.nc"), m)
    assert err.value.field == "target.field_file"


def test_a_scenario_file_with_a_netcdf_field_and_an_unquoted_start(tmp_path):
    import yaml

    from poc_env.sim import core as sim

    write(lonlat_dataset(), tmp_path, "cur.nc")
    data = load_scenario("small").to_dict()
    data["map"]["origin_deg"] = list(ORIGIN)
    data["target"] = {"model": "drift", "field_file": "cur.nc"}
    text = yaml.safe_dump(data)
    text = text.replace(
        "field_file: cur.nc", "field_file: cur.nc\n  field_start: 2024-05-01T02:30:00+02:00"
    )
    path = tmp_path / "moving.yaml"
    path.write_text(text)
    sc = load_scenario(str(path))  # YAML reads the time as a datetime: back to UTC text
    assert sc.target.field_start == "2024-05-01T00:30:00"
    assert sc.target.field_file == str(tmp_path / "cur.nc")  # relative to the YAML
    sc = load_scenario(str(path), {"episode.horizon_steps": 60})  # 30 min of 30 s steps
    params = sim.make_params(sc)
    assert params.motion is not None and params.motion.field is not None
    assert params.motion.field.times_s is not None
    np.testing.assert_array_equal(params.motion.field.times_s, [-1800.0, 1800.0])


def test_campaign_found_field_files_are_refused_naming_the_field(tmp_path):
    """Issue 27's campaign (datafiles target): a .npz archive named .npy (an AttributeError
    before), a wind whose variables are named uo/vo (read as a current before), and a chunked
    file declaring terabytes (read into memory before) are ConfigErrors naming the field."""
    m = small_map()
    npz = tmp_path / "cur.npy"
    with open(npz, "wb") as fh:
        np.savez(fh, a=np.zeros((2, *SHAPE)))
    with pytest.raises(ConfigError, match="npz archive") as err:
        check(str(npz), m)
    assert err.value.field == "target.field_file"
    ds = lonlat_dataset()
    ds["uo"].attrs["standard_name"] = "x_wind"
    ds["vo"].attrs["standard_name"] = "y_wind"
    with pytest.raises(ConfigError, match="a current") as err:
        check(write(ds, tmp_path, "wind.nc"), m)
    assert err.value.field == "target.field_file"
    import h5netcdf

    huge = tmp_path / "huge.nc"
    with h5netcdf.File(huge, "w") as f:
        f.dimensions = {"time": 100_000, "latitude": 1000, "longitude": 1000}
        for name, std in (("uo", "eastward"), ("vo", "northward")):
            v = f.create_variable(name, ("time", "latitude", "longitude"), float,
                                  chunks=(1, 100, 100), fillvalue=0.0)  # fmt: skip
            v.attrs["standard_name"] = f"{std}_sea_water_velocity"
            v.attrs["units"] = "m s-1"
        for d, std, units in (("latitude", "latitude", "degrees_north"),
                              ("longitude", "longitude", "degrees_east")):  # fmt: skip
            c = f.create_variable(d, (d,), float, data=np.linspace(44, 46, 1000))
            c.attrs.update({"standard_name": std, "units": units})
        t = f.create_variable("time", ("time",), float, data=np.arange(100_000.0))
        t.attrs["units"] = "seconds since 2024-05-01"
    with pytest.raises(ConfigError, match="memory limit") as err:
        check(str(huge), m)
    assert err.value.field == "target.field_file"
