"""The functional core of the environment, batched over ``n_envs`` x ``n_agents``.

``make_params(scenario)`` turns a scenario into the constants of the dynamics;
``initial(params, rngs)`` draws a fresh :class:`State` for each env from its own generator;
``step(params, state, actions, rngs)`` advances every env by one time step (in place, for
speed) and returns the step's :class:`Events`; :func:`terminal`, :func:`truncated` and
:func:`episode_over` say whose episode has ended. The PettingZoo env is the ``n_envs == 1`` case;
the SB3 vector env is this module with many envs. Nothing here imports gymnasium or matplotlib.

One step, for each flying UAV (eq. numbers are the paper's):

1. actions in [-1, 1]^3 scale to the increments (dv, d alpha, d beta) within the per-step
   limits ``max_accel * dt``, ``max_turn_rate * dt``, ``max_pitch_rate * dt``; in ``shield``
   mode the heading change is replaced by the closest safe one (:func:`constraints.shield_heading`);
2. eq. 19: alpha' = alpha + d alpha, beta' = clip(beta + d beta), the position moves by
   ``v dt (cos alpha' cos beta', sin alpha' cos beta', sin beta')`` with the *old* speed, then
   v' = clip(v + dv, v_min, v_max);
3. the sensor sweeps the horizontal segment flown (:func:`search_theory.sweep_segments`) and the
   belief is updated by eq. 14, UAV after UAV so that overlaps are credited once (§3.1.6); the
   step's POS is what was found (eq. 12), POSC its running sum (eq. 13);
4. the hidden target is detected with the probability the belief uses at its location: at reset
   each env draws ``u ~ U(0, 1)`` and the target is found at the first step at which the
   cumulative detection exponent at the target reaches ``-ln(1 - u)`` -- the same distribution
   as a Bernoulli draw per step, without a random draw per step;
5. constraints (eq. 20-24) are evaluated and flagged; the time model advances (eq. 17-18);
   agents land, crash or run out of endurance.

Speed: after the sweep, the bookkeeping of steps 3-5 and the topology update run as a few
compiled passes (:mod:`poc_env._kernels.swarm`: ``step``, ``auto_links``;
:mod:`poc_env._kernels.sensing`: ``target_pod``) over the same kernels the numpy-facing
functions of :mod:`constraints` and :mod:`comms` use, with the pairwise distances computed
once per step; no-fly zones and threat peaks stay in numpy (only when the map has them).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np

import poc_env._kernels.autopilot as _autopilot
import poc_env._kernels.sensing as _sensing
import poc_env._kernels.swarm as _swarm
import poc_env.limits as limits
from poc_env.config import Scenario
from poc_env.errors import ConfigError
from poc_env.sim import comms as comms_mod
from poc_env.sim import constraints as cons
from poc_env.theory import motion as motion_mod
from poc_env.theory.detection import detection_law
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import sweep_segments, window_size

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class Params:
    """Constants of one scenario's dynamics (derived once from the config)."""

    scenario: Scenario
    grid: Grid
    s: int  # sample points per cell side
    n_agents: int
    dt: float
    prior: np.ndarray  # (ny, nx) default prior
    takeoff: np.ndarray  # (n, 2)
    landing: np.ndarray  # (n, 2)
    bounds: tuple[float, float, float, float]  # operating area (eq. 20)
    zones: cons.NoFlyZones
    threat_centers: np.ndarray
    threat_lambdas: np.ndarray
    window: int  # side of the sensing window in fine cells
    cutoff_m: float
    horizon: int
    switcher: comms_mod.Table2Switcher | None = field(default=None, compare=False)
    #: how the target moves (:mod:`poc_env.theory.motion`); None: static
    motion: motion_mod.Motion | None = field(default=None, compare=False)

    @property
    def fine_shape(self) -> tuple[int, int]:
        return (self.grid.ny * self.s, self.grid.nx * self.s)

    @functools.cached_property
    def motion_constants(self) -> np.ndarray:
        """The UAV limits of the compiled eq. 19 kinematics (:data:`poc_env._kernels.sensing.
        MOTION_CONSTANTS`), packed once per Params."""
        u = self.scenario.uav
        return _sensing.motion_constants(
            dt_s=self.dt,
            max_accel_mps2=u.max_accel_mps2,
            max_turn_rate_rad_s=u.max_turn_rate_rad_s,
            max_pitch_rate_rad_s=u.max_pitch_rate_rad_s,
            max_pitch_rad=u.max_pitch_rad,
            min_speed_mps=u.min_speed_mps,
            max_speed_mps=u.max_speed_mps,
            max_altitude_m=u.max_altitude_m,
        )

    @functools.cached_property
    def autopilot_constants(self) -> np.ndarray:
        """The scalars of the compiled autopilot (:data:`poc_env._kernels.autopilot.
        CONSTANTS`), packed once per Params."""
        u = self.scenario.uav
        bx0, by0, bx1, by1 = self.bounds
        gx0, gy0, gx1, gy1 = self.grid.bounds
        return _autopilot.constants(
            dt_s=self.dt,
            bx0=bx0, by0=by0, bx1=bx1, by1=by1,
            gx0=gx0, gy0=gy0, gx1=gx1, gy1=gy1,
            max_altitude_m=u.max_altitude_m,
            min_speed_mps=u.min_speed_mps,
            max_speed_mps=u.max_speed_mps,
            max_pitch_rad=u.max_pitch_rad,
            max_turn_rate_rad_s=u.max_turn_rate_rad_s,
            max_accel_mps2=u.max_accel_mps2,
            max_pitch_rate_rad_s=u.max_pitch_rate_rad_s,
            cruise_altitude_m=u.cruise_altitude_m,
            cruise_speed_mps=u.cruise_speed_mps,
            search_speed_mps=u.search_speed_mps,
            usable_endurance_s=u.usable_endurance_s,
        )  # fmt: skip

    @functools.cached_property
    def step_constants(self) -> np.ndarray:
        """The scalar constants of the compiled step (:data:`poc_env._kernels.swarm.
        STEP_CONSTANTS`), packed once per Params."""
        sc = self.scenario
        u, ep = sc.uav, sc.episode
        x0, y0, x1, y1 = self.bounds
        return _swarm.step_constants(
            dt_s=self.dt,
            usable_s=u.usable_endurance_s,
            time_share=self.dt / u.usable_endurance_s,
            endurance_s=u.endurance_s,
            x0=x0,
            y0=y0,
            x1=x1,
            y1=y1,
            safety_distance_m=sc.constraints.safety_distance_m,
            range_m=sc.comms.range_m,
            min_neighbours=int(sc.comms.min_neighbours),
            landing_radius_m=ep.landing_radius_m,
            landing_max_altitude_m=ep.landing_max_altitude_m,
            landing_max_speed_mps=ep.landing_max_speed_mps,
            terminate=sc.constraints.violation == "terminate",
        )


