"""Moving targets in the batched core and engine: the belief as a Bayesian filter (predict by
the motion model, update by eq. 14), mass_out, the zero-field equivalence with the static
environment, the hidden target, the scenario section."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim import core
from poc_env.sim.engine import Engine

ZERO_FIELDS = {
    "diffusion": {"target.model": "diffusion", "target.diffusion_m2_s": 0.0},
    "drift": {"target.model": "drift", "target.current_kmh": [0.0, 0.0]},
    "leeway": {"target.model": "leeway", "target.wind_kmh": [0.0, 0.0]},
}


def run(overrides: dict, steps: int = 60, n_envs: int = 3, control: str = "heading"):
    sc = load_scenario("small", {"episode.horizon_steps": steps, **overrides})
    eng = Engine(sc, n_envs, control=control, obs_type="compass", seeds=[5, 6, 7])
    obs, info = eng.reset()
    rng = np.random.default_rng(11)
    out = [(obs, None, info)]
    for _ in range(steps):
        act = rng.uniform(-1, 1, (n_envs, eng.n_agents, eng.action_dim))
        tr = eng.step(act)
        out.append((tr.obs, tr.reward, tr.info))
        st = eng.current
        if st.mass_out is not None:  # in-map + found + out-of-map = the prior's mass
            total = st.belief.sum(axis=(1, 2)) + st.posc + st.mass_out
            np.testing.assert_allclose(total, st.initial_mass, rtol=0, atol=1e-9)
    return eng, out


@pytest.mark.parametrize("model", sorted(ZERO_FIELDS))
def test_zero_field_reproduces_the_static_episodes(model):
    _, static = run({})
    eng, moving = run(ZERO_FIELDS[model])
    assert eng.params.motion is not None and eng.params.motion.model.name == model
    assert sum(float(r.sum()) for _, r, _ in static[1:]) > 0  # the UAVs find something
    for (o1, r1, i1), (o2, r2, i2) in zip(static, moving, strict=True):
        np.testing.assert_allclose(o2, o1, rtol=0, atol=1e-12)
        if r1 is not None:
            np.testing.assert_allclose(r2, r1, rtol=0, atol=1e-12)
        assert set(i2) == set(i1) | {"mass_out"}
        np.testing.assert_array_equal(i2["mass_out"], 0.0)
        for key, value in i1.items():
            np.testing.assert_allclose(i2[key], value, rtol=0, atol=1e-12, err_msg=key)


def test_the_static_path_has_no_filter():
    eng, out = run({}, steps=3)
    assert eng.params.motion is None
    st = eng.current
    assert st.mass_out is None and st.drift is None and st.target_noise is None
    assert "mass_out" not in out[-1][2]


def test_drift_moves_the_belief_and_conserves_mass():
    over = {"target.model": "drift", "target.current_kmh": [30.0, 0.0]}
    over["target.diffusion_m2_s"] = 100.0
    eng, out = run(over, steps=80)
    st = eng.current
    assert np.all(st.mass_out > 0.01)  # 30 km/h for 40 min: mass leaves the 40 km map
    mass_out = out[-1][2]["mass_out"]
    np.testing.assert_allclose(mass_out, np.repeat(st.mass_out[:, None], eng.n_agents, axis=1))


def test_random_currents_per_reset_reach_20_kmh():
    sc = load_scenario("paper_6_2", {"target.model": "drift", "target.random_current_kmh": 25.0})
    eng = Engine(sc, 64, seeds=list(range(64)))
    eng.reset()
    speeds = np.hypot(*eng.current.drift.T) * 3.6
    assert speeds.max() >= 20.0 and len(np.unique(speeds)) == 64
    first = eng.current.drift.copy()
    eng.reset()
    assert not np.allclose(eng.current.drift, first)  # a new current at every reset


def test_the_target_moves_with_the_belief_statistically():
    over = {"target.model": "drift", "target.current_kmh": [18.0, -9.0]}
    over["target.diffusion_m2_s"] = 200.0
    sc = load_scenario("paper_6_2", over)
    params = core.make_params(sc)
    e, steps = 400, 10
    rngs = [np.random.default_rng(s) for s in range(e)]
    st = core.initial(params, rngs)
    h = params.grid.cell_m / params.s
    ny, nx = params.fine_shape
    yy, xx = (np.mgrid[:ny, :nx] + 0.5) * h
    ox, oy = params.grid.origin_m

    def centre(b):
        return np.array([(b * xx).sum(), (b * yy).sum()]) / b.sum() + [ox, oy]

    c0 = centre(st.belief[0])
    t0 = st.target.copy()
    for _ in range(steps):
        core.predict(params, st)
        st.step += 1
    # the prior's 2 % background at the edges: a little mass leaves (3 km moved, 100 km map)
    assert st.mass_out is not None and st.mass_out.max() < 5e-3
    assert st.target_out is not None
    moved = st.target - t0
    expect = np.array([5.0, -2.5]) * params.dt * steps
    sd = np.sqrt(2 * 200.0 * params.dt * steps)
    np.testing.assert_allclose(moved.mean(axis=0), expect, atol=4 * sd / np.sqrt(e))
    # the belief's centre of mass moves by the same v t (less the edge's loss: < 400 m)
    np.testing.assert_allclose(centre(st.belief[0]) - c0, expect, atol=400.0)
    # the targets stay a sample of the belief: their mean is the belief's centre of mass
    inside = st.target[~st.target_out]
    spread = float(np.std(inside, axis=0).max()) / np.sqrt(len(inside))
    np.testing.assert_allclose(inside.mean(axis=0), centre(st.belief[0]), atol=4 * spread)


def test_a_target_out_of_the_map_cannot_be_detected():
    sc = load_scenario("small", {"target.model": "diffusion", "target.diffusion_m2_s": 1.0})
    params = core.make_params(sc)
    st = core.initial(params, [np.random.default_rng(0)])
    assert st.target_out is not None
    st.target_out[:] = True
    st.target[:] = params.takeoff[0]  # under the UAVs, but beyond the map's edge
    for _ in range(5):
        core.step(params, st, np.zeros((1, params.n_agents, 3)), [np.random.default_rng(0)])
    assert st.target_exponent[0] == 0.0 and not st.detected[0]


def test_bad_target_sections_name_the_field(tmp_path):
    with pytest.raises(ConfigError) as err:
        load_scenario("small", {"target.diffusion_m2_s": -5.0})
    assert err.value.field == "target.diffusion_m2_s"
    with pytest.raises(ConfigError) as err:
        core.make_params(load_scenario("small", {"target.model": "teleport"}))
    assert err.value.field == "target.model"
    with pytest.raises(ConfigError) as err:
        core.make_params(
            load_scenario("small", {"target.model": "leeway", "target.leeway_class": "whale"})
        )
    assert err.value.field == "target.leeway_class"
    with pytest.raises(ConfigError) as err:
        core.make_params(
            load_scenario("small", {"target.model": "drift", "comms.belief_sharing": "comms"})
        )
    assert err.value.field == "target.model"
    with pytest.raises(ConfigError) as err:
        load_scenario("small", {"target.wind": 3})
    assert err.value.field == "target.wind"


def test_a_scenario_file_with_a_gridded_field(tmp_path):
    data = load_scenario("small").to_dict()
    field = np.zeros((2, 8, 8))
    field[0] = 0.5
    np.save(tmp_path / "current.npy", field)
    data["target"] = {"model": "drift", "field_file": "current.npy", "diffusion_m2_s": 10.0}
    path = tmp_path / "moving.yaml"
    path.write_text(yaml.safe_dump(data))
    sc = load_scenario(str(path))
    assert sc.target.field_file == str(tmp_path / "current.npy")
    params = core.make_params(sc)
    assert params.motion is not None and params.motion.field is not None
    bad = field.copy()
    bad[1, 3, 3] = np.nan
    np.save(tmp_path / "current.npy", bad)
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(ConfigError) as err:
        core.make_params(load_scenario(str(path)))
    assert err.value.field == "target.field_file"
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written
