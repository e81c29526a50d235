"""A tighter bound for one UAV: the rule-aware bound with the travel between searched blocks
charged (issue 24, "how loose is the bound?").

The rule-aware bound (:func:`poc_env.theory.bound.rule_bound`) charges each cell its own round
trip from the field but not the flying *between* the cells one UAV searches: it lets one
flight spread its effort over blobs, or a ring around its field, that no single flight of
0.85 T can visit. This module bounds what any single flight that keeps the plan rules can
collect, charging that travel, with a mixed-integer program solved by HiGHS
(:func:`scipy.optimize.milp`). It is printed beside the rule-aware bound, never instead of it
(the issue's target is normalised by the rule-aware bound).

**The relaxation.** The map's cells are grouped into square *blocks* of ``f x f`` cells; a
set ``V`` of them (the ``keep`` blocks of most reachable mass) is *valuable*. A valuable block
is *visited* when any of its cells receives effort; effort reaches a cell only from track
within ``rho`` of it (``rho`` the sensor's spill, :attr:`~poc_env.theory.bound.EnvLimits.
spill_m`), so a visited block's *region* ``R_j`` (the block grown by ``rho``) holds some of
the track. Take any flight from the take-off field ``s`` to the landing field ``l`` that keeps
the plan rules (back within the usable endurance ``T_u``, eq. 18's return rule at every
point, speeds up to ``v_max``), and let ``S`` be the valuable blocks it visits. Split its track
into the part inside ``U = union of R_j, j in S`` (length ``L_in``) and outside it
(``L_out``); lengths are at most ``v_max T_u`` in all: ``L_in + L_out <= v_max T_u``.

1. *Travel.* Walking along the flight, every maximal piece outside ``U`` joins two regions
   (or a field and a region) and is at least as long as the gap between them; a piece inside
   ``U`` moves between overlapping regions (gap 0). So the flight induces a walk from ``s``
   to ``l`` through every node of ``S`` in the graph whose edge lengths are these gaps, of
   length at most ``L_out``; shortcutting it on the graph's shortest-path metric ``d'``
   (Floyd-Warshall) gives a path ``s -> S (in the order of first visit) -> l`` of length
   ``<= L_out``. The program chooses that path (arcs ``x_ij`` in and out of each visited
   block, a single-commodity flow against subtours).
2. *Effort* (m^2, ``W`` per metre of track: the bounds' effort model). All cells together get
   at most ``W (L_in + L_out)``; the cells of valuable blocks at most ``W L_in`` (track outside
   ``U`` is farther than ``rho`` from every visited block, and unvisited valuable blocks get
   none).
3. *Value.* A cell's POS ``m_j POD(C_j)`` (``C_j`` its effort over its area) is concave, so it
   is below each of its tangents, taken at the coverages :data:`COVERAGES`, and below ``m_j``.
4. *Rules.* The rule-aware bound's own nested constraints, per cell (its transit ``tau_j``):
   the effort of the cells with ``tau >= t`` is at most ``W v_max (T_u - t)``.

Without 1 and 2 this is the rule-aware bound (up to the tangents, which only raise it), so the
program is never looser, and every rule-keeping flight maps to a feasible point of it with an
objective at least its POS (under the bounds' effort model, with the inverse-cube caveat of
:mod:`poc_env.theory.bound`). The program's optimum -- and the solver's *dual* bound
(``mip_dual_bound``), valid even if the time limit stops it early -- is an upper bound;
:func:`tour_bound` returns the least of it (per ``keep``) and the lone UAV's rule-aware bound.

What it does not charge: the shape of the effort *inside* the visited regions (a lawnmower
must join its lines; the allocation may want a ring or a graded density), the turns, and the
spill (effort may land up to ``rho`` = 20 km from the track at the full rate ``W`` per metre);
the regions of two blocks less than ``2 rho`` = 40 km apart overlap, so only travel across
wider gaps is charged. With ``spill_m=0`` it bounds the planners' own coverage
model (effort only in the cells the track crosses), where the regions are the blocks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import coo_matrix

from poc_env.config import Scenario
from poc_env.errors import ConfigError
from poc_env.theory.bound import cell_distances, env_limits, rule_bound
from poc_env.theory.detection import detection_law
from poc_env.theory.probability_map import Grid

#: block side (km) of the relaxation.
BLOCK_KM = 20.0
#: sizes of the valuable set tried (blocks of most mass); the least bound is kept.
KEEPS = (4, 8, 12)
#: coverages (eq. 10) at which each cell's POD is kept from above by its tangent.
COVERAGES = (0.0, 0.1, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0)
#: seconds HiGHS may spend per program (its dual bound stays valid when it stops early).
TIME_LIMIT_S = 20.0


@dataclass(frozen=True)
class TourBound:
    """Result of :func:`tour_bound`."""

    #: the least of the bounds below (report this).
    upper: float
    #: the lone UAV's rule-aware bound (:func:`poc_env.theory.bound.rule_bound`).
    rule: float
    #: the program's dual bound per ``keep`` (``{keep: bound}``).
    by_keep: dict[int, float]
    #: the program's primal value per ``keep`` (the relaxation's best visit set found).
    primal: dict[int, float]
    #: seconds spent in HiGHS.
    solve_s: float


def _rect_gap(a: np.ndarray, b: np.ndarray) -> float:
    """Distance between the rectangles ``a`` and ``b`` (x0, y0, x1, y1)."""
    dx = max(0.0, b[0] - a[2], a[0] - b[2])
    dy = max(0.0, b[1] - a[3], a[1] - b[3])
    return float(np.hypot(dx, dy))


def _point_gap(p: np.ndarray, r: np.ndarray) -> float:
    dx = max(0.0, r[0] - p[0], p[0] - r[2])
    dy = max(0.0, r[1] - p[1], p[1] - r[3])
    return float(np.hypot(dx, dy))


def _blocks(grid: Grid, prior: np.ndarray, f: int):
    """Block index of every cell, the blocks' rectangles and masses."""
    by = np.arange(grid.ny) // f
    bx = np.arange(grid.nx) // f
    nbx = int(bx.max()) + 1
    label = by[:, None] * nbx + bx[None, :]
    nb = int(label.max()) + 1
    ox, oy = grid.origin_m
    c = grid.cell_m
    rects = np.zeros((nb, 4))
    for b in range(nb):
        iy, ix = np.nonzero(label == b)
        rects[b] = [ox + ix.min() * c, oy + iy.min() * c, ox + (ix.max() + 1) * c,
                    oy + (iy.max() + 1) * c]  # fmt: skip
    mass = np.bincount(label.ravel(), weights=prior.ravel(), minlength=nb)
    return label, rects, mass