def operating_area(scenario: Scenario) -> tuple[float, float, float, float]:
    """Eq. 20's operating area ``(x0, y0, x1, y1)``: the bounding box of the grid and the
    airfields grown by ``episode.boundary_margin_km``."""
    sc = scenario
    pts = np.vstack([np.asarray(sc.takeoff_m), np.asarray(sc.landing_m)])
    x0, y0, x1, y1 = Grid.from_config(sc.map).bounds
    m = sc.episode.boundary_margin_m
    return (
        float(min(x0, pts[:, 0].min()) - m),
        float(min(y0, pts[:, 1].min()) - m),
        float(max(x1, pts[:, 0].max()) + m),
        float(max(y1, pts[:, 1].max()) + m),
    )


def make_params(scenario: Scenario, prior: np.ndarray | None = None) -> Params:
    """Derive the constants of :func:`step` from a scenario (and an optional prior)."""
    sc = scenario
    grid = Grid.from_config(sc.map)
    s = sc.sensor.samples_per_cell
    u = sc.uav
    dt = sc.episode.dt_s
    cutoff = sc.sensor.cutoff_sweep_widths * sc.sensor.sweep_width_m
    win = window_size(grid, s, u.max_speed_mps * dt, cutoff)
    bounds = operating_area(sc)
    centers, lambdas = cons.threat_arrays(sc.map.threat_peaks)
    horizon = sc.horizon_steps
    switcher = None
    if sc.comms.topology == "table2":
        switcher = comms_mod.Table2Switcher(
            n_agents=sc.n_uavs, min_neighbours=sc.comms.min_neighbours
        )
    motion = motion_mod.check(sc.target, (grid.ny, grid.nx), horizon * dt, sc.map)
    if motion.moves and sc.comms.belief_sharing == "comms":
        raise ConfigError(
            "target.model", sc.target.model, "'static' with comms.belief_sharing: comms (the "
            "per-UAV beliefs of a moving target are not modelled yet)",
        )  # fmt: skip
    return Params(
        scenario=sc,
        grid=grid,
        s=s,
        n_agents=sc.n_uavs,
        dt=dt,
        prior=build_prior(sc.map) if prior is None else np.asarray(prior, dtype=float),
        takeoff=np.asarray(sc.takeoff_m, dtype=float),
        landing=np.asarray(sc.landing_m, dtype=float),
        bounds=bounds,
        zones=cons.NoFlyZones.from_config(sc.map),
        threat_centers=centers,
        threat_lambdas=lambdas,
        window=win,
        cutoff_m=cutoff,
        horizon=horizon,
        switcher=switcher,
        motion=motion if motion.moves else None,
    )


