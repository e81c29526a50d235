"""The table of target motion models (poc_env.theory.motion): conservation, the moments of
diffusion and drift, the leeway table, bad inputs."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.config import TargetConfig, load_scenario
from poc_env.errors import ConfigError
from poc_env.theory import motion

H = 1000.0  # cell side, m


def blob(e: int = 1, n: int = 61, sigma: float = 3.0) -> np.ndarray:
    y, x = np.mgrid[:n, :n] - (n - 1) / 2
    m = np.exp(-(x * x + y * y) / (2 * sigma * sigma))
    return np.repeat((m / m.sum())[None], e, axis=0)


def moments(m: np.ndarray):
    """(mass, mean x, mean y, var x, var y) of each env's masses, in metres."""
    ny, nx = m.shape[1:]
    y, x = np.mgrid[:ny, :nx] * H
    w = m.sum(axis=(1, 2))
    mx = (m * x).sum(axis=(1, 2)) / w
    my = (m * y).sum(axis=(1, 2)) / w
    vx = (m * x * x).sum(axis=(1, 2)) / w - mx**2
    vy = (m * y * y).sum(axis=(1, 2)) / w - my**2
    return w, mx, my, vx, vy


@pytest.mark.parametrize("model", motion.MODEL_NAMES)
def test_every_model_conserves_mass_over_many_steps(model, tmp_path):
    rng = np.random.default_rng(0)
    field = None
    if model == "drift":  # a gridded, time-varying field on 8 x 8 map cells of 4 x 4 fine cells
        path = tmp_path / "field.npy"
        np.save(path, rng.uniform(-1.0, 1.0, (5, 2, 8, 8)))
        field = str(path)
    tracks = None
    if model == "particles":  # 2000 random walkers over the map, 10-min outputs
        tracks = str(tmp_path / "tracks.npz")
        walk = rng.normal(0.0, 600.0, (2000, 11, 2)) + np.array([300.0, -200.0])
        walk[:, 0] = 0.0  # the start
        xy = rng.uniform(0, 40e3, (2000, 1, 2)) + walk.cumsum(axis=1)
        np.savez(tracks, x_m=xy[..., 0], y_m=xy[..., 1], t_s=600.0 * np.arange(11))
    mm = motion.MODELS[model]  # each value only where the model uses it (else refused)
    cfg = TargetConfig(
        model=model,
        diffusion_m2_s=200.0 if mm.moves and not tracks else 0.0,
        particles_file=tracks,
        current_kmh=(7.0, -3.0) if mm.uses_current else (0.0, 0.0),
        random_current_kmh=10.0 if mm.uses_current else 0.0,
        wind_kmh=(30.0, 20.0) if mm.uses_wind else (0.0, 0.0),
        leeway_class="life_raft_deep_ballast",
        field_file=field,
        field_dt_s=600.0 if field else None,
    )
    mo = motion.check(cfg, (8, 8), 6000.0 if tracks else 2400.0, load_scenario("small").map)
    m = rng.random((3, 32, 32))
    m /= m.sum(axis=(1, 2), keepdims=True)
    uniform = np.stack([mo.draw(rng) for _ in range(3)])
    out = np.zeros(3)
    for k in range(100):
        out += motion.predict(mo, m, uniform, 60.0 * k, 60.0, H, 4)
        assert m.min() >= -1e-15  # positive scheme
    np.testing.assert_allclose(m.sum(axis=(1, 2)) + out, 1.0, rtol=0, atol=1e-9)
    if model != "static":
        assert out.min() > 1e-3  # the open boundary lets mass out, and it is counted


def test_diffusion_spreads_with_variance_2dt():
    d, dt, steps = 500.0, 120.0, 20
    m = blob()
    _, mx0, my0, vx0, vy0 = moments(m)
    for _ in range(steps):
        assert motion.advect_diffuse(m, np.zeros(1), np.zeros(1), d, dt, H)[0] < 1e-12
    _, mx, my, vx, vy = moments(m)
    t = steps * dt
    np.testing.assert_allclose([vx - vx0, vy - vy0], [[2 * d * t]] * 2, rtol=1e-6)
    np.testing.assert_allclose([mx - mx0, my - my0], [[0.0]] * 2, atol=1e-6)
    assert motion.substeps(0.0, 0.0, d, dt, H) == 1  # 4 D dt / h^2 = 0.24


def test_drift_moves_the_centre_of_mass_by_v_t():
    u, v, dt, steps = np.array([[[1.5]], [[-0.4]]]), np.array([[[-0.7]], [[0.9]]]), 300.0, 20
    m = blob(2)
    _, mx0, my0, _, _ = moments(m)
    for _ in range(steps):
        motion.advect_diffuse(m, u, v, 10.0, dt, H)
    _, mx, my, _, _ = moments(m)
    t = steps * dt
    np.testing.assert_allclose(mx - mx0, u.ravel() * t, rtol=0, atol=1e-3)
    np.testing.assert_allclose(my - my0, v.ravel() * t, rtol=0, atol=1e-3)


