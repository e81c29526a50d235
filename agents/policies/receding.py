"""``de_receding``: the paper's §5 / Fig. 14 loop -- every step, adaptive DE picks the next
moves of all UAVs under the motion, safety and communication constraints.

Each step the decision is the vector of normalised heading changes of the UAVs still searching
(eq. 19: within +-max_turn_rate x dt; speed is held at v_s, flight level). A candidate is scored
by the expected POS of flying its headings straight for ``lookahead`` steps over the current
belief (the POC raster of the observations; the UAVs' detections combined as
``1 - prod(1 - p_i)``, eq. 12-14, with the environment's detection law at cell centres), minus
an exterior penalty (eq. 26 style) for predicted separation below d_s (eq. 21), UAVs with fewer
than the required neighbours in communication range (eq. 24) and positions outside the
operating area (eq. 20). The optimiser is :func:`poc_env.agents.planning.optimizers.adaptive_de`
(eq. 27-32)
with a small budget (``popsize`` x ``maxiter`` per step), seeded from the episode's seed. Outside
the search area (on the way from the airfield) a UAV flies towards ``greedy_bayes``'s cell;
UAVs return to land with the follower's rule.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from poc_env.agents.planning.optimizers import adaptive_de
from poc_env.agents.policies.base import BeliefPolicy, Reading
from poc_env.agents.policies.greedy import best_cell
from poc_env.sim.autopilot import steer_to
from poc_env.theory.search_theory import segment_pod


class DERecedingPolicy(BeliefPolicy):
    """``de_receding`` (module docstring)."""

    name = "de_receding"

    def __init__(
        self, popsize: int = 16, maxiter: int = 12, lookahead: int = 3, penalty: float = 10.0
    ):
        self.popsize = popsize
        self.maxiter = maxiter
        self.lookahead = lookahead
        self.penalty = penalty

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.rng = np.random.default_rng([seed, 13])

    def _objective(self, poc, qs, ks):
        p = self.params
        sc = p.scenario
        u = sc.uav
        xy = np.array([qs[k]["xy"] for k in ks])  # (m, 2)
        heading = np.array([qs[k]["heading"] for k in ks])
        step = u.search_speed_mps * p.dt
        centers = p.grid.centers
        bx0, by0, bx1, by1 = p.bounds
        d_s = sc.constraints.safety_distance_m
        rc = sc.comms.range_m
        need = min(sc.comms.min_neighbours, len(self.agents) - 1)
        others = np.array([qs[k]["xy"] for k in qs if k not in ks], dtype=float).reshape(-1, 2)

        def f(pop: np.ndarray) -> np.ndarray:
            h = heading[None] + pop * u.max_turn_rate_rad_s * p.dt  # (P, m)
            d = np.stack([np.cos(h), np.sin(h)], axis=-1)
            nxt = xy[None] + step * d  # (P, m, 2)
            end = xy[None] + step * self.lookahead * d
            pod = segment_pod(
                centers[None, None],
                xy[None, :, None, None],
                end[:, :, None, None],
                sc.sensor.sweep_width_m,
                sc.sensor.law,
                p.cutoff_m,
                p.grid.cell_m,
                p.grid.origin_m,
            )  # (P, m, ny, nx)
            gain = np.sum(poc * (1.0 - np.prod(1.0 - pod, axis=1)), axis=(1, 2))
            pts = np.concatenate([nxt, np.broadcast_to(others, (len(pop), *others.shape))], 1)
            dist = np.hypot(*(pts[:, :, None] - pts[:, None]).transpose(3, 0, 1, 2))
            eye = np.eye(pts.shape[1], dtype=bool)[None]
            close = np.sum((dist < d_s) & ~eye, axis=(1, 2)) / 2
            lonely = np.sum(np.sum((dist <= rc) & ~eye, axis=2) < need, axis=1)
            outside = np.sum(
                (nxt[..., 0] < bx0)
                | (nxt[..., 0] > bx1)
                | (nxt[..., 1] < by0)
                | (nxt[..., 1] > by1),
                axis=1,
            )
            scale = max(float(poc.sum()), 1e-12)
            return -gain / scale + self.penalty * (close + 0.1 * lonely + outside)

        return f

    def search(self, searching: list[Reading], readings: list[Reading]) -> dict[str, Any]:
        p = self.params
        u = p.scenario.uav
        actions = {}
        qs = {r.k: r.q for r in readings}
        poc = readings[0].poc if readings else None  # the first live UAV's belief
        searching_k = [r.k for r in searching]
        if searching_k:
            f = self._objective(poc, qs, searching_k)
            bounds = [(-1.0, 1.0)] * len(searching_k)
            seed = int(self.rng.integers(2**31))
            res = adaptive_de(f, bounds, popsize=self.popsize, maxiter=self.maxiter, rng=seed)
            for j, k in enumerate(searching_k):
                q = qs[k]
                a = steer_to(p, q, q["xy"], u.search_speed_mps)
                a[1] = res.x[j]
                if not p.grid.contains(q["xy"]):  # transit from the airfield to the area
                    goal = p.grid.centers.reshape(-1, 2)[best_cell(p, poc, q, k)]  # type: ignore[arg-type]
                    a = steer_to(p, q, goal, u.cruise_speed_mps)
                actions[self.agents[k]] = a.astype(np.float32)
        return actions
