"""receding_choice's truncated lookahead ended by a learned value (i28-lookvalue):
``oracle~H`` and ``oracle~H+VALUE.json`` (agents/policies/replan_choice.py)."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.agents.planning.spacetime import airborne_poc
from poc_env.agents.policies.moving import drift_of
from poc_env.agents.policies.registry import make_policy
from poc_env.agents.policies.replan_choice import (
    STATE_FEATURES,
    ChooserModel,
    ReplanChoicePolicy,
    ValueModel,
    from_spec,
)
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.errors import ConfigError
from poc_env.tasks import get_task

TASK = "UAVSearch-Small-Drift-Heading-v1"


def _fly(pol, seed, stop_at=None):
    env = UAVSearchParallelEnv(scenario=get_task(TASK).load_scenario({}))
    obs, _ = env.reset(seed=seed)
    pol.reset(env, seed)
    while env.agents:
        if stop_at is not None and env.sim_state.step[0] * env.params.dt >= stop_at:
            return env, obs
        actions, _ = pol.predict(obs)
        obs, *_ = env.step(actions)
    return env, obs


def _toy_value(tmp_path):
    rng = np.random.default_rng(0)
    x = rng.uniform(size=(300, len(STATE_FEATURES)))
    y = 0.3 * x[:, 0] + 0.1 * x[:, -1] * x[:, 3]
    model = ValueModel.fit(x, y, 1e-4, "quadratic", meta={"note": "toy"})
    return model, model.save(tmp_path / "value.json")


def test_truncated_rollout_stops_at_h_and_leaves_the_live_env_untouched(tmp_path):
    now = 1200.0
    pol = ReplanChoicePolicy("oracle", decide_min=(20.0,), snap_min=(25.0, 30.0), variants=False)
    env, obs = _fly(pol, 3, stop_at=now)  # the step before the decision's
    before = {
        k: np.array(v, copy=True)
        for k, v in vars(env.sim_state).items()
        if isinstance(v, np.ndarray)
    }
    index = np.array(pol.follower.index, copy=True)
    ks, xy = pol.searching(obs)
    belief = np.array(env.sim_state.belief[0])
    poc = airborne_poc(env.scenario, belief, drift_of(env), env.params.s, xy, now, ks)
    cand = pol.candidates(ks, xy, now, belief, poc)[1]
    full = pol.rollout(obs, cand, ks, now)  # to the end, snapshots at 25 and 30 min
    (t25, x25, posc25), (t30, _, posc30) = pol.snaps
    assert (t25, t30) == (1500.0, 1800.0) and posc25 < posc30 <= full
    assert len(x25) == len(STATE_FEATURES)
    pol.horizon_s = 300.0  # 5 min: stops at 25 min, before the 30-min snapshot
    assert pol.rollout(obs, cand, ks, now) == posc25
    assert [s[0] for s in pol.snaps] == [1500.0]
    value, _ = _toy_value(tmp_path)
    pol.value = value  # the POSC at 25 min plus the value of the state reached then
    expect = posc25 + float(value.predict(np.asarray(x25))[0])
    assert pol.rollout(obs, cand, ks, now) == pytest.approx(expect, abs=1e-12)
    after = vars(env.sim_state)
    for k, v in before.items():
        assert np.array_equal(v, after[k]), k
    assert np.array_equal(index, pol.follower.index)


def test_value_model_round_trips_and_is_not_a_chooser_model(tmp_path):
    model, path = _toy_value(tmp_path)
    again = ValueModel.load(path)
    x = np.random.default_rng(1).uniform(size=(9, len(STATE_FEATURES)))
    assert np.array_equal(model.predict(x), again.predict(x))
    assert again.meta["expand"] == "quadratic" and again.meta["note"] == "toy"
    assert np.corrcoef(model.predict(x), 0.3 * x[:, 0] + 0.1 * x[:, -1] * x[:, 3])[0, 1] > 0.99
    with pytest.raises(ConfigError, match="chooser model over the features"):
        ChooserModel.load(path)
    with pytest.raises(ConfigError, match="value model file"):
        ValueModel.load(tmp_path / "missing.json")


def test_within_group_fit_ranks_inside_groups():
    # across groups the feature and the target go opposite ways; inside a group the same way
    rng = np.random.default_rng(2)
    groups = np.repeat(np.arange(40), 5)
    level = rng.normal(size=40)[groups]
    x = np.zeros((200, len(STATE_FEATURES)))
    x[:, 0] = level + 0.1 * rng.normal(size=200)
    y = -3.0 * level + (x[:, 0] - level)
    pooled = ValueModel.fit(x, y, 1e-6, "linear")
    within = ValueModel.fit(x, y, 1e-6, "linear", groups=groups)
    assert pooled.weights[0] < 0 < within.weights[0]
    assert within.meta["within"] and not pooled.meta["within"]


def test_truncated_value_chooser_is_deterministic_and_parsed(tmp_path):
    _, path = _toy_value(tmp_path)
    pols = [from_spec(f"oracle~5+{path}@20", variants=False) for _ in range(2)]
    assert pols[0].horizon_s == 300.0 and pols[0].value is not None
    assert pols[0].decide_s == (1200.0,)
    assert make_policy(f"receding_choice:oracle~5+{path}@20").value is not None
    envs = [_fly(p, 9, stop_at=1290.0)[0] for p in pols]  # the decision taken at 20 min
    assert float(envs[0].sim_state.posc[0]) == float(envs[1].sim_state.posc[0])
    (a,), (b,) = pols[0].decisions, pols[1].decisions
    assert a["flown"] == b["flown"] and a["pick"] == b["pick"]
    assert a["pick"] == int(np.argmax(a["flown"]))
    assert from_spec("oracle~5@10").value is None


@pytest.mark.parametrize(
    "spec,field",
    [
        ("oracle+value.json@10", "spec"),  # a value without truncation
        ("oracle~x@10", "spec"),
        ("oracle~0@10", "horizon_min"),
        ("rule~5@10", "horizon_min"),  # nothing to truncate
        ("oracle~5+missing.json@10", "path"),
    ],
)
def test_bad_truncation_specs_name_the_field(spec, field):
    with pytest.raises(ConfigError, match=field):
        from_spec(spec)
