"""spacetime_plan and spacetime_receding: flown in a drifting environment."""

import numpy as np

from poc_env.agents.policies.moving import SpacetimePlanPolicy, SpacetimeRecedingPolicy
from poc_env.agents.policies.registry import make_policy
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.errors import ConfigError

DRIFT = {"target__model": "drift", "target__current_kmh": [30.0, 10.0]}


def _fly(pol, seed=0, **kw):
    env = UAVSearchParallelEnv(scenario="small", **{**DRIFT, **kw})
    obs, _ = env.reset(seed=seed)
    pol.reset(env, seed)
    worst = 0.0
    while env.agents:
        act = pol.predict(obs)[0]
        worst = max([worst, *(float(np.abs(a).max()) for a in act.values())])
        obs, *_ = env.step(act)
    return env, worst


def test_spacetime_plan_flies_and_lands():
    pol = make_policy("spacetime_plan")
    assert isinstance(pol, SpacetimePlanPolicy)
    env, worst = _fly(pol)
    st = env.sim_state
    assert worst <= 1.0
    assert st.landed[0].all() and not st.crashed[0].any()
    assert pol.plan["planner"] == "spacetime"
    assert np.allclose(pol.plan["drift_mps"], st.drift[0])


def test_receding_replans_from_the_belief():
    pol = make_policy("spacetime_receding", replan_min=10)
    assert isinstance(pol, SpacetimeRecedingPolicy)
    env, worst = _fly(pol, seed=1)
    st = env.sim_state
    assert worst <= 1.0
    assert not st.crashed[0].any()
    assert pol.plans >= 3  # 40 min of endurance, a plan at take-off and every 10 min
    assert st.posc[0] > 0
    assert len(pol.scores) == pol.plans - 1  # every re-plan scored against the routes flown
    taken = [sc for sc in pol.scores if sc[1] > sc[0] + pol.margin]
    assert pol.switches == len(taken)


def test_receding_keeps_the_plan_unless_a_replan_scores_more():
    """With a margin no re-plan can clear, the receding policy flies the take-off plan:
    the same episode as spacetime_plan."""
    keep = make_policy("spacetime_receding", replan_min=10, switch_margin=1.0)
    env, _ = _fly(keep, seed=1)
    ref, _ = _fly(make_policy("spacetime_plan"), seed=1)
    assert keep.plans >= 3 and keep.switches == 0
    assert env.sim_state.posc[0] == ref.sim_state.posc[0]


def test_receding_refuses_a_bad_interval():
    for bad in (0.0, -5, "x", float("nan")):
        try:
            SpacetimeRecedingPolicy(replan_min=bad)  # type: ignore[arg-type]
        except ConfigError as err:
            assert err.field == "replan_min"
        else:
            raise AssertionError(bad)
    for bad in (-0.1, 2.0, "x", float("nan")):
        try:
            SpacetimeRecedingPolicy(switch_margin=bad)  # type: ignore[arg-type]
        except ConfigError as err:
            assert err.field == "switch_margin"
        else:
            raise AssertionError(bad)
