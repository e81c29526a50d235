"""``greedy_rectangles``: the greedy rectangle plan made for each episode, then flown.

A baseline for ``allocation_plan`` (issue 24): each UAV in turn takes the axis-aligned
rectangle holding the most remaining prior mass that it can search and still be home within
0.85 T (:func:`poc_env.agents.planning.greedy_rectangles.make_greedy_rectangles_plan`); the
waypoint follower flies the lawnmower lines, as ``allocation_plan`` flies its routes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.planning.greedy_rectangles import make_greedy_rectangles_plan
from poc_env.agents.policies.base import PlanPolicy


class GreedyRectanglesPolicy(PlanPolicy):
    """``greedy_rectangles``: best remaining axis-aligned rectangle per UAV, then flown."""

    name = "greedy_rectangles"

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        return make_greedy_rectangles_plan(env.scenario, prior=prior, seed=seed)
