"""The batched simulator core: mass conservation, determinism, batched == single env."""

import numpy as np
import pytest

from poc_env.config import load_scenario
from poc_env.sim import core as sim
from poc_env.sim.observations import RASTER_INDEX


def _run(name, seeds, steps, action_seed=0, overrides=None):
    p = sim.make_params(load_scenario(name, overrides))
    rngs = [np.random.default_rng(s) for s in seeds]
    st = sim.initial(p, rngs)
    arng = np.random.default_rng(action_seed)
    acts = arng.uniform(-1, 1, (steps, len(seeds), p.n_agents, 3))
    acts[..., 1] *= 0.2  # gentle turns: the UAVs reach the area from their airfields
    acts[..., 2] = 0.0  # level flight
    for k in range(steps):
        sim.step(p, st, acts[k], rngs)
    return p, st


@pytest.mark.parametrize("name", ["small", "paper_6_2"])
def test_mass_is_conserved(name):
    _, st = _run(name, [1, 2], 45)
    np.testing.assert_allclose(st.posc + st.belief.sum(axis=(1, 2)), st.initial_mass, atol=1e-9)
    assert np.all(st.belief >= 0) and st.posc.max() > 0
    np.testing.assert_allclose(st.agent_pos.sum(axis=1), st.posc, atol=1e-12)


def test_same_seed_same_episode():
    _, a = _run("small", [5], 30)
    _, b = _run("small", [5], 30)
    for f in ("pos", "belief", "posc", "target", "detect_step", "links"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))


def test_batched_core_equals_single_envs():
    p = sim.make_params(load_scenario("small"))
    seeds = [11, 12, 13]
    arng = np.random.default_rng(4)
    acts = arng.uniform(-1, 1, (20, 3, p.n_agents, 3))
    acts[..., 2] = 0.0
    rngs = [np.random.default_rng(s) for s in seeds]
    batch = sim.initial(p, rngs)
    singles = []
    for s in seeds:
        r = [np.random.default_rng(s)]
        singles.append((sim.initial(p, r), r))
    for k in range(20):
        sim.step(p, batch, acts[k], rngs)
        for e, (st, r) in enumerate(singles):
            sim.step(p, st, acts[k, e : e + 1], r)
    for e, (st, _) in enumerate(singles):
        np.testing.assert_array_equal(batch.pos[e], st.pos[0])
        np.testing.assert_array_equal(batch.belief[e], st.belief[0])
        assert batch.posc[e] == st.posc[0]


def test_eq19_kinematics_one_step():
    p = sim.make_params(load_scenario("small"))
    st = sim.initial(p, [np.random.default_rng(0)])
    x0, v0, a0 = st.pos[0, 0].copy(), st.speed[0, 0], st.heading[0, 0]
    act = np.zeros((1, p.n_agents, 3))
    act[0, 0] = [1.0, 0.5, 0.0]
    sim.step(p, st, act, [np.random.default_rng(0)])
    u = p.scenario.uav
    alpha = a0 + 0.5 * u.max_turn_rate_rad_s * p.dt
    np.testing.assert_allclose(
        st.pos[0, 0, :2], x0[:2] + v0 * p.dt * np.array([np.cos(alpha), np.sin(alpha)])
    )  # eq. 19 uses the old speed with the new heading
    assert st.speed[0, 0] == pytest.approx(min(v0 + u.max_accel_mps2 * p.dt, u.max_speed_mps))


def test_topology_excludes_uavs_that_finished_this_step():
    p = sim.make_params(load_scenario("small", {"episode.horizon_steps": 3}))
    rngs = [np.random.default_rng(0)]
    st = sim.initial(p, rngs)
    st.left_home[:] = True  # over the airfield after a flight, slow: lands on the next step
    st.speed[:] = p.scenario.uav.min_speed_mps
    sim.step(p, st, np.zeros((1, p.n_agents, 3)), rngs)
    assert st.landed.all() and not st.links.any()


def _comms_run(range_km, steps=6):
    over = {"comms.belief_sharing": "comms", "comms.range_km": range_km}
    p = sim.make_params(load_scenario("small", over))
    rngs = [np.random.default_rng(0)]
    st = sim.initial(p, rngs)
    st.pos[0, :, :2] = [(8e3, 10e3), (32e3, 30e3), (20e3, 20e3)]  # over the area, apart
    for _ in range(steps):
        sim.step(p, st, np.zeros((1, p.n_agents, 3)), rngs)
    return p, st


def test_comms_belief_sharing_connected_swarm_knows_everything():
    _, st = _comms_run(range_km=200)
    beliefs = st.agent_beliefs()[0]
    for i in range(3):
        np.testing.assert_allclose(beliefs[i], st.belief[0], rtol=1e-12, atol=1e-15)