@dataclass
class State:
    """Mutable state of ``E`` envs with ``N`` UAVs each (arrays lead with (E, N))."""

    pos: np.ndarray  # (E, N, 3) x, y, z in metres
    speed: np.ndarray  # (E, N) m/s
    heading: np.ndarray  # (E, N) alpha, rad, from the x axis
    pitch: np.ndarray  # (E, N) beta, rad
    elapsed: np.ndarray  # (E, N) flight time in s (eq. 17)
    flying: np.ndarray  # (E, N) bool
    landed: np.ndarray  # (E, N) bool
    crashed: np.ndarray  # (E, N) bool
    left_home: np.ndarray  # (E, N) bool: has been farther than the landing radius
    belief: np.ndarray  # (E, NY, NX) POC on the fine grid (eq. 14)
    initial_mass: np.ndarray  # (E,)
    posc: np.ndarray  # (E,) cumulative POS (eq. 13)
    agent_pos: np.ndarray  # (E, N) POS credited to each UAV
    target: np.ndarray  # (E, 2) hidden target
    target_threshold: np.ndarray  # (E,) -ln(1 - u)
    target_exponent: np.ndarray  # (E,) cumulative detection exponent at the target
    detected: np.ndarray  # (E,) bool
    detect_step: np.ndarray  # (E,) int, -1 until detected
    step: np.ndarray  # (E,) int
    links: np.ndarray  # (E, N, N) bool, active communication topology
    topology: np.ndarray  # (E,) int topology code (Table 2) or -1 (auto)
    violations: np.ndarray  # (E, N) int, cumulative constraint violations
    # belief_sharing "comms" only (None otherwise): what each UAV knows
    prior_fine: np.ndarray | None = None  # (E, NY, NX) the episode's prior on the fine grid
    own_survival: np.ndarray | None = None  # (E, N, NY, NX) prod (1 - p) of UAV j's own sweeps
    known: np.ndarray | None = None  # (E, N, N, NY, NX) UAV i's latest copy of j's own_survival
    # moving targets only (None while the target is static, :mod:`poc_env.theory.motion`)
    mass_out: np.ndarray | None = None  # (E,) belief mass that drifted out of the map
    drift: np.ndarray | None = None  # (E, 2) the episode's uniform velocity (m/s)
    target_out: np.ndarray | None = None  # (E,) bool: the hidden target has left the map
    target_noise: np.ndarray | None = None  # (E, H, 2) the target's random-walk draws
    leeway_side: np.ndarray | None = None  # (E,) +1/-1 crosswind side (leeway wind files only)
    target_particle: np.ndarray | None = None  # (E,) int: the particle the target follows, or -1

    @property
    def n_envs(self) -> int:
        return self.pos.shape[0]

    def agent_beliefs(self) -> np.ndarray:
        """(E, N, NY, NX) each UAV's own belief: the global one in ``global`` mode, else the prior
        times the survival of every sweep it knows of (its own and its last copies of others')."""
        if self.known is None:
            return np.broadcast_to(
                self.belief[:, None], (*self.flying.shape, *self.belief.shape[1:])
            )
        assert self.prior_fine is not None
        return self.prior_fine[:, None] * np.prod(self.known, axis=2)


@dataclass
class Events:
    """What happened in one step (all arrays lead with (E,) or (E, N))."""

    pos_agent: np.ndarray  # (E, N) POS found by each UAV this step
    pos_team: np.ndarray  # (E,)
    time_term: np.ndarray  # (E, N) eq. 25 time share dt / (0.85 T) of each flying UAV
    overtime: np.ndarray  # (E, N) bool: flying beyond 0.85 T (eq. 18)
    out_of_bounds: np.ndarray  # (E, N) bool (eq. 20, boundary)
    no_fly: np.ndarray  # (E, N) bool (eq. 20, no-fly zones)
    collision: np.ndarray  # (E, N) bool (eq. 21)
    threat: np.ndarray  # (E, N) bool (eq. 23)
    comms_ok: np.ndarray  # (E, N) bool (eq. 24, two-neighbour rule)
    shielded: np.ndarray  # (E, N) bool
    landed_now: np.ndarray  # (E, N) bool
    crashed_now: np.ndarray  # (E, N) bool
    detected_now: np.ndarray  # (E,) bool
    connected: np.ndarray  # (E,) bool: swarm connected through relays

    @property
    def violation(self) -> np.ndarray:
        """(E, N) bool: any safety or communication constraint violated this step."""
        return self.out_of_bounds | self.no_fly | self.collision | self.threat | ~self.comms_ok

    @classmethod
    def from_parts(cls, parts: tuple[np.ndarray, ...]) -> Events:
        """The events of a step's ``parts`` ``(found, team, time_term, flags, no_fly, threat,
        shielded, detected_now, connected)``, ``flags`` the swarm kernel's ``(6, E, N)`` rows
        (:data:`poc_env._kernels.swarm.OVERTIME` ...); :meth:`as_parts` is the inverse."""
        found, team, time_term, flags, nofly, threat, shielded, detected_now, connected = parts
        return cls(
            pos_agent=found,
            pos_team=team,
            time_term=time_term,
            overtime=flags[_swarm.OVERTIME],
            out_of_bounds=flags[_swarm.OOB],
            no_fly=nofly,
            collision=flags[_swarm.COLLISION],
            threat=threat,
            comms_ok=flags[_swarm.COMMS_OK],
            shielded=shielded,
            landed_now=flags[_swarm.LANDED],
            crashed_now=flags[_swarm.CRASHED],
            detected_now=detected_now,
            connected=connected,
        )

    def as_parts(self) -> tuple[np.ndarray, ...]:
        """The ``parts`` of :meth:`from_parts`."""
        flags = np.empty((_swarm.N_FLAGS, *self.pos_agent.shape), dtype=bool)
        flags[_swarm.OVERTIME] = self.overtime
        flags[_swarm.OOB] = self.out_of_bounds
        flags[_swarm.COLLISION] = self.collision
        flags[_swarm.COMMS_OK] = self.comms_ok
        flags[_swarm.LANDED] = self.landed_now
        flags[_swarm.CRASHED] = self.crashed_now
        return (
            self.pos_agent, self.pos_team, self.time_term, flags, self.no_fly, self.threat,
            self.shielded, self.detected_now, np.asarray(self.connected, dtype=bool),
        )  # fmt: skip


