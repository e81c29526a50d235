"""The single environment's step: :meth:`Engine.step <poc_env.sim.engine.Engine.step>` with
its glue formed once, in three compiled calls.

The PettingZoo env steps one env of a few UAVs, where a dozen numpy calls on ``(1, N)`` arrays
cost more than the arithmetic they do, and numba's dispatch of a kernel (about 60 ns per array
argument, more inside tuples) more than some kernels' work. :class:`SingleStep` runs the
engine's step in the same order: the autopilot (:func:`~poc_env.sim.control.swarm_increments`),
the core step (:func:`poc_env.sim.core.step`'s kernels called with the arguments
:class:`_Constants` forms once per scenario: the eq. 19 kinematics, the sweep and the hidden
target's POD in one call, :func:`poc_env._kernels.sensing.fly_sense`; the shield keeps
that function), the hidden target's ``log1p(-p)`` in numpy when a UAV may detect it (numba's
``log1p`` may differ from numpy's in the last bit: numpy's uses SVML on AVX-512 CPUs), then
the target's exponent, the bookkeeping, the auto topology and, in place of the reward terms
and total (:mod:`poc_env.sim.rewards`), the episode end (:func:`~poc_env.sim.core.terminal`,
:func:`~poc_env.sim.core.truncated`, :func:`~poc_env.sim.core.episode_over`) and the info values
(:func:`~poc_env.sim.engine.info_parts`), one call of :func:`poc_env._kernels.swarm.step_end`
(:func:`~poc_env._kernels.swarm.end_step` alone after another topology), which also groups the
per-agent info values by Python type so that the adapter builds its per-agent info dicts from
three ``tolist()`` calls; then the ``dict`` and ``flat`` observations in one call
(:func:`poc_env._kernels.observations.rasters_vectors`, the kernels of
:func:`poc_env.sim.observations.observe`). The step's arrays that stay inside it are scratch
(:class:`_Scratch`, reused at the next step; :meth:`Step.copy` keeps them); its
:class:`~poc_env.sim.core.Events` are made only when asked for (:attr:`Step.events`).

Every value is the engine's, bit for bit: ``tests/sim/test_single.py`` runs both on random
actions over several tasks and options (and the core step on crafted states, the fused calls
against the kernels they join) and compares every array, info and the state. (The cache rule
of :mod:`poc_env._kernels` keeps sensing, the swarm's arithmetic and the observations in
separate modules, so in separate calls.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

import poc_env._kernels.observations as _obs_kernels
import poc_env._kernels.sensing as _sensing
import poc_env._kernels.swarm as _swarm
from poc_env.sim import comms as comms_mod
from poc_env.sim import core as sim
from poc_env.sim import observations as obs_mod
from poc_env.sim import rewards as rewards_mod
from poc_env.sim.control import swarm_increments
from poc_env.theory.detection import detection_law
from poc_env.theory.search_theory import _reach

#: The per-agent info keys of :attr:`Step.finfo`, :attr:`Step.binfo` and :attr:`Step.iinfo`.
FLOAT_INFOS = _swarm.FLOAT_INFOS
BOOL_INFOS = _swarm.BOOL_INFOS
INT_INFOS = _swarm.INT_INFOS
#: The reward terms in the order of ``end_step``'s ``terms`` rows (:data:`poc_env.spec.
#: REWARD_TERMS`; the engine's test pins them).
TERMS = ("pos", "time", "violation", "overtime", "crash")
_F8 = np.dtype(np.float64)  # (float64 arrays' own descriptor: an identity check)


def events_of(parts: tuple[np.ndarray, ...]) -> sim.Events:
    """The :class:`~poc_env.sim.core.Events` of a step's ``parts`` (``Events.from_parts``)."""
    return sim.Events.from_parts(parts)


def parts_of(ev: sim.Events) -> tuple[np.ndarray, ...]:
    """The inverse of :func:`events_of` (``Events.as_parts``)."""
    return ev.as_parts()


