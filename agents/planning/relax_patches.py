"""Relaxation patches: each UAV its own patch of an allocation's graded coverage (i24-relax).

A start of the allocation planner (:func:`poc_env.agents.planning.allocation.
make_allocation_plan`, ``PlanOptions.relax_start``, off by default). The allocation start lays
the relaxation's coverage (:func:`poc_env.theory.bound.reach_optimum`) as one route chained over
the whole map and cut into pieces per UAV; the boxes start
(:mod:`~poc_env.agents.planning.coverage_boxes`) gives each UAV its own box and one spacing.
Here each UAV gets its own patch of an allocation's cells, and its coverage there is laid
graded as the allocation start lays it, so the footprint and the grading both come from the
allocation; for each effort scale ``eta`` of ``PlanOptions.etas`` (the pattern sweeps
``eta W v_s`` m^2/s):

1. **Fields** (:func:`dedicated_allocation`). The relaxation's polymatroid charges a set of
   cells only its nearest cell's transit, which one UAV's patch reaching farther cannot keep
   (laid in patches, the relaxation's own coverage overran the near field's time by a third on
   ``large_400``). So the coverage is allocated again with a UAV *dedicated* to a distance:
   searching at out-and-back time ``t`` it has ``B - t`` for its pattern, and field f's
   coverage needs ``sum_j a_j C_fj / (eta W v_s (B - t_fj)) <= n_f`` UAVs; most
   ``sum_j m_j POD(sum_f C_fj)`` (eq. 10), one linear program (POD piecewise linear).
2. **Patches** (:func:`patches`). A field's coverage is cut by bearing from the field into one
   sector per UAV of equal time (pattern time plus its mean transit, :func:`sectors`), so
   field-mates fly side by side; on coarse cells on sub-cells (:func:`subcells`). (Compact
   blocks by recursive bisection were tried too and scored less on every field of four
   validation priors; not kept.)
3. **Lines** (:func:`relax_routes`). In each patch the coverage, scaled by each of
   ``PlanOptions.relax_scales``, is laid with the allocation start's lines
   (:func:`~poc_env.agents.planning.coverage_lines.layered_tracks`, each of the ``levels`` and
   both line directions; lines flown row by row or layer by layer,
   :func:`by_layer`), chained nearest first from the take-off and cut at its far end until eq.
   17-18 hold (:func:`~poc_env.agents.planning.coverage_boxes.cut_lines`,
   :func:`~poc_env.agents.planning.refine.route_fits`); each UAV keeps the variant of most POS
   on its own patch by W x length per cell (eq. 10 per cell, the score that ranks starts).

**Measured** (docs/PLANNER.md, "Relaxation patches (i24-relax, 2026-11-28)"): on ``large_400``'s
validation priors the default effort keeps the start on 1 of 8 (+0.0018 of the rule-aware
bound on the mean), and in the boxes' place (the same refinement) it plans 0.021 less: its
loss is footprint and effort (a dedicated UAV gets a small sector at the rim of its reach;
graded nested layers cost connections), not grading. On ``paper_6_2`` the default effort keeps
it on 8 of 13 (+0.0045) at 2.1-2.6 times the CPU time; so it stays off by default.
"""

from __future__ import annotations

import numpy as np

from poc_env.agents.planning.coverage_boxes import cut_lines
from poc_env.agents.planning.coverage_lines import COVER_CAP, chain_regions, layered_tracks
from poc_env.agents.planning.flight_rules import Speeds
from poc_env.agents.planning.flight_rules import path_coverage as _path_coverage
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.refine import route_fits
from poc_env.theory.bound import field_key
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import pod_from_coverage

#: coverages between which :func:`dedicated_allocation` takes eq. 10's POD as linear (up to
#: the allocation start's ``COVER_CAP``).
BREAKS = (0.0, 0.1, 0.2, 0.35, 0.5, 0.7, 0.9, 1.15, 1.45, 1.8, 2.3)
#: (sub-)cells of coverage per UAV the patches are cut from, at least (:func:`subcells`) ...
CELLS_PER_UAV = 6
#: ... with cells split into at most this many sub-cells a side.
MAX_SUB = 4


