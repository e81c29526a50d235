"""de_receding: the Fig. 14 loop (DE every step) flies, finds POC, keeps apart, lands."""

import numpy as np

from poc_env.agents.experiments.evaluate import evaluate
from poc_env.agents.policies.receding import DERecedingPolicy
from poc_env.envs.parallel import UAVSearchParallelEnv


def test_de_receding_beats_random_and_the_lawnmower_and_lands():
    """Planning every step over the belief must pay: on the same seeds (1000-1003) de_receding
    finds more than the prior-blind lawnmower. Measured: 0.491 on average against 0.411 (single
    episodes vary with the DE's draws, 0.455 to 0.521 on these seeds; hence the mean)."""
    ev = evaluate("small", ["de_receding", "random", "lawnmower"], episodes=4)
    rows = {r["policy"]: r for r in ev.rows()}
    assert rows["de_receding"]["posc_mean"] > 2 * rows["random"]["posc_mean"]
    assert rows["de_receding"]["posc_mean"] > rows["lawnmower"]["posc_mean"]
    assert rows["de_receding"]["landed"] == 3
    again = evaluate("small", ["de_receding"], episodes=1).episodes
    assert again[0] == next(e for e in ev.episodes if e.policy == "de_receding")


def test_separation_penalty_steers_apart():
    """Two UAVs side by side heading north: the DE turns them away from each other."""
    env = UAVSearchParallelEnv("small", overrides={"constraints.safety_distance_km": 3.0})
    env.reset(seed=0)
    s = env.sim_state
    s.pos[0, :, :2] = [(19e3, 20e3), (21e3, 20e3), (5e3, 35e3)]
    s.heading[0, :] = np.pi / 2
    pol = DERecedingPolicy(popsize=20, maxiter=20)
    pol.reset(env, 0)
    obs = env._observations()
    ras = np.zeros_like(obs["uav_0"]["raster"])
    ras[0] = 1.0  # uniform belief: only the penalties distinguish the choices
    obs = {a: {"raster": ras, "vector": o["vector"]} for a, o in obs.items()}
    acts, _ = pol.predict(obs)
    assert acts["uav_0"][1] > 0 > acts["uav_1"][1]  # left one turns left, right one right