def airspace_violations(params, moving, a2, b2, new) -> tuple[np.ndarray, np.ndarray]:
    """``(no_fly, threat)`` ``(E, N)`` of a step: the moving UAVs whose leg ``a2 -> b2``
    crosses a no-fly zone (eq. 20) and whose new position ``new`` is over a threat peak's
    threshold (eq. 23); numpy, and only when the map has zones or threats."""
    e, n = moving.shape
    if len(params.zones):
        nofly = moving & params.zones.segment_crosses(a2, b2)
    else:
        nofly = np.zeros((e, n), dtype=bool)
    if len(params.threat_lambdas):
        threat = moving & cons.threat_violation(
            new[..., :2], params.threat_centers, params.threat_lambdas,
            params.scenario.map.threat_threshold,
        )  # fmt: skip
    else:
        threat = np.zeros((e, n), dtype=bool)
    return nofly, threat


def target_cdf(prior_fine: np.ndarray) -> np.ndarray | None:
    """The cumulative distribution over the sub-cells of the fine prior that
    ``Generator.choice(size, p=flat / flat.sum())`` builds (``p.cumsum()``, then divided by its
    last value), or None when ``choice`` would refuse ``p`` (negative, NaN, not summing to 1):
    computed once per prior rather than once per draw."""
    flat = prior_fine.ravel()
    p = flat / flat.sum()
    cdf = p.cumsum()
    if not (np.isfinite(cdf[-1]) and abs(cdf[-1] - 1.0) <= 1e-8 and p.min() >= 0.0):
        return None
    cdf /= cdf[-1]
    return cdf


def detection_threshold(u):
    """The hidden target's detection threshold ``-ln(1 - u)`` of a uniform ``u`` in [0, 1):
    the target is found at the first step its cumulative exponent (eq. 14's ``-sum log(1 -
    p)``) reaches it, i.e. with probability ``1 - exp(-exponent)``. ``log1p`` keeps the
    small-``u`` end exact."""
    return -np.log1p(-u)


def _draw_target(
    prior_fine: np.ndarray, h: float, origin, rng: np.random.Generator, cdf: np.ndarray | None
):
    """A target position drawn from the fine prior: a sub-cell by mass, uniform inside it.

    The sub-cell is ``rng.choice(size, p=flat / flat.sum())``'s draw: one uniform placed in
    ``cdf`` (:func:`target_cdf`, the same draw from the same stream; a test pins it to
    ``choice``); ``cdf`` None falls back to ``choice`` itself (which raises on a bad prior)."""
    if cdf is None:
        flat = prior_fine.ravel()
        k = int(rng.choice(flat.size, p=flat / flat.sum()))
    else:
        k = int(cdf.searchsorted(rng.random(), side="right"))
    j, i = divmod(k, prior_fine.shape[1])
    du, dv = rng.random(2)
    return (origin[0] + (i + du) * h, origin[1] + (j + dv) * h)


def _draw_targets(
    cdfs: list, nx: int, h: float, origin, rngs: list, target: np.ndarray, threshold: np.ndarray
) -> None:
    """:func:`_draw_target` then the :func:`detection_threshold` of every env into
    ``target (E, 2)`` and ``threshold (E,)``, the four uniforms of each env drawn at once
    (``rng.random(4)``: the stream's next four, as ``random()``, ``random(2)``, ``random()``
    draw them) and the rest as arrays (the same operations on each element). ``cdfs``: each
    env's :func:`target_cdf`, all the same object when the envs share the prior."""
    u = np.stack([rng.random(4) for rng in rngs])
    if all(c is cdfs[0] for c in cdfs):
        k = cdfs[0].searchsorted(u[:, 0], side="right")
    else:
        k = np.array([c.searchsorted(v, side="right") for c, v in zip(cdfs, u[:, 0].tolist())])
    j, i = np.divmod(k, nx)
    target[:, 0] = origin[0] + (i + u[:, 1]) * h
    target[:, 1] = origin[1] + (j + u[:, 2]) * h
    threshold[:] = detection_threshold(u[:, 3])


def takeoff_heading(bounds, takeoff) -> np.ndarray:
    """Every UAV's heading at take-off (rad): towards the centre of the map ``bounds``
    ``(x0, y0, x1, y1)`` from its take-off point (``takeoff`` (n, 2))."""
    cx, cy = np.mean(np.reshape(bounds, (2, 2)), axis=0)
    t = np.asarray(takeoff, dtype=float).reshape(-1, 2)
    return np.arctan2(cy - t[:, 1], cx - t[:, 0])


