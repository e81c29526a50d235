"""The CNN+MLP extractor (poc_env.agents.rl.networks) on SwarmVecEnv observations, trained by SB3
PPO."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.envs.vector import SwarmVecEnv
from poc_env.errors import ConfigError


def test_extractor_shapes_for_small_and_paper_grids():
    import torch as th

    from poc_env.agents.rl.networks import SwarmExtractor

    for name in ("small", "paper_6_2"):
        vec = SwarmVecEnv(name, n_envs=1, seed=0)
        ext = SwarmExtractor(vec.observation_space)
        obs = vec.reset()
        out = ext({k: th.as_tensor(v) for k, v in obs.items()})
        assert out.shape == (vec.num_envs, 192) == (vec.num_envs, ext.features_dim)
    flat = SwarmVecEnv("small", n_envs=1, obs_type="flat")
    with pytest.raises(ConfigError, match="observation_space"):
        SwarmExtractor(flat.observation_space)


def _train(seed: int):
    import torch as th
    from stable_baselines3 import PPO
    from stable_baselines3.common.utils import set_random_seed

    from poc_env.agents.rl.networks import SwarmExtractor

    th.manual_seed(seed)
    set_random_seed(seed)
    vec = SwarmVecEnv("small", n_envs=2, seed=seed, overrides={"episode.horizon_steps": 10})
    model = PPO(
        "MultiInputPolicy",
        vec,
        policy_kwargs=dict(features_extractor_class=SwarmExtractor),
        n_steps=16,
        batch_size=48,
        seed=seed,
        device="cpu",
    )
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(96)
    return model, before


def test_ppo_trains_the_extractor_reproducibly():
    """SB3 PPO trains a SwarmExtractor policy on SwarmVecEnv, bit-identically for one seed.

    That training raises the POSC is measured by ``test_ppo_learns_on_small`` in test_train.py.
    """
    import torch as th

    threads = th.get_num_threads()
    th.set_num_threads(1)  # tiny nets: extra threads only spin, badly on a busy 2-core runner
    try:
        m1, before = _train(0)
        m2, _ = _train(0)
    finally:
        th.set_num_threads(threads)
    p1 = list(m1.policy.parameters())
    p2 = list(m2.policy.parameters())
    assert m1.num_timesteps == 96
    assert any(not np.array_equal(a.detach(), b) for a, b in zip(p1, before))  # it trained
    for a, b in zip(p1, p2):
        np.testing.assert_array_equal(a.detach().numpy(), b.detach().numpy())
    eps = list(m1.ep_info_buffer)  # horizon 10 in 16 steps: every agent's episode recorded
    assert len(eps) >= m1.n_envs
    assert all({"r", "l", "t", "posc"} <= set(ep) for ep in eps)


def test_set_extractor_is_invariant_to_the_order_and_padding_of_the_neighbours():
    import torch as th

    from poc_env import spec
    from poc_env.agents.rl.networks import SetExtractor

    th.manual_seed(0)
    vec = SwarmVecEnv("wide_400", n_envs=1, seed=0, obs_type="set", control="heading")
    ext = SetExtractor(vec.observation_space)
    obs = th.as_tensor(vec.reset())  # 12 UAVs: 8 real neighbour rows each
    ego, k, w = spec.SET_EGO_SIZE, spec.K_NEIGHBOURS, spec.NEIGHBOUR_SIZE
    rows = obs[:, ego:].reshape(-1, k, w)
    out = ext(obs)
    assert out.shape == (12, ext.features_dim)
    perm = th.randperm(k)
    shuffled = th.cat([obs[:, :ego], rows[:, perm].reshape(len(obs), -1)], dim=1)
    th.testing.assert_close(ext(shuffled), out)  # a set: the row order does not matter
    # padding rows (mask 0) take no part, whatever they hold; a real row does
    few = rows.clone()
    few[:, 5:] = 0.0
    base = ext(th.cat([obs[:, :ego], few.reshape(len(obs), -1)], dim=1))
    junk = few.clone()
    junk[:, 5:, :-1] = 7.0
    th.testing.assert_close(ext(th.cat([obs[:, :ego], junk.reshape(len(obs), -1)], dim=1)), base)
    assert not th.allclose(base, out)
    with pytest.raises(ConfigError, match="observation_space"):
        SetExtractor(SwarmVecEnv("small", n_envs=1, obs_type="compass").observation_space)
