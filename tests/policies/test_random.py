"""The random floors: increments (level flight), random headings and random waypoints."""

from __future__ import annotations

import numpy as np
import pytest

import poc_env
from poc_env.agents.policies.registry import make_policy


@pytest.mark.parametrize("control", ["heading", "waypoint"])
def test_random_heading_and_waypoint_fly_the_control_levels_autopilot(control):
    # the policy on the increments env flies exactly what the control-level env flies for the
    # same uniform draws: one autopilot (poc_env.sim.control), no second implementation
    seed = 3
    pol = make_policy(f"random_{control}")
    env = poc_env.parallel_env("small", overrides={"episode.horizon_steps": 40})
    ref = poc_env.parallel_env("small", control=control, overrides={"episode.horizon_steps": 40})
    obs, _ = env.reset(seed=seed)
    ref.reset(seed=seed)
    pol.reset(env, seed)
    draws = np.random.default_rng([seed, 7])  # the policy's own stream (RandomPolicy.reset)
    steps = 0
    while env.agents:
        live = list(env.agents)
        act = draws.uniform(-1.0, 1.0, (len(live), 2))
        acts, _ = pol.predict(obs)
        obs, r1, *_ = env.step(acts)
        _, r2, *_ = ref.step({a: act[j] for j, a in enumerate(live)})
        assert r1 == r2
        np.testing.assert_array_equal(env.sim_state.pos, ref.sim_state.pos)
        steps += 1
    assert steps == 40 or not ref.agents
    assert env.sim_state.posc[0] > 0
