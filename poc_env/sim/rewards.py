"""Rewards: alpha x POS - beta x the eq. 25 time term - constraint penalties.

Per step and agent ``i`` of an env with ``n`` UAVs:

* POS term: ``alpha * POS_team`` (``credit: team``, every agent gets what the swarm found this
  step) or ``alpha * POS_i`` (``credit: individual``, what UAV i found first; §3.1.6);
* time term (eq. 25): ``beta * (1/n) * sum_i dt / (0.85 T)`` over flying UAVs for the team, or
  ``beta * dt / (0.85 T) / n`` for UAV i alone, so individual terms add up to the team's;
* penalties (own): ``violation_penalty`` for a step with any safety or communication
  violation (eq. 20-24), ``overtime_penalty`` for a step beyond 0.85 T (eq. 18),
  ``crash_penalty`` once when the UAV crashes.

Summed over an episode with team credit, the POS term is ``alpha * POSC`` (eq. 13). The terms,
in order, are the table :data:`poc_env.spec.REWARD_TERMS` (each is an info key
``reward_<term>``); a term added here and not there, or there and not here, raises.
"""

from __future__ import annotations

import numpy as np

import poc_env.spec as spec
from poc_env.config import RewardConfig
from poc_env.sim.core import Events

_TERMS = spec.names(spec.REWARD_TERMS)


def reward_terms(cfg: RewardConfig, events: Events) -> dict[str, np.ndarray]:
    """Each term of the reward, shaped (E, N), with the sign it enters the reward with."""
    n = events.pos_agent.shape[1]
    if cfg.credit == "team":  # each env's value for its n agents (np.repeat: no Python wrapper)
        pos = np.repeat(events.pos_team[:, None], n, axis=1)
        time = np.repeat(events.time_term.sum(axis=1, keepdims=True) / n, n, axis=1)
    else:
        pos = events.pos_agent
        time = events.time_term / n
    out = {
        "pos": cfg.alpha * pos,
        "time": -cfg.beta * time,
        "violation": -cfg.violation_penalty * events.violation,
        "overtime": -cfg.overtime_penalty * events.overtime,
        "crash": -cfg.crash_penalty * events.crashed_now,
    }
    if tuple(out) != _TERMS:
        raise RuntimeError(f"reward terms {tuple(out)} differ from poc_env.spec {_TERMS}")
    return out


def total_reward(terms: dict[str, np.ndarray]) -> np.ndarray:
    """Sum of :func:`reward_terms`, (E, N)."""
    return sum(np.asarray(t, dtype=float) for t in terms.values())  # type: ignore[return-value]