def out_and_back(grid: Grid, takeoff: np.ndarray, landing: np.ndarray, v: Speeds) -> np.ndarray:
    """Each UAV's out-and-back time to each cell (``(n, ny, nx)`` s): out at ``v.out``, home
    at ``v.home`` (the allocation planner's transit, step 1 of its module docstring)."""
    from poc_env.theory.bound import cell_distances

    return cell_distances(grid, takeoff) / v.out + cell_distances(grid, landing) / v.home


def field_groups(takeoff: np.ndarray, landing: np.ndarray) -> list[list[int]]:
    """The UAVs of each airfield (same take-off and landing to the millimetre), fields in
    order of their coordinates."""
    n = len(takeoff)
    keys = [field_key(takeoff[k], landing[k]) for k in range(n)]
    fields = sorted(set(keys))
    return [[k for k in range(n) if keys[k] == f] for f in fields]


def dedicated_allocation(
    prior: np.ndarray,
    cell_area_m2: float,
    t_f: np.ndarray,
    sizes,
    rate: float,
    budget: float,
    law: str,
) -> np.ndarray:
    """Each field's coverage (``(F, *prior.shape)``), step 1 of the module docstring: most
    ``sum_j m_j POD(C_j)`` (eq. 10), ``C_j = sum_f C_fj``, when a UAV of field f searching at
    out-and-back time ``t_fj`` has ``budget - t_fj`` for its pattern at ``rate`` m^2/s, so a
    second of pattern there takes ``1 / (budget - t_fj)`` of a UAV, and field f has
    ``sizes[f]`` UAVs: ``sum_j a_j C_fj / (rate (budget - t_fj)) <= n_f``. (The relaxation's
    polymatroid, :func:`poc_env.theory.bound.reach_optimum`, charges a set of cells only its
    nearest cell's transit, which a UAV's patch reaching farther cannot keep.) Solved as one
    linear program (HiGHS) with POD piecewise linear between :data:`BREAKS` (concave, so the
    segments fill in order); a cell may be shared by fields. Coverage at most ``COVER_CAP``."""
    from scipy.optimize import linprog
    from scipy.sparse import coo_matrix

    nf = t_f.shape[0]
    out = np.zeros((nf, *prior.shape))
    m = prior.ravel()
    tf = t_f.reshape(nf, -1)
    cells = np.flatnonzero((m > 0) & (tf < budget).any(axis=0))
    nj = cells.size
    if not nj:
        return out
    brk = np.asarray([b for b in BREAKS if b < COVER_CAP] + [COVER_CAP])
    width = np.diff(brk)
    slope = np.diff(pod_from_coverage(brk, law)) / width  # (L,)
    nl = width.size
    fi, ji = np.nonzero(tf[:, cells] < budget)  # the fields reaching each cell
    ny_ = nj * nl
    nz = fi.size
    # rows 0..nj-1: sum_l y_jl - sum_f z_fj = 0; rows nj..nj+nf-1: each field's UAVs
    y_rows = np.repeat(np.arange(nj), nl)
    z_use = cell_area_m2 / (rate * (budget - tf[fi, cells[ji]]))
    a = coo_matrix(
        (
            np.concatenate([np.ones(ny_), -np.ones(nz), z_use]),
            (
                np.concatenate([y_rows, ji, nj + fi]),
                np.concatenate([np.arange(ny_), ny_ + np.arange(nz), ny_ + np.arange(nz)]),
            ),
        ),
        shape=(nj + nf, ny_ + nz),
    ).tocsr()
    cost = np.concatenate([-(m[cells][:, None] * slope[None, :]).ravel(), np.zeros(nz)])
    upper = np.concatenate([np.tile(width, nj), np.full(nz, COVER_CAP)])
    res = linprog(
        cost, A_ub=a[nj:], b_ub=np.asarray(sizes, dtype=float), A_eq=a[:nj], b_eq=np.zeros(nj),
        bounds=np.stack([np.zeros(ny_ + nz), upper], axis=1), method="highs",
    )  # fmt: skip
    if res.status != 0:
        return out
    z = np.maximum(res.x[ny_:], 0.0)
    flat = out.reshape(nf, -1)
    flat[fi, cells[ji]] = z
    return out