def initial(
    params: Params,
    rngs: list[np.random.Generator],
    priors: np.ndarray | None = None,
) -> State:
    """A fresh state for ``len(rngs)`` envs: UAVs airborne over their airfields.

    Take-off is instantaneous: each UAV starts at its take-off field at cruise altitude and
    cruise speed, level, heading for the centre of the grid. ``priors`` (E, ny, nx) overrides
    the scenario's prior per env (randomised priors); each env's hidden target and detection
    threshold come from that env's generator, in that order.
    """
    e, n = len(rngs), params.n_agents
    u = params.scenario.uav
    s = params.s
    cells = params.prior.size
    comms = params.scenario.comms.belief_sharing == "comms"
    limits.check_memory(
        "n_envs", e, limits.env_bytes(cells, s, n, e, comms), f"{e} envs x {cells} cells"
    )
    priors_given = priors
    if priors is None:  # every env's the scenario's: one fine prior, copied
        one = np.repeat(np.repeat(np.asarray(params.prior, dtype=float), s, 0), s, 1) / (s * s)
        belief = np.broadcast_to(one, (e, *one.shape)).copy()
    else:
        belief = np.repeat(np.repeat(np.asarray(priors, dtype=float), s, 1), s, 2) / (s * s)
    pos = np.zeros((e, n, 3))
    pos[:, :, :2] = params.takeoff[None]
    pos[:, :, 2] = u.cruise_altitude_m
    heading = takeoff_heading(params.grid.bounds, params.takeoff)
    h = params.grid.cell_m / s
    target = np.zeros((e, 2))
    threshold = np.zeros(e)
    shared = target_cdf(belief[0]) if priors_given is None and e else None
    cdfs = [shared] * e if priors_given is None else [target_cdf(b) for b in belief]
    if e and all(c is not None for c in cdfs):  # each env's four uniforms at once
        _draw_targets(cdfs, belief.shape[2], h, params.grid.origin_m, rngs, target, threshold)
    else:  # a prior choice refuses: its error (or an env's draw through choice)
        for k, rng in enumerate(rngs):
            target[k] = _draw_target(belief[k], h, params.grid.origin_m, rng, cdfs[k])
            threshold[k] = detection_threshold(rng.random())
    links = np.zeros((e, n, n), dtype=bool)
    topology = np.full(e, -1, dtype=int)
    state = State(
        pos=pos,
        speed=np.full((e, n), u.cruise_speed_mps),
        heading=np.broadcast_to(heading, (e, n)).copy(),
        pitch=np.zeros((e, n)),
        elapsed=np.zeros((e, n)),
        flying=np.ones((e, n), dtype=bool),
        landed=np.zeros((e, n), dtype=bool),
        crashed=np.zeros((e, n), dtype=bool),
        left_home=np.zeros((e, n), dtype=bool),
        belief=belief,
        initial_mass=belief.sum(axis=(1, 2)),
        posc=np.zeros(e),
        agent_pos=np.zeros((e, n)),
        target=target,
        target_threshold=threshold,
        target_exponent=np.zeros(e),
        detected=np.zeros(e, dtype=bool),
        detect_step=np.full(e, -1, dtype=int),
        step=np.zeros(e, dtype=int),
        links=links,
        topology=topology,
        violations=np.zeros((e, n), dtype=int),
    )
    if params.scenario.comms.belief_sharing == "comms":
        fine = belief.shape[1:]
        state.prior_fine = belief.copy()
        state.own_survival = np.ones((e, n, *fine))
        state.known = np.ones((e, n, n, *fine))
    if params.motion is not None:
        _initial_motion(params, state, rngs)
    _update_topology(params, state, rngs)
    return state


def _initial_motion(params: Params, state: State, rngs) -> None:
    """A moving target's episode: each env's uniform velocity from its generator (after the
    target and threshold), and the target's random-walk noise from a stream of its own
    (``rng.spawn``: the env's stream is not advanced)."""
    motion = params.motion
    assert motion is not None
    e = len(rngs)
    state.mass_out = np.zeros(e)
    drawn = [motion.draw_episode(rng) for rng in rngs]
    state.drift = np.stack([v for v, _ in drawn]) if e else np.zeros((0, 2))
    if motion.wind_field is not None:  # a wind file: the leeway varies, its side is kept
        state.leeway_side = np.array([side for _, side in drawn], dtype=float)
    if motion.particles is not None:  # the target follows a particle of its fine cell
        from poc_env.theory.particles import pick_particle

        h = params.grid.cell_m / params.s
        origin = np.asarray(params.grid.origin_m, dtype=float)
        state.target_particle = np.array(
            [
                pick_particle(motion.particles, state.target[k] - origin, h, params.fine_shape, r)
                for k, r in enumerate(rngs)
            ],
            dtype=np.int64,
        )
    state.target_out = np.zeros(e, dtype=bool)
    noise = np.zeros((e, max(params.horizon, 1), 2))
    if motion.diffusion > 0:
        for k, rng in enumerate(rngs):
            noise[k] = rng.spawn(1)[0].standard_normal((noise.shape[1], 2))
    state.target_noise = noise


