"""PettingZoo-style versioned module: ``from poc_env import uav_search_v0``.

``parallel_env(**kw)`` is the parallel API, ``env(**kw)`` the AEC API (``parallel_to_aec``),
``raw_env`` the parallel class. Both take PettingZoo's ``max_cycles=N`` (every agent still
flying is truncated after N steps; it sets the scenario's ``episode.horizon_steps``) and
``random_prior=True`` (a seeded random Gaussian-mixture prior at every reset), besides the
arguments of :class:`~poc_env.envs.parallel.UAVSearchParallelEnv`.
"""

from __future__ import annotations

from pettingzoo.utils.conversions import parallel_to_aec

from poc_env.envs.parallel import UAVSearchParallelEnv

raw_env = UAVSearchParallelEnv


def parallel_env(**kwargs):
    """The parallel environment; keyword arguments as :class:`UAVSearchParallelEnv`."""
    return UAVSearchParallelEnv(**kwargs)


def env(**kwargs):
    """The AEC environment (the parallel env through ``parallel_to_aec``)."""
    return parallel_to_aec(UAVSearchParallelEnv(**kwargs))


__all__ = ["env", "parallel_env", "raw_env"]
