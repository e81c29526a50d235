"""``greedy_bayes``: a belief-driven online baseline (in the spirit of the paper's [38]).

It acts from the observations alone (the POC raster, which the environment keeps up to date by
eq. 14, and the state vector), re-decides every step and returns to land with the follower's
rule (:func:`poc_env.sim.autopilot.must_return`). Each UAV heads for the cell with the most
expected POS per unit of time, ``POC_cell * exp(-distance / L)`` with ``L`` = one hour of search
flight; UAVs choose in turn and a cell already chosen this step is not chosen again.
:func:`best_cell` is also the way into the area of ``potential_game`` and ``de_receding``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.policies.base import BeliefPolicy, Reading
from poc_env.sim.autopilot import steer_to


def best_cell(params, poc: np.ndarray, q: dict, k: int, taken=()) -> int:
    """Index (row-major) of the cell with the most ``POC * exp(-distance / L)`` that UAV ``k``
    can reach and still get home within its usable endurance; ``taken`` cells are skipped."""
    u = params.scenario.uav
    centers = params.grid.centers.reshape(-1, 2)
    dist = np.hypot(*(centers - q["xy"]).T)
    home = np.hypot(*(centers - params.landing[k]).T)
    left = q["usable"] * u.usable_endurance_s * u.cruise_speed_mps
    score = poc.ravel() * np.exp(-dist / (u.search_speed_mps * 3600.0))
    score[(dist + home) > left] = -1.0  # cannot get there and back in time
    if len(taken):
        score[list(taken)] = -1.0
    return int(np.argmax(score))


class GreedyBayesPolicy(BeliefPolicy):
    """``greedy_bayes``: head for the best reachable cell (see the module docstring)."""

    name = "greedy_bayes"

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.centers = env.params.grid.centers.reshape(-1, 2)

    def search(self, searching: list[Reading], readings: list[Reading]) -> dict[str, Any]:
        p = self.params
        u = p.scenario.uav
        taken: set[int] = set()
        actions = {}
        for r in searching:  # in turn: a cell already chosen this step is not chosen again
            q = r.q
            best = best_cell(p, r.poc, q, r.k, taken)
            taken.add(best)
            actions[r.agent] = steer_to(p, q, self.centers[best], u.search_speed_mps).astype(
                np.float32
            )
        return actions
