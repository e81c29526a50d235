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


def test_no_moving_bound_for_a_gridded_field(tmp_path):
    """The bound covers uniform drift only: a gridded field leaves the column out (no crash)."""
    f = tmp_path / "v.npy"
    np.save(f, np.full((2, 8, 8), 0.5))
    sc = load_scenario("small", {"target.model": "drift", "target.field_file": str(f)})
    assert moving_effort_bound(sc, 0) is None
    ev = evaluate(sc, ["lawnmower"], episodes=1)
    assert "POSC/moving" not in ev.table()
