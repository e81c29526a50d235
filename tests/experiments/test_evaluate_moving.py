"""evaluate on a moving target: the moving-target bound beside every policy (issue 25)."""

import numpy as np
import pytest

from poc_env.agents.experiments.evaluate import evaluate, moving_effort_bound
from poc_env.config import load_scenario
from poc_env.errors import ConfigError


def test_moving_bound_column_when_the_target_moves():
    sc = load_scenario("small", {"target.model": "drift", "target.random_current_kmh": 25.0})
    ev = evaluate(sc, ["lawnmower", "random"], episodes=2, seed0=5)
    for e in ev.episodes:  # each seed's own drift: the bound of its episode
        assert e.bound_moving == moving_effort_bound(sc, e.seed)
        assert e.posc <= e.bound_moving
    assert ev.episodes[0].bound_moving != ev.episodes[1].bound_moving
    for r in ev.rows():
        eps = [e for e in ev.episodes if e.policy == r["policy"]]
        assert r["normalised_moving"] == pytest.approx(
            np.mean([e.posc / e.bound_moving for e in eps])
        )
    assert "POSC/moving" in ev.table() and "moving-target bound" in ev.table()
    assert "bound_moving" in ev.episodes_csv().splitlines()[0]


def test_no_moving_bound_for_a_static_target():
    sc = load_scenario("small")
    assert moving_effort_bound(sc, 0) is None
    ev = evaluate(sc, ["lawnmower"], episodes=1)
    assert ev.episodes[0].bound_moving is None
    assert "normalised_moving" not in ev.rows()[0]
    assert "POSC/moving" not in ev.table()


@pytest.mark.parametrize("varying", [False, True])
def test_moving_bound_for_a_gridded_field(tmp_path, varying):
    """A gridded (stationary or time-varying) field gets the moving bound too (the sparse
    adjoint of the filter, poc_env.theory.moving_bound), above every flown POSC."""
    f = tmp_path / "v.npy"
    rng = np.random.default_rng(0)
    frames = rng.normal(0.0, 2.0, (4 if varying else 1, 2, 8, 8))
    np.save(f, frames)
    over = {"target.model": "drift", "target.field_file": str(f), "target.diffusion_m2_s": 30.0}
    if varying:
        over["target.field_dt_s"] = 1200.0
    sc = load_scenario("small", over)
    ev = evaluate(sc, ["lawnmower", "greedy_bayes"], episodes=1)
    for e in ev.episodes:
        assert e.bound_moving is not None and e.bound_moving == moving_effort_bound(sc, e.seed)
        assert e.posc <= e.bound_moving
    assert "POSC/moving" in ev.table()


def test_moving_bound_for_leeway():
    """Leeway in a uniform wind is a uniform drift per episode: reported as well."""
    over = {"target.model": "leeway", "target.wind_kmh": [30.0, 0.0]}
    sc = load_scenario("small", over)
    ev = evaluate(sc, ["lawnmower"], episodes=1)
    assert ev.episodes[0].bound_moving is not None
    assert ev.episodes[0].posc <= ev.episodes[0].bound_moving
    assert "POSC/moving" in ev.table()


def test_moving_bound_for_a_wind_file_uses_the_episodes_crosswind_side(tmp_path):
    """A gridded, time-varying wind (``target.wind_file``): the bound's adjoint is built for the
    episode's own crosswind side (``sim_state.leeway_side``): the other side's bound differs,
    and a bound asked for without a side is refused."""
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.theory import moving_bound as mb

    wind = np.zeros((3, 2, 8, 8))
    wind[:, 0] = 6.0 + np.arange(8.0)[None, None, :]  # an east wind growing eastward
    wind[:, 1] = np.array([0.0, 4.0, 8.0])[:, None, None]  # a north wind rising in time
    f = tmp_path / "wind.npy"
    np.save(f, wind)
    over = {
        "target.model": "leeway",
        "target.leeway_class": "life_raft_deep_ballast",
        "target.wind_file": str(f),
        "target.wind_dt_s": 1800.0,
    }
    sc = load_scenario("small", over)
    ev = evaluate(sc, ["lawnmower", "greedy_bayes"], episodes=2)
    for e in ev.episodes:
        assert e.bound_moving is not None and e.bound_moving == moving_effort_bound(sc, e.seed)
        assert e.posc <= e.bound_moving
    env = UAVSearchParallelEnv(scenario=sc)
    env.reset(seed=0)
    st = env.sim_state
    side = float(st.leeway_side[0])
    args = (env.scenario, st.belief[0], st.drift[0], env.params.s)
    assert mb.moving_bound(*args, side=side).upper == moving_effort_bound(sc, 0)
    assert mb.moving_bound(*args, side=-side).upper != moving_effort_bound(sc, 0)
    with pytest.raises(ConfigError, match="side"):  # no side: refused, never a guessed one
        mb.moving_bound(*args)


def test_moving_bound_for_particles_uses_each_steps_transition(tmp_path):
    """The ``particles`` model: one transition matrix per step (they differ with time), each
    checked against the filter; the bound sits above every flown POSC."""
    rng = np.random.default_rng(0)
    n, ts = 2000, np.arange(0.0, 4 * 3600.0 + 1, 600.0)
    x0, y0 = rng.uniform(5e3, 35e3, n), rng.uniform(5e3, 35e3, n)
    ang = rng.uniform(0, 2 * np.pi, n)
    speed = 1.0 + ts[None] / 3600.0  # accelerating: each step's transition is its own
    x = np.clip(x0[:, None] + np.cos(ang)[:, None] * speed * ts[None], -1e4, 5e4)
    y = np.clip(y0[:, None] + np.sin(ang)[:, None] * speed * ts[None], -1e4, 5e4)
    f = tmp_path / "tracks.npz"
    np.savez(f, x_m=x, y_m=y, t_s=ts)
    over = {"target.model": "particles", "target.particles_file": str(f)}
    sc = load_scenario("small", over)
    ev = evaluate(sc, ["lawnmower", "greedy_bayes"], episodes=1)
    for e in ev.episodes:
        assert e.bound_moving is not None and e.bound_moving == moving_effort_bound(sc, e.seed)
        assert e.posc <= e.bound_moving <= 1.0
