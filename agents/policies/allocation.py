"""``allocation_plan``: the allocation planner's routes made for each episode, then flown.

At the start of every episode the policy plans with
:func:`poc_env.agents.planning.allocation.make_allocation_plan` on the environment's prior (the fine
belief summed to the grid's cells) and flies each UAV's waypoints with the waypoint follower
(transit at cruise speed, the route at search speed, home on eq. 18), as ``de_plan`` does.

``allocation_plan_thorough`` is the same policy at the ``"thorough"`` effort level
(:meth:`poc_env.agents.planning.options.PlanOptions.preset`): a slower plan of more POS;
``allocation_plan_standard`` at the ``"standard"`` one (i24-fastpolish): the default plan
polished, within the issue's 2 s on ``paper_6_2``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.planning.allocation import SPEED, make_allocation_plan
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.policies.base import PlanPolicy


class AllocationPlanPolicy(PlanPolicy):
    """``allocation_plan``: plan routes from the reach-aware allocation, then fly them.

    ``effort``: the planner's effort level (:meth:`~poc_env.agents.planning.options.
    PlanOptions.preset`); ``levels``, ``margin`` and ``refine`` override its fields when given.
    """

    name = "allocation_plan"

    def __init__(
        self,
        levels: int | tuple[int, ...] | None = None,
        margin: float | None = None,
        speed: str = SPEED,
        refine: int | None = None,
        effort: str = "default",
    ) -> None:
        self.options = PlanOptions.preset(effort)
        self.effort = effort
        self.levels = levels
        self.margin = margin
        self.speed = speed
        self.refine = refine
        if effort != "default":
            self.name = f"allocation_plan_{effort}"

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        return make_allocation_plan(
            env.scenario,
            prior=prior,
            seed=seed,
            levels=self.levels,
            margin=self.margin,
            speed=self.speed,
            refine=self.refine,
            options=self.options,
        )
