"""An upper bound on the POS of a search for a moving target (Brown's algorithm, certified).

The static bounds (:mod:`poc_env.theory.bound`) allocate a total effort over a prior that
stands still. A moving target's belief is a Bayesian filter (:mod:`poc_env.theory.motion`):
every step ``t`` the environment first *predicts* (a linear, mass-conserving map ``M`` on the
fine grid, the mass leaving the map absorbed outside it) and then *updates* by eq. 14. Seen
from one target, the filter is a Markov chain ``X_0, X_1, ...`` on the fine cells (the
predicted cell after step ``t``'s predict is ``X_t``), absorbed outside the map, and the
environment's POSC is the probability that some step detects it.

**The model.** Let ``c_t(f) >= 0`` be the coverage a search puts on fine cell ``f`` at step
``t`` (effort ``a_f c_t(f)``, m^2: sweep width x track length credited to the cell; ``a_f`` its
area). The bound assumes that a target whose path is ``X`` is detected with probability
``F(Y)``, ``Y = sum_t c_t(X_t)`` the coverage accumulated along its path and ``F`` the
environment's detection law as a function of coverage (:attr:`~poc_env.theory.detection.
DetectionLaw.pod`). For the ``exponential`` law this is exactly the environment: a step
detects a point with ``1 - exp(-W L_j / a_j)`` (its cell's coverage) and the exponents of
successive steps add. For the other laws it is the static bound's model of the best a given
coverage can do (eq. 10 for the inverse cube; ``min(C, 1)`` for the definite range), applied
along the path: a static target gets exactly the static bound's objective. The same caveats
as :mod:`poc_env.theory.bound` hold (sample points against area averages, alignment).

**The constraints** are those of :func:`poc_env.theory.bound.reach_bound`, per step: UAV ``i``
sweeps at most ``W v_max dt`` m^2 per step while it can sense (:func:`~poc_env.theory.bound.
sensing_time_s`), and at step ``t`` only fine cells whose nearest point lies within
``v_max (t + 1) dt + spill`` of its take-off field (it cannot be farther by the end of the step;
``spill`` the farthest a detected point lies from the track).

**The relaxation** (the most favourable law). For any ``kappa > 0`` let
``delta(kappa) = sup_C [F(C) - (1 - exp(-kappa C))]`` (0 for the exponential law at
``kappa = 1``; computed on a fine grid of ``C`` plus its Lipschitz margin,
:func:`law_slack`). Then pointwise ``F(Y) <= 1 - exp(-kappa Y) + delta(kappa)``, so for every
search

    POS <= E[F(Y)] <= 1 - E[exp(-sum_t kappa c_t(X_t))] + delta(kappa),

and the middle term is the POS of a search with the exponential law and ``kappa`` times the
effort. That problem (*Brown*, 1980, "Optimal search for a moving target in discrete time and
space", Operations Research 28(6)) minimises ``N(c) = E[exp(-sum_t c_t(X_t))]`` over efforts in
a polyhedron; ``N`` is convex in ``c`` (an expectation of exponentials of linear functions), so
for any ``c >= 0`` (feasible or not) and the optimum ``c*``

    N(c*) >= N(c) + grad N(c) . (c* - c) >= N(c) + min_{y feasible} grad N(c) . (y - c),

and ``1 - N(c) - min_y grad N(c) . (y - c)`` is a certified upper bound (a Frank-Wolfe duality
gap). The gradient is ``-alpha_t(f) exp(-c_t(f)) beta_t(f)`` with the forward (undetected,
predicted) mass ``alpha_t`` and the backward survival ``beta_t = M_{t+1}^T (exp(-c_{t+1})
beta_{t+1}) + (1 - M_{t+1}^T 1)`` (paths leaving the map are never detected); the linear
minimum puts each UAV's step effort on its best reachable cell. The bound reported is
``min(1, min_kappa [upper(kappa) + delta(kappa)])`` (:class:`MovingBound`).

**Brown's algorithm** only supplies a good ``c``: sweeps of coordinate ascent over the steps,
each step's effort water-filled (:func:`poc_env.theory.bound.physical_optimum`'s exponential
law, in closed form: :func:`water_fill`) on the weights ``alpha_t beta_t`` over the cells some
UAV reaches (a relaxation of the per-UAV reach: it does not matter, the certificate is valid at
any ``c``).

**The adjoint** (any velocity field). Step ``t``'s predict is ``M_t = S_t^{n_t}``, ``S_t`` one
sub-step of the filter's finite-volume scheme for the velocities of ``[t dt, (t + 1) dt]`` (the
episode's uniform velocity plus the gridded field at ``t dt``, as the environment's
:func:`~poc_env.theory.motion.predict`) and ``n_t`` its sub-steps. ``S_t`` is assembled as a
sparse matrix by :func:`poc_env.theory.motion.substep_matrix`, probed from the filter's own
kernel (one implementation of the scheme), so ``M_t^T = (S_t^T)^{n_t}`` is the exact adjoint
for a uniform drift, a gridded field and a time-varying one alike
(``tests/theory/test_moving_bound.py`` checks ``<M x, y> = <x, M^T y>`` and ``M x`` against
the filter); one matrix per distinct velocity slice (a uniform drift or a stationary field:
one for the episode), checked against the filter's predict at every step (a motion it does
not reproduce is a ValueError, never a silently wrong bound). For a uniform drift it agrees
to 1e-12 with the earlier adjoint, the scheme run at ``-v`` (tested).

**What the bound covers** (every model of :mod:`poc_env.theory.motion` whose belief the
filter moves): ``static`` (no predict: the reach-aware problem, step by step), ``diffusion``
(``v = 0``), ``drift`` with a uniform current, a random current, a gridded field (``.npy``,
CSV, CF NetCDF) stationary or time-varying, plus diffusion, and ``leeway`` (current plus the
class's leeway in the uniform wind: a uniform drift per episode, its crosswind side drawn at
reset; or in a gridded, time-varying wind file, for the episode's crosswind side), and
``particles`` (each step's transition matrix, :mod:`poc_env.theory.particles`). It bounds
the POS of the *belief's* model, the filter's Markov chain: the hidden target moves by the
continuous random walk (:func:`~poc_env.theory.motion.move_targets`), whose detections the
filter approximates (upwind numerical diffusion). Not covered: a batch of environments whose
uniform velocities differ takes its sub-steps from the batch's fastest
(:func:`~poc_env.theory.motion.predict_uniform`), a finer discretisation of the same motion
than the single episode's the bound uses.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from poc_env.config import Scenario
from poc_env.errors import ConfigError
from poc_env.theory import motion as motion_mod
from poc_env.theory.bound import cell_distances, env_limits
from poc_env.theory.detection import detection_law
from poc_env.theory.probability_map import Grid

#: ``op(t, x)``: step ``t``'s predict ``M_t x`` (or its adjoint ``M_t^T x``), a new array
Op = Callable[[int, np.ndarray], np.ndarray]

#: The coverage scales tried for laws other than the exponential (the bound takes the best).
KAPPAS = (1.5, 1.75, 2.0)


@dataclass(frozen=True)
class BrownResult:
    """Result of :func:`brown_optimum` (exponential law): ``pos = 1 - N(c)`` of the effort
    found (``coverage (T, F)``), ``upper`` the certified upper bound on the optimum."""

    pos: float
    upper: float
    coverage: np.ndarray

    @property
    def gap(self) -> float:
        return self.upper - self.pos


@dataclass(frozen=True)
class MovingBound:
    """Result of :func:`moving_bound`: ``upper`` is the bound to report (``min(1, best
    kappa's certificate + slack)``); ``pos`` the model POS of the effort found at that
    ``kappa`` (exponential law: a lower estimate of the model's optimum)."""

    upper: float
    pos: float
    kappa: float
    slack: float
    law: str


def law_slack(law: str, kappa: float, c_max: float = 40.0, n: int = 400_001) -> float:
    """``delta(kappa) = sup_{C >= 0} [F(C) - 1 + exp(-kappa C)]`` for the law ``F`` (module
    docstring): the maximum on a grid of ``n`` points over ``[0, c_max]`` plus the Lipschitz
    margin ``(F'(0) + kappa) h / 2`` (``F' <= F'(0)`` for the concave laws), and beyond
    ``c_max`` at most ``exp(-kappa c_max)``. Exactly 0 for the exponential law at kappa 1."""
    entry = detection_law(law)
    if entry.name == "exponential" and kappa == 1.0:
        return 0.0
    c = np.linspace(0.0, c_max, n)
    gap = entry.pod(c) - 1.0 + np.exp(-kappa * c)
    lip = float(entry.pod_slope(np.zeros(1))[0]) + kappa
    return max(float(gap.max()) + lip * (c[1] - c[0]) / 2.0, float(np.exp(-kappa * c_max)), 0.0)


def water_fill(w: np.ndarray, a: np.ndarray, effort: float) -> np.ndarray:
    """The exponential law's optimal coverage of the weights ``w`` (cell areas ``a``) for
    ``effort`` m^2: :func:`poc_env.theory.bound.physical_optimum` with ``law="exponential"``
    (``C_j = ln(w_j / (a_j lambda))^+``), with ``lambda`` in closed form instead of by root
    finding: over the densest ``k`` cells ``ln lambda = (sum a_j ln d_j - effort) / sum a_j``
    (``d = w / a``), for the ``k`` that leaves ``d_k >= lambda > d_{k+1}``."""
    d = w / a
    order = np.argsort(-d, kind="stable")
    ld = np.log(d[order])
    aa = a[order]
    sa = np.cumsum(aa)
    loglam = (np.cumsum(aa * ld) - effort) / sa
    nxt = np.append(ld[1:], -np.inf)
    k = int(np.argmax(loglam >= nxt))  # the first k whose lambda lies above the next density
    cov = np.zeros_like(d)
    cov[order[: k + 1]] = np.maximum(ld[: k + 1] - loglam[k], 0.0)
    return cov


def brown_optimum(
    prior: np.ndarray,
    area: np.ndarray | float,
    step: Op,
    adjoint: Op,
    budgets: np.ndarray,
    reach: np.ndarray,
    sweeps: int = 4,
) -> BrownResult:
    """Certified optimum of ``1 - E[exp(-sum_t c_t(X_t))]`` (module docstring).

    ``prior (F,)`` the cell masses at the start (total <= 1; the rest is never detected),
    ``area (F,)`` the cell areas; ``step(t, x)`` returns step ``t``'s predict ``M_t x`` and
    ``adjoint(t, y)`` ``M_t^T y`` (new arrays; :func:`predict_operators`); ``budgets (G, T)``
    the effort (m^2) each group of searchers may spend at step ``t``; ``reach (G, T, F)``
    bool, the cells group ``g`` may search at step ``t``. ``sweeps`` passes of Brown's
    coordinate ascent.
    """
    m = np.asarray(prior, dtype=float).ravel()
    a = np.broadcast_to(np.asarray(area, dtype=float), m.shape)
    budgets = np.asarray(budgets, dtype=float)
    g_n, t_n = budgets.shape
    if reach.shape != (g_n, t_n, m.size):
        raise ConfigError("reach", reach.shape, f"(groups, steps, cells) = {(g_n, t_n, m.size)}")
    union = np.asarray(np.asarray(reach, dtype=bool).any(axis=0))
    total = budgets.sum(axis=0)
    c = np.zeros((t_n, m.size))

    def backward() -> np.ndarray:
        # beta_{t-1} = M_t^T (exp(-c_t) beta_t) + (1 - M_t^T 1): the paths leaving survive
        beta = np.empty((t_n, m.size))
        beta[-1] = 1.0
        for t in range(t_n - 1, 0, -1):
            beta[t - 1] = 1.0 + adjoint(t, np.exp(-c[t]) * beta[t] - 1.0)
        return beta

    for _ in range(sweeps):
        beta = backward()
        alpha = m.copy()
        for t in range(t_n):
            alpha = step(t, alpha)
            c[t] = 0.0
            cells = union[t] & (alpha * beta[t] > 0)
            if total[t] > 0 and cells.any():
                w = alpha[cells] * beta[t][cells]
                c[t][cells] = water_fill(w, a[cells], total[t])
            alpha = alpha * np.exp(-c[t])
    # the certificate at c: N(c), its gradient, and the best feasible linear step
    beta = backward()
    alpha = m.copy()
    lin = 0.0  # max_y -grad N . y
    dot = 0.0  # -grad N . c
    pos = 0.0  # the mass detected: 1 - N(c) over the prior's mass
    for t in range(t_n):
        alpha = step(t, alpha)
        pos += float(alpha @ -np.expm1(-c[t]))
        grad = alpha * np.exp(-c[t]) * beta[t]  # -dN/dc_t
        dot += float(grad @ c[t])
        ratio = grad / a
        for g in range(g_n):
            if budgets[g, t] > 0 and reach[g, t].any():
                lin += budgets[g, t] * float(ratio[reach[g, t]].max())
        alpha = alpha * np.exp(-c[t])
    upper = min(float(m.sum()), pos + max(lin - dot, 0.0))
    return BrownResult(pos, max(upper, pos), c)


def fine_grid(grid: Grid, s: int) -> Grid:
    """The environment's fine grid (``s x s`` sub-cells per map cell)."""
    return Grid(grid.nx * s, grid.ny * s, grid.cell_m / s, grid.origin_m)


def predict_operators(
    motion: motion_mod.Motion,
    velocity,
    dt: float,
    h: float,
    s: int,
    shape: tuple[int, int],
    side: float | None = None,
) -> tuple[Op, Op]:
    """``(step, adjoint)`` of the filter of one episode (module docstring): ``step(t, x)`` is
    the predict of step ``t`` (over ``[t dt, (t + 1) dt]``) of the fine cell masses ``x (F,)``
    on the fine grid of ``shape``, ``adjoint(t, y)`` its transpose; ``velocity (2,)`` the
    episode's uniform velocity (m/s), the gridded field (if any) read from ``motion``. One
    sparse sub-step matrix (:func:`poc_env.theory.motion.substep_matrix`) per distinct slice
    of the cells' velocities, built when first asked for (a time-varying field keeps one per
    step: ``5 F`` values each); at each step's first use, ``M_t`` is checked against the
    filter's predict (ValueError if it differs). A static target: the identity. ``side``:
    the episode's crosswind side (``sim_state.leeway_side``), for a wind file's leeway;
    ``particles``: one matrix per step (its transition varies with time)."""
    vel = np.asarray(velocity, dtype=float).reshape(1, 2)
    sides = None if side is None else np.array([side], dtype=float)
    cache: dict[bytes, tuple[Any, int]] = {}  # by the cells' velocities
    steps: dict[int, tuple[Any, int]] = {}  # by step, each checked against the filter once

    def matrix(t: int) -> tuple[Any, int]:
        got = steps.get(t)
        if got is None:
            if motion.particles is not None:  # the transition varies with time
                key = repr(float(t * dt)).encode()
            else:
                u, v = motion_mod.cell_velocity(motion, vel, t * dt, s, sides)
                key = hashlib.sha1(
                    np.ascontiguousarray(u).tobytes() + b"|" + np.ascontiguousarray(v).tobytes()
                ).digest()
            if key not in cache:
                cache[key] = motion_mod.substep_matrix(
                    motion, vel[0], t * dt, dt, h, s, shape, side
                )
            got = cache[key]
            _check_against_filter(*got, motion, vel, t * dt, dt, h, s, shape, sides)
            steps[t] = got
        return got

    def step(t: int, x: np.ndarray) -> np.ndarray:
        y = np.array(x, dtype=float).ravel()
        if motion.moves:
            mat, n = matrix(t)
            for _ in range(n):
                y = mat @ y
        return y

    def adjoint(t: int, x: np.ndarray) -> np.ndarray:
        y = np.array(x, dtype=float).ravel()
        if motion.moves:
            mat, n = matrix(t)
            tr = mat.T
            for _ in range(n):
                y = tr @ y
        return y

    return step, adjoint


def _check_against_filter(mat, n, motion, vel, t, dt, h, s, shape, sides=None) -> None:
    """``S^n x`` against the filter's own predict (:func:`poc_env.theory.motion.predict`) on
    a fixed positive ``x``: a motion the matrix does not reproduce (a model whose predict is
    not the advection-diffusion scheme of :func:`~poc_env.theory.motion.substep_matrix`) is an
    error, never a silently wrong bound."""
    x = 1.0 + (np.arange(shape[0] * shape[1]) % 7) / 7.0
    y = x.copy()
    for _ in range(n):
        y = mat @ y
    ref = x.reshape(1, *shape).copy()
    motion_mod.predict(motion, ref, vel, t, dt, h, s, sides)
    err = float(np.abs(y - ref.ravel()).max())
    if not err <= 1e-10:
        raise ValueError(
            f"moving bound: the predict matrix of model {motion.model.name!r} at t = {t:g} s "
            f"differs from the filter by {err:.3g}: this motion is not covered"
        )


def moving_bound(
    scenario: Scenario,
    prior_fine: np.ndarray,
    velocity,
    s: int | None = None,
    sweeps: int = 4,
    kappas: tuple[float, ...] | None = None,
    side: float | None = None,
) -> MovingBound:
    """The moving-target bound of ``scenario`` for one episode (module docstring).

    ``prior_fine (NY, NX)`` the episode's prior on the fine grid (the environment's
    ``sim_state.prior_fine[k]`` or its belief at reset), ``velocity (2,)`` the episode's
    uniform velocity (m/s; ``sim_state.drift[k]``: the current, the random current, the
    leeway), to which the scenario's gridded field (``target.field_file``) is added as the
    environment does; ``s`` sub-cells per cell (default from the prior's shape); ``side``
    the episode's crosswind side (``sim_state.leeway_side[k]``) where a wind file gives the
    leeway (ignored otherwise).
    """
    sc = scenario
    grid = Grid.from_config(sc.map)
    p = np.asarray(prior_fine, dtype=float)
    if s is None:
        s = p.shape[0] // grid.ny
    if p.shape != (grid.ny * s, grid.nx * s):
        raise ConfigError("prior_fine", p.shape, f"the fine grid {(grid.ny * s, grid.nx * s)}")
    dt = sc.episode.dt_s
    steps = sc.horizon_steps
    motion = motion_mod.check(sc.target, (grid.ny, grid.nx), steps * dt, sc.map)
    fine = fine_grid(grid, s)
    h = fine.cell_m
    vel = np.asarray(velocity, dtype=float).reshape(2) if motion.moves else np.zeros(2)
    step, adjoint = predict_operators(motion, vel, dt, h, s, p.shape, side)

    lim = env_limits(sc)
    sense = round(lim.time_s / dt)
    pts, counts = np.unique(lim.takeoff_m, axis=0, return_counts=True)
    dist = cell_distances(fine, pts).reshape(len(pts), -1)
    t_end = (np.arange(steps) + 1.0) * dt
    reach = (dist[:, None, :] - lim.spill_m) <= lim.speed_mps * t_end[None, :, None]
    per_step = lim.rate_m2_s * dt * (np.arange(steps) < sense)
    budgets = counts[:, None] * per_step[None, :]
    entry = detection_law(lim.law)
    if kappas is None:
        kappas = (1.0,) if entry.name == "exponential" else KAPPAS
    best: MovingBound | None = None
    for kappa in kappas:
        res = brown_optimum(p.ravel(), h * h, step, adjoint, kappa * budgets, reach, sweeps)
        slack = law_slack(entry.name, kappa)
        up = min(1.0, res.upper + slack)
        if best is None or up < best.upper:
            best = MovingBound(up, res.pos, kappa, slack, entry.name)
    assert best is not None
    return best
