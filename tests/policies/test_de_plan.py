"""de_plan: the §6.2 plan made on the episode's prior, then flown by the follower."""

import pytest

import poc_env
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.policies import make_policy
from poc_env.agents.policies.de_plan import DEPlanPolicy
from poc_env.errors import ConfigError


def test_de_plan_policy_flies_its_plan():
    env = poc_env.parallel_env("small")
    obs, _ = env.reset(seed=0)
    pol = DEPlanPolicy(popsize=16, maxiter=20)
    pol.reset(env, 0)
    while env.agents:
        obs, *_ = env.step(pol.predict(obs)[0])
    st = env.sim_state
    assert st.posc[0] > 0.5 * pol.plan["posc"]  # the flown plan finds what it promised, roughly
    assert st.landed.all()


def test_optimizer_plan_flies_the_named_optimisers_plan():
    """``optimizer_plan:NAME`` plans with optimiser NAME (the same plan as make_plan with it),
    so every optimiser can be flown on the same episodes; an unknown name is a ConfigError."""
    env = poc_env.parallel_env("small")
    env.reset(seed=2)
    pol = make_policy("optimizer_plan:classic_de", popsize=12, maxiter=8)
    pol.reset(env, 2)
    prior = env.params.grid.coarsen(env.sim_state.belief[0], env.params.s)
    ref = make_plan(
        env.scenario, prior=prior, seed=2, popsize=12, maxiter=8, optimizer="classic_de"
    )
    assert pol.plan["optimizer"]["name"] == "classic_de"
    assert pol.plan["x"] == ref["x"]
    default = DEPlanPolicy(popsize=12, maxiter=8)
    default.reset(env, 2)
    assert default.plan["x"] != ref["x"]  # adaptive DE: another plan
    with pytest.raises(ConfigError, match="optimizer"):
        make_policy("optimizer_plan:bogus")