def sectors(tau: np.ndarray, load: np.ndarray, bearing: np.ndarray, n: int) -> np.ndarray:
    """Each cell's sector (0..n-1): cells in order of ``bearing`` cut into ``n`` runs of about
    equal time, a run's time its load-weighted mean transit plus its load (step 2)."""
    order = np.argsort(bearing, kind="stable")
    part = np.zeros(len(load), dtype=int)
    if n <= 1 or not len(load):
        return part
    t, ld = tau[order], load[order]

    def cut(target: float) -> np.ndarray:
        lab = np.zeros(len(ld), dtype=int)
        k, acc, acc_t = 0, 0.0, 0.0
        for i in range(len(ld)):
            if (
                acc > 0
                and k < n - 1
                and (acc_t + t[i] * ld[i]) / (acc + ld[i]) + acc + ld[i] > target
            ):
                k, acc, acc_t = k + 1, 0.0, 0.0
            lab[i] = k
            acc += ld[i]
            acc_t += t[i] * ld[i]
        return lab

    lo, hi = 0.0, float(t.max() + ld.sum())
    for _ in range(30):  # the least target that needs at most n runs
        mid = 0.5 * (lo + hi)
        lab = cut(mid)
        last = lab == lab.max()
        span = (
            float(np.average(t[last], weights=ld[last]) + ld[last].sum())
            if ld[last].sum() > 0
            else 0.0
        )
        if span > mid:
            lo = mid
        else:
            hi = mid
    part[order] = cut(hi)
    return part


def subcells(field_cov: np.ndarray, groups: list[list[int]]) -> int:
    """Sub-cells a side (1-:data:`MAX_SUB`) for the patches: the least ``s`` giving every field
    at least :data:`CELLS_PER_UAV` (sub-)cells of coverage per UAV (on coarse cells a field's
    few cells could not be cut into one sector per UAV)."""
    for s in range(1, MAX_SUB + 1):
        if all(
            np.count_nonzero(field_cov[f]) * s * s >= CELLS_PER_UAV * len(g)
            or not field_cov[f].any()
            for f, g in enumerate(groups)
        ):
            return s
    return MAX_SUB


def patches(
    field_cov: np.ndarray, grid: Grid, tau: np.ndarray, groups: list[list[int]],
    takeoff: np.ndarray, rate: float,
) -> np.ndarray:  # fmt: skip
    """Each UAV's coverage (``(n, ny, nx)``), step 2 of the module docstring: each field's
    coverage ``field_cov[f]`` cut into one sector per UAV (:func:`sectors`). ``tau``: each
    UAV's out-and-back time per cell, ``rate`` the pattern's sweep rate (m^2/s)."""
    n = len(takeoff)
    out = np.zeros((n, *grid.shape))
    for f, g in enumerate(groups):
        cells = np.flatnonzero(field_cov[f].ravel() > 0)
        if not cells.size:
            continue
        cov = field_cov[f].ravel()[cells]
        load = cov * grid.cell_area_m2 / rate
        ys, xs = np.divmod(cells, grid.nx)
        a = takeoff[g[0]]
        dx = grid.origin_m[0] + (xs + 0.5) * grid.cell_m - a[0]
        dy = grid.origin_m[1] + (ys + 0.5) * grid.cell_m - a[1]
        centre = np.arctan2(np.sum(load * dy), np.sum(load * dx))
        bearing = np.angle(np.exp(1j * (np.arctan2(dy, dx) - centre)))
        part = sectors(tau[g[0]].ravel()[cells], load, bearing, len(g))
        for i, k in enumerate(g):
            out[k].ravel()[cells[part == i]] = cov[part == i]
    return out


