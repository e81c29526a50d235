"""allocation_plan: the allocation planner's routes flown by the follower in the environment."""

import numpy as np

import poc_env
from poc_env.agents.policies.allocation import AllocationPlanPolicy
from poc_env.agents.policies.de_plan import DEPlanPolicy
from poc_env.agents.policies.registry import make_policy


def _fly(pol, seed=0):
    env = poc_env.parallel_env("small")
    obs, _ = env.reset(seed=seed)
    pol.reset(env, seed)
    worst = 0.0
    while env.agents:
        act = pol.predict(obs)[0]
        worst = max([worst, *(float(np.abs(a).max()) for a in act.values())])
        obs, *_ = env.step(act)
    return env, worst


def test_allocation_plan_flies_within_limits_and_lands_in_time():
    pol = make_policy("allocation_plan")
    assert isinstance(pol, AllocationPlanPolicy)
    env, worst = _fly(pol)
    st = env.sim_state
    assert worst <= 1.0  # eq. 19: every action within its per-step limit
    assert st.landed[0].all() and not st.crashed[0].any()
    assert np.all(st.elapsed[0] <= env.scenario.uav.usable_endurance_s)
    assert st.posc[0] > 0.5 * pol.plan["posc"]


def test_no_more_separation_violations_than_de_plan():
    """Both effort levels (the thorough one picks its plan by POS less the environment's
    violation penalty at the planned positions: without it, 9 steps here)."""
    de, _ = _fly(DEPlanPolicy(popsize=16, maxiter=20), seed=1)
    for effort in ("default", "thorough"):
        alloc, _ = _fly(AllocationPlanPolicy(effort=effort), seed=1)
        assert alloc.sim_state.violations[0].sum() <= de.sim_state.violations[0].sum(), effort
