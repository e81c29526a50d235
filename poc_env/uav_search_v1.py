"""PettingZoo-style versioned module, version 1: ``from poc_env import uav_search_v1``.

The same environment as :mod:`poc_env.uav_search_v0` with one default changed: ``control``
is ``"heading"`` (each action a map-frame direction flown by the autopilot of
:mod:`poc_env.sim.control`, which holds the cruise altitude and brings each UAV home), not
``"increments"``. Under v0's default, uniformly random actions command a random pitch: at the
paper's 1000 m cruise altitude the 15 degree limit is reached in one 60 s step, a drop of up
to 776 m per step, so random flight hits the ground within 2-4 steps and PettingZoo's
``max_cycles_test`` (random actions, most agents alive after 4 steps) failed. With this
module's defaults it passes. Every other argument and default is v0's: ``control=
"increments"`` gives v0's environment (the metadata name aside).

``parallel_env(**kw)`` is the parallel API, ``env(**kw)`` the AEC API (``parallel_to_aec``),
``raw_env`` the parallel class; both take PettingZoo's ``max_cycles=N``, ``random_prior`` and
the other arguments of :class:`~poc_env.envs.parallel.UAVSearchParallelEnv`.

Version history: v0 (:mod:`poc_env.uav_search_v0`, unchanged) defaults to
``control="increments"``; v1 defaults to ``control="heading"``.
"""

from __future__ import annotations

from typing import Any

from pettingzoo.utils.conversions import parallel_to_aec

from poc_env.config import Scenario
from poc_env.envs.parallel import UAVSearchParallelEnv

#: This module's default control level (v0's is ``"increments"``).
DEFAULT_CONTROL = "heading"


class raw_env(UAVSearchParallelEnv):  # PettingZoo names the module's class raw_env
    """:class:`~poc_env.envs.parallel.UAVSearchParallelEnv` with ``control="heading"`` by
    default and the metadata name ``uav_search_v1``."""

    metadata = {**UAVSearchParallelEnv.metadata, "name": "uav_search_v1"}

    def __init__(
        self,
        scenario: str | Scenario = "paper_6_2",
        render_mode: str | None = None,
        *,
        control: str = DEFAULT_CONTROL,
        **kwargs: Any,
    ) -> None:
        super().__init__(scenario, render_mode, control=control, **kwargs)


def parallel_env(**kwargs: Any) -> raw_env:
    """The parallel environment; keyword arguments as :class:`UAVSearchParallelEnv`, with
    ``control="heading"`` unless given."""
    return raw_env(**kwargs)


def env(**kwargs: Any):
    """The AEC environment (the parallel env through ``parallel_to_aec``)."""
    return parallel_to_aec(raw_env(**kwargs))


__all__ = ["DEFAULT_CONTROL", "env", "parallel_env", "raw_env"]
