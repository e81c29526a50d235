"""``potential_game``: a belief-driven online baseline (in the spirit of the paper's [39]).

It acts from the observations alone (the POC raster, which the environment keeps up to date by
eq. 14, and the state vector), re-decides every step, returns to land with the follower's rule
(:func:`poc_env.sim.autopilot.must_return`), and plans with the same detection law as the
environment (:func:`poc_env.theory.search_theory.segment_pod`, evaluated at cell centres: a
planning approximation of the cell average).

Each UAV chooses among ``K`` heading changes (while no choice would sweep any POC, e.g. on the
way from the airfield, it flies towards ``greedy_bayes``'s cell,
:func:`poc_env.agents.policies.greedy.best_cell`); its utility is its marginal expected POS over a
``lookahead``-step straight flight, the POS of the swarm's choices minus the POS without its own
(a "wonderful life" utility, so the game is a potential game whose potential is the swarm's
expected POS). Log-linear learning: in each of ``rounds`` rounds one UAV drawn by the policy's
seeded generator re-chooses with probability proportional to
``exp((utility - best) / (tau * best))``: a choice ``tau`` (5 %) worse than the best is ``e``
times rarer.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.policies.base import BeliefPolicy, Reading
from poc_env.agents.policies.greedy import best_cell
from poc_env.sim.autopilot import steer_to
from poc_env.theory.search_theory import segment_pod


class PotentialGamePolicy(BeliefPolicy):
    """``potential_game``: log-linear learning over heading changes (module docstring)."""

    name = "potential_game"

    def __init__(self, choices: int = 7, lookahead: int = 3, rounds: int = 12, tau: float = 0.05):
        self.choices = choices
        self.lookahead = lookahead
        self.rounds = rounds
        self.tau = tau

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.rng = np.random.default_rng([seed, 11])
        self.centers = env.params.grid.centers
        self.turns = np.linspace(-1.0, 1.0, self.choices)
        self.choice = np.full(len(self.agents), self.choices // 2)

    def _pods(self, q: dict) -> np.ndarray:
        """(K, ny, nx) detection probability of each candidate straight flight."""
        p = self.params
        u = p.scenario.uav
        dt = p.dt
        heading = q["heading"] + self.turns * u.max_turn_rate_rad_s * dt
        length = q["speed"] * dt * self.lookahead
        a = np.broadcast_to(q["xy"], (self.choices, 2))
        b = a + length * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
        sensor = p.scenario.sensor
        return segment_pod(
            self.centers[None],
            a[:, None, None],
            b[:, None, None],
            sensor.sweep_width_m,
            sensor.law,
            p.cutoff_m,
            p.grid.cell_m,
            p.grid.origin_m,
        )

    def search(self, searching: list[Reading], readings: list[Reading]) -> dict[str, Any]:
        p = self.params
        u = p.scenario.uav
        actions = {}
        players = [r.k for r in searching]
        qs = {r.k: r.q for r in searching}
        pods = {r.k: self._pods(r.q) for r in searching}
        poc = searching[0].poc if searching else None  # the first searching UAV's belief
        for _ in range(self.rounds if players else 0):
            k = players[int(self.rng.integers(len(players)))]
            others = np.ones_like(poc)
            for j in players:
                if j != k:
                    others = others * (1.0 - pods[j][self.choice[j]])
            # marginal expected POS of each of k's choices given the others' (wonderful life)
            utility = np.sum(poc * others * pods[k], axis=(1, 2))
            # temperature relative to the best utility: a choice tau worse is e times rarer
            z = (utility - utility.max()) / (self.tau * max(float(utility.max()), 1e-300))
            prob = np.exp(z)
            self.choice[k] = int(self.rng.choice(self.choices, p=prob / prob.sum()))
        centers = self.centers.reshape(-1, 2)
        assert poc is not None or not players
        for k in players:
            q = qs[k]
            if not np.any(poc * pods[k][self.choice[k]] > 0):  # nothing in sight: go find it
                goal = centers[best_cell(p, poc, q, k)]  # type: ignore[arg-type]
                actions[self.agents[k]] = steer_to(p, q, goal, u.cruise_speed_mps).astype(
                    np.float32
                )
                continue
            # speed and altitude as the follower holds them; the heading change is the choice
            a = steer_to(p, q, q["xy"], u.search_speed_mps)
            a[1] = self.turns[self.choice[k]]
            actions[self.agents[k]] = a.astype(np.float32)
        return actions
