"""Constraints inside episodes (eq. 20-24, §3.2.5) and invariants under random configs."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import poc_env

ZERO = np.zeros(3)


def _place(env, positions_km, headings_deg=None):
    s = env.sim_state
    for i, (x, y) in enumerate(positions_km):
        s.pos[0, i, :2] = (x * 1e3, y * 1e3)
        s.left_home[0, i] = True
        if headings_deg is not None:
            s.heading[0, i] = np.radians(headings_deg[i])


def _step(env, actions=None):
    return env.step(actions or {a: ZERO for a in env.agents})


def test_collision_is_flagged_and_penalised():
    env = poc_env.parallel_env("small", overrides={"constraints.safety_distance_km": 1.0})
    env.reset(seed=0)
    _place(env, [(20, 20), (20.3, 20), (5, 35)], [0, 0, 0])  # 0 and 1 fly in formation
    _, _, _, _, infos = _step(env)
    flags = [infos[a]["violation_collision"] for a in env.possible_agents]
    assert flags == [True, True, False]
    assert infos["uav_0"]["reward_violation"] < 0


def test_collision_terminates_in_terminate_mode():
    env = poc_env.parallel_env(
        "small", overrides={"constraints.violation": "terminate", "comms.min_neighbours": 0}
    )
    env.reset(seed=0)
    _place(env, [(20, 20), (20.3, 20), (5, 35)], [0, 0, 0])
    _, _, term, _, infos = _step(env)
    assert term["uav_0"] and term["uav_1"] and infos["uav_0"]["crashed"]
    assert not term["uav_2"]


NOFLY = {
    "map.no_fly_zones_km": [[[24, 15], [30, 15], [30, 25], [24, 25]]],
    "comms.min_neighbours": 0,
}


def test_no_fly_entry_is_flagged():
    env = poc_env.parallel_env("small", overrides=NOFLY)
    env.reset(seed=0)
    _place(env, [(23, 20), (5, 5), (5, 35)], [0, 90, 90])  # uav_0 heads east into the zone
    _, _, _, _, infos = _step(env)
    assert infos["uav_0"]["violation_no_fly"]
    assert not infos["uav_1"]["violation_no_fly"]


def test_no_fly_entry_is_shielded():
    env = poc_env.parallel_env("small", overrides={**NOFLY, "constraints.violation": "shield"})
    env.reset(seed=0)
    _place(env, [(23, 20), (5, 5), (5, 35)], [0, 90, 90])
    _, _, _, _, infos = _step(env)
    assert not infos["uav_0"]["violation_no_fly"]
    assert infos["uav_0"]["shielded"] and not infos["uav_1"]["shielded"]
    x, y = env.sim_state.pos[0, 0, :2] / 1e3
    assert not (24 <= x <= 30 and 15 <= y <= 25)


def test_two_neighbour_rule():
    env = poc_env.parallel_env("small", overrides={"comms.range_km": 10})
    env.reset(seed=0)
    # a line spaced 8 km: the ends have one neighbour in range, the middle two
    _place(env, [(10, 20), (18, 20), (26, 20)], [90, 90, 90])
    _, _, _, _, infos = _step(env)
    assert [infos[a]["violation_comms"] for a in env.possible_agents] == [True, False, True]
    env2 = poc_env.parallel_env("small", overrides={"comms.range_km": 20})
    env2.reset(seed=0)
    _place(env2, [(10, 20), (18, 20), (26, 20)], [90, 90, 90])
    _, _, _, _, infos2 = _step(env2)
    assert not any(infos2[a]["violation_comms"] for a in env2.possible_agents)


FIVE = {
    "fleet": [{"takeoff": "A", "count": 5}],
    "comms.topology": "table2",
    "comms.range_km": 12,
    "comms.min_neighbours": 0,
}


@pytest.mark.parametrize(
    ("far_pair", "expected"), [((3, 4), "E"), ((4, 5), "F"), ((1, 3), "C"), ((2, 4), "B")]
)
def test_table2_switch_inside_an_episode(far_pair, expected):
    """UAVs i and j (1-based) drift out of range of each other; the rest stay in range."""
    env = poc_env.parallel_env("small", overrides=FIVE)
    env.reset(seed=0)
    assert env.sim_state.topology[0] >= 0  # a Table 2 topology, not the auto rule
    pts = {k: (20.0, 20.0) for k in range(1, 6)}
    pts.update({k: (14.0 + 2 * k, 22.0) for k in range(1, 6)})
    i, j = far_pair
    pts[i], pts[j] = (12.0, 18.0), (28.0, 18.0)  # 16 km apart, both within 12 km of the others
    others = [k for k in range(1, 6) if k not in far_pair]
    for n, k in enumerate(others):
        pts[k] = (20.0, 16.0 + 3 * n)
    _place(env, [pts[k] for k in range(1, 6)], [90] * 5)
    _, _, _, _, infos = _step(env)
    assert env.topology == expected
    assert infos["uav_0"]["topology"] == env.params.switcher.code(expected)
    assert (i - 1, j - 1) not in env.links
    assert not infos[f"uav_{i - 1}"]["links"][j - 1] and not infos[f"uav_{j - 1}"]["links"][i - 1]


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    law=st.sampled_from(["inverse_cube", "exponential", "definite_range"]),
    s=st.integers(1, 4),
    dt=st.sampled_from([20, 30, 60]),
    w=st.floats(1.0, 6.0),
    mode=st.sampled_from(["penalize", "terminate", "shield"]),
    credit=st.sampled_from(["team", "individual"]),
    sharing=st.sampled_from(["global", "comms"]),
)
def test_invariants_under_random_configs_and_actions(seed, law, s, dt, w, mode, credit, sharing):
    env = poc_env.parallel_env(
        "small",
        overrides={
            "sensor.law": law,
            "sensor.samples_per_cell": s,
            "sensor.sweep_width_km": w,
            "episode.dt_s": dt,
            "episode.horizon_steps": 25,
            "constraints.violation": mode,
            "reward.credit": credit,
            "comms.belief_sharing": sharing,
        },
    )
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    st_ = env.sim_state
    while env.agents:
        _, rew, _, _, _ = env.step({a: rng.uniform(-1, 1, 3) for a in env.agents})
        assert all(np.isfinite(r) for r in rew.values())
        assert np.all(st_.belief >= 0) and np.all(st_.belief <= 1)
        np.testing.assert_allclose(
            st_.posc + st_.belief.sum(axis=(1, 2)), st_.initial_mass, atol=1e-9
        )
        beliefs = st_.agent_beliefs()
        assert np.all(beliefs >= st_.belief[:, None] - 1e-15)  # nobody knows more than all