@dataclass(slots=True)
class Step:
    """One step of :class:`SingleStep`: the engine's :class:`~poc_env.sim.engine.Transition`
    fields (``terms`` as a ``(5, E, N)`` array in :data:`TERMS` order, the events as their
    ``parts``: :func:`events_of`) and the info values grouped by type: ``finfo (E, N,
    len(FLOAT_INFOS))``, ``binfo``, ``iinfo`` (the keys of :data:`FLOAT_INFOS`,
    :data:`BOOL_INFOS`, :data:`INT_INFOS`). Every array but the observations is scratch of
    :class:`SingleStep`, valid until its next step: :meth:`copy` keeps them."""

    obs: Any
    reward: np.ndarray
    terms: np.ndarray
    parts: tuple[np.ndarray, ...]
    terminated: np.ndarray
    truncated: np.ndarray
    over: np.ndarray
    finfo: np.ndarray
    binfo: np.ndarray
    iinfo: np.ndarray

    @property
    def events(self) -> sim.Events:
        """The step's :class:`~poc_env.sim.core.Events` (made when asked for)."""
        return events_of(self.parts)

    def terms_dict(self) -> dict[str, np.ndarray]:
        """The reward terms as :func:`~poc_env.sim.rewards.reward_terms` returns them."""
        return {t: self.terms[k] for k, t in enumerate(TERMS)}

    def copy(self) -> Step:
        """This step with copies of its scratch arrays (the observations are its own)."""
        return Step(
            self.obs, self.reward.copy(), self.terms.copy(), tuple(a.copy() for a in self.parts),
            self.terminated.copy(), self.truncated.copy(), self.over.copy(), self.finfo.copy(),
            self.binfo.copy(), self.iinfo.copy(),
        )  # fmt: skip


class _Scratch:
    """The arrays of :class:`SingleStep` for ``E`` envs of ``N`` UAVs that each step
    overwrites: the kernels' outputs that never leave a step (what a :class:`Step` holds
    but its observations; :meth:`Step.copy` keeps them) and their temporaries."""

    def __init__(self, e: int, n: int) -> None:
        self.shape = (e, n)
        sw = _swarm
        self.finfo = np.empty((e, n, len(sw.FLOAT_INFOS)))
        self.binfo = np.empty((e, n, len(sw.BOOL_INFOS)), dtype=bool)
        self.iinfo = np.empty((e, n, len(sw.INT_INFOS)), dtype=np.int64)
        self.dist = np.empty((e, n, n))
        self.p_t = np.empty((e, n))
        self.neg_p_t = np.empty((e, n))
        self.sin_cos = np.empty((2, e, n))  # the headings' sines and cosines (vectors)
        self.sin_h, self.cos_h = self.sin_cos
        self.team = np.empty(e)
        # step_end's arrays of one shape and dtype, as the rows of one array each
        self.rows_f = np.empty((sw.ROWS_F, e, n))
        #: (the no-fly, threat and shielded rows of a map without zones or threats: always
        #: False, never written)
        self.rows_b = np.zeros((sw.ROWS_B, e, n), dtype=bool)
        self.rows_e = np.empty((sw.ROWS_E, e), dtype=bool)
        # their views, formed once
        f, b, v = self.rows_f, self.rows_b, self.rows_e
        self.found, self.time_term = f[sw.FOUND], f[sw.TIME_TERM]
        self.log_miss = f[sw.LOG_MISS]  # log1p(-p_t): the hidden target's miss
        self.values = f[sw.VALUES :]  # the reward terms, then the reward
        self.flags = b[sw.FLAGS : sw.ENDS]
        self.ends = b[sw.ENDS : sw.NOFLY]  # terminated, truncated
        self.airspace = (b[sw.NOFLY], b[sw.THREAT], b[sw.SHIELDED])  # no-fly, threat, shielded
        self.detected_now = v[sw.DETECTED_NOW]
        self.connected = v[sw.CONNECTED]
        self.over = v[sw.OVER]
        self.terms, self.reward = self.values[:5], self.values[5]
        self.terminated, self.truncated = self.ends[0], self.ends[1]

    def __reduce__(self) -> tuple[type, tuple[int, int]]:
        """Pickled as its shape, made afresh: copies of the views above would no longer see
        the arrays the kernels write (a pickled :class:`Step` keeps its own copies)."""
        return (_Scratch, self.shape)


