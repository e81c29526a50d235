"""Adversarial flights in the environment never beat the honest plain bound or the reach-aware
bound (poc_env.theory.bound): full throttle for the whole endurance (overtime until the crash at
T), touring the densest cells or circling over the densest one, on random priors, every law."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import poc_env
from poc_env.theory.bound import honest_optimum, reach_bound
from poc_env.theory.probability_map import Grid, random_gaussian_mixture


def _fly(env, prior, seed, mode):
    """One episode: every UAV at full speed towards its next target cell; ``circle``: circles
    at the full turn rate over the densest cell once there; ``tour``: visits the densest cells
    in turn (UAV i the i-th, (i + n)-th, ... densest)."""
    env.reset(seed=seed, options={"prior": prior})
    p = env.params
    grid = p.grid
    order = np.argsort(-prior, axis=None)
    cy, cx = np.unravel_index(order, prior.shape)
    centres = np.stack(
        [grid.origin_m[0] + (cx + 0.5) * grid.cell_m, grid.origin_m[1] + (cy + 0.5) * grid.cell_m],
        axis=1,
    )
    n = p.n_agents
    nxt = np.arange(n) if mode == "tour" else np.zeros(n, dtype=int)
    turn_step = p.scenario.uav.max_turn_rate_rad_s * p.dt
    while env.agents:
        st = env.sim_state
        actions = {}
        for name in env.agents:
            i = int(name.split("_")[1])
            xy = st.pos[0, i, :2]
            goal = centres[nxt[i] % len(centres)]
            d = np.hypot(*(goal - xy))
            if d < 1500.0:
                if mode == "tour":
                    nxt[i] += n
                    goal = centres[nxt[i] % len(centres)]
                else:
                    actions[name] = np.array([1.0, 1.0, 0.0], dtype=np.float32)
                    continue
            bearing = np.arctan2(goal[1] - xy[1], goal[0] - xy[0])
            err = (bearing - st.heading[0, i] + np.pi) % (2 * np.pi) - np.pi
            actions[name] = np.array([1.0, np.clip(err / turn_step, -1, 1), 0.0], dtype=np.float32)
        env.step(actions)
    st = env.sim_state
    return float(st.posc[0]), float(st.elapsed[0].max()), int(st.crashed[0].sum())


@pytest.mark.parametrize("horizon", [None, 12])
@pytest.mark.parametrize("law", ["inverse_cube", "exponential", "definite_range"])
def test_adversarial_flights_stay_below_both_bounds(law, horizon):
    """Full endurance (every UAV overtime until its crash at T) and a 12-step horizon, where the
    transit from the airfield binds (the reach-aware bound is then far below the plain one)."""
    overrides = {"sensor.law": law}
    if horizon is not None:
        overrides["episode.horizon_steps"] = horizon
    env = poc_env.parallel_env("small", overrides=overrides)
    sc = env.scenario
    grid = Grid.from_config(sc.map)
    worst = 0.0
    for seed in range(3):
        prior = random_gaussian_mixture(grid, np.random.default_rng([seed, 77]))
        plain = honest_optimum(sc, prior).pos
        reach = reach_bound(sc, prior)
        assert reach.upper <= plain + 1e-9
        for mode in ("circle", "tour"):
            posc, flown, crashed = _fly(env, prior, seed, mode)
            if horizon is None:  # overtime: flew until the crash at T
                assert flown >= sc.uav.endurance_s and crashed == sc.n_uavs
            assert 0.0 < posc <= reach.upper + 1e-12
            worst = max(worst, posc / reach.upper)
    assert worst > 0.3  # the flights are real searches, not idle ones


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    law=st.sampled_from(["inverse_cube", "exponential", "definite_range"]),
    field_b=st.tuples(st.floats(-30, 70), st.floats(-30, 70)),
    counts=st.tuples(st.integers(1, 3), st.integers(0, 2)),
    max_speed=st.floats(225, 320),
    endurance_h=st.floats(0.2, 0.7),
    dt_s=st.sampled_from([15.0, 30.0, 45.0]),
    seed=st.integers(0, 10_000),
    mode=st.sampled_from(["circle", "tour"]),
)
def test_no_flight_beats_the_bounds_over_random_configs(
    law, field_b, counts, max_speed, endurance_h, dt_s, seed, mode
):
    """Random priors and configs (law, a second airfield anywhere near the area, fleet split,
    max speed, endurance, step): the adversarial flights stay below both bounds."""
    fleet = [{"takeoff": "A", "count": counts[0]}]
    if counts[1]:
        fleet.append({"takeoff": "B", "count": counts[1], "landing": "A"})
    overrides = {
        "sensor.law": law,
        "airfields": [
            {"name": "A", "position_km": [20, -5]},
            {"name": "B", "position_km": list(field_b)},
        ],
        "fleet": fleet,
        "uav.max_speed_kmh": max_speed,
        "uav.endurance_h": endurance_h,
        "episode.dt_s": dt_s,
        "comms.min_neighbours": 0,
    }
    env = poc_env.parallel_env("small", overrides=overrides)
    sc = env.scenario
    prior = random_gaussian_mixture(Grid.from_config(sc.map), np.random.default_rng(seed))
    plain = honest_optimum(sc, prior).pos
    reach = reach_bound(sc, prior)
    assert reach.gap <= 1e-9 and reach.upper <= plain + 1e-9
    posc, _, _ = _fly(env, prior, seed, mode)
    assert posc <= reach.upper + 1e-12