def predict(params: Params, state: State) -> None:
    """The predict step of the filter (moving targets): the motion model moves the fine
    belief over this step (mass leaving the map goes to ``state.mass_out``) and the hidden
    targets (:func:`poc_env.theory.motion.predict`, :func:`~poc_env.theory.motion.
    move_targets`). The belief stays a probability: at the scheme's stability limit a cell
    keeps none of its own mass and rounding can leave entries of -5e-324, set to 0 here
    (config-audit; the linear kernels also carry signed vectors for the moving bound)."""
    _predict_moves(params, state)
    np.maximum(state.belief, 0.0, out=state.belief)


def _predict_moves(params: Params, state: State) -> None:
    """:func:`predict`'s moves, before the belief's rounding below 0 is cleared."""
    motion = params.motion
    assert motion is not None and state.mass_out is not None and state.drift is not None
    assert state.target_out is not None and state.target_noise is not None
    h = params.grid.cell_m / params.s
    dt = params.dt
    side = state.leeway_side
    if not motion.gridded:  # one velocity per env: belief and targets in one compiled call
        motion_mod.predict_uniform(
            motion, state.belief, state.drift, state.mass_out, state.target, state.target_out,
            state.target_noise, state.step, dt, h, params.grid.origin_m, params.grid.cell_m,
            (params.grid.ny, params.grid.nx),
        )  # fmt: skip
        return
    fields = [f for f in (motion.field, motion.wind_field) if f is not None]
    varying = motion.particles is not None or any(len(f.frames) > 1 for f in fields)
    if not varying:  # one velocity per env for the whole batch: in place, no copies
        state.mass_out += motion_mod.predict(
            motion, state.belief, state.drift, 0.0, dt, h, params.s, side
        )
        idx = np.minimum(state.step, state.target_noise.shape[1] - 1)
        noise = state.target_noise[np.arange(len(idx)), idx]
        motion_mod.move_targets(
            motion, state.target, state.target_out, state.drift, noise, 0.0, dt,
            params.grid.origin_m, params.grid.cell_m, (params.grid.ny, params.grid.nx), side,
        )  # fmt: skip
        return
    for k in np.unique(state.step).tolist():  # a time-varying field: envs grouped by their time
        rows = state.step == k
        t = k * dt
        belief = state.belief[rows]
        state.mass_out[rows] += motion_mod.predict(
            motion, belief, state.drift[rows], t, dt, h, params.s,
            None if side is None else side[rows],
        )  # fmt: skip
        state.belief[rows] = belief
        target, out = state.target[rows], state.target_out[rows]
        idx = np.minimum(state.step[rows], state.target_noise.shape[1] - 1)
        noise = state.target_noise[rows][np.arange(len(idx)), idx]
        which = None if state.target_particle is None else state.target_particle[rows]
        motion_mod.move_targets(
            motion, target, out, state.drift[rows], noise, t, dt, params.grid.origin_m,
            params.grid.cell_m, (params.grid.ny, params.grid.nx),
            None if side is None else side[rows], which,
        )  # fmt: skip
        state.target[rows], state.target_out[rows] = target, out


def share_beliefs(params: Params, state: State, a: np.ndarray, b: np.ndarray) -> None:
    """``belief_sharing: comms``: each UAV keeps the survival of its own sweeps (eq. 14 on its own
    map) and, whenever the active topology connects it to another UAV, possibly through relays,
    copies that UAV's latest own survival. A UAV's belief is the prior times the product of what
    it knows (:meth:`State.agent_beliefs`): exact, no sweep counted twice, and equal to the
    global belief while the swarm stays connected. Memory: E x N x N fine maps.
    """
    e, n = state.flying.shape
    own = state.own_survival
    known = state.known
    assert own is not None and known is not None
    sensor = params.scenario.sensor
    sweep_segments(
        own.reshape(e * n, *own.shape[2:]),
        params.grid,
        params.s,
        a.reshape(e * n, 1, 2),
        b.reshape(e * n, 1, 2),
        sensor.sweep_width_m,
        sensor.law,
        params.cutoff_m,
    )
    reach = comms_mod.reachable(state.links) | np.eye(n, dtype=bool)[None]
    known[reach] = np.broadcast_to(own[:, None], known.shape)[reach]


def step_is_per_env(params: Params) -> bool:
    """Whether :func:`step` changes each env by what that env holds alone: it draws nothing from
    the env generators (no link failures, eq. 24's failure model in :func:`_update_topology`),
    keeps no state outside the batch (no topology switcher) and sub-steps no moving target by
    the batch's fastest current. Then stepping an env whose episode has ended changes nothing
    but its own state, which a batched autoreset replaces (``gymnasium.make_vec``)."""
    return (
        params.scenario.comms.link_failure_prob <= 0
        and params.switcher is None
        and params.motion is None
    )