def test_comms_belief_sharing_isolated_uavs_know_only_their_own_sweeps():
    _, st = _comms_run(range_km=1)
    beliefs = st.agent_beliefs()[0]
    prior = st.prior_fine[0]
    for i in range(3):
        own = prior * st.own_survival[0, i]
        np.testing.assert_allclose(beliefs[i], own, rtol=1e-12, atol=1e-15)
        assert not np.allclose(beliefs[i], st.belief[0])  # others' sweeps are unknown to it
    # the global belief (the reward's) is still the product of everyone's sweeps
    np.testing.assert_allclose(
        st.belief[0], prior * st.own_survival[0].prod(axis=0), rtol=1e-9, atol=1e-15
    )


def test_comms_belief_observations_are_per_agent():
    import poc_env

    env = poc_env.parallel_env("small", comms__belief_sharing="comms", comms__range_km=1)
    env.reset(seed=0)
    s = env.sim_state
    s.pos[0, :, :2] = [(8e3, 10e3), (32e3, 30e3), (20e3, 20e3)]
    for _ in range(4):
        obs, *_ = env.step({a: np.zeros(3) for a in env.agents})
    poc = RASTER_INDEX["poc"]
    r0, r1 = obs["uav_0"]["raster"][poc], obs["uav_1"]["raster"][poc]
    assert not np.allclose(r0, r1)


def test_landing_needs_an_approach_speed():
    p = sim.make_params(load_scenario("small"))
    rngs = [np.random.default_rng(0)]
    st = sim.initial(p, rngs)
    st.left_home[:] = True  # back over the field at cruise speed: a fly-over, not a landing
    sim.step(p, st, np.zeros((1, p.n_agents, 3)), rngs)
    assert not st.landed.any() and st.flying.all()


# ---------------------------------------------------------------------- episode end


def _fresh(overrides=None, seeds=(0,)):
    p = sim.make_params(load_scenario("small", overrides))
    rngs = [np.random.default_rng(s) for s in seeds]
    return p, sim.initial(p, rngs), rngs


def _zero(p, st):
    return np.zeros((st.n_envs, p.n_agents, 3))


def test_no_episode_end_mid_flight():
    p, st, rngs = _fresh()
    for _ in range(5):
        sim.step(p, st, _zero(p, st), rngs)
        assert st.flying.all() and 0 < st.step[0] < p.horizon
        assert sim.terminal(p, st).shape == sim.truncated(p, st).shape == (1, p.n_agents)
        assert not sim.terminal(p, st).any()
        assert not sim.truncated(p, st).any()
        assert not sim.horizon_reached(p, st).any() and not sim.episode_over(p, st).any()


def test_terminal_at_landing_and_at_crash_and_stays_terminal():
    p, st, rngs = _fresh()
    u = p.scenario.uav
    sim.step(p, st, _zero(p, st), rngs)
    st.pos[0, 0, :2] = p.landing[0]  # UAV 0: back over its field after a flight, slow
    st.left_home[0, 0] = True
    st.speed[0, 0] = u.min_speed_mps
    st.elapsed[0, 1] = u.endurance_s - p.dt / 2  # UAV 1: endurance T runs out in this step
    sim.step(p, st, _zero(p, st), rngs)
    assert st.landed[0].tolist() == [True, False, False]
    assert st.crashed[0].tolist() == [False, True, False]
    assert sim.terminal(p, st)[0].tolist() == [True, True, False]
    assert not sim.truncated(p, st).any() and not sim.episode_over(p, st).any()
    st.pos[0, 2, 2] = 0.0  # UAV 2: on the ground (altitude <= 0) is a crash
    sim.step(p, st, _zero(p, st), rngs)
    assert st.crashed[0, 2]
    assert sim.terminal(p, st)[0].tolist() == [True, True, True]
    assert sim.episode_over(p, st).tolist() == [True]  # every UAV finished before the horizon
    assert not sim.horizon_reached(p, st).any() and not sim.truncated(p, st).any()


def test_overtime_beyond_085_T_is_not_terminal():
    p, st, rngs = _fresh()
    u = p.scenario.uav
    st.elapsed[0, 0] = u.usable_endurance_s  # beyond 0.85 T (eq. 18), well before T
    ev = sim.step(p, st, _zero(p, st), rngs)
    assert ev.overtime[0, 0] and not sim.terminal(p, st).any()


