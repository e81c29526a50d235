"""Particle files in (issue 25): OpenDrift-style trajectory NetCDF as the prior of an imported
scenario, checked against the grid filter on particles our own drift model moved; every bad
file named. Fixtures: small synthetic files written by xarray."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from poc_env.agents.mission import geoimport
from poc_env.agents.mission.crs import make_crs, to_geographic, to_local
from poc_env.agents.mission.particles import read_particles
from poc_env.config import TargetConfig
from poc_env.errors import ConfigError
from poc_env.theory import motion

xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")

T0 = np.datetime64("2024-05-01T00:00:00", "ns")
AREA = [[126.0, 45.3], [127.2, 45.3], [127.2, 46.1], [126.0, 46.1], [126.0, 45.3]]
FIELDS = [("Harbin", 126.25, 45.62), ("Acheng", 126.95, 45.25)]


def trajectory_file(path, lon, lat, every_s=600.0, **attrs):
    """An OpenDrift-like output: lon/lat (trajectory, time), CF featureType trajectory."""
    n, t = lon.shape
    times = T0 + (np.arange(t) * every_s * 1e9).astype("timedelta64[ns]")
    ds = xr.Dataset(
        {
            "lon": (("trajectory", "time"), lon,
                    {"standard_name": "longitude", "units": "degrees_east"}),
            "lat": (("trajectory", "time"), lat,
                    {"standard_name": "latitude", "units": "degrees_north"}),
        },
        coords={"trajectory": np.arange(n), "time": ("time", times)},
        attrs={"featureType": "trajectory", "Conventions": "CF-1.6", **attrs},
    )  # fmt: skip
    ds.to_netcdf(path, engine="h5netcdf")
    return path


def test_particles_moved_by_the_drift_model_match_the_grid_filter(tmp_path):
    """N particles moved by the drift model's own law (motion.move_targets, seeded) and the grid
    filter started from the same particles: the centres of mass agree within their sampling
    error, and the spreads differ by exactly the upwind scheme's numerical diffusion
    ``D_num = |u| h / 2 (1 - |u| tau / h)`` per axis (the documented difference of the grid
    filter; particles carry none), within sampling error."""
    rng = np.random.default_rng(2024)
    n, h, dt, steps, every = 20_000, 1000.0, 60.0, 120, 10
    shape = (80, 80)  # 80 km x 80 km, 1 km cells, local origin (0, 0)
    vel = np.array([0.5, -0.3])
    d = 20.0
    mot = motion.check(TargetConfig(model="drift", diffusion_m2_s=d), shape, steps * dt)
    pos = rng.normal([30e3, 45e3], 3e3, (n, 2))
    out = np.zeros(n, dtype=bool)
    uniform = np.broadcast_to(vel, (n, 2))
    rec = make_crs("aeqd", (45.0, 10.0))
    track = [pos.copy()]
    for k in range(steps):
        motion.move_targets(
            mot, pos, out, uniform, rng.standard_normal((n, 2)), k * dt, dt, (0.0, 0.0), h, shape
        )
        if (k + 1) % every == 0:
            track.append(pos.copy())
    assert not out.any()
    ll = np.array([to_geographic(p, rec) for p in track])  # (T, n, 2) lat, lon
    path = trajectory_file(tmp_path / "run.nc", ll[..., 1].T, ll[..., 0].T, every * dt)

    def binned(time):
        p = read_particles(path, time)
        xy = np.array(to_local(np.column_stack([p.lat, p.lon]), rec))
        m, _, _ = np.histogram2d(xy[:, 1], xy[:, 0], bins=shape, range=[[0, 80e3], [0, 80e3]])
        return m / n

    start, end = binned("2024-05-01T00:00:00Z"), binned(None)  # None: the last time
    belief = start[None].copy()
    mass_out = np.zeros(1)
    for _ in range(steps):
        mass_out += motion.advect_diffuse(belief, vel[0], vel[1], d, dt, h)
    assert mass_out[0] < 1e-9  # the whole cloud stays on the map: moments are exact

    def moments(m):
        y, x = (np.mgrid[: shape[0], : shape[1]] + 0.5) * h
        mx, my = (m * x).sum(), (m * y).sum()
        return np.array([mx, my]), np.array([(m * x * x).sum() - mx**2, (m * y * y).sum() - my**2])

    (m0, v0), (mg, vg), (mp, vp) = moments(start), moments(belief[0]), moments(end)
    t = steps * dt
    np.testing.assert_allclose(mg - m0, vel * t, atol=1e-6)  # the filter's mean: exact v t
    # centre of mass: the particles' noise mean (sd sqrt(2 D t / n)) and two binnings
    # (sd h / sqrt(12 n) each)
    se = np.sqrt(2 * d * t / n + 2 * h * h / (12 * n))
    assert np.all(np.abs(mp - mg) < 5 * se), (mp - mg, se)
    # spread: grid = 2 (D + D_num) t, particles = 2 D t (+ sampling error of the change)
    d_num = np.abs(vel) * h / 2 * (1 - np.abs(vel) * dt / h)
    np.testing.assert_allclose(vg - v0, 2 * (d + d_num) * t, rtol=1e-9)
    se_v = 2 * np.sqrt(v0 * 2 * d * t / n) + 2 * d * t * np.sqrt(2 / n) + h * h / np.sqrt(n)
    assert np.all(np.abs((vg - vp) - 2 * d_num * t) < 5 * se_v), (vg - vp, 2 * d_num * t, se_v)
    assert np.all(2 * d_num * t > 20 * se_v)  # and the test can tell D_num apart


def _gis(tmp_path):
    feat = {"type": "Feature", "properties": {},
            "geometry": {"type": "Polygon", "coordinates": [AREA]}}  # fmt: skip
    (tmp_path / "area.geojson").write_text(json.dumps(feat))
    pts = [
        {"type": "Feature", "properties": {"name": nm},
         "geometry": {"type": "Point", "coordinates": [lon, lat]}}
        for nm, lon, lat in FIELDS
    ]  # fmt: skip
    (tmp_path / "fields.geojson").write_text(
        json.dumps({"type": "FeatureCollection", "features": pts})
    )
    return str(tmp_path / "area.geojson"), str(tmp_path / "fields.geojson")


def _cloud(tmp_path, name="p.nc", n=500, **attrs):
    rng = np.random.default_rng(3)
    lon = rng.normal(126.7, 0.15, (n, 4))
    lat = rng.normal(45.7, 0.1, (n, 4))
    lon[:5, -1] = np.nan  # stranded / deactivated at the last time
    lat[:5, -1] = np.nan
    lon[5:9, -1] = 128.5  # drifted out of the area
    return trajectory_file(tmp_path / name, lon, lat, **attrs), lon, lat


def test_scenario_import_takes_the_particles_as_the_prior(tmp_path):
    area, fields = _gis(tmp_path)
    path, lon, lat = _cloud(tmp_path)
    res = geoimport.import_scenario(area, airfields=fields, particles=str(path), name="p")
    rep = res["report"]["prior"]
    assert rep["particles"] == 500 and rep["inactive"] == 5 and rep["samples"] == 495
    assert rep["time"] == "2024-05-01T00:30:00"
    assert rep["outside_share"] == pytest.approx(4 / 495)
    # the prior: the active particles inside the area, one equal mass each, in their cells
    m = res["scenario"]["map"]
    xy = np.array(to_local(np.column_stack([lat[9:, -1], lon[9:, -1]]), res["crs"]))
    ny, nx = res["prior"].shape
    x0, y0 = (v * 1000 for v in m["origin_km"])
    c = m["cell_km"] * 1000
    want, _, _ = np.histogram2d(
        xy[:, 1], xy[:, 0], bins=(ny, nx), range=[[y0, y0 + ny * c], [x0, x0 + nx * c]]
    )
    np.testing.assert_allclose(res["prior"], want / want.sum(), atol=1e-15)
    # an earlier time of the run: all 500 active
    early = geoimport.import_scenario(
        area, airfields=fields, particles=str(path), particles_time="2024-05-01T00:10:00", name="p"
    )
    assert early["report"]["prior"]["inactive"] == 0
    # the command writes the three files
    p = argparse.ArgumentParser()
    geoimport.add_scenario_import_arguments(p)
    out = tmp_path / "out" / "drift.yaml"
    out.parent.mkdir()
    args = p.parse_args([area, "--airfields", fields, "--particles", str(path), "--out", str(out)])
    assert geoimport.cmd_scenario_import(args) == 0
    assert sorted(f.name for f in out.parent.iterdir()) == [
        "drift.crs.json", "drift.npy", "drift.yaml"
    ]  # fmt: skip
    np.testing.assert_allclose(np.load(out.parent / "drift.npy"), res["prior"], atol=1e-15)


def test_bad_particle_files_are_refused_naming_what_is_wrong(tmp_path):
    area, fields = _gis(tmp_path)
    good = _cloud(tmp_path)[0]
    cases = {}
    cases["feature type"] = (_cloud(tmp_path, "ts.nc", featureType="timeSeries")[0], "featureType")
    ds = xr.open_dataset(good).load()
    xy = ds.rename({"lon": "x", "lat": "y"})
    for v in ("x", "y"):
        xy[v].attrs = {"units": "m"}
    xy.to_netcdf(tmp_path / "xy.nc", engine="h5netcdf")
    cases["no lon/lat"] = (tmp_path / "xy.nc", "another CRS")
    bad = ds.copy()
    bad["lon"].attrs["units"] = "m"
    bad.to_netcdf(tmp_path / "units.nc", engine="h5netcdf")
    cases["units"] = (tmp_path / "units.nc", "lon.units")
    nad = ds.copy()
    clarke = {"grid_mapping_name": "latitude_longitude", "semi_major_axis": 6378206.4,
              "inverse_flattening": 294.9786982}  # fmt: skip
    nad["crs"] = ((), 0, clarke)
    nad["lon"].attrs["grid_mapping"] = "crs"
    nad.to_netcdf(tmp_path / "nad.nc", engine="h5netcdf")
    cases["datum"] = (tmp_path / "nad.nc", "WGS84")
    empty = ds.copy()
    empty["lon"][:, -1] = np.nan
    empty.to_netcdf(tmp_path / "empty.nc", engine="h5netcdf")
    cases["no active"] = (tmp_path / "empty.nc", "no active particle")
    (tmp_path / "junk.nc").write_bytes(b"not netcdf")
    cases["junk"] = (tmp_path / "junk.nc", "unreadable")
    cases["missing"] = (tmp_path / "none.nc", "an existing NetCDF")
    for name, (path, text) in cases.items():
        with pytest.raises(ConfigError) as err:
            geoimport.import_scenario(area, airfields=fields, particles=str(path))
        assert text in str(err.value), (name, str(err.value))
    with pytest.raises(ConfigError) as err:
        read_particles(good, "2024-06-01T00:00:00")
    assert err.value.field == "particles_time"
    with pytest.raises(ConfigError) as err:
        geoimport.import_scenario(area, airfields=fields, particles=str(good), prior="x.csv")
    assert err.value.field == "particles"
    # nothing written by a refused command
    p = argparse.ArgumentParser()
    geoimport.add_scenario_import_arguments(p)
    out = tmp_path / "o" / "s.yaml"
    out.parent.mkdir()
    args = p.parse_args(
        [area, "--airfields", fields, "--particles", str(tmp_path / "ts.nc"), "--out", str(out)]
    )
    with pytest.raises(ConfigError):
        geoimport.cmd_scenario_import(args)
    assert list(out.parent.iterdir()) == []


def test_a_particle_file_declaring_more_than_the_memory_limit_is_refused_unread(tmp_path):
    """Issue 27's campaign (datafiles target): a chunked NetCDF of a few kB may declare
    terabytes of positions; its declared size is refused before anything is read."""
    import h5netcdf

    p = tmp_path / "huge.nc"
    with h5netcdf.File(p, "w") as f:
        f.dimensions = {"trajectory": 1_000_000, "time": 100_000}
        f.attrs["featureType"] = "trajectory"
        for name, std, un in (("lon", "longitude", "degrees_east"),
                              ("lat", "latitude", "degrees_north")):  # fmt: skip
            v = f.create_variable(name, ("trajectory", "time"), float, chunks=(1000, 100),
                                  fillvalue=np.nan)  # fmt: skip
            v.attrs.update({"standard_name": std, "units": un})
    assert p.stat().st_size < 1_000_000
    with pytest.raises(ConfigError, match="memory limit") as err:
        read_particles(p)
    assert err.value.field == "particles"


def _drifting(tmp_path, name="run.nc", n=400, hours=1.5, every=600.0, seed=4):
    """An OpenDrift-like run of ``n`` particles drifting east at ~1 m/s from around the area's
    centre, outputs ``every`` seconds for ``hours``; a few stranded (NaN) after 40 min."""
    rng = np.random.default_rng(seed)
    t = round(hours * 3600 / every) + 1
    rec = make_crs("aeqd", (45.7, 126.6))
    x0 = rng.normal(0.0, 4e3, n)
    y0 = rng.normal(0.0, 4e3, n)
    times = np.arange(t) * every
    x = x0[:, None] + 1.0 * times[None] + rng.normal(0, 50.0, (n, t)).cumsum(axis=1)
    y = y0[:, None] + 0.2 * times[None]
    ll = np.array(to_geographic(np.column_stack([x.ravel(), y.ravel()]), rec)).reshape(n, t, 2)
    lon, lat = ll[..., 1].copy(), ll[..., 0].copy()
    lon[:7, 5:], lat[:7, 5:] = np.nan, np.nan  # stranded: deactivated from the 5th output
    return trajectory_file(tmp_path / name, lon, lat, every), lon, lat


def test_particle_motion_import_writes_the_tracks_and_the_environment_runs_them(tmp_path):
    from poc_env.config import load_scenario
    from poc_env.sim.engine import Engine

    area, fields = _gis(tmp_path)
    path, lon, _ = _drifting(tmp_path)
    p = argparse.ArgumentParser()
    geoimport.add_scenario_import_arguments(p)
    out = tmp_path / "out" / "moving.yaml"
    args = p.parse_args(
        [area, "--airfields", fields, "--particles", str(path), "--particle-motion",
         "--base", "small", "--cell-km", "5", "--out", str(out)]
    )  # fmt: skip
    assert geoimport.cmd_scenario_import(args) == 0
    assert sorted(f.name for f in out.parent.iterdir()) == [
        "moving.crs.json", "moving.npy", "moving.particles.npz", "moving.yaml"
    ]  # fmt: skip
    sc = load_scenario(str(out))
    assert sc.target.model == "particles"
    assert sc.target.particles_file == str(out.parent / "moving.particles.npz")
    with np.load(sc.target.particles_file) as z:
        assert str(z["start"]) == "2024-05-01T00:00:00"  # default: the run's first time
        np.testing.assert_array_equal(z["t_s"], np.arange(10) * 600.0)
        np.testing.assert_array_equal(z["lon"][:, 0], lon[:, 0])
        np.testing.assert_array_equal(z["lon"][:7, 5:], lon[:7, 4:5].repeat(5, axis=1))  # held
    eng = Engine(sc, 2, control="heading", seeds=[0, 1])
    eng.reset()
    st = eng.current
    b0 = st.belief.copy()
    for _ in range(60):
        eng.step(np.zeros((2, eng.n_agents, eng.action_dim)))
        total = st.belief.sum(axis=(1, 2)) + st.posc + st.mass_out
        np.testing.assert_allclose(total, st.initial_mass, rtol=0, atol=1e-9)
    # the belief moved east with the particles (~1 m/s for 30 min: ~1.8 km)
    x = np.arange(b0.shape[2])
    east = ((st.belief.sum(axis=1) * x).sum(axis=1) / st.belief.sum(axis=(1, 2))) - (
        (b0.sum(axis=1) * x).sum(axis=1) / b0.sum(axis=(1, 2))
    )
    h = sc.map.cell_m / sc.sensor.samples_per_cell
    assert np.all(east * h > 1000.0), east * h


def test_bad_particle_motion_inputs_are_refused_and_nothing_is_written(tmp_path):
    area, fields = _gis(tmp_path)
    p = argparse.ArgumentParser()
    geoimport.add_scenario_import_arguments(p)
    short = _drifting(tmp_path, "short.nc", hours=0.5)[0]  # small's episode: 40.5 min
    few = _drifting(tmp_path, "few.nc", n=60)[0]
    ds = xr.open_dataset(_drifting(tmp_path)[0]).load()
    ds.isel(time=0).drop_vars("time").to_netcdf(tmp_path / "untimed.nc", engine="h5netcdf")
    xy = ds.rename({"lon": "x", "lat": "y"})
    for v in ("x", "y"):
        xy[v].attrs = {"units": "m"}
    xy.to_netcdf(tmp_path / "xy.nc", engine="h5netcdf")
    nad = ds.copy()
    nad["crs"] = (
        (),
        0,
        {
            "grid_mapping_name": "latitude_longitude",
            "semi_major_axis": 6378206.4,
            "inverse_flattening": 294.9786982,
        },
    )
    nad["lon"].attrs["grid_mapping"] = "crs"
    nad.to_netcdf(tmp_path / "nad.nc", engine="h5netcdf")
    cases = {
        "no lonlat": (tmp_path / "xy.nc", [], "another CRS"),
        "datum": (tmp_path / "nad.nc", [], "WGS84"),
        "short": (short, [], "covering the episode"),
        "few": (few, [], "at least 100 particles"),
        "no time": (tmp_path / "untimed.nc", [], "no CF time coordinate"),
        "late start": (short, ["--particles-time", "2024-05-01T00:30:00"], "covering"),
        "bad start": (short, ["--particles-time", "2024-06-01T00:00:00"], "one of the file's"),
    }
    for name, (path, extra, text) in cases.items():
        out = tmp_path / name.replace(" ", "_") / "s.yaml"
        out.parent.mkdir()
        args = p.parse_args(
            [area, "--airfields", fields, "--particles", str(path), "--particle-motion",
             "--base", "small", "--out", str(out), *extra]
        )  # fmt: skip
        with pytest.raises(ConfigError, match=text):
            geoimport.cmd_scenario_import(args)
        assert list(out.parent.iterdir()) == [], name
    with pytest.raises(ConfigError) as err:
        geoimport.import_scenario(area, airfields=fields, particle_motion=True)
    assert err.value.field == "particle_motion"