def by_layer(regions: list[list[tuple]], h: float, levels: int) -> list[list[tuple]]:
    """The lines of :func:`~poc_env.agents.planning.coverage_lines.layered_tracks` regions
    (``(y, x_start, x_end, row)``, lattice spacing ``h`` from the frame's origin, as it lays
    them) regrouped by layer: each layer's lines (every ``levels``-th lattice line, spacing
    ``levels h``) flown boustrophedon on their own, so consecutive lines differ by one layer
    spacing instead of by the layers' extents."""
    lines = [ln for reg in regions for ln in reg]
    if not lines:
        return []
    y0 = min(ln[0] for ln in lines)
    layers: dict[int, list[tuple]] = {}
    for ln in lines:
        i = round((ln[0] - y0) / h)
        layers.setdefault(i % levels, []).append(ln)
    out = []
    for key in sorted(layers):
        seq, flip = [], False
        for y in sorted({ln[0] for ln in layers[key]}):
            row = sorted((ln for ln in layers[key] if ln[0] == y), key=lambda t: t[1], reverse=flip)
            seq += [(y, b, a, r) if flip else (y, a, b, r) for (_, a, b, r) in row]
            flip = not flip
        out.append(seq)
    return out


def relax_routes(
    prior: np.ndarray,
    grid: Grid,
    w: float,
    law: str,
    v: Speeds,
    takeoff: np.ndarray,
    landing: np.ndarray,
    tau: np.ndarray,
    eta: float,
    budget: float,
    turn_rate: float,
    reserve: float,
    headings,
    levels: tuple[int, ...],
    scales: tuple[float, ...],
    options: PlanOptions | None = None,
) -> list[list[list[float]]]:
    """Waypoints per UAV of the relaxation patches (module docstring) of ``coverage`` (the
    relaxation's ``C_j`` at effort scale ``eta``): lawnmower lines, two waypoints a line, each
    route within the map and flown whole under eq. 17-18 (``budget`` the usable endurance,
    ``reserve`` eq. 18's reserve, ``headings`` the take-off headings)."""

    n = len(takeoff)
    groups = field_groups(takeoff, landing)
    rate = eta * w * v.line
    t_f = np.stack([tau[g[0]] for g in groups])
    field_cov = dedicated_allocation(
        prior, grid.cell_area_m2, t_f, [len(g) for g in groups], rate, budget, law
    )
    sub = subcells(field_cov, groups)
    if sub > 1:  # coarse cells: patches cut on sub-cells (coverage and transit repeated)
        field_cov = np.repeat(np.repeat(field_cov, sub, axis=1), sub, axis=2)
        tau = np.repeat(np.repeat(tau, sub, axis=1), sub, axis=2)
        prior = grid.refine(prior, sub)
        grid = Grid(grid.nx * sub, grid.ny * sub, grid.cell_m / sub, grid.origin_m)
    own_cov = patches(field_cov, grid, tau, groups, takeoff, rate)
    mirrored = Grid(grid.ny, grid.nx, grid.cell_m, (grid.origin_m[1], grid.origin_m[0]))
    routes: list[list[list[float]]] = [[] for _ in range(n)]
    for k in range(n):
        mask = own_cov[k] > 0
        if not mask.any():
            continue
        own = prior * mask
        best: tuple[float, np.ndarray] | None = None
        for scale in scales:
            cov = np.minimum(own_cov[k] * scale, COVER_CAP)
            for swap in (False, True):
                g_f = mirrored if swap else grid
                start = takeoff[k][::-1] if swap else takeoff[k]
                for lv in levels:
                    regions = layered_tracks(cov.T if swap else cov, g_f, w, lv)
                    if not regions:
                        continue
                    h = w / float(cov.max())  # the lattice of layered_tracks
                    for order in (
                        chain_regions(regions, start),
                        chain_regions(by_layer(regions, h, lv), start),
                    ):
                        wps = np.array([[x, y] for (y, a, b, _) in order for x in (a, b)])
                        if swap:
                            wps = wps[:, ::-1]

                        def fits(q, k=k) -> bool:
                            return route_fits(
                                np.vstack([takeoff[k], q, landing[k]]),
                                v,
                                turn_rate,
                                budget,
                                reserve,
                                headings[k],
                            )

                        wps = cut_lines(wps, fits, w, options)[0]
                        if len(wps) < 2:
                            continue
                        path = np.vstack([takeoff[k], wps, landing[k]])
                        cover = _path_coverage(path, grid, w)
                        val = float(np.sum(own * pod_from_coverage(cover, law)))
                        if best is None or val > best[0]:
                            best = (val, wps)
        if best is not None:
            routes[k] = best[1].tolist()
    return routes