def test_safety_violation_is_terminal_only_in_terminate_mode():
    for mode, expect in (("penalize", False), ("terminate", True)):
        p, st, rngs = _fresh({"constraints.violation": mode})
        st.pos[0, :, 0] = [10e3, 20e3, 30e3]  # apart: no collision (eq. 21) at the start
        sim.step(p, st, _zero(p, st), rngs)
        assert not sim.terminal(p, st).any()
        st.pos[0, 0, 0] = p.bounds[0] - 10e3  # far outside the operating area (eq. 20)
        ev = sim.step(p, st, _zero(p, st), rngs)
        assert ev.out_of_bounds[0].tolist() == [True, False, False]
        assert not ev.comms_ok[0].any()  # eq. 24 broken for all: never terminal by itself
        assert sim.terminal(p, st)[0].tolist() == [expect, False, False]


def test_detection_is_terminal_for_the_whole_env_only_when_configured():
    for ends in (False, True):
        p, st, rngs = _fresh({"episode.detection_ends_episode": ends}, seeds=(0, 1))
        sim.step(p, st, _zero(p, st), rngs)
        st.target[1] = st.pos[1, 0, :2]  # under UAV 0 of env 1: detected in the next step
        st.target_threshold[1] = 1e-9
        sim.step(p, st, _zero(p, st), rngs)
        assert st.detected.tolist() == [False, True] and st.flying.all()
        assert sim.terminal(p, st).tolist() == [[False] * 3, [ends] * 3]
        assert sim.episode_over(p, st).tolist() == [False, ends]


def test_truncated_at_the_horizon_except_who_terminates_there():
    horizon = 4
    p, st, rngs = _fresh({"episode.horizon_steps": horizon})
    assert p.horizon == horizon
    for _ in range(horizon - 1):
        sim.step(p, st, _zero(p, st), rngs)
        assert not sim.truncated(p, st).any() and not sim.episode_over(p, st).any()
    st.pos[0, 0, :2] = p.landing[0]  # UAV 0 lands in the horizon step
    st.left_home[0, 0] = True
    st.speed[0, 0] = p.scenario.uav.min_speed_mps
    sim.step(p, st, _zero(p, st), rngs)
    assert st.step[0] == horizon and sim.horizon_reached(p, st).tolist() == [True]
    assert sim.terminal(p, st)[0].tolist() == [True, False, False]
    assert sim.truncated(p, st)[0].tolist() == [False, True, True]  # never both
    assert sim.episode_over(p, st).tolist() == [True]


def test_default_horizon_is_the_endurance_in_steps():
    p = sim.make_params(load_scenario("small"))
    u = p.scenario.uav
    assert p.horizon == int(np.ceil(u.endurance_s / p.dt))


def test_episode_over_with_an_adapters_own_finished_mask():
    p, st, rngs = _fresh(seeds=(0, 1))
    sim.step(p, st, _zero(p, st), rngs)
    finished = np.array([[True, True, True], [True, False, True]])
    assert sim.episode_over(p, st, finished).tolist() == [True, False]
    assert sim.episode_over(p, st).tolist() == [False, False]  # default: terminal()


@pytest.mark.parametrize("name", ["small", "paper_6_2"])
def test_targets_are_drawn_as_generator_choice_draws_them(name):
    """The hidden target and threshold of a reset (one cumulative distribution per prior,
    :func:`sim.target_cdf`) are the draws of ``rng.choice(size, p=flat / flat.sum())`` and
    the stream is left where ``choice`` leaves it: the scenario's prior shared by every env,
    and a random prior per env; a prior ``choice`` refuses still raises its error."""
    from poc_env.theory.probability_map import random_gaussian_mixture

    params = sim.make_params(load_scenario(name))
    s, h = params.s, params.grid.cell_m / params.s

    def reference(priors, rngs):
        belief = np.repeat(np.repeat(priors, s, axis=1), s, axis=2) / (s * s)
        out = []
        for k, rng in enumerate(rngs):
            flat = belief[k].ravel()
            idx = int(rng.choice(flat.size, p=flat / flat.sum()))
            j, i = divmod(idx, belief.shape[2])
            du, dv = rng.random(2)
            x0, y0 = params.grid.origin_m
            out.append((x0 + (i + du) * h, y0 + (j + dv) * h, -np.log1p(-rng.random())))
        return np.array(out)

    rng = np.random.default_rng(4)
    shared = np.broadcast_to(params.prior, (40, *params.prior.shape))
    drawn = np.stack([random_gaussian_mixture(params.grid, rng) for _ in range(40)])
    for priors, given in ((shared, None), (drawn, drawn)):
        st = sim.initial(params, [np.random.default_rng(k) for k in range(40)], given)
        rngs = [np.random.default_rng(k) for k in range(40)]
        want = reference(priors, rngs)
        np.testing.assert_array_equal(st.target, want[:, :2])
        np.testing.assert_array_equal(st.target_threshold, want[:, 2])
    bad = drawn[:2].copy()
    bad[:, 0, 0] = -1.0
    with pytest.raises(ValueError, match=r"(?i)probabilities"):
        sim.initial(params, [np.random.default_rng(k) for k in range(2)], bad)
