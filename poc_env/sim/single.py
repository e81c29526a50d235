"""The single environment's step: :meth:`Engine.step <poc_env.sim.engine.Engine.step>` with
its end in one compiled call.

The PettingZoo env steps one env of a few UAVs, where a dozen numpy calls on ``(1, N)`` arrays
cost more than the arithmetic they do. :class:`SingleStep` runs the same step as the engine
(the autopilot, :func:`poc_env.sim.core.step`, the observations) and then, in place of the
reward terms and total (:mod:`poc_env.sim.rewards`), the episode end (:func:`~poc_env.sim.core.
terminal`, :func:`~poc_env.sim.core.truncated`, :func:`~poc_env.sim.core.episode_over`) and
the info values (:func:`~poc_env.sim.engine.info_parts`), one call of the kernel
:func:`poc_env._kernels.rewards.end_step`, which also groups the per-agent info values by
Python type so that the adapter builds its per-agent info dicts from three ``tolist()`` calls.

Every value is the engine's, bit for bit: ``tests/sim/test_single.py`` runs both on random
actions over several tasks and options and compares every array and info.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

import poc_env._kernels.rewards as _rewards
from poc_env.sim import core as sim
from poc_env.sim.control import swarm_increments

#: The per-agent info keys of :attr:`Step.finfo`, :attr:`Step.binfo` and :attr:`Step.iinfo`.
FLOAT_INFOS = _rewards.FLOAT_INFOS
BOOL_INFOS = _rewards.BOOL_INFOS
INT_INFOS = _rewards.INT_INFOS
#: The reward terms in the order of ``end_step``'s ``terms`` rows (:data:`poc_env.spec.
#: REWARD_TERMS`; the engine's test pins them).
TERMS = ("pos", "time", "violation", "overtime", "crash")


@dataclass
class Step:
    """One step of :class:`SingleStep`: the engine's :class:`~poc_env.sim.engine.Transition`
    fields (``terms`` as a ``(5, E, N)`` array in :data:`TERMS` order) and the info values
    grouped by type: ``finfo (E, N, len(FLOAT_INFOS))``, ``binfo``, ``iinfo`` (the keys of
    :data:`poc_env._kernels.rewards.FLOAT_INFOS`, ``BOOL_INFOS``, ``INT_INFOS``)."""

    obs: Any
    reward: np.ndarray
    terms: np.ndarray
    events: sim.Events
    terminated: np.ndarray
    truncated: np.ndarray
    over: np.ndarray
    finfo: np.ndarray
    binfo: np.ndarray
    iinfo: np.ndarray

    def terms_dict(self) -> dict[str, np.ndarray]:
        """The reward terms as :func:`~poc_env.sim.rewards.reward_terms` returns them."""
        return {t: self.terms[k] for k, t in enumerate(TERMS)}


class SingleStep:
    """The step of ``engine`` (every env) with its end compiled; see the module docstring.

    Only for engines whose every env is stepped at once (the PettingZoo env) and whose UAVs
    share one belief (``comms.belief_sharing: global``): :meth:`supports`."""

    def __init__(self, engine: Any) -> None:
        self.engine = engine
        sc = engine.scenario
        r = sc.reward
        # the signed coefficients exactly as reward_terms forms them (-0 of an int is 0)
        self._coef_of = (r.alpha, -r.beta, -r.violation_penalty, -r.overtime_penalty)
        self._crash = -r.crash_penalty
        self._team = r.credit == "team"
        self._ends = bool(sc.episode.detection_ends_episode)
        self._coef: np.ndarray | None = None
        self._coef_dt: float | None = None

    @staticmethod
    def supports(engine: Any) -> bool:
        """Whether :meth:`step` can run ``engine``: global beliefs (per-UAV ones keep the
        engine's step)."""
        return engine.scenario.comms.belief_sharing != "comms"

    def _coefficients(self, dt: float) -> np.ndarray:
        if self._coef is None or self._coef_dt != dt:
            c = np.empty(len(_rewards.COEFFICIENTS))
            for k, v in enumerate((*self._coef_of, self._crash)):
                # reward_terms multiplies an array by this Python number: the same float64
                c[k] = np.float64(v)
            c[5] = dt
            self._coef, self._coef_dt = c, dt
        return self._coef

    def step(self, actions: np.ndarray) -> Step:
        """Advance every env by one step under ``actions (E, N, ACTION_DIMS[control])``:
        :meth:`Engine.step <poc_env.sim.engine.Engine.step>` with ``with_info=False``."""
        eng = self.engine
        p = eng.params
        st = eng.current
        inc = swarm_increments(p, eng.control, st, actions, eng.auto_return, eng.return_increments)
        ev = sim.step(p, st, inc, eng.rngs)
        connected = np.asarray(ev.connected, dtype=bool)
        e, n = st.flying.shape
        terms = np.empty((5, e, n))
        reward = np.empty((e, n))
        terminated = np.empty((e, n), dtype=bool)
        truncated = np.empty((e, n), dtype=bool)
        over = np.empty(e, dtype=bool)
        finfo = np.empty((e, n, len(_rewards.FLOAT_INFOS)))
        binfo = np.empty((e, n, len(_rewards.BOOL_INFOS)), dtype=bool)
        iinfo = np.empty((e, n, len(_rewards.INT_INFOS)), dtype=np.int64)
        _rewards.end_step(
            (ev.pos_agent, ev.pos_team, ev.time_term, ev.overtime, ev.out_of_bounds, ev.no_fly,
             ev.collision, ev.threat, ev.comms_ok, ev.crashed_now, ev.shielded, connected),
            (st.posc, st.elapsed, st.detected, st.detect_step, st.topology, st.violations,
             st.landed, st.crashed, st.step),
            self._coefficients(p.dt), p.horizon, self._ends, self._team,
            (terms, reward, terminated, truncated, over, finfo, binfo, iinfo),
        )  # fmt: skip
        obs = eng.observe_state(st)
        return Step(obs, reward, terms, ev, terminated, truncated, over, finfo, binfo, iinfo)
