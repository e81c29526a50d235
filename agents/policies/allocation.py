"""``allocation_plan``: the allocation planner's routes made for each episode, then flown.

At the start of every episode the policy plans with
:func:`poc_env.agents.planning.allocation.make_allocation_plan` on the environment's prior (the fine
belief summed to the grid's cells) and flies each UAV's waypoints with the waypoint follower
(transit at cruise speed, the route at search speed, home on eq. 18), as ``de_plan`` does.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.planning.allocation import LEVELS, MARGIN, REFINE, SPEED, make_allocation_plan
from poc_env.agents.policies.base import PlanPolicy


class AllocationPlanPolicy(PlanPolicy):
    """``allocation_plan``: plan routes from the reach-aware allocation, then fly them."""

    name = "allocation_plan"

    def __init__(
        self,
        levels: int | tuple[int, ...] = LEVELS,
        margin: float = MARGIN,
        speed: str = SPEED,
        refine: int = REFINE,
    ) -> None:
        self.levels = levels
        self.margin = margin
        self.speed = speed
        self.refine = refine

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        return make_allocation_plan(
            env.scenario,
            prior=prior,
            seed=seed,
            levels=self.levels,
            margin=self.margin,
            speed=self.speed,
            refine=self.refine,
        )