def _update_topology(
    params: Params, state: State, rngs, dist: np.ndarray | None = None
) -> comms_mod.CommsTopology:
    """Eq. 24 adjacency (with the failure model) and the active topology (§3.2.5).

    ``dist`` optionally passes the pairwise distances of the UAVs' current positions.
    """
    cc = params.scenario.comms
    xy = state.pos[:, :, :2]
    if dist is None:
        dist = cons.pairwise_distances(xy)
    if cc.link_failure_prob <= 0 and params.switcher is None:
        # the common case, in one compiled call: the in-range graph, then the auto rule on it
        e, n = state.flying.shape
        links = np.empty((e, n, n), dtype=bool)
        n_comp = np.empty(e, dtype=np.int64)
        k_nearest = comms_mod.nearest_count(cc.min_neighbours, n)
        _swarm.auto_links(dist, float(cc.range_m), state.flying, k_nearest, links, n_comp)
        state.links = links
        return comms_mod.CommsTopology(links=links, connected=n_comp <= 1, n_components=n_comp)
    adj = comms_mod.in_range(xy, cc.range_m, state.flying, dist)
    if cc.link_failure_prob > 0:
        adj = np.stack(
            [comms_mod.link_failures(adj[k], cc.link_failure_prob, r) for k, r in enumerate(rngs)]
        )
    if params.switcher is not None:
        topo = params.switcher.switch(state.topology, adj, xy, state.flying)
        state.topology = np.asarray(topo.topology)
    else:
        topo = comms_mod.auto_topology(adj, xy, state.flying, cc.min_neighbours, dist)
    state.links = topo.links
    return topo


def scale_actions(params: Params, actions: np.ndarray):
    """Normalised actions (E, N, 3) in [-1, 1] -> increments (dv, d alpha, d beta)."""
    a = np.asarray(actions, dtype=float)
    out = np.empty((3, *a.shape[:-1]))
    _sensing.scale_actions(a, params.motion_constants, out)
    return out[0], out[1], out[2]


def kinematics(params: Params, state: State, actions, moving, turn=None):
    """Eq. 19 for the ``moving`` UAVs under normalised ``actions (E, N, 3)`` (``turn (E, N)``:
    heading increments replacing the actions', the shield's); updates heading, pitch and
    speed and returns the new position array (E, N, 3). One compiled pass
    (:func:`poc_env._kernels.sensing.kinematics`)."""
    new = np.empty_like(state.pos)
    alpha = np.empty_like(state.heading)
    beta = np.empty_like(state.pitch)
    speed = np.empty_like(state.speed)
    _sensing.kinematics(
        actions, turn, moving, state.pos, state.heading, state.pitch, state.speed,
        params.motion_constants, (new, alpha, beta, speed),
    )  # fmt: skip
    state.heading = alpha
    state.pitch = beta
    state.speed = speed
    return new