def test_substeps_keep_the_scheme_positive():
    assert motion.substeps(20.0, 0.0, 0.0, 60.0, 100.0) == 12
    m = blob()
    motion.advect_diffuse(m, np.full(1, 20.0), np.zeros(1), 1e4, 60.0, 100.0)
    assert m.min() >= 0.0


def test_zero_field_and_zero_diffusion_leave_the_belief_bit_identical():
    m = np.random.default_rng(1).random((2, 16, 16))
    before = m.copy()
    out = motion.advect_diffuse(m, np.zeros(1), np.zeros(1), 0.0, 60.0, H)
    np.testing.assert_array_equal(m, before)
    np.testing.assert_array_equal(out, 0.0)


def test_leeway_uses_the_table():
    cls = motion.LEEWAY_CLASSES["person_in_water"]
    assert (cls.dwl_slope_pct, cls.cwl_right_slope_pct, cls.cwl_left_slope_pct) == (
        0.96,
        0.54,
        -0.54,
    )
    cfg = TargetConfig(model="leeway", wind_kmh=(36.0, 0.0), leeway_class="person_in_water")
    mo = motion.check(cfg, (4, 4), 600.0)
    sides = {tuple(np.round(mo.draw(np.random.default_rng(s)), 12)) for s in range(40)}
    # 10 m/s east: 0.096 m/s downwind (east), 0.054 m/s crosswind to the right (south) or left
    assert sides == {(0.096, -0.054), (0.096, 0.054)}
    raft = motion.LEEWAY_CLASSES["life_raft_deep_ballast"]
    v = motion.leeway_velocity(raft, (0.0, 10.0), 1.0)  # wind to the north, right is east
    np.testing.assert_allclose(v, [0.0062 * 10 - 0.03, 0.0352 * 10 - 0.025])
    np.testing.assert_array_equal(motion.leeway_velocity(raft, (0.0, 0.0), 1.0), 0.0)
    assert "Allen, A. A. and Plourde" in (motion.LeewayClass.__doc__ or "")


def test_random_current_reaches_20_kmh():
    cfg = TargetConfig(model="drift", random_current_kmh=25.0)
    mo = motion.check(cfg, (4, 4), 600.0)
    speeds = [np.hypot(*mo.draw(np.random.default_rng(s))) * 3.6 for s in range(200)]
    assert max(speeds) >= 20.0 and min(speeds) >= 0.0 and max(speeds) <= 25.0


def test_the_moving_target_follows_the_belief_statistically():
    cfg = TargetConfig(model="drift", current_kmh=(9.0, 3.6), diffusion_m2_s=300.0)
    mo = motion.check(cfg, (40, 40), 1e5)
    rng = np.random.default_rng(2)
    e, steps, dt = 4000, 30, 60.0
    start = np.full((e, 2), 20e3)
    target = start.copy()
    out = np.zeros(e, dtype=bool)
    uniform = np.broadcast_to(mo.draw(rng), (e, 2))
    for k in range(steps):
        noise = rng.standard_normal((e, 2))
        motion.move_targets(mo, target, out, uniform, noise, k * dt, dt, (0, 0), H, (40, 40))
    t = steps * dt
    disp = target - start
    v = np.array([2.5, 1.0])
    sd = np.sqrt(2 * 300.0 * t)
    np.testing.assert_allclose(disp.mean(axis=0), v * t, atol=4 * sd / np.sqrt(e))
    np.testing.assert_allclose(disp.var(axis=0), sd**2, rtol=0.1)
    # the belief of a point mass moves with the same mean
    m = np.zeros((1, 40, 40))
    m[0, 20, 20] = 1.0
    _, mx0, my0, _, _ = moments(m)
    for k in range(steps):
        motion.predict(mo, m, uniform[:1], k * dt, dt, H, 1)
    _, mx, my, vx, _ = moments(m)
    np.testing.assert_allclose([mx[0] - mx0[0], my[0] - my0[0]], disp.mean(axis=0), atol=50.0)
    assert vx[0] >= 2 * 300.0 * t  # diffusion plus the upwind scheme's own


def _field(tmp_path, arr, name="f.npy"):
    p = tmp_path / name
    np.save(p, arr)
    return str(p)