class _Constants:
    """What the kernels of one :class:`~poc_env.sim.core.Params` take besides the state: the
    arguments the numpy-facing wrappers (:func:`poc_env.sim.core.sense`,
    :func:`~poc_env.sim.core._update_topology`, :func:`poc_env.sim.observations.rasters` and
    :func:`~poc_env.sim.observations.vectors`) form at each call, formed once."""

    def __init__(self, p: sim.Params) -> None:
        sc = p.scenario
        sensor, cc, u = sc.sensor, sc.comms, sc.uav
        g = p.grid
        self.params = p
        #: the end-of-step kernel's coefficients (:meth:`SingleStep._coefficients`; set there)
        self.coef = np.empty(0)
        law = detection_law(sensor.law)
        ox, oy = g.origin_m
        #: :func:`poc_env._kernels.sensing.sense_step`'s constants: the origin, then sweep's
        self.sense = (
            float(ox), float(oy), law.code, float(sensor.sweep_width_m), float(p.cutoff_m),
            float(_reach(g, sensor.law, sensor.sweep_width_m, p.cutoff_m)), float(g.cell_m),
            g.cell_m / p.s,
        )  # fmt: skip
        #: no-fly zones or threats (:func:`~poc_env.sim.core.airspace_violations`)
        self.airspace = bool(len(p.zones) or len(p.threat_lambdas))
        #: the common topology: in-range graph and the auto rule, one kernel
        self.auto = cc.link_failure_prob <= 0 and p.switcher is None
        self.range_m = float(cc.range_m)
        self.k_nearest = comms_mod.nearest_count(cc.min_neighbours, p.n_agents)
        x0, y0, x1, y1 = g.bounds
        self.own_sum = g.nx > 1 and p.s < 8  # as observations.rasters
        self.raster = (float(x0), float(y0), float(x1), float(y1), float(g.cell_m))
        bx0, by0, bx1, by1 = p.bounds
        w, h = bx1 - bx0, by1 - by0
        n = p.n_agents
        #: ``vectors_of``'s scalars (one float64 array), then the clip bounds
        scalars = (
            float(bx0), float(by0), float(w), float(h), obs_mod._diagonal(w, h),
            float(u.max_altitude_m), float(u.min_speed_mps),
            float(u.max_speed_mps - u.min_speed_mps), float(u.max_pitch_rad),
            float(u.endurance_s), float(u.usable_endurance_s), float(p.horizon),
            float(cc.range_m), float(max(n - 1, 1)),
        )  # fmt: skip
        self.vector = (np.array(scalars, dtype=np.float64), obs_mod._LOW, obs_mod._HIGH)
        #: the same as the rows of one array (``rasters_vectors``' ``c_low_high``)
        self.vector_rows = np.stack(self.vector)


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
        self._k: _Constants | None = None
        self._scratch: _Scratch | None = None
        self._pass_through = engine.control == "increments" and not engine.return_increments
        self._shield = sc.constraints.violation == "shield"
        self._hazard = comms_mod._shaped(engine.hazard, engine.params.grid.shape, np.float32)
        self._coef_dt: float | None = None

    @staticmethod
    def supports(engine: Any) -> bool:
        """Whether :meth:`step` can run ``engine``: global beliefs (per-UAV ones keep the
        engine's step)."""
        return engine.scenario.comms.belief_sharing != "comms"

    def _coefficients(self, dt: float) -> np.ndarray:
        if self._coef is None or self._coef_dt != dt:
            c = np.empty(len(_swarm.COEFFICIENTS))
            for k, v in enumerate((*self._coef_of, self._crash)):
                # reward_terms multiplies an array by this Python number: the same float64
                c[k] = np.float64(v)
            c[5] = dt
            self._coef, self._coef_dt = c, dt
        return self._coef

    def _constants(self, p: sim.Params) -> _Constants:
        k = self._k
        if k is None or k.params is not p:  # random_airfields: new Params at each reset
            k = self._k = _Constants(p)
            k.coef = self._coefficients(p.dt)
        return k

    def step(self, actions: np.ndarray) -> Step:
        """Advance every env by one step under ``actions (E, N, ACTION_DIMS[control])``:
        :meth:`Engine.step <poc_env.sim.engine.Engine.step>` with ``with_info=False``."""
        spec_terms = rewards_mod._TERMS
        if spec_terms != TERMS:  # as reward_terms: the spec's terms are the kernel's
            raise RuntimeError(f"reward terms {TERMS} differ from poc_env.spec {spec_terms}")
        eng = self.engine
        p = eng.params
        st = eng.current
        k = self._constants(p)
        e, n = st.flying.shape
        if self._pass_through:  # swarm_increments' increments level: the actions as floats
            inc = actions
            if type(inc) is not np.ndarray or inc.dtype is not _F8 or inc.shape != (e, n, 3):
                inc = np.asarray(actions, dtype=float).reshape(e, n, 3)
        else:
            inc = swarm_increments(
                p, eng.control, st, actions, eng.auto_return, eng.return_increments
            ).astype(float, copy=False)
        s = self.scratch(e, n)
        if self._shield:
            parts = parts_of(sim.step(p, st, inc, eng.rngs))
            self._end_step(p, st, parts, s)
        else:
            parts = self._core_step(p, k, st, inc, s)
        obs = self._observe(p, k, st, s)
        return Step(
            obs, s.reward, s.terms, parts, s.terminated, s.truncated, s.over, s.finfo, s.binfo,
            s.iinfo,
        )  # fmt: skip

    def _end_step(self, p: sim.Params, st: sim.State, parts: tuple, s: _Scratch) -> None:
        """The reward terms and total, the episode end and the info values of the step whose
        events are ``parts`` (after its topology) into the scratch ``s``: :func:`poc_env.
        _kernels.swarm.end_step`."""
        _swarm.end_step(
            parts,
            (st.posc, st.elapsed, st.detected, st.detect_step, st.topology, st.violations,
             st.landed, st.crashed, st.step),
            self._coefficients(p.dt), p.horizon, self._ends, self._team,
            (s.terms, s.reward, s.terminated, s.truncated, s.over, s.finfo, s.binfo, s.iinfo),
        )  # fmt: skip

    def scratch(self, e: int, n: int) -> _Scratch:
        """The step's scratch arrays for ``E`` envs of ``N`` UAVs (made at the first step)."""
        s = self._scratch
        if s is None or s.shape != (e, n):
            s = self._scratch = _Scratch(e, n)
        return s

    def _core_step(
        self, p: sim.Params, k: _Constants, st: sim.State, actions: np.ndarray, s: _Scratch
    ) -> tuple[np.ndarray, ...]:
        """:func:`poc_env.sim.core.step` without the shield (which keeps that function), its
        kernels called with the arguments of :class:`_Constants`, in the same order, on the
        float64 increments ``actions (E, N, 3)``, then the end of the step (:meth:`_end_step`:
        with the bookkeeping and the auto topology in one call, ``swarm.step_end``); returns
        the events' parts (:func:`events_of`), arrays of the scratch ``s`` (:meth:`scratch`) but
        the no-fly and threat flags of a map with zones or threats."""
        moving = st.flying.copy()  # (a copy: half the time of np.copyto into scratch)
        e, n = moving.shape
        dist, p_t = s.dist, s.p_t
        if p.motion is not None:  # the filter's predict step; static targets skip it
            sim.predict(p, st)
        old = st.pos  # kinematics writes the new positions into a new array: old stays
        new = np.empty_like(old)
        alpha = np.empty((e, n))
        beta = np.empty((e, n))
        speed = np.empty((e, n))
        found = s.found
        # the kinematics, the sweep on the grid-relative legs and the hidden target's POD
        hit = _sensing.fly_sense(
            actions, moving, old, st.heading, st.pitch, st.speed, p.motion_constants, new, alpha,
            beta, speed, st.belief, st.target, *k.sense, found, p_t,
        )  # fmt: skip
        st.heading = alpha
        st.pitch = beta
        st.speed = speed
        log_miss = s.log_miss
        if hit:  # numpy's log1p(-p_t) (core.step's; numba's log1p may differ in the last bit)
            if st.target_out is not None:  # a target that left the map is beyond the search
                p_t[st.target_out] = 0.0
            np.negative(p_t, out=s.neg_p_t)
            if hit == 1:  # no POD of 1: no log1p(-1) warning to silence
                np.log1p(s.neg_p_t, out=log_miss)
            else:
                with np.errstate(divide="ignore"):
                    np.log1p(s.neg_p_t, out=log_miss)
            if not k.auto:  # (step_end adds it, in numpy's order)
                st.target_exponent += -np.add.reduce(log_miss, axis=1)
        st.pos = new
        nofly, threat, shielded = s.airspace  # no zones, no threats: all False (never written)
        if k.airspace:  # (the scenario's zones and threats: every step of this scratch has them)
            nofly[...], threat[...] = sim.airspace_violations(
                p, moving, old[..., :2], new[..., :2], new
            )
        team, flags, time_term, detected_now = s.team, s.flags, s.time_term, s.detected_now
        detect_step = st.detect_step.copy()
        if k.auto:  # the bookkeeping, the common topology and the end of step: one call
            links = np.empty((e, n, n), dtype=bool)  # the state's: a new array
            connected = s.connected
            _swarm.step_end(
                st.agent_pos, st.posc, new, st.speed, st.target_exponent, st.target_threshold,
                st.step, st.detected, detect_step, st.elapsed, st.left_home, st.landed,
                st.crashed, st.flying, st.violations, st.topology,
                moving, hit, team, dist, links, s.rows_f, s.rows_b, s.rows_e,
                p.landing, p.step_constants, k.range_m, k.k_nearest,
                k.coef, p.horizon, self._ends, self._team, s.finfo, s.binfo, s.iinfo,
            )  # fmt: skip
            st.detect_step = detect_step
            st.links = links
            return (found, team, time_term, flags, nofly, threat, shielded, detected_now, connected)
        _swarm.step(
            (
                st.agent_pos, st.posc, new, st.speed, st.target_exponent, st.target_threshold,
                st.step, st.detected, detect_step, st.elapsed, st.left_home, st.landed,
                st.crashed, st.flying, st.violations,
            ),
            (found, moving, nofly, threat),
            (team, detected_now, time_term, flags, dist),
            p.landing,
            p.step_constants,
        )  # fmt: skip
        st.detect_step = detect_step
        topo = sim._update_topology(p, st, self.engine.rngs, dist)
        connected = np.asarray(topo.connected, dtype=bool)
        parts = (found, team, time_term, flags, nofly, threat, shielded, detected_now, connected)
        self._end_step(p, st, parts, s)
        return parts

    def _observe(self, p: sim.Params, k: _Constants, st: sim.State, s: _Scratch) -> Any:
        """The engine's observations (:func:`poc_env.sim.observations.observe`); ``dict`` and
        ``flat`` through their kernels with the arguments of :class:`_Constants`."""
        eng = self.engine
        kind = eng.obs_type
        if kind not in ("dict", "flat"):
            return eng.observe_state(st)
        e, n = st.flying.shape
        g = p.grid
        size = obs_mod.RASTER_CHANNELS * g.ny * g.nx
        if kind == "dict":
            raster = np.empty((e, n, obs_mod.RASTER_CHANNELS, g.ny, g.nx), dtype=np.float32)
            vector = np.empty((e, n, obs_mod.VECTOR_SIZE), dtype=np.float32)
        else:
            flat = np.empty((e, n, size + obs_mod.VECTOR_SIZE), dtype=np.float32)
            raster = flat[:, :, :size].reshape(e, n, -1, g.ny, g.nx)
            vector = flat[:, :, size:]
        coarse = obs_mod._NO_COARSE if k.own_sum else g.coarsen(st.belief, p.s)
        np.sin(st.heading, out=s.sin_h)
        np.cos(st.heading, out=s.cos_h)
        _obs_kernels.rasters_vectors(
            st.belief, p.s, coarse, k.own_sum, eng.poc_scale, self._hazard, st.pos, st.flying,
            *k.raster, st.speed, s.sin_cos, st.pitch, st.elapsed, st.step, p.landing,
            k.vector_rows, raster, vector,
        )  # fmt: skip
        if kind == "dict":
            return {"raster": raster, "vector": vector}
        return flat