def sense(params: Params, state: State, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Sweep every UAV's segment a -> b (E, N, 2) over its env's belief; return POS (E, N).

    One call of the fused kernel :func:`search_theory.sweep_segments`: UAVs of an env are applied
    one after another, so a point two UAVs sweep in the same step is credited once, to the first.
    """
    sensor = params.scenario.sensor
    return sweep_segments(
        state.belief,
        params.grid,
        params.s,
        a,
        b,
        sensor.sweep_width_m,
        sensor.law,
        params.cutoff_m,
    )


def step(params: Params, state: State, actions: np.ndarray, rngs) -> Events:
    """Advance every env by ``dt`` (in place); see the module docstring for the order."""
    sc = params.scenario
    u = sc.uav
    moving = state.flying.copy()
    e, n = moving.shape
    actions = np.asarray(actions, dtype=float)
    shielded = np.zeros((e, n), dtype=bool)
    turn = None
    if sc.constraints.violation == "shield":
        dalpha = scale_actions(params, actions)[1]
        res = cons.shield_heading(
            state.pos[..., :2],
            state.heading,
            state.speed * np.cos(state.pitch),
            params.dt,
            dalpha,
            u.max_turn_rate_rad_s * params.dt,
            zones=params.zones if len(params.zones) else None,
            bounds=params.bounds,
            d_s=sc.constraints.safety_distance_m,
            active=moving,
            threat=(params.threat_centers, params.threat_lambdas, sc.map.threat_threshold)
            if len(params.threat_lambdas)
            else None,
        )
        shielded = res.shielded & moving
        turn = np.where(moving, res.turn, dalpha)
    if params.motion is not None:  # the filter's predict step; static targets skip it
        predict(params, state)
    a2 = state.pos[..., :2].copy()
    new = kinematics(params, state, actions, moving, turn)
    b2 = new[..., :2]
    found = sense(params, state, a2, b2)
    state.pos = new

    # hidden target (same law and cut-off as the belief, at its exact position)
    p_t = np.empty(moving.shape)
    ox, oy = params.grid.origin_m
    if _sensing.target_pod(
        state.target,
        a2,
        b2,
        moving,
        float(ox),
        float(oy),
        detection_law(sc.sensor.law).code,
        float(sc.sensor.sweep_width_m),
        float(params.cutoff_m),
        float(params.grid.cell_m),
        p_t,
    ):  # log1p(-0) = -0 adds nothing: numpy's log1p only when some UAV may detect
        if state.target_out is not None:  # a target that left the map is beyond the search
            p_t[state.target_out] = 0.0
        with np.errstate(divide="ignore"):
            state.target_exponent += -np.log1p(-p_t).sum(axis=1)

    nofly, threat = airspace_violations(params, moving, a2, b2, new)

    # POS bookkeeping (eq. 12-13), detection, time model (eq. 17-18), constraints (eq. 20-24),
    # landing, the step counter: one compiled pass
    team = np.empty(e)
    flags = np.empty((_swarm.N_FLAGS, e, n), dtype=bool)
    time_term = np.empty((e, n))
    detected_now = np.empty(e, dtype=bool)
    dist = np.empty((e, n, n))
    detect_step = state.detect_step.copy()
    _swarm.step(
        (
            state.agent_pos, state.posc, new, state.speed, state.target_exponent,
            state.target_threshold, state.step, state.detected, detect_step, state.elapsed,
            state.left_home, state.landed, state.crashed, state.flying, state.violations,
        ),
        (found, moving, nofly, threat),
        (team, detected_now, time_term, flags, dist),
        params.landing,
        params.step_constants,
    )  # fmt: skip
    state.detect_step = detect_step
    # the topology among the UAVs still flying after this step (§3.2.5)
    connected = np.asarray(_update_topology(params, state, rngs, dist).connected)
    if state.known is not None:
        share_beliefs(params, state, a2, b2)
    return Events.from_parts(
        (found, team, time_term, flags, nofly, threat, shielded, detected_now, connected)
    )


# --------------------------------------------------------------------------- episode end
# The rule of when a UAV's or an env's episode ends, written once (in the style of Gymnasium's
# ``FuncEnv.terminal``): functions of the state alone, used by every adapter.


def terminal(params: Params, state: State) -> np.ndarray:
    """(E, N) bool: the UAVs whose episode has ended for good (Gymnasium's ``terminated``).

    A UAV terminates when it

    * lands: after having been farther than ``episode.landing_radius_m`` from its landing field,
      it is back within that radius at or below ``episode.landing_max_altitude_m`` and
      ``episode.landing_max_speed_mps`` (an approach, not a fly-over);
    * crashes: altitude <= 0, flight time reaching the endurance T (eq. 17; the 0.85 T of eq. 18
      is a reserve whose overrun is only penalised), or, with ``constraints.violation:
      terminate``, a safety violation (eq. 20-23; the communication rule of eq. 24 never ends a
      flight);
    * or, with ``episode.detection_ends_episode``, its env's hidden target has been detected
      (then every UAV of that env terminates).

    :func:`step` records landings, crashes and detection in the state and they stay true until
    the next :func:`initial`, so a UAV that is terminal stays terminal.
    """
    done = state.landed | state.crashed
    if params.scenario.episode.detection_ends_episode:
        done = done | state.detected[:, None]
    return done


def horizon_reached(params: Params, state: State) -> np.ndarray:
    """(E,) bool: the env has run ``params.horizon`` steps (``episode.horizon_steps``, by default
    the endurance T / dt rounded up: eq. 17's T)."""
    return state.step >= params.horizon


def truncated(params: Params, state: State) -> np.ndarray:
    """(E, N) bool: the UAVs cut off by the time limit (Gymnasium's ``truncated``).

    Once an env reaches the horizon (:func:`horizon_reached`), each of its UAVs that is not
    :func:`terminal` is truncated. A UAV that lands or crashes in the horizon step is terminal,
    not truncated: the two are never both true.
    """
    return horizon_reached(params, state)[:, None] & ~terminal(params, state)


def episode_over(params: Params, state: State, finished: np.ndarray | None = None) -> np.ndarray:
    """(E,) bool: the env's episode is over: it reached the horizon, or every UAV is finished.

    ``finished`` (E, N) says which UAVs are finished; by default :func:`terminal`. An adapter
    that ends a UAV's episode for reasons of its own as well (the ``pilot`` VecEnv ends it when
    the autopilot takes the UAV home) passes ``terminal`` or'ed with those.
    """
    if finished is None:
        finished = terminal(params, state)
    return horizon_reached(params, state) | np.all(finished, axis=1)


def take_envs(state: State, envs: np.ndarray) -> State:
    """The sub-batch of ``state`` holding envs ``envs`` (copies of every array)."""
    return dataclasses.replace(
        state,
        **{
            f.name: getattr(state, f.name)[envs]
            for f in dataclasses.fields(state)
            if getattr(state, f.name) is not None
        },
    )


def scatter_envs(state: State, fresh: State, envs: np.ndarray) -> None:
    """Write the sub-batch ``fresh`` into rows ``envs`` of every array of ``state``."""
    for f in dataclasses.fields(state):
        dst = getattr(state, f.name)
        if dst is None:
            continue
        if not dst.flags.writeable:
            dst = dst.copy()
            setattr(state, f.name, dst)
        dst[envs] = getattr(fresh, f.name)