def _program(
    keep_idx: np.ndarray,
    label: np.ndarray,
    rects: np.ndarray,
    prior: np.ndarray,
    tau: np.ndarray,
    cell_area: float,
    s: np.ndarray,
    l_: np.ndarray,
    v: float,
    w: float,
    rho: float,
    budget: float,
    law: str,
    time_limit: float,
) -> tuple[float, float]:
    """The program of the module docstring for the valuable blocks ``keep_idx`` (``tau`` the
    rule-aware bound's transit per cell, s): (dual bound, primal value). Efforts are in units
    of the flight's whole effort ``W v_max T_u``, lengths in units of ``v_max T_u``."""
    entry = detection_law(law)
    k = len(keep_idx)
    emax = w * v * budget
    cells = np.flatnonzero((prior.ravel() > 0) & (tau.ravel() < budget))
    nc = len(cells)
    lab = label.ravel()[cells]
    m = prior.ravel()[cells]
    t_c = tau.ravel()[cells]
    in_v = {int(b): u for u, b in enumerate(keep_idx)}

    # nodes: 0 = take-off, 1..k = valuable blocks, k + 1 = landing
    n = k + 2
    gap = np.zeros((n, n))
    regs = rects[keep_idx]
    for a in range(k):
        gap[0, a + 1] = gap[a + 1, 0] = max(0.0, _point_gap(s, regs[a]) - rho)
        gap[k + 1, a + 1] = gap[a + 1, k + 1] = max(0.0, _point_gap(l_, regs[a]) - rho)
        for b in range(a + 1, k):
            gap[a + 1, b + 1] = gap[b + 1, a + 1] = max(0.0, _rect_gap(regs[a], regs[b]) - 2 * rho)
    gap[0, k + 1] = gap[k + 1, 0] = float(np.hypot(*(s - l_)))
    # shortest-path metric of the gap graph (Floyd-Warshall; zero gaps are edges: overlapping
    # regions are joined for free)
    d = gap.copy()
    for mid in range(n):
        d = np.minimum(d, d[:, mid : mid + 1] + d[mid : mid + 1, :])
    d = d / (v * budget)

    arcs = [(i, j) for i in range(k + 1) for j in range(1, n) if i != j]
    na = len(arcs)
    # variables: x (na, binary), g (na, flow), y (k, binary), e (nc), z (nc), L_in, L_out,
    # S (nc: the effort of the cells at least as far, in the order of ``rank``)
    ix_x, ix_g, ix_y = 0, na, 2 * na
    ix_e = ix_y + k
    ix_z = ix_e + nc
    ix_in = ix_z + nc
    ix_out = ix_in + 1
    ix_s = ix_out + 1
    nv = ix_s + nc
    r_i: list[int] = []
    c_i: list[int] = []
    vals: list[float] = []
    lo: list[float] = []
    hi: list[float] = []

    def row(coef: dict[int, float], lo_r: float, hi_r: float) -> None:
        r = len(lo)
        for col, val in coef.items():
            r_i.append(r)
            c_i.append(col)
            vals.append(val)
        lo.append(lo_r)
        hi.append(hi_r)

    out_of = [[a for a, (i, _) in enumerate(arcs) if i == u] for u in range(n)]
    into = [[a for a, (_, j) in enumerate(arcs) if j == u] for u in range(n)]
    row({ix_x + a: 1.0 for a in out_of[0]}, 1.0, 1.0)
    row({ix_x + a: 1.0 for a in into[k + 1]}, 1.0, 1.0)
    for u in range(1, k + 1):
        c = {ix_x + a: 1.0 for a in into[u]}
        c[ix_y + u - 1] = -1.0
        row(c, 0.0, 0.0)
        c = {ix_x + a: 1.0 for a in out_of[u]}
        c[ix_y + u - 1] = -1.0
        row(c, 0.0, 0.0)
        c = {ix_g + a: 1.0 for a in into[u]}  # flow: a visited block keeps one unit
        for a in out_of[u]:
            c[ix_g + a] = c.get(ix_g + a, 0.0) - 1.0
        c[ix_y + u - 1] = -1.0
        row(c, 0.0, 0.0)
    c = {ix_g + a: 1.0 for a in out_of[0]}
    for u in range(k):
        c[ix_y + u] = -1.0
    row(c, 0.0, 0.0)
    for a in range(na):
        row({ix_g + a: 1.0, ix_x + a: -float(k)}, -np.inf, 0.0)
    # travel outside the visited regions, and the flight's length
    c = {ix_x + a: d[i, j] for a, (i, j) in enumerate(arcs)}
    c[ix_out] = -1.0
    row(c, -np.inf, 0.0)
    row({ix_in: 1.0, ix_out: 1.0}, -np.inf, 1.0)
    # effort: all of it from the whole track, the valuable cells' from the inside part only,
    # and none in an unvisited valuable block
    row({**{ix_e + q: 1.0 for q in range(nc)}, ix_in: -1.0, ix_out: -1.0}, -np.inf, 0.0)
    c = {ix_e + q: 1.0 for q in range(nc) if int(lab[q]) in in_v}
    c[ix_in] = -1.0
    row(c, -np.inf, 0.0)
    for q in range(nc):
        blk = in_v.get(int(lab[q]))
        if blk is not None:
            row({ix_e + q: 1.0, ix_y + blk: -1.0}, -np.inf, 0.0)
    # value per cell: m POD(C), C = e emax / a, from above by tangents at COVERAGES
    cov = np.asarray(COVERAGES, dtype=float)
    pod = entry.pod(cov)
    slope = entry.pod_slope(cov)
    for q in range(nc):
        for c_k, p_k, s_k in zip(cov, pod, slope):
            lam = m[q] * s_k * emax / cell_area  # d(m POD)/de
            e_k = c_k * cell_area / emax
            row({ix_z + q: 1.0, ix_e + q: -lam}, -np.inf, m[q] * p_k - lam * e_k)
    # the rule-aware bound's nested constraints, per cell: S_r = e_(r) + S_(r+1), cells ranked
    # by transit, farthest first; S_r <= 1 - tau_(r) / T_u
    rank = np.argsort(-t_c, kind="stable")
    for r, q in enumerate(rank):
        c = {ix_s + r: 1.0, ix_e + q: -1.0}
        if r > 0:
            c[ix_s + r - 1] = -1.0
        row(c, 0.0, 0.0)
        row({ix_s + r: 1.0}, -np.inf, max(0.0, 1.0 - t_c[q] / budget))

    a_mat = coo_matrix((vals, (r_i, c_i)), shape=(len(lo), nv)).tocsr()
    obj = np.zeros(nv)
    obj[ix_z : ix_z + nc] = -1.0
    integ = np.zeros(nv)
    integ[ix_x : ix_x + na] = 1
    integ[ix_y : ix_y + k] = 1
    ub = np.full(nv, np.inf)
    ub[ix_x : ix_x + na] = 1.0
    ub[ix_y : ix_y + k] = 1.0
    ub[ix_g : ix_g + na] = float(k)
    ub[ix_z : ix_z + nc] = m
    res = milp(
        obj,
        constraints=LinearConstraint(a_mat, np.array(lo), np.array(hi)),
        integrality=integ,
        bounds=Bounds(np.zeros(nv), ub),
        options={"time_limit": float(time_limit), "disp": False},
    )
    dual = getattr(res, "mip_dual_bound", None)
    if dual is None or not np.isfinite(dual):
        raise RuntimeError(f"HiGHS gave no dual bound ({res.message})")
    primal = -float(res.fun) if res.x is not None else float("nan")
    return -float(dual), primal


