"""A rule-aware bound that charges the sensor's spill by its own lateral law (issue 24,
i24-spill).

The rule-aware bound (:func:`poc_env.theory.bound.rule_bound`) credits a cell *full* effort
from track up to ``rho`` away (``rho`` the inverse-cube cut-off, 20 km on the shipped maps):
the transit to cell j is ``(d - rho)^+``. A UAV whose reach ends at the rim of a blob is
credited the blob's first 20 km as if it flew over them, while the environment's sensor
detects 7.6 % of a pass at 5 km and 0.9 % at 15 km (:func:`poc_env.theory.search_theory.
lateral_range`). This module bounds the same rule-keeping flights, charging that spill by the
kernel the environment senses with. It is reported beside the rule-aware bound and can only be
below it (:func:`spill_bound` returns the least of the two); the issue's figures stay quoted
over the rule-aware bound.

**The kernel.** The environment's inverse-cube step (:func:`poc_env.theory.search_theory.
segment_exponent`, compiled in :mod:`poc_env._kernels.sensing`) gives a sample point ``P`` the
exponent ``F = W^2 / (8 pi) * integral ds / R(s)^3`` over the step (``R`` the distance from
``P`` to the track point ``s``: the segment formula is this integral), if ``P`` is within the
cut-off ``rho`` of the step, and 0 otherwise; exponents of successive steps add and a point's
POD is ``1 - exp(-F)``; a cell's POD is the mean over its ``s x s`` sample points. A step is
at most ``l = v_max dt`` long, so track contributes to ``P`` only from ``|P - s| <= rho' =
rho + l`` (24 km on the shipped maps), at the rate ``k(R) = W^2 / (8 pi R^3)`` per metre.

**The combination.** For each cell j and fleet group g (the UAVs of one take-off/landing pair)
pick a *near radius*: ``rho`` (*full* mode, the rule-aware bound's own credit) or ``r_1`` (a
sweep width; *charged* mode). Split the exponent at a sample point ``P`` of cell j into
``F_near`` (from the track of each group g within its near radius of cell j) and ``F_far``
(the rest), and let ``phi_j`` be the largest ``F_far`` over the cell's sample points. Then

    POD_j <= 1 - exp(-phi_j) (1 - E(C_j)) <= E(C_j + phi_j)                    (1)

where ``E(C) = erf(sqrt(pi)/2 C)`` (eq. 10) bounds the mean of ``1 - exp(-F_near)`` for the
near effort ``C_j`` attributed to cell j, exactly as the rule-aware bound does (the same model,
with its inverse-cube caveat, :mod:`poc_env.theory.bound`). The first step is pointwise
(``exp(-F_far) >= exp(-phi_j)``); the second holds because the hazard ``E'(C) / (1 - E(C))``
of eq. 10 is at least 1 for every ``C >= 0`` (it is 1 at 0 and increases: ``1 - E`` is a
Gaussian tail), so ``1 - E(C + phi) <= exp(-phi) (1 - E(C))``; both are checked on a fine grid
in ``tests/theory/test_spill_bound.py``.

**The far budget.** Cut the distances at ``r_1 < r_2 < ... < r_K = rho'`` (:func:`band_edges`).
A metre of track at ``s`` raises ``phi_j`` by at most ``k(d(s, j))``, ``d(s, j)`` the distance
from ``s`` to cell j's nearest sample point, so over the cells whose ``d(s, j)`` lies in
``[r_k, r_{k+1})`` it adds at most

    sum_j a_j k(d(s, j)) <= h_k W       (a_j = c^2, the cell area)               (2)

to ``sum_j a_j phi_j``, with ``h_k`` the largest lattice sum over ``s`` (:func:`band_rates`:
0.21, 0.084, 0.066, 0.031, 0.014 for 5 km cells, W = 5 km, 2 x 2 sample points and edges 5,
7.5, 10, 15, 20, 24 km).

**The reach.** Track within ``R`` of cell j's sample points lies at points ``p`` with
``d_o(p) >= d_o(j) - R`` (triangle inequality; ``d_o(j)`` the distance from the take-off field
to the box of the cell's sample points, likewise ``d_l`` for the landing field), so its
rule-aware transit is at least ``tau_j(R) = (d_o(j) - R)^+ / v_max + (d_l(j) - R)^+ / v_c``,
and the track a UAV flies at points of transit ``>= t`` is at most ``v_max (T_u - t)^+`` (the
rule-aware bound's claim, :func:`poc_env.theory.bound.rule_bound`).

So every rule-keeping flight of the fleet gives, per group g, a near effort (``W`` per metre,
each metre attributed to one cell within its near radius) in the polymatroid of transit row
``tau_j(near radius)`` and rate ``W v_max`` per UAV, and for each band k a far exponent-area on
the cells charged for g in the polymatroid of transit row ``tau_j(r_{k+1})`` and rate
``h_k W v_max`` per UAV (:func:`relaxation_blocks`). Each holds on its own, so their product is
a relaxation, and the coverage ``Y_j = C_j + phi_j`` lies in the sum of these polymatroids:

    maximise sum_j m_j E(Y_j)                                                   (3)

over it is an upper bound on the POS of every rule-keeping flight (under the near model).
:func:`spill_bound` solves (3) as a linear program with HiGHS (:func:`scipy.optimize.linprog`):
nested constraints as prefix sums per polymatroid (as :mod:`poc_env.theory.tour_bound`), ``E``
from above by tangents (at :data:`COVERAGES`, then at the program's own coverages, a few
rounds of cutting planes; tangents of a concave function only raise it, so every round's
optimum is an upper bound and the least is kept). The groups are separate variables, so three
or more airfields need no merging.

*Which cells are charged* (any choice gives a valid bound): cell j for group g when its near
transit ``tau_j(r_1)`` is at least ``theta T_u`` -- with ``theta = 1`` exactly the cells that g
reaches only through the spill -- and, with ``alone``, no other group reaches it within
``r_1``. Charging is not free: (1) counts the far exponent on top of eq. 10, which already
holds the tails of the near lines, so charging cells that other groups cover (or a group's own
interior) raises the program; ``alone`` keeps the charge to the cells only the far group
reaches. With no cell charged the program is the rule-aware relaxation itself (up to the
tangents), so where every cell is reachable the least of the two is the rule-aware bound.

Only the inverse-cube law spills by a decaying kernel; for the other laws the result is the
rule-aware bound.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, vstack

from poc_env.config import Scenario
from poc_env.errors import ConfigError
from poc_env.theory.bound import cell_distances, env_limits, rule_bound
from poc_env.theory.detection import detection_law
from poc_env.theory.probability_map import Grid

#: coverages (eq. 10) at which each cell's POD is kept from above by its tangent.
COVERAGES = tuple(np.round(np.arange(0.0, 3.21, 0.2), 2))
#: most rounds of cutting planes (tangents at the program's coverages).
ROUNDS = 3
#: the rounds stop when the program's value exceeds the POS of its own coverages by this.
GAP = 1e-5
#: (near radius r_1 in sweep widths, theta) pairs tried; the least bound is kept.
CONFIGS = ((1.0, 1.0, True),)
#: HiGHS method of :func:`scipy.optimize.linprog`.
METHOD = "highs"
#: band edges beyond r_1, in multiples of r_1 (cut at rho').
BAND_FACTORS = (1.5, 2.0, 3.0, 4.0)


@dataclass(frozen=True)
class SpillBound:
    """Result of :func:`spill_bound`."""

    #: the least of the bounds below (report this).
    upper: float
    #: the rule-aware bound (:func:`poc_env.theory.bound.rule_bound`).
    rule: float
    #: the program's optimum per configuration ``(r_1 in m, theta, alone)``.
    by_config: dict[tuple[float, float, bool], float]
    #: seconds spent building and solving the programs.
    solve_s: float

    @property
    def how(self) -> str:
        """``"rule"`` when the rule-aware bound is the least, else the winning configuration."""
        if not self.by_config or self.upper >= self.rule:
            return "rule"
        r, th, alone = min(self.by_config, key=self.by_config.__getitem__)
        return f"r1={r / 1000:g}km,theta={th:g}" + (",alone" if alone else "")


def band_edges(near_m: float, rho_prime_m: float) -> np.ndarray:
    """The distance bands' edges ``r_1 < ... < r_K = rho'`` for the near radius ``near_m``."""
    edges = [near_m * f for f in (1.0, *BAND_FACTORS) if near_m * f < rho_prime_m]
    return np.array([*edges, rho_prime_m])


def band_rates(
    edges: np.ndarray, sweep_width_m: float, cell_m: float, samples_per_cell: int, grid: int = 16
) -> np.ndarray:
    """``h_k`` of eq. (2) of the module docstring for each band ``[r_k, r_{k+1})``, in units of
    ``W``: the most that one metre of track at any point ``s`` adds to ``sum_j a_j k(d(s, j))``
    over the cells ``j`` whose nearest *sample point* (the environment senses ``samples_per_cell
    ^2`` points per cell, at the centres of its sub-cells) lies at ``d(s, j)`` in the band
    (``k(R) = W^2 / (8 pi R^3)``, ``a_j = c^2``). The sum is periodic in ``s`` with the cell, so
    ``s`` runs over the centres of ``grid x grid`` sub-squares of one cell; a point ``s'`` of the
    cell is within ``e = c / (grid sqrt 2)`` of one of them, so ``d(s', j) >= d(s, j) - e``: each
    centre counts the cells of the band widened by ``e`` at ``k(max(r_k, d - e))``, an upper
    bound of the sum at every ``s'`` near it."""
    c = float(cell_m)
    w = float(sweep_width_m)
    span = int(np.ceil(edges[-1] / c)) + 2
    lo = np.arange(-span, span + 1) * c
    h = c / samples_per_cell
    pts = (lo[:, None] + (np.arange(samples_per_cell) + 0.5)[None, :] * h).ravel()
    sub = (np.arange(grid) + 0.5) * c / grid
    e = c / grid / np.sqrt(2.0)
    out = np.zeros(len(edges) - 1)
    for sx in sub:
        dx = np.abs(pts - sx).reshape(lo.size, samples_per_cell).min(axis=1)
        for sy in sub:
            dy = np.abs(pts - sy).reshape(lo.size, samples_per_cell).min(axis=1)
            d = np.hypot(dx[None, :], dy[:, None]).ravel()
            for k in range(len(edges) - 1):
                sel = (d >= edges[k] - e) & (d < edges[k + 1] + e)
                dd = np.maximum(d[sel] - e, edges[k])
                out[k] = max(out[k], float(np.sum(c * c * w * w / (8.0 * np.pi * dd**3))))
    return out / w


def sample_distances(grid: Grid, point, samples_per_cell: int) -> np.ndarray:
    """(ny * nx,) distance from ``point`` to the box of each cell's sample points (at most the
    distance to its nearest sample point)."""
    p = np.asarray(point, dtype=float).ravel()
    ox, oy = grid.origin_m
    c = grid.cell_m
    h = c / samples_per_cell
    x0 = ox + c * np.arange(grid.nx) + h / 2
    y0 = oy + c * np.arange(grid.ny) + h / 2
    x1, y1 = x0 + c - h, y0 + c - h
    dx = np.maximum(np.maximum(x0 - p[0], p[0] - x1), 0.0)
    dy = np.maximum(np.maximum(y0 - p[1], p[1] - y1), 0.0)
    return np.hypot(dy[:, None], dx[None, :]).ravel()


def _groups(scenario: Scenario):
    """Distinct (take-off, landing) pairs of the fleet and their UAV counts."""
    lim = env_limits(scenario)
    keys: list[tuple] = []
    count: list[int] = []
    for t, l_ in zip(lim.takeoff_m, lim.landing_m, strict=True):
        key = (tuple(t), tuple(l_))
        if key in keys:
            count[keys.index(key)] += 1
        else:
            keys.append(key)
            count.append(1)
    return [(np.array(k[0]), np.array(k[1])) for k in keys], count


def _program(
    prior: np.ndarray,
    blocks: list[tuple[np.ndarray, np.ndarray, float]],
    budget: float,
) -> float:
    """Solve (3) of the module docstring. ``blocks``: (cell indices, their transit (s), rate in
    coverage units per second) per polymatroid. Returns the optimum (an upper bound)."""
    m = prior.ravel()
    cells = np.flatnonzero(m > 0)
    col = -np.ones(m.size, dtype=np.int64)
    col[cells] = np.arange(cells.size)
    nc = cells.size
    # variables: u (nc), Y (nc), then one prefix sum per block cell
    ix_u, ix_y = 0, nc
    nv = 2 * nc
    rows_i: list[np.ndarray] = []
    cols_i: list[np.ndarray] = []
    vals: list[np.ndarray] = []
    ub_rows: list[np.ndarray] = []
    nrow = 0
    ub_var: list[np.ndarray] = [np.asarray(m[cells]), np.full(nc, np.inf)]
    # Y_j - sum(efforts of j) = 0
    eq_i: list[np.ndarray] = [np.arange(nc)]
    eq_c: list[np.ndarray] = [ix_y + np.arange(nc)]
    eq_v: list[np.ndarray] = [np.ones(nc)]
    for idx, tau, rate in blocks:
        keep = (tau < budget) & (m[idx] > 0)
        idx, tau = idx[keep], tau[keep]
        if not idx.size or rate <= 0:
            continue
        order = np.argsort(-tau, kind="stable")  # farthest first
        idx, tau = idx[order], tau[order]
        n = idx.size
        s = nv + np.arange(n)
        nv += n
        ub_var.append(rate * (budget - tau))
        # the effort of the r-th cell, S_r - S_(r-1) >= 0
        if n > 1:
            r = nrow + np.arange(n - 1)
            rows_i += [r, r]
            cols_i += [s[:-1], s[1:]]
            vals += [np.ones(n - 1), -np.ones(n - 1)]
            ub_rows.append(np.zeros(n - 1))
            nrow += n - 1
        agg = col[idx]
        eq_i += [agg, agg[1:]]
        eq_c += [s, s[:-1]]
        eq_v += [-np.ones(n), np.ones(n - 1)]
    entry = detection_law("inverse_cube")
    mj = m[cells]
    base = (
        coo_matrix((np.concatenate(vals), (np.concatenate(rows_i), np.concatenate(cols_i))),
                   shape=(nrow, nv)).tocsr() if vals else coo_matrix((0, nv)).tocsr(),
        np.concatenate(ub_rows) if ub_rows else np.zeros(0),
    )  # fmt: skip
    a_eq = coo_matrix(
        (np.concatenate(eq_v), (np.concatenate(eq_i), np.concatenate(eq_c))), shape=(nc, nv)
    ).tocsr()
    obj = np.zeros(nv)
    obj[ix_u : ix_u + nc] = -1.0
    bounds = np.column_stack([np.zeros(nv), np.concatenate(ub_var)])
    # tangents of m_j E(Y_j): u_j - m_j E'(c) Y_j <= m_j (E(c) - E'(c) c); a coarse set first,
    # then a tangent at each cell's coverage where the program's u_j exceeds m_j E(Y_j)
    # (cutting planes: every program's optimum is an upper bound, the last the least)
    tan_cell = [np.repeat(np.arange(nc), len(COVERAGES))]
    tan_cov = [np.tile(np.asarray(COVERAGES, dtype=float), nc)]
    best = np.inf
    for _ in range(ROUNDS):
        tc, cv = np.concatenate(tan_cell), np.concatenate(tan_cov)
        pod, slope = entry.pod(cv), entry.pod_slope(cv)
        r = np.arange(tc.size)
        tan = coo_matrix(
            (np.concatenate([np.ones(tc.size), -mj[tc] * slope]),
             (np.concatenate([r, r]), np.concatenate([ix_u + tc, ix_y + tc]))),
            shape=(tc.size, nv),
        ).tocsr()  # fmt: skip
        res = linprog(
            obj,
            A_ub=vstack([base[0], tan]).tocsr(),
            b_ub=np.concatenate([base[1], mj[tc] * (pod - slope * cv)]),
            A_eq=a_eq,
            b_eq=np.zeros(nc),
            bounds=bounds,
            method=METHOD,
        )
        if res.status != 0:
            raise RuntimeError(f"HiGHS did not solve the spill program ({res.message})")
        best = min(best, -float(res.fun))
        y = res.x[ix_y : ix_y + nc]
        over = res.x[ix_u : ix_u + nc] - mj * entry.pod(y)
        if float(over.sum()) <= GAP:
            break
        add = np.flatnonzero(over > GAP / nc)
        tan_cell.append(add)
        tan_cov.append(y[add])
    return best


@dataclass(frozen=True)
class Block:
    """One polymatroid of the relaxation (module docstring): group ``group``'s near effort
    (``band == 0``) or its far exponent-area from track at nearest-sample distance in
    ``[lo_m, hi_m)`` (``band >= 1``), on ``cells`` (flat indices) of transit ``transit_s``, at
    ``rate`` (coverage units per second: m^2/s over the cell area)."""

    group: int
    band: int
    lo_m: float
    hi_m: float
    cells: np.ndarray
    transit_s: np.ndarray
    rate: float


def lim_budget(scenario: Scenario) -> float:
    """The rule-aware budget: the usable endurance ``T_u`` (s)."""
    return float(scenario.uav.usable_endurance_s)


def relaxation_blocks(scenario: Scenario, config: tuple[float, float, bool]) -> list[Block]:
    """The polymatroids of the relaxation for one configuration ``(r_1 in sweep widths, theta,
    alone)`` (module docstring): per fleet group (distinct take-off/landing pair, in order of
    first appearance), its near block on every cell (full mode: transit ``tau_j(rho)`` to the
    cell; charged: ``tau_j(r_1)`` to its sample points) and one far block per band on its
    charged cells (transit ``tau_j(r_{k+1})``, rate ``h_k`` x the near rate). A cell is charged
    for group g when ``tau_j(r_1) >= theta T_u`` and, with ``alone``, no other group reaches it
    within ``r_1``."""
    lim = env_limits(scenario)
    grid = Grid.from_config(scenario.map)
    w = lim.sweep_width_m
    v = lim.speed_mps
    v_home = min(float(scenario.uav.cruise_speed_mps), v)
    budget = lim_budget(scenario)
    rho = lim.spill_m
    rho_p = rho + v * float(scenario.episode.dt_s)
    area = float(grid.cell_area_m2)
    fields, counts = _groups(scenario)
    spc = int(scenario.sensor.samples_per_cell)
    dist = [
        (cell_distances(grid, s)[0].ravel(), cell_distances(grid, l_)[0].ravel())
        for s, l_ in fields
    ]
    dist_sp = [
        (sample_distances(grid, s, spc), sample_distances(grid, l_, spc)) for s, l_ in fields
    ]

    def tau(g: int, r: float, sp: bool = True) -> np.ndarray:
        d_o, d_l = (dist_sp if sp else dist)[g]
        return np.maximum(d_o - r, 0.0) / v + np.maximum(d_l - r, 0.0) / v_home

    r1_w, th, alone = config
    r1 = float(r1_w) * w
    edges = band_edges(r1, rho_p)
    h = band_rates(edges, w, grid.cell_m, spc)
    near = np.array([tau(g, r1) < budget for g in range(len(counts))])
    all_cells = np.arange(grid.nx * grid.ny)
    blocks = []
    for g, n in enumerate(counts):
        rate = n * w * v / area
        t_full, t_near = tau(g, rho, sp=False), tau(g, r1)
        charged = t_near >= th * budget
        if alone:
            charged &= ~np.delete(near, g, axis=0).any(axis=0)
        blocks.append(Block(g, 0, 0.0, r1, all_cells, np.where(charged, t_near, t_full), rate))
        cc = np.flatnonzero(charged)
        for k, hk in enumerate(h):
            hi = float(edges[k + 1])
            blocks.append(Block(g, k + 1, float(edges[k]), hi, cc, tau(g, hi)[cc], hk * rate))
    return blocks


def spill_bound(
    scenario: Scenario,
    prior,
    configs: tuple[tuple[float, float, bool], ...] = CONFIGS,
) -> SpillBound:
    """The spill-charged rule-aware bound of ``scenario`` on ``prior`` (module docstring):
    the least of :func:`poc_env.theory.bound.rule_bound` and the program (3) for each
    ``(r_1 in sweep widths, theta, alone)`` of ``configs`` (:func:`relaxation_blocks`)."""
    lim = env_limits(scenario)
    grid = Grid.from_config(scenario.map)
    prior = np.asarray(prior, dtype=float)
    if prior.shape != grid.shape:
        raise ConfigError("prior", prior.shape, f"an array of the grid's shape {grid.shape}")
    rule = float(rule_bound(scenario, prior).upper)
    if lim.law != "inverse_cube" or rule <= 0.0:  # nothing to charge: no spill, or no mass
        return SpillBound(rule, rule, {}, 0.0)
    for cfg in configs:
        if not (len(cfg) == 3 and cfg[0] > 0 and np.isfinite(cfg[0]) and 0 < cfg[1] <= 1):
            raise ConfigError(
                "configs", cfg, "triples (near radius > 0 sweep widths, 0 < theta <= 1, alone)"
            )
    t0 = time.perf_counter()
    by_config: dict[tuple[float, float, bool], float] = {}
    for cfg in configs:
        blocks = relaxation_blocks(scenario, cfg)
        by_config[(float(cfg[0]) * lim.sweep_width_m, float(cfg[1]), bool(cfg[2]))] = _program(
            prior, [(b.cells, b.transit_s, b.rate) for b in blocks], lim_budget(scenario)
        )
    solve = time.perf_counter() - t0
    upper = min([rule, *by_config.values()])
    return SpillBound(upper, rule, by_config, solve)
