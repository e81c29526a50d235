"""``de_plan``: the paper's §6.2 plan (eq. 26, adaptive DE) made for each episode, then flown.

At the start of every episode the policy plans with
:func:`poc_env.agents.planning.planner.make_plan`
on the environment's prior (the fine belief summed to the grid's cells) with the episode's seed,
and flies each UAV's waypoints with the waypoint follower, which also brings it home to land.
``popsize`` and ``maxiter`` default to the scenario's ``planner`` section (NP = 100, G = 300).

``optimizer_plan:NAME`` is the same policy with another optimiser of
:data:`poc_env.agents.planning.optimizers.OPTIMIZERS` (``optimizer_plan:cmaes``, ...) on the same
objective and budget, so every optimiser's plan can be flown on the same episodes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.planning.optimizers import get_optimizer
from poc_env.agents.planning.planner import make_plan
from poc_env.agents.policies.base import PlanPolicy


class DEPlanPolicy(PlanPolicy):
    """``de_plan``: plan with adaptive DE on the episode's prior, then fly it (follower)."""

    name = "de_plan"

    def __init__(
        self,
        popsize: int | None = None,
        maxiter: int | None = None,
        optimizer: str = "adaptive_de",
    ) -> None:
        get_optimizer(optimizer)  # ConfigError naming the allowed optimisers
        self.popsize = popsize
        self.maxiter = maxiter
        self.optimizer = optimizer

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        return make_plan(
            env.scenario,
            prior=prior,
            seed=seed,
            popsize=self.popsize,
            maxiter=self.maxiter,
            optimizer=self.optimizer,
        )
