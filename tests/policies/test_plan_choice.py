"""plan_choice: allocation_plan with the options a chooser picks from the prior at take-off
(agents/policies/plan_choice.py, i28-editplan)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from poc_env.agents.policies.plan_choice import (
    CANDIDATES,
    FEATURES,
    KINDS,
    PRIOR_FEATURES,
    PlanChoiceModel,
    PlanChoicePolicy,
    expand,
    from_spec,
    prior_features,
    rows,
    shipped_choosers,
)
from poc_env.agents.policies.registry import make_policy
from poc_env.config import load_scenario
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.errors import ConfigError


def _fly(pol, seed, scenario="small"):
    from poc_env.agents.experiments.evaluate import play

    env = UAVSearchParallelEnv(scenario=load_scenario(scenario))
    play(env, pol, seed)
    return env


def _model(prefer: str | None) -> PlanChoiceModel:
    """A model of the ``kinds`` expansion predicting +0.01 for ``prefer`` and -0.01 for every
    other candidate (all -0.01 if None)."""
    w = np.array([0.01 if k == prefer else -0.01 for k in KINDS])
    n = len(KINDS)
    return PlanChoiceModel(np.zeros(n), np.ones(n), w, 0.0, {"expand": "kinds"})


def test_default_flies_allocation_plans_episode_exactly():
    a = _fly(make_policy("allocation_plan"), 1)
    pol = make_policy("plan_choice:default")
    b = _fly(pol, 1)
    assert float(b.sim_state.posc[0]) == float(a.sim_state.posc[0])
    assert np.array_equal(a.sim_state.agent_pos, b.sim_state.agent_pos)
    assert pol.decision["chosen"] == "default"
    # a model that predicts no gain anywhere keeps the default plan too
    c = _fly(PlanChoicePolicy("model", model=_model(None)), 1)
    assert np.array_equal(a.sim_state.agent_pos, c.sim_state.agent_pos)


def _planned(pol, seed=5000):
    """``pol`` reset (its plan made) on ``paper_6_2``'s random prior of evaluation seed
    ``seed`` (5000: ``sampled`` and ``levels_wide`` plan other routes than ``default``)."""
    from poc_env.agents.experiments.evaluate import episode_prior

    sc = load_scenario("paper_6_2")
    env = UAVSearchParallelEnv(scenario=sc)
    env.reset(seed=seed, options={"prior": episode_prior(sc, seed)})
    pol.reset(env, seed)
    return [u["waypoints_m"] for u in pol.plan["uavs"]]


@pytest.mark.parametrize("prefer", ["sampled", "levels_wide"])
def test_the_chosen_candidate_is_the_models_argmax(prefer):
    pol = PlanChoicePolicy("model", model=_model(prefer))
    got = _planned(pol)
    assert pol.decision["chosen"] == prefer
    pred = pol.decision["predicted"]
    assert max(pred, key=pred.get) == prefer
    # and the plan made is that candidate's: the constant policy's routes, not the default's
    assert got == _planned(make_policy(f"plan_choice:{prefer}"))
    assert got != _planned(make_policy("plan_choice:default"))


def test_prior_features_read_where_the_mass_is():
    sc = load_scenario("paper_6_2")
    from poc_env.theory.probability_map import Grid

    g = Grid.from_config(sc.map)
    near, far = np.zeros((g.ny, g.nx)), np.zeros((g.ny, g.nx))
    near[0, 4] = 1.0  # the south-west corner, near airfield A (20 km, -60 km)
    far[-1, -1] = 1.0  # the north-east corner
    fn, ff = prior_features(sc, near), prior_features(sc, far)
    i = PRIOR_FEATURES.index("reach_mean")
    assert fn[i] < ff[i]
    assert fn[PRIOR_FEATURES.index("spread")] == 0.0
    x = rows(fn)
    assert x.shape == (len(KINDS), len(FEATURES))
    assert expand(x, "interact").shape == (len(KINDS), len(KINDS) * (1 + len(PRIOR_FEATURES)))


def test_bad_specs_are_refused(tmp_path):
    with pytest.raises(ConfigError, match="spec"):
        from_spec("nonsense")
    with pytest.raises(ConfigError, match="candidate"):
        PlanChoicePolicy("fixed", fixed="nonsense")
    path = tmp_path / "m.json"
    path.write_text(json.dumps({"features": ["x"], "mean": [0], "scale": [1], "weights": [0]}))
    with pytest.raises(ConfigError, match="path"):
        from_spec(str(path))
    assert set(KINDS) | {"default"} == set(CANDIDATES)


def test_the_paper62_chooser_is_shipped():
    assert "plan_chooser_paper62" in shipped_choosers()  # else the test below runs on nothing


@pytest.mark.parametrize("name", shipped_choosers())
def test_shipped_chooser_loads_and_replays_its_card(name):
    """A shipped chooser loads by name, chooses on its card's replay prior what it chose when
    it was fitted, and flies that episode to its recorded POSC."""
    from poc_env.agents.experiments.evaluate import episode_prior, play

    pol = make_policy(f"plan_choice:{name}")
    rep = pol.model.meta["replay"]
    sc = load_scenario(rep["scenario"])
    env = UAVSearchParallelEnv(scenario=sc)
    play(env, pol, rep["seed"], episode_prior(sc, rep["seed"]))
    assert pol.decision["chosen"] == rep["chosen"]
    # recorded on another machine: sums may round their last bits by CPU
    assert float(env.sim_state.posc[0]) == pytest.approx(rep["posc"], rel=1e-3)
