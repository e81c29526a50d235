"""Scenario configs far from the paper's values (config-audit): each defect the config fuzzer
(results/audit/config/fuzz_configs.py) found, as the smallest config that showed it."""

import math

import numpy as np
import pytest

import poc_env


def _episode_is_sane(env, seed=0, steps=5):
    """Reset and a few random steps: observations inside their spaces, rewards finite."""
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        for a, o in obs.items():
            assert np.all(np.isfinite(o)), a
            assert env.observation_space(a).contains(o), a
        if not env.agents:
            break
        shape = env.action_space(env.agents[0]).shape
        obs, rew, *_ = env.step({a: rng.uniform(-1, 1, shape) for a in env.agents})
        assert all(math.isfinite(r) for r in rew.values())


FIXED_SPEED = {
    f"uav.{k}": 180.0
    for k in ("min_speed_kmh", "max_speed_kmh", "cruise_speed_kmh", "search_speed_kmh")
}


@pytest.mark.parametrize("obs_type", ["compass", "flat"])
def test_a_fixed_speed_uav_observes_a_finite_speed(obs_type):
    """v_min = v_max (a fixed-speed UAV) made the speed feature (v - v_min) / (v_max - v_min)
    0 / 0: NaN in every observation."""
    env = poc_env.parallel_env("small", obs_type=obs_type, overrides=FIXED_SPEED)
    _episode_is_sane(env)


def test_a_mixture_off_the_map_without_background_is_refused_naming_it():
    """A prior whose every component lies off the grid, with no background, loaded and then
    failed when the env was built, with a message that said nothing of what is allowed. It
    is refused where the prior is built (the layout keeps the prior out of the config layer),
    naming the components, the grid and what is allowed."""
    from poc_env.config import load_scenario
    from poc_env.errors import ConfigError

    off = {
        "map.prior.components": [{"mean_km": [5000, 5000], "sigma_km": [1, 1]}],
        "map.prior.background": 0.0,
    }
    sc = load_scenario("small", off)
    with pytest.raises(ConfigError, match=r"map\.prior\.components: .*allowed: .*on the 8 x 8"):
        poc_env.parallel_env(sc)
    on = {**off, "map.prior.components": [{"mean_km": [20, 20], "sigma_km": [1, 1]}]}
    _episode_is_sane(poc_env.parallel_env("small", obs_type="compass", overrides=on))


def test_a_comms_range_below_the_safety_distance_is_refused():
    """Eq. 24 wants neighbours within the comms range, eq. 21 every pair at least the safety
    distance apart: with range < d_s no position satisfies both, so every step of every UAV
    was a violation whatever it did (config-audit). Refused, unless no neighbour is needed."""
    from poc_env.config import load_scenario
    from poc_env.errors import ConfigError

    bad = {"comms.range_km": 0.5, "constraints.safety_distance_km": 2.0}
    with pytest.raises(ConfigError, match=r"comms\.range_km: got 0\.5; allowed: .*at least"):
        load_scenario("small", bad)
    load_scenario("small", {**bad, "comms.min_neighbours": 0})  # no link needed: fine
    load_scenario("small", {**bad, "fleet": [{"takeoff": "A", "count": 1}]})  # nobody to link
    load_scenario("small", {**bad, "comms.range_km": 2.0})  # range = d_s: one distance fits


def test_a_step_longer_than_the_endurance_is_refused():
    """dt > T: the episode was one step, in which every UAV flew (and sensed) past its
    endurance and crashed, whatever it did (config-audit: dt = 3600 s on small, T = 40 min:
    POSC 0, every UAV crashed, for every policy). Refused; dt = T still loads."""
    from poc_env.config import load_scenario
    from poc_env.errors import ConfigError

    with pytest.raises(
        ConfigError, match=r"episode\.dt_s: got 1801.*allowed: at most the endurance.* 1800 s"
    ):
        load_scenario("small", {"episode.dt_s": 1801, "uav.endurance_h": 0.5})
    assert load_scenario("small", {"episode.dt_s": 1800, "uav.endurance_h": 0.5}).horizon_steps == 1


def test_a_diffusion_whose_filter_step_would_take_minutes_is_refused():
    """D = 1e7 m^2/s on a 400 x 400 km map of 2 km cells at dt = 600 s: the predict step's
    sub-steps (4 D dt / h^2 on the filter's sub-cells) made one env step about 6e10 cell
    updates, minutes a step (config-audit: the fuzzer's case ran past its time limit inside
    the compiled kernel). Refused at load, naming the largest diffusion that fits."""
    from poc_env.config import load_scenario
    from poc_env.errors import ConfigError

    big = {"map.width_km": 400, "map.height_km": 400, "map.cell_km": 2, "episode.dt_s": 600}
    big["target.model"] = "drift"
    with pytest.raises(
        ConfigError,
        match=r"target\.diffusion_m2_s: got 10000000\.0; allowed: at most 1\.04e\+05 m\^2/s",
    ):
        load_scenario("small", {**big, "target.diffusion_m2_s": 1e7})
    load_scenario("small", {**big, "target.diffusion_m2_s": 50})  # the Drift tasks' D


def test_a_diffusion_at_the_stability_limit_keeps_the_belief_non_negative():
    """D = 1e7 m^2/s on 2.5 km filter sub-cells at dt = 30 s: 768 sub-steps, each exactly at
    the stability limit 4 D tau / h^2 = 1, where a cell keeps none of its own mass and
    rounding left belief entries of -5e-324 (config-audit; eq. 14's belief must stay >= 0)."""
    over = {"map.width_km": 135, "map.height_km": 5, "target.model": "drift"}
    over["target.diffusion_m2_s"] = 1e7
    env = poc_env.parallel_env("small", obs_type="compass", control="heading", overrides=over)
    env.reset(seed=0)
    for _ in range(12):
        env.step({a: np.array([1.0, 0.0]) for a in env.agents})
        assert env.sim_state.belief.min() >= 0.0


def test_a_diffusion_needing_thousands_of_filter_sub_steps_is_refused():
    """D = 1e7 m^2/s on 125 m filter sub-cells: 76,800 stability sub-steps every 30 s step,
    cheap on a 1 x 29 cell map for the environment (3.6e7 updates a step) but the moving
    target's bound of ``evaluate`` runs them forwards and backwards per sweep and ran past the
    fuzzer's 300 s (config-audit). At most ``limits.MAX_FILTER_SUBSTEPS`` a step."""
    from poc_env.config import load_scenario
    from poc_env.errors import ConfigError

    thin = {"map.cell_km": 0.5, "map.width_km": 0.5, "map.height_km": 14.5}
    thin["target.model"] = "drift"
    with pytest.raises(ConfigError, match=r"target\.diffusion_m2_s: got 10000000\.0; allowed"):
        load_scenario("small", {**thin, "target.diffusion_m2_s": 1e7})
    load_scenario("small", {**thin, "target.diffusion_m2_s": 50})
