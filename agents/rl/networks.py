"""Policy networks for the per-agent observation of poc-env.

:class:`SetExtractor` (``poc-env train --task ...-Set-... --net set``) reads the ``set``
observation (:data:`poc_env.spec.SET_BLOCKS`) of any fleet size: DeepSets over the neighbour
rows, concatenated with the ego features (its docstring).

:class:`SwarmExtractor` is an SB3 ``features_extractor_class`` for the ``Dict`` observation
(``obs_type="dict"``) of :class:`poc_env.envs.parallel.UAVSearchParallelEnv` and
:class:`poc_env.envs.vector.SwarmVecEnv`:

* **raster** (``4 x ny x nx``: POC, own cell, other UAVs, hazard) -> a small CNN: two 3 x 3
  convolutions with stride 2 and padding 1 (16 then 32 channels, ReLU), which halve the grid
  twice (``8 x 8 -> 2 x 2`` on ``small``, ``30 x 40 -> 8 x 10`` on ``paper_6_2``), then flatten
  and a linear layer to 128 features (ReLU). The flattened size is measured on a dummy
  raster, so any grid works. No pooling: the policy needs *where* the probability mass is
  relative to the UAV, which the own-cell channel and the flattened map keep;
* **vector** (14 normalised kinematic and timing values) -> an MLP, one linear layer to 64
  features (ReLU);
* the two are concatenated: ``features_dim = 128 + 64 = 192``. SB3's policy and value heads
  (``net_arch``) sit on top.

Usage::

    PPO("MultiInputPolicy", vec_env, policy_kwargs=dict(features_extractor_class=SwarmExtractor))

Sizes (trainable parameters of the extractor): about 23 k on ``small`` and about 334 k on
``paper_6_2``, dominated by the ``flatten -> 128`` layer (``32 * 8 * 10 * 128``).
"""

from __future__ import annotations

import torch as th
from gymnasium import spaces
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from poc_env import spec
from poc_env.errors import ConfigError


class SwarmExtractor(BaseFeaturesExtractor):
    """CNN over the belief raster + MLP over the state vector, concatenated (module docstring).

    Parameters
    ----------
    observation_space:
        ``Dict(raster=Box(C, ny, nx), vector=Box(D,))``.
    channels:
        Output channels of the two stride-2 convolutions.
    raster_features, vector_features:
        Widths of the raster and vector embeddings; ``features_dim`` is their sum.
    """

    def __init__(
        self,
        observation_space: spaces.Dict,
        channels: tuple[int, int] = (16, 32),
        raster_features: int = 128,
        vector_features: int = 64,
    ) -> None:
        if not isinstance(observation_space, spaces.Dict) or set(observation_space.spaces) != {
            "raster",
            "vector",
        }:
            raise ConfigError(
                "observation_space",
                observation_space,
                "Dict(raster=..., vector=...) (the env's obs_type='dict')",
            )
        super().__init__(observation_space, features_dim=raster_features + vector_features)
        raster_shape = tuple(observation_space["raster"].shape or ())
        vector_shape = tuple(observation_space["vector"].shape or ())
        if len(raster_shape) != 3 or len(vector_shape) != 1:
            raise ConfigError(
                "observation_space", observation_space, "raster (C, ny, nx) and vector (D,)"
            )
        c1, c2 = channels
        self.cnn = nn.Sequential(
            nn.Conv2d(raster_shape[0], c1, kernel_size=3, stride=2, padding=1),
            nn.ReLU(),
            nn.Conv2d(c1, c2, kernel_size=3, stride=2, padding=1),
            nn.ReLU(),
            nn.Flatten(),
        )
        with th.no_grad():
            n_flat = self.cnn(th.zeros(1, *raster_shape)).shape[1]
        self.raster_head = nn.Sequential(nn.Linear(n_flat, raster_features), nn.ReLU())
        self.vector_mlp = nn.Sequential(nn.Linear(vector_shape[0], vector_features), nn.ReLU())

    def forward(self, observations: dict[str, th.Tensor]) -> th.Tensor:
        r = self.raster_head(self.cnn(observations["raster"]))
        v = self.vector_mlp(observations["vector"])
        return th.cat([r, v], dim=1)


class SetExtractor(BaseFeaturesExtractor):
    """A permutation-invariant encoder of the ``set`` observation: one policy for any N.

    The observation (``Box((SET_SIZE,))``, :data:`poc_env.spec.SET_BLOCKS`) is split into the
    ego features (the first :data:`~poc_env.spec.SET_EGO_SIZE` values: state vector, belief
    compass, role, centroid, fleet size) and :data:`~poc_env.spec.K_NEIGHBOURS` neighbour rows
    of :data:`~poc_env.spec.NEIGHBOUR_FIELDS` whose last field is the mask. DeepSets (Zaheer
    et al., 2017): each row goes through the same MLP ``phi`` (two layers, ReLU), the rows are
    pooled by a masked mean and a masked max (padding rows take no part), so permuting the
    neighbours changes nothing and any number of them up to K is read the same way; the ego
    features go through a linear layer (ReLU). ``features_dim = ego_features + 2 *
    set_features``; SB3's policy and value heads (``net_arch``) sit on top. Parameter-shared
    over the UAVs by :class:`poc_env.envs.vector.SwarmVecEnv`, so the same weights fly 3 or 24.

    Usage::

        PPO("MlpPolicy", vec_env, policy_kwargs=dict(features_extractor_class=SetExtractor))
    """

    def __init__(
        self, observation_space: spaces.Box, ego_features: int = 128, set_features: int = 64
    ) -> None:
        shape = tuple(observation_space.shape or ())
        if not isinstance(observation_space, spaces.Box) or shape != (spec.SET_SIZE,):
            raise ConfigError(
                "observation_space",
                observation_space,
                f"Box(({spec.SET_SIZE},)) (the env's obs_type='set', a -Set task)",
            )
        super().__init__(observation_space, features_dim=ego_features + 2 * set_features)
        self.k = spec.K_NEIGHBOURS
        self.width = spec.NEIGHBOUR_SIZE
        self.ego = nn.Sequential(nn.Linear(spec.SET_EGO_SIZE, ego_features), nn.ReLU())
        self.phi = nn.Sequential(
            nn.Linear(self.width, set_features),
            nn.ReLU(),
            nn.Linear(set_features, set_features),
            nn.ReLU(),
        )

    def forward(self, observations: th.Tensor) -> th.Tensor:
        ego = self.ego(observations[:, : spec.SET_EGO_SIZE])
        rows = observations[:, spec.SET_EGO_SIZE :].reshape(-1, self.k, self.width)
        mask = rows[..., -1:]  # (B, K, 1): 1 for a real neighbour
        h = self.phi(rows) * mask
        count = mask.sum(dim=1).clamp(min=1.0)
        mean = h.sum(dim=1) / count
        top = h.max(dim=1).values  # h >= 0 (ReLU) and 0 on padding: the max of the real rows
        return th.cat([ego, mean, top], dim=1)
