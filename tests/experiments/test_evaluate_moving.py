"""evaluate on a moving target: the moving-target bound beside every policy (issue 25)."""

import numpy as np
import pytest

from poc_env.agents.experiments.evaluate import evaluate, moving_effort_bound
from poc_env.config import load_scenario


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
