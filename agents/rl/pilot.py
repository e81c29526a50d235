"""The ``pilot`` recipe: PPO chooses where each UAV heads, an autopilot flies eq. 19.

Learning eq. 19 increments end to end (the ``shared`` recipe) asks PPO to discover, from a
random walk, four things at once: flying 60 km to the area, holding altitude, spreading over
the probability mass, and coming back to land within 0.85 T with the speed low enough to land.
The ``pilot`` recipe keeps the decision that matters -- where to search next -- for the
policy and hands the rest to the same flight layer the planned baselines use
(:mod:`poc_env.sim.autopilot`), so PPO and ``de_plan`` are compared on equal terms:

* **Action** ``Box(-1, 1, (2,))`` per UAV: a direction ``(a_x, a_y)`` in the map frame. The
  autopilot (:func:`pilot_actions`) turns towards the point 10 km along it with eq. 19
  increments within their limits (:func:`poc_env.sim.autopilot.steer`), at the search speed over
  the grid and the cruise speed outside it, level at the cruise altitude. A zero direction
  keeps the heading. As soon as the remaining usable endurance only covers the flight home
  (:func:`poc_env.sim.autopilot.returning`, eq. 18) the autopilot flies home and lands
  (:func:`poc_env.sim.autopilot.homing`); the policy's action is then ignored.
* **Observation** ``Box((FEATURES,))`` per UAV, computed from the env's own observation
  (raster + vector) by :class:`PilotFeatures`, so a checkpoint acts on
  :class:`~poc_env.envs.parallel.UAVSearchParallelEnv` observations through
  :class:`poc_env.agents.rl.policy.PPOPolicy`. It is the environment's ``compass``
  observation: the state vector, the belief compass (the share of the remaining POC in each of
  8 map-frame sectors x 4 distance rings), other UAVs per sector, the mean remaining POC and
  the UAV's index as a one-hot, block by block in :data:`poc_env.spec.COMPASS` (rendered in
  ``docs/environment.md``).

  The index matters: with parameter sharing, UAVs taking off together from one airfield see
  identical observations, so a deterministic policy without it flies them as one stacked
  pack (every step a separation violation). Knowing its index lets each UAV break the
  symmetry (agent indication, Gupta et al. 2017; Terry et al. 2020).

* **RL episode of a UAV** ends when the autopilot takes it home (:class:`PilotVecEnv`), besides
  the core's rule (:func:`poc_env.sim.core.terminal`, :func:`~poc_env.sim.core.truncated`); the
  env resets once every UAV is home-bound or finished, so no rollout rows are spent on
  flights the policy cannot influence. Logged episode POSC is therefore the POSC at that
  moment (what the return legs still find is not included).
* **Reward**: the scenario's (alpha x team POS - penalties), plus an optional
  potential-based approach term (Ng et al., 1999) ``c (gamma Phi(s') - Phi(s))`` with
  ``Phi = -(distance from the UAV to the grid in km)``, which pays for closing the 60 km
  transit without changing which policies are optimal.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces

from poc_env.config import Scenario
from poc_env.envs.vector import SwarmVecEnv
from poc_env.sim import core as sim
from poc_env.sim import observations as obs_mod
from poc_env.sim.autopilot import returning
from poc_env.sim.control import heading_increments
from poc_env.sim.core import Params
from poc_env.sim.observations import (
    FEATURE_HIGH,
    FEATURE_LOW,
    CompassFeatures,
    decode_vector,
)

OBSERVATION_SPACE = spaces.Box(FEATURE_LOW, FEATURE_HIGH, dtype=np.float32)
ACTION_SPACE = spaces.Box(-1.0, 1.0, (2,), np.float32)


#: The pilot features are the environment's ``compass`` observation.
PilotFeatures = CompassFeatures


def pilot_actions(params: Params, vector: np.ndarray, action: np.ndarray, k) -> np.ndarray:
    """Eq. 19 actions ``(B, 3)`` flying the pilot ``action (B, 2)`` (module docstring) for UAVs
    ``k (B,)`` whose observation vectors are ``vector (B, VECTOR_SIZE)``: the environment's
    ``control="heading"`` level (:func:`poc_env.sim.control.heading_increments`)."""
    q = decode_vector(params, np.asarray(vector, dtype=np.float32))
    return heading_increments(params, q, action, k)


def grid_distance(params: Params, xy: np.ndarray) -> np.ndarray:
    """Distance (m) from positions ``(..., 2)`` to the grid rectangle (0 inside)."""
    x0, y0, x1, y1 = params.grid.bounds
    dx = np.maximum(np.maximum(x0 - xy[..., 0], xy[..., 0] - x1), 0.0)
    dy = np.maximum(np.maximum(y0 - xy[..., 1], xy[..., 1] - y1), 0.0)
    return np.hypot(dx, dy)


class PilotVecEnv(SwarmVecEnv):
    """:class:`~poc_env.envs.vector.SwarmVecEnv` with the pilot's features, actions and RL episodes.

    Parameters are those of :class:`~poc_env.envs.vector.SwarmVecEnv` (``obs_type`` is fixed to
    ``"dict"`` underneath) plus ``approach_shaping`` (the coefficient ``c`` of the approach
    potential, per km) and ``gamma`` (the discount the shaping is built for)."""

    def __init__(
        self,
        scenario: str | Scenario = "paper_6_2",
        n_envs: int = 8,
        seed: int | None = 0,
        random_priors: bool = False,
        overrides: Mapping[str, Any] | None = None,
        approach_shaping: float = 0.0,
        gamma: float = 0.99,
    ) -> None:
        super().__init__(
            scenario, n_envs, seed, "compass", random_priors, overrides, control="heading"
        )
        self.approach_shaping = float(approach_shaping)
        self.gamma = float(gamma)
        self._phi = np.zeros((self.n_envs, self.n_agents))

    def _potential(self, state: sim.State) -> np.ndarray:
        return -grid_distance(self.params, state.pos[..., :2]) / 1e3

    def _sim_actions(self, a: np.ndarray) -> np.ndarray:
        assert self.state is not None
        self._phi = self._potential(self.state)
        return super()._sim_actions(a)

    def _reward(self, reward: np.ndarray, state: sim.State) -> np.ndarray:
        r = super()._reward(reward, state)
        if self.approach_shaping:
            phi = np.where(state.flying, self._potential(state), 0.0)
            r = r + self.approach_shaping * (self.gamma * phi - self._phi)
        return r

    def _rl_done(self, state: sim.State) -> np.ndarray:
        """The flying UAVs the autopilot takes home (:func:`~poc_env.sim.autopilot.returning`):
        their RL episode ends; the env's ends once every UAV is home-bound or terminal."""
        vec = obs_mod.vectors(self.params, state)
        q = decode_vector(self.params, vec)
        k = np.broadcast_to(np.arange(self.n_agents), state.flying.shape)
        return state.flying & returning(self.params, q["xy"], q["usable"], k)
