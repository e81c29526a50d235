"""greedy_bayes and potential_game fly from observations, find POC, and land."""

import numpy as np
import pytest

from poc_env.agents.experiments.evaluate import evaluate
from poc_env.agents.policies.game import PotentialGamePolicy
from poc_env.agents.policies.greedy import best_cell
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.sim.observations import decode_vector


@pytest.fixture(scope="module")
def scores():
    policies = ["greedy_bayes", "potential_game", "random", "lawnmower"]
    ev = evaluate("small", policies, episodes=6)
    return {r["policy"]: r for r in ev.rows()}, ev


def test_belief_policies_beat_random_and_land(scores):
    rows, _ = scores
    for name in ("greedy_bayes", "potential_game"):
        assert rows[name]["posc_mean"] > 2 * rows["random"]["posc_mean"] > 0
        assert rows[name]["crashed"] == 0 and rows[name]["landed"] == 3


def test_belief_policies_beat_the_lawnmower_on_the_same_seeds(scores):
    """Reading the belief must pay: both find more than the prior-blind lawnmower flying the
    same episodes. Measured on seeds 1000-1005: lawnmower 0.411, greedy_bayes 0.503 (every
    seed), potential_game 0.493 on average (its log-linear learning draws its choices, so one
    episode may fall short, seed 1000: 0.346; hence the mean over six seeds)."""
    rows, ev = scores
    lawn = rows["lawnmower"]["posc_mean"]
    greedy = [e.posc for e in ev.episodes if e.policy == "greedy_bayes"]
    assert min(greedy) > lawn
    assert rows["potential_game"]["posc_mean"] > lawn


def test_same_seed_same_episode():
    a = evaluate("small", ["potential_game"], episodes=1).episodes
    b = evaluate("small", ["potential_game"], episodes=1).episodes
    assert a == b


def test_best_cell_prefers_near_mass_and_skips_taken_cells():
    env = UAVSearchParallelEnv("small", obs_type="dict")
    obs, _ = env.reset(seed=0)
    q = decode_vector(env.params, obs["uav_0"]["vector"])
    poc = np.zeros(env.params.grid.shape)
    poc[7, 7] = 1.0  # far corner
    poc[1, 4] = 0.9  # close to the airfield, south edge
    assert best_cell(env.params, poc, q, 0) == 1 * env.params.grid.nx + 4
    near = 1 * env.params.grid.nx + 4
    assert best_cell(env.params, poc, q, 0, taken={near}) == 7 * env.params.grid.nx + 7


def test_log_linear_learning_prefers_the_better_heading():
    env = UAVSearchParallelEnv("small", obs_type="dict")
    obs, _ = env.reset(seed=0)
    s = env.sim_state
    s.pos[0, :, :2] = [(20e3, 8e3), (5e3, 35e3), (35e3, 35e3)]
    s.heading[0, 0] = np.pi / 2  # uav_0 faces north
    obs = env._observations()
    pol = PotentialGamePolicy(rounds=60)
    pol.reset(env, 1)
    ras = obs["uav_0"]["raster"].copy()
    ras[0] = 0.0
    ras[0, 2:6, 5:8] = 1.0  # all the mass north-east of uav_0
    obs["uav_0"] = {"raster": ras, "vector": obs["uav_0"]["vector"]}
    for a in ("uav_1", "uav_2"):
        obs[a] = {"raster": ras, "vector": obs[a]["vector"]}
    acts, _ = pol.predict(obs)
    assert acts["uav_0"][1] < 0  # turns right (clockwise) towards the north-east
