"""de_plan: the §6.2 plan made on the episode's prior, then flown by the follower."""

import poc_env
from agents.policies.de_plan import DEPlanPolicy


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