def test_bad_inputs_name_the_field(tmp_path):
    ok = np.zeros((3, 2, 4, 4))
    cases = {
        "nan": ok.copy(),
        "shape": np.zeros((2, 5, 4)),
        "units": np.full((3, 2, 4, 4), 30.0),
        "span": ok,
    }
    cases["nan"][1, 0, 2, 2] = np.nan
    for name, arr in cases.items():
        cfg = TargetConfig(model="drift", field_file=_field(tmp_path, arr), field_dt_s=600.0)
        with pytest.raises(ConfigError) as err:
            motion.check(cfg, (4, 4), 5000.0 if name == "span" else 600.0)
        assert err.value.field == "target.field_file", name
    with pytest.raises(ConfigError, match=r"target\.field_file"):
        motion.check(TargetConfig(model="drift", field_file=str(tmp_path / "no.npy")), (4, 4), 60.0)
    with pytest.raises(ConfigError) as err:  # refused when the scenario loads, not later
        load_scenario("small", {"target.model": "teleport"})
    assert err.value.field == "target.model"
    with pytest.raises(ConfigError) as err:  # and by the table itself
        motion.motion_model("teleport")
    assert err.value.field == "target.model"
    with pytest.raises(ConfigError) as err:
        motion.leeway_class("submarine")
    assert err.value.field == "target.leeway_class"


@pytest.mark.parametrize("model", ["static", "leeway", "drift"])
def test_an_unknown_leeway_class_is_refused_when_the_scenario_loads(model):
    """Issue 27: ``target.leeway_class`` was checked only when leeway dynamics were built, so
    a typo loaded (and plan/survey ran) until the model was switched to ``leeway``."""
    with pytest.raises(ConfigError) as err:
        load_scenario("small", {"target.model": model, "target.leeway_class": "submarine"})
    assert err.value.field == "target.leeway_class" and err.value.value == "submarine"
    assert all(name in str(err.value) for name in motion.LEEWAY_CLASSES)  # what is allowed
    for name in motion.LEEWAY_CLASSES:  # every class of the table loads
        load_scenario("small", {"target.model": model, "target.leeway_class": name})
    with pytest.raises(ConfigError, match="diffusion_m2_s"):
        TargetConfig(model="diffusion", diffusion_m2_s=-1.0)
    with pytest.raises(ConfigError, match="field_file"):
        TargetConfig(model="diffusion", field_file="x.npy")
    with pytest.raises(ConfigError, match="current_kmh"):
        TargetConfig(model="drift", current_kmh=(float("nan"), 0.0))


def test_a_stationary_field_and_a_time_varying_one(tmp_path):
    frames = np.zeros((3, 2, 2, 2))
    frames[1, 0] = 1.0
    frames[2, 0] = 2.0
    cfg = TargetConfig(model="drift", field_file=_field(tmp_path, frames), field_dt_s=100.0)
    mo = motion.check(cfg, (2, 2), 200.0)
    assert mo.field is not None
    np.testing.assert_allclose(mo.field.at(50.0)[0], 0.5)
    np.testing.assert_allclose(mo.field.at(150.0)[0], 1.5)
    np.testing.assert_allclose(mo.field.at(1e9)[0], 2.0)
    one = motion.check(
        TargetConfig(model="drift", field_file=_field(tmp_path, frames[1], "s.npy")), (2, 2), 1e9
    )
    assert one.field is not None and one.field.frames.shape == (1, 2, 2, 2)


@pytest.mark.parametrize(
    ("model", "field", "value"),
    [
        ("static", "current_kmh", [25.0, 0.0]),
        ("diffusion", "current_kmh", [0.0, -10.0]),
        ("diffusion", "random_current_kmh", 25.0),
        ("static", "random_current_kmh", 25.0),
        ("drift", "wind_kmh", [30.0, 0.0]),
        ("static", "diffusion_m2_s", 50.0),
    ],
)
def test_a_motion_value_the_model_ignores_is_refused(model, field, value):
    """Issue 25 audit: ``target.current_kmh=[25,0]`` with ``target.model`` left ``static`` (or
    a wind on a drift) was accepted and ignored: the target stood still and ``evaluate`` ran.
    Each is refused naming the field and the models that use it; the same values load under a
    model that uses them."""
    target = TargetConfig(model=model, **{field: value})
    with pytest.raises(ConfigError) as err:
        motion.check(target, (9, 9), 3600.0)
    assert err.value.field == f"target.{field}"
    assert "target.model" in str(err.value)
    uses = {"wind_kmh": "leeway", "diffusion_m2_s": "diffusion"}.get(field, "drift")
    motion.check(TargetConfig(model=uses, **{field: value}), (9, 9), 3600.0)


@pytest.mark.parametrize("key", ["current_kmh", "wind_kmh"])
def test_a_bad_current_or_wind_says_its_components_and_direction(key):
    """Issue 25 audit: a bad ``target.current_kmh`` / ``wind_kmh`` was "a pair of finite numbers
    [x, y]": neither the unit nor the axes nor whether the vector points where the water or
    air goes (oceanographic, the code's) or where it comes from (a weather report's wind)."""
    with pytest.raises(ConfigError) as err:
        TargetConfig(model="leeway", **{key: (25.0,)})
    assert err.value.field == key
    for word in ("[east, north]", "km/h", "toward", "from the west"):
        assert word in str(err.value)
