"""Gridded, time-varying winds for the leeway model (``target.wind_file``): one reader with the
current (:mod:`poc_env.theory.fields`, kind ``"wind"``), the leeway per cell and time, the
episode's crosswind side from its generator as with a uniform wind, and bad input named."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.config import TargetConfig, load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.engine import Engine
from poc_env.theory import motion

SHAPE = (8, 8)  # the small scenario: 40 km x 40 km of 5 km cells
CLASS = "life_raft_deep_ballast"  # offsets and unequal left/right crosswind: the side matters


def run(overrides: dict, steps: int = 40, n_envs: int = 4):
    sc = load_scenario("small", {"episode.horizon_steps": steps, **overrides})
    eng = Engine(sc, n_envs, control="heading", obs_type="compass", seeds=[5, 6, 7, 8])
    obs, info = eng.reset()
    rng = np.random.default_rng(11)
    out = [(obs, None, info, eng.current.target.copy())]
    for _ in range(steps):
        tr = eng.step(rng.uniform(-1, 1, (n_envs, eng.n_agents, eng.action_dim)))
        out.append((tr.obs, tr.reward, tr.info, eng.current.target.copy()))
        st = eng.current
        total = st.belief.sum(axis=(1, 2)) + st.posc + st.mass_out
        np.testing.assert_allclose(total, st.initial_mass, rtol=0, atol=1e-9)
    return eng, out


def npy(tmp_path, arr, name="wind.npy"):
    path = tmp_path / name
    np.save(path, np.asarray(arr, dtype=float))
    return str(path)


def test_a_uniform_wind_file_reproduces_the_uniform_wind_episodes(tmp_path):
    wind_kmh = (36.0, -18.0)  # 10 m/s east, 5 m/s south: exact in m/s
    frames = np.zeros((2, *SHAPE))
    frames[0], frames[1] = 10.0, -5.0
    base = {"target.model": "leeway", "target.leeway_class": CLASS}
    base["target.current_kmh"] = [3.6, 7.2]
    base["target.diffusion_m2_s"] = 20.0
    eng_u, uniform = run({**base, "target.wind_kmh": list(wind_kmh)})
    eng_f, filed = run({**base, "target.wind_file": npy(tmp_path, frames)})
    assert eng_f.params.motion.wind_field is not None and eng_u.params.motion.wind != (0, 0)
    sides = eng_f.current.leeway_side
    assert set(sides.tolist()) == {1.0, -1.0}  # both sides drawn over the four seeds
    # the same sides as the uniform wind's draw: the drift differs by exactly that leeway
    cls = motion.LEEWAY_CLASSES[CLASS]
    for k, side in enumerate(sides):
        lee = motion.leeway_velocity(cls, (10.0, -5.0), side)
        np.testing.assert_allclose(eng_u.current.drift[k], eng_f.current.drift[k] + lee, atol=0)
    moved = 0.0
    for (o1, r1, i1, t1), (o2, r2, i2, t2) in zip(uniform, filed, strict=True):
        np.testing.assert_allclose(o2, o1, rtol=0, atol=1e-12)
        np.testing.assert_allclose(t2, t1, rtol=0, atol=1e-9)  # metres (values ~ 1e4)
        if r1 is not None:
            np.testing.assert_allclose(r2, r1, rtol=0, atol=1e-12)
        for key, value in i1.items():
            np.testing.assert_allclose(i2[key], value, rtol=0, atol=1e-12, err_msg=key)
        moved = max(moved, float(np.abs(t2 - filed[0][3]).max()))
    assert moved > 1000.0  # the targets did move (10 m/s wind, 20 min)


def test_a_gridded_time_varying_wind_gives_each_cell_its_leeway(tmp_path):
    t_frames = 3
    wind = np.zeros((t_frames, 2, *SHAPE))
    cols = np.arange(SHAPE[1], dtype=float)
    wind[:, 0] = 2.0 + cols[None, None, :]  # east wind growing eastward
    wind[:, 1] = np.array([0.0, 4.0, 8.0])[:, None, None]  # a north wind rising in time
    cfg = TargetConfig(
        model="leeway", leeway_class=CLASS, wind_file=npy(tmp_path, wind), wind_dt_s=600.0,
        current_kmh=(3.6, 0.0),
    )  # fmt: skip
    mo = motion.check(cfg, SHAPE, 1200.0)
    cls = motion.LEEWAY_CLASSES[CLASS]
    uniform, side = mo.draw_episode(np.random.default_rng(3))
    np.testing.assert_array_equal(uniform, [1.0, 0.0])  # the current only
    assert side in (1.0, -1.0)
    t, s = 900.0, 2  # halfway between frames 1 and 2
    u, v = motion.cell_velocity(mo, uniform[None], t, s, np.array([side]))
    for j, i in ((0, 0), (3, 5), (7, 7)):
        w = (2.0 + i, 6.0)  # the wind at (j, i) at 900 s
        speed = np.hypot(*w)
        down = np.array(w) / speed
        dw, cw = cls.leeway(speed, side)
        expect = np.array([1.0, 0.0]) + dw * down + cw * np.array([down[1], -down[0]])
        # the wind is linear in time between frames, the leeway that of the local wind
        np.testing.assert_allclose(
            [u[0, 2 * j, 2 * i], v[0, 2 * j + 1, 2 * i + 1]], expect, rtol=1e-12, atol=1e-15
        )
    # the other side's field: the crosswind to the other side
    u2, _ = motion.cell_velocity(mo, uniform[None], t, s, np.array([-side]))
    assert not np.allclose(u2, u)
    with pytest.raises(ConfigError, match="side") as err:  # one velocity per episode: refused
        motion.cell_velocity(mo, uniform[None], t, s)
    assert err.value.field == "target.wind_file"


def test_a_cf_netcdf_wind_and_a_current_given_as_wind(tmp_path):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    t0 = np.datetime64("2024-05-01T00:00:00", "ns")
    times = t0 + np.arange(3) * np.timedelta64(3600, "s")
    xs = np.linspace(-5000.0, 45000.0, 11)

    def ds(names, units="knots"):
        u = np.full((3, len(xs), len(xs)), 10.0)
        v = np.zeros_like(u)
        coord = {"units": "m"}
        return xr.Dataset(
            {
                "a": (("time", "y", "x"), u, {"standard_name": names[0], "units": units}),
                "b": (("time", "y", "x"), v, {"standard_name": names[1], "units": units}),
            },
            coords={"time": ("time", times), "x": ("x", xs, {**coord, "axis": "X"}),
                    "y": ("y", xs, {**coord, "axis": "Y"})},
        )  # fmt: skip

    path = tmp_path / "wind.nc"
    ds(("eastward_wind", "northward_wind")).to_netcdf(path, engine="h5netcdf")
    sc_map = load_scenario("small").map
    cfg = TargetConfig(model="leeway", wind_file=str(path), wind_start="2024-05-01T00:30")
    mo = motion.check(cfg, SHAPE, 3600.0, sc_map)
    cls = motion.LEEWAY_CLASSES["person_in_water"]
    want = motion.leeway_velocity(cls, (10.0 * 1852 / 3600, 0.0), 1.0)  # 10 knots east
    u, v = motion.cell_velocity(mo, np.zeros((1, 2)), 1800.0, 1, np.array([1.0]))
    np.testing.assert_allclose([u[0, 3, 4], v[0, 3, 4]], want, rtol=1e-12)
    # x_wind / y_wind are a wind too
    ds(("x_wind", "y_wind"), "m s-1").to_netcdf(tmp_path / "xy.nc", engine="h5netcdf")
    cfg = TargetConfig(model="leeway", wind_file=str(tmp_path / "xy.nc"))
    assert motion.check(cfg, SHAPE, 3600.0, sc_map).wind_field is not None
    # a current given as the wind, and a wind given as the current: refused, naming the key
    cur = tmp_path / "cur.nc"
    ds(("eastward_sea_water_velocity", "northward_sea_water_velocity"), "cm s-1").to_netcdf(
        cur, engine="h5netcdf"
    )
    with pytest.raises(ConfigError, match="a current") as err:
        motion.check(TargetConfig(model="leeway", wind_file=str(cur)), SHAPE, 3600.0, sc_map)
    assert err.value.field == "target.wind_file"
    with pytest.raises(ConfigError, match="a wind") as err:
        motion.check(TargetConfig(model="leeway", field_file=str(path)), SHAPE, 3600.0, sc_map)
    assert err.value.field == "target.field_file"
    # the episode beyond the file's times
    with pytest.raises(ConfigError, match="covering the episode") as err:
        motion.check(TargetConfig(model="leeway", wind_file=str(path)), SHAPE, 3 * 3600.0, sc_map)
    assert err.value.field == "target.wind_file"
    with pytest.raises(ConfigError) as err:
        motion.check(
            TargetConfig(model="leeway", wind_file=str(path), wind_start="2023-01-01"),
            SHAPE, 60.0, sc_map,
        )  # fmt: skip
    assert err.value.field == "target.wind_file"


def test_a_leeway_target_may_also_drift_in_a_current_field(tmp_path):
    cur = np.zeros((2, *SHAPE))
    cur[0] = 0.5
    wind = np.zeros((2, *SHAPE))
    wind[1] = 10.0
    cfg = TargetConfig(
        model="leeway", field_file=npy(tmp_path, cur, "c.npy"),
        wind_file=npy(tmp_path, wind, "w.npy"),
    )  # fmt: skip
    mo = motion.check(cfg, SHAPE, 600.0)
    u, v = motion.cell_velocity(mo, np.zeros((1, 2)), 0.0, 1, np.array([-1.0]))
    lee = motion.leeway_velocity(motion.LEEWAY_CLASSES["person_in_water"], (0.0, 10.0), -1.0)
    np.testing.assert_allclose(u[0], 0.5 + lee[0], rtol=1e-15)
    np.testing.assert_allclose(v[0], lee[1], rtol=1e-15)


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("nan", "NaN"),
        ("shape", "shape"),
        ("units", "km/h"),
        ("short", "covering the episode"),
        ("no_dt", "time between frames"),
    ],
)
def test_bad_wind_files_name_the_key(tmp_path, case, message):
    good = np.full((2, *SHAPE), 5.0)
    dt = None
    if case == "nan":
        good[0, 1, 2] = np.nan
    elif case == "shape":
        good = np.zeros((2, 4, 4))
    elif case == "units":
        good = np.full((2, *SHAPE), 100.0)  # 100 "m/s": km/h given as m/s
    elif case == "short":
        good, dt = np.full((3, 2, *SHAPE), 5.0), 100.0  # 200 s of frames, 600 s episode
    elif case == "no_dt":
        good = np.full((3, 2, *SHAPE), 5.0)
    cfg = TargetConfig(model="leeway", wind_file=npy(tmp_path, good), wind_dt_s=dt)
    with pytest.raises(ConfigError, match=message) as err:
        motion.check(cfg, SHAPE, 600.0)
    assert err.value.field.startswith("target.wind_"), err.value.field


def test_wind_file_keys_are_checked_when_the_scenario_loads(tmp_path):
    with pytest.raises(ConfigError, match="wind_file"):
        TargetConfig(model="drift", wind_file="w.npy")
    path = npy(tmp_path, np.full((2, *SHAPE), 5.0))
    with pytest.raises(ConfigError) as err:
        motion.check(TargetConfig(model="leeway", wind_file=path, wind_kmh=(10, 0)), SHAPE, 60.0)
    assert err.value.field == "target.wind_kmh"
    # a relative wind_file is read from the scenario file's folder
    import yaml

    data = load_scenario("small").to_dict()
    data["target"] = {"model": "leeway", "wind_file": "wind.npy"}
    (tmp_path / "sc.yaml").write_text(yaml.safe_dump(data))
    sc = load_scenario(str(tmp_path / "sc.yaml"))
    assert sc.target.wind_file == path


def test_a_time_varying_wind_moves_the_targets_by_each_steps_leeway(tmp_path):
    """The engine's time-varying branch (envs grouped by their time): with a wind turning from
    east to north over 20 min, each hidden target moves by the sum over steps of its side's
    leeway in the wind of that step's start (no diffusion), and mass is conserved."""
    frames = np.zeros((3, 2, *SHAPE))
    frames[0, 0], frames[1, 0], frames[1, 1], frames[2, 1] = 12.0, 6.0, 6.0, 12.0
    over = {"target.model": "leeway", "target.leeway_class": CLASS, "target.wind_dt_s": 600.0}
    eng, out = run({**over, "target.wind_file": npy(tmp_path, frames)}, steps=40)
    st = eng.current
    cls = motion.LEEWAY_CLASSES[CLASS]
    dt = eng.params.dt
    for k, side in enumerate(st.leeway_side):
        if st.target_out[k]:
            continue
        want = out[0][3][k].copy()
        for step in range(40):
            w = min(step * dt / 600.0, 2.0)
            i = min(int(w), 1)
            wind = (1 - (w - i)) * frames[i, :, 0, 0] + (w - i) * frames[i + 1, :, 0, 0]
            want += motion.leeway_velocity(cls, wind, side) * dt
        np.testing.assert_allclose(st.target[k], want, rtol=0, atol=1e-6)
    assert np.all(np.abs(st.target - out[0][3]).max(axis=1) > 200.0)  # ~ 0.1 m/s for 20 min