def tour_bound(
    scenario: Scenario,
    prior,
    block_km: float = BLOCK_KM,
    keeps: tuple[int, ...] = KEEPS,
    time_limit_s: float = TIME_LIMIT_S,
    spill_m: float | None = None,
) -> TourBound:
    """The tour-charged bound of a one-UAV ``scenario`` on ``prior`` (module docstring).
    ``spill_m`` replaces the sensor's spill ``rho`` (None: the environment's); ``spill_m=0``
    bounds the planners' coverage model (effort only in the cells the track crosses, the
    *planned* POS), not the flown POS."""
    import time

    lim = env_limits(scenario)
    if len(lim.takeoff_m) != 1:
        raise ConfigError("fleet", len(lim.takeoff_m), "exactly one UAV (the bound is per flight)")
    grid = Grid.from_config(scenario.map)
    prior = np.asarray(prior, dtype=float)
    if prior.shape != grid.shape:
        raise ConfigError("prior", prior.shape, f"an array of the grid's shape {grid.shape}")
    if not (block_km > 0 and np.isfinite(block_km)):
        raise ConfigError("block_km", block_km, "a block side > 0 km")
    f = max(1, round(block_km * 1000.0 / grid.cell_m))
    label, rects, mass = _blocks(grid, prior, f)
    rule = float(rule_bound(scenario, prior, spill_m).upper)
    rho = lim.spill_m if spill_m is None else float(spill_m)
    v = lim.speed_mps
    v_home = min(float(scenario.uav.cruise_speed_mps), v)
    budget = float(scenario.uav.usable_endurance_s)
    # the rule-aware bound's transit per cell (s); no effort lands where it is >= T_u
    tau = (
        np.maximum(cell_distances(grid, lim.takeoff_m)[0] - rho, 0.0) / v
        + np.maximum(cell_distances(grid, lim.landing_m)[0] - rho, 0.0) / v_home
    )
    reach = tau < budget
    mass = np.bincount(label.ravel(), weights=(prior * reach).ravel(), minlength=len(mass))
    order = np.argsort(-mass, kind="stable")  # the valuable blocks: most reachable mass
    by_keep: dict[int, float] = {}
    primal: dict[int, float] = {}
    t0 = time.perf_counter()
    for keep in keeps:
        idx = order[: min(int(keep), int(np.sum(mass > 0)))]
        if not len(idx):
            continue
        by_keep[int(keep)], primal[int(keep)] = _program(
            idx, label, rects, prior, tau, float(grid.cell_area_m2), lim.takeoff_m[0],
            lim.landing_m[0], v, lim.sweep_width_m, rho, budget, lim.law, time_limit_s,
        )  # fmt: skip
    solve = time.perf_counter() - t0
    upper = min([rule, *by_keep.values()])
    return TourBound(upper, rule, by_keep, primal, solve)
