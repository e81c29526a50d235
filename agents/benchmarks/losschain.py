"""Where a route plan's POS goes, link by link: the loss chain from the rule-aware bound down
to the flown POS (issue 24, session i24-losschain; script and records in
results/plan_scale/losschain, the table in docs/PLANNER.md).

Every value is a POS (a share of the target's probability found) computed by code; every link
is the difference of two consecutive values, so the links add up to ``bound - flown`` exactly.
The chain (:data:`VALUES`, in order):

``bound``
    :func:`poc_env.theory.bound.rule_bound`, the rule-aware bound (the sensor's spill ``rho``
    credited as reach: a cell's transit is shortened by ``rho`` at both ends).
``bound_nospill``
    the same with ``spill_m=0``: effort only in cells the track reaches (the bound of the
    planners' coverage model, W x length per cell with eq. 10's POD). Link **spill credit**.
``plan_effort``
    the same relaxation with the plan's own effort: every UAV's sweep rate scaled by
    ``s = Z_plan / Z_bound`` (``Z_plan`` = W x the plan's track length inside the map, transit
    and connections included, as :func:`poc_env.agents.planning.flight_rules.path_coverage`
    counts it; ``Z_bound`` the relaxation's effort). Link **effort**: the time the plan does not
    sweep the map (turns, transit beyond the bound's straight one, the time left unused when the
    last line is cut for eq. 18, the return rule's reserve).
``footprint``
    each UAV's own effort (W x its track inside the map) spread over the cells its own track
    crosses, graded optimally for the fleet together (:func:`footprint_optimum`). Link
    **footprint**: where each UAV flies (the cells of its boxes and transit) against where the
    relaxation puts the same effort (the relaxation's reach is not the plan's, so it may be
    negative).
``cell_model``
    the plan's POS in the planners' model, :func:`path_coverage` of every UAV's whole path
    summed per cell and eq. 10's POD. Link **grading** (never negative: the plan is one of the
    spreads :func:`footprint_optimum` maximises over): a few line spacings over rectangles
    instead of a graded coverage, and double coverage where UAVs' tracks overlap.
``ideal_lines``
    the plan's per-cell coverage laid as ideal parallel lines, evenly spaced in each cell
    (:func:`ideal_tracks`), scored by the environment's sensor model (:func:`ideal_pos`: the
    lateral-range law and cut-off on the sample points). Link **sensor law**: eq. 10's erf(C)
    per cell against the lateral law, the outermost lines' sweep falling outside the searched
    cells (a loss) and detections beyond them (a gain).
``planned``
    the plan's planned POS (``posc``: the sensor model over the plan's own whole paths,
    :func:`poc_env.agents.planning.allocation.sampled_sweep`). Link **line geometry**: the
    plan's lines where they are instead of evenly spread in each cell (lines of UAVs sharing
    cells laid without regard to each other, lines whose lateral sweep falls on thinner
    cells than the ones W x length per cell credits, the sample points' lattice).
``flown``
    the POSC of the ``allocation_plan`` policy flown in the environment. Link **flying**.

Beside the chain (:func:`loss_chain`'s ``side``): the relaxation's own allocation laid as ideal
parallel tracks and scored by the sensor model (:func:`ideal_pos`: the modelling gap between the
bound's erf(C) per cell and the environment's law with its cut-off), the fleet's time budget
(:func:`time_budget`), the share of the plan's effort in cells two UAVs cross and of its track
on top of another UAV's (:func:`coincident_share`), the relaxation's coverage with 1-3 line
spacings (:func:`quantised`), ceilings of the plan's structure (its coverage pattern with the
lost effort returned; the best graded coverage on its footprint at full effort), and the two
sensor-model links split per cell into the cells two or more UAVs cross, one crosses and none
crosses (exactly additive).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from poc_env.agents.planning.allocation import sampled_sweep
from poc_env.agents.planning.flight_rules import path_coverage, plan_speeds
from poc_env.agents.planning.refine import route_time
from poc_env.config import Scenario
from poc_env.errors import ConfigError
from poc_env.sim.core import takeoff_heading
from poc_env.theory.bound import rule_bound
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import clip_length, pod_from_coverage, sweep_segments

#: the chain's values, from the bound down to the flown POS.
VALUES = (
    "bound",
    "bound_nospill",
    "plan_effort",
    "footprint",
    "cell_model",
    "ideal_lines",
    "planned",
    "flown",
)
#: the links: ``LINKS[i]`` = ``VALUES[i] - VALUES[i + 1]``.
LINKS = (
    "spill credit",
    "effort",
    "footprint",
    "grading",
    "sensor law",
    "line geometry",
    "flying",
)
#: line phases (share of the line spacing) :func:`ideal_pos` averages over: the sample points
#: sit on a fixed lattice, so one phase alone aliases with it.
PHASES = (0.125, 0.375, 0.625, 0.875)
#: numbers of line spacings of the relaxation's coverage quantised (:func:`quantised`).
QUANTISED = (1, 2, 3)


def ideal_tracks(coverage, grid: Grid, w: float, phase: float = 0.5) -> tuple[np.ndarray, ...]:
    """Segments ``(a, b)`` (each (L, 2)) laying ``coverage`` (eq. 10 per cell) as parallel lines
    along x: cell j gets ``n = C_j c / W`` lines' worth of track (c the cell side), as
    ``ceil(n)`` lines evenly spaced across the cell (at ``(i + phase) c / ceil(n)``), each
    ``c n / ceil(n)`` long and centred; so W x the track in each cell is ``C_j a_j`` exactly."""
    cov = np.asarray(coverage, dtype=float)
    if cov.shape != grid.shape or not np.all(np.isfinite(cov)) or np.any(cov < 0):
        raise ConfigError(
            "coverage", "array", f"finite coverages >= 0 of the grid's shape {grid.shape}"
        )
    if not 0.0 <= phase < 1.0:
        raise ConfigError("phase", phase, "a share of the line spacing in [0, 1)")
    c = grid.cell_m
    ox, oy = grid.origin_m
    rows, cols = np.nonzero(cov > 0)
    n = cov[rows, cols] * c / float(w)
    k = np.ceil(n - 1e-12).astype(np.int64)
    keep = k > 0
    rows, cols, n, k = rows[keep], cols[keep], n[keep], k[keep]
    cell = np.repeat(np.arange(len(k)), k)
    i = np.arange(int(k.sum())) - np.repeat(np.cumsum(k) - k, k)
    y = oy + c * rows[cell] + c * (i + phase) / k[cell]
    half = 0.5 * c * n[cell] / k[cell]
    xc = ox + c * (cols[cell] + 0.5)
    a = np.stack([xc - half, y], axis=1)
    b = np.stack([xc + half, y], axis=1)
    return a, b


def segments_pos(sc: Scenario, grid: Grid, prior, a, b) -> tuple[float, np.ndarray]:
    """POS of the segments ``a -> b`` (unconnected) under the environment's sensor model (the
    lateral law and cut-off on the scenario's sample points, eq. 14, as
    :func:`poc_env.agents.planning.allocation.sampled_sweep` for a path) and the mass found per
    cell."""
    s = sc.sensor.samples_per_cell
    w = sc.sensor.sweep_width_m
    belief = np.ascontiguousarray(grid.refine(np.asarray(prior, dtype=float), s))[None]
    before = belief[0].copy()
    a = np.asarray(a, dtype=float).reshape(1, -1, 2)
    b = np.asarray(b, dtype=float).reshape(1, -1, 2)
    if a.shape[1] == 0:
        return 0.0, np.zeros(grid.shape)
    cutoff = sc.sensor.cutoff_sweep_widths * w
    found = sweep_segments(belief, grid, s, a, b, w, sc.sensor.law, cutoff)
    return float(found.sum()), grid.coarsen(before - belief[0], s)


def ideal_found(sc: Scenario, grid: Grid, prior, coverage, phases=PHASES):
    """What ``coverage`` is worth laid as ideal parallel tracks (:func:`ideal_tracks`) and swept
    by the environment's sensor model (:func:`segments_pos`), averaged over line ``phases``: the
    POS and the mass found per cell."""
    w = sc.sensor.sweep_width_m
    runs = [segments_pos(sc, grid, prior, *ideal_tracks(coverage, grid, w, ph)) for ph in phases]
    return float(np.mean([r[0] for r in runs])), np.mean([r[1] for r in runs], axis=0)


def ideal_pos(sc: Scenario, grid: Grid, prior, coverage, phases=PHASES) -> float:
    """The POS of :func:`ideal_found`."""
    return ideal_found(sc, grid, prior, coverage, phases)[0]


def _paths(plan: dict[str, Any]) -> list[np.ndarray]:
    """Every UAV's whole path (take-off, waypoints, landing) of a route plan; empty if none."""
    out = []
    for u in plan["uavs"]:
        wps = np.asarray(u["waypoints_m"], dtype=float).reshape(-1, 2)
        if len(wps) == 0:
            out.append(np.zeros((0, 2)))
            continue
        out.append(np.vstack([u["takeoff_m"], wps, u["landing_m"]]))
    return out


def time_budget(sc: Scenario, plan: dict[str, Any]) -> dict[str, float]:
    """The fleet's usable time (n x 0.85 T, s) as the plan spends it: ``in_map`` (flying over
    the map, where every leg sweeps), ``outside`` (transit outside it), ``turns`` (eq. 17's
    turn time at every waypoint, :func:`poc_env.agents.planning.refine.route_time`) and
    ``unused``; the four add up to ``total``. Legs are flown at the plan's speeds
    (:func:`poc_env.agents.planning.flight_rules.plan_speeds`)."""
    grid = Grid.from_config(sc.map)
    v = plan_speeds(sc, plan.get("speed_rule", "max"))
    t_u = sc.uav.usable_endurance_s
    heads = takeoff_heading(grid.bounds, np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2))
    out = {"total": 0.0, "in_map": 0.0, "outside": 0.0, "turns": 0.0, "unused": 0.0}
    for k, path in enumerate(_paths(plan)):
        out["total"] += t_u
        if len(path) < 2:
            out["unused"] += t_u
            continue
        p, q = path[:-1], path[1:]
        speed = np.full(len(p), v.line)
        speed[0], speed[-1] = v.out, v.home
        length = np.hypot(*(q - p).T)
        inside = clip_length(p, q, np.array(grid.bounds[:2]), np.array(grid.bounds[2:]))
        t_in = float(np.sum(inside / speed))
        t_out = float(np.sum((length - inside) / speed))
        total = route_time(path, v, sc.uav.max_turn_rate_rad_s, float(heads[k]))
        out["in_map"] += t_in
        out["outside"] += t_out
        out["turns"] += total - t_in - t_out
        out["unused"] += t_u - total
    return out


#: block-coordinate passes of :func:`footprint_optimum` at most, and its stopping gain (a few
#: records stop at 200 passes: there 2000 move the value by less than 1e-8, checked on
#: `paper_6_2` 5007 and `large_400` 5001).
PASSES = 200
PASS_TOL = 1e-10


def footprint_optimum(prior, cell_area_m2: float, coverages, law: str = "inverse_cube"):
    """Most POS (eq. 10 per cell) when UAV k spreads its effort ``Z_k = a sum_j C_kj`` over the
    cells where ``coverages[k] > 0`` (its footprint) only, in any proportions, the fleet's
    coverages adding per cell: maximise ``sum_j m_j POD(sum_k x_kj / a)`` with
    ``sum_j x_kj = Z_k``, ``x_kj >= 0`` on k's footprint. Concave over a product of simplices:
    block-coordinate ascent from ``coverages`` itself (so never below its POS), UAV k's block a
    water-filling over its footprint given the others' coverage (KKT: ``m_j / a POD'(C_j) =
    lambda_k`` where k adds effort). Returns (POS, passes made)."""
    from scipy.optimize import brentq

    from poc_env.theory.detection import detection_law

    entry = detection_law(law)
    m = np.asarray(prior, dtype=float).ravel()
    cov = [np.asarray(c, dtype=float).ravel().copy() for c in coverages]
    if not cov:
        return 0.0, 0
    total = np.sum(cov, axis=0)
    value = float(np.sum(m * entry.pod(total)))
    opt = entry.optimal_coverage
    if opt is None:
        raise ConfigError("law", law, "a law with an optimal coverage (inverse_cube, exponential)")
    dens = m / float(cell_area_m2)
    feet = [c > 0 for c in cov]  # fixed: a footprint cell may be given no effort
    passes = 0
    while passes < PASSES:
        passes += 1
        for k, ck in enumerate(cov):
            foot = feet[k]
            z = float(ck.sum())
            if z <= 0 or not np.any(dens[foot] > 0):
                continue
            base = total[foot] - ck[foot]
            d = dens[foot]

            def target(mu: float, base=base, d=d) -> np.ndarray:
                with np.errstate(divide="ignore"):
                    gg = np.log(np.where(d > 0, d, 1e-300)) - mu
                return np.maximum(opt(np.maximum(gg, 0.0)) - base, 0.0)

            def excess(mu: float, z=z, target=target) -> float:
                return float(target(mu).sum()) - z

            lo = float(np.log(d[d > 0].min())) - 60.0
            hi = float(np.log(d.max())) + 1.0
            if excess(lo) <= 0:  # cannot spend it (never at these efforts): keep the block
                continue
            mu = brentq(excess, lo, hi, xtol=1e-13)
            new = target(mu)
            new *= z / new.sum()
            ck[foot] = new
            total[foot] = base + new
        now = float(np.sum(m * entry.pod(total)))
        gain, value = now - value, max(value, now)
        if gain < PASS_TOL:
            break
    return value, passes


#: raster (m) on which :func:`coincident_share` compares tracks, and the step along them.
COINCIDENT_M = 250.0


def coincident_share(paths, grid: Grid) -> float:
    """Share of the fleet's track inside the map (sampled every ``COINCIDENT_M / 2``) lying on
    ``COINCIDENT_M`` raster squares another UAV's track also crosses: lines flown on top of
    each other (crossings count a few squares each)."""
    x0, y0, x1, y1 = grid.bounds
    nx = int(np.ceil((x1 - x0) / COINCIDENT_M))
    keys = []
    for path in paths:
        if len(path) < 2:
            keys.append(np.zeros(0, dtype=np.int64))
            continue
        p, q = path[:-1], path[1:]
        n = np.maximum(1, np.ceil(np.hypot(*(q - p).T) / (0.5 * COINCIDENT_M))).astype(np.int64)
        leg = np.repeat(np.arange(len(p)), n)
        t = (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n) + 0.5) / n[leg]
        xy = p[leg] + t[:, None] * (q - p)[leg]
        ok = (xy[:, 0] >= x0) & (xy[:, 0] < x1) & (xy[:, 1] >= y0) & (xy[:, 1] < y1)
        ix = ((xy[ok, 0] - x0) // COINCIDENT_M).astype(np.int64)
        iy = ((xy[ok, 1] - y0) // COINCIDENT_M).astype(np.int64)
        keys.append(iy * nx + ix)
    uniq = [np.unique(k) for k in keys]
    if not any(len(k) for k in keys):
        return 0.0
    owners = np.bincount(np.concatenate(uniq)) if any(len(u) for u in uniq) else np.zeros(1)
    shared = sum(int(np.sum(owners[k] >= 2)) for k in keys)
    return shared / sum(len(k) for k in keys)


def quantised(coverage, levels: int) -> np.ndarray:
    """``coverage`` with its positive values replaced by ``levels`` values (1-D k-means, each
    cell its cluster's mean; the effort, ``sum C``, is kept): the coverage of lawnmowers with
    ``levels`` line spacings over the same cells."""
    c = np.asarray(coverage, dtype=float)
    pos = c > 0
    v = c[pos]
    if v.size == 0:
        return c.copy()
    k = max(1, min(int(levels), v.size))
    centres = np.quantile(v, (np.arange(k) + 0.5) / k)
    for _ in range(100):
        lab = np.argmin(np.abs(v[:, None] - centres[None]), axis=1)
        new = np.array([v[lab == i].mean() if np.any(lab == i) else centres[i] for i in range(k)])
        if np.allclose(new, centres, rtol=0, atol=1e-12):
            break
        centres = new
    lab = np.argmin(np.abs(v[:, None] - centres[None]), axis=1)
    out = np.zeros_like(c)
    out[pos] = np.array([v[lab == i].mean() if np.any(lab == i) else 0.0 for i in range(k)])[lab]
    return out


def loss_chain(
    sc: Scenario, prior, plan: dict[str, Any], flown: float | None = None
) -> dict[str, Any]:
    """The loss chain of route ``plan`` (a schema-2 route plan of ``sc`` on ``prior``, e.g.
    :func:`poc_env.agents.planning.allocation.make_allocation_plan`'s) flown to POSC ``flown``
    (None: the planned POS stands in, the last link is 0). Returns ``values`` (:data:`VALUES`),
    ``links`` (:data:`LINKS`, each the drop from one value to the next; they add up to
    ``bound - flown``) and ``side`` figures (module docstring)."""
    grid = Grid.from_config(sc.map)
    prior = np.asarray(prior, dtype=float)
    if prior.shape != grid.shape:
        raise ConfigError("prior", prior.shape, f"an array of the grid's shape {grid.shape}")
    w = sc.sensor.sweep_width_m
    law = sc.sensor.law
    area = grid.cell_area_m2
    paths = _paths(plan)
    per_uav = [path_coverage(p, grid, w) if len(p) else np.zeros(grid.shape) for p in paths]
    cov = np.sum(per_uav, axis=0) if per_uav else np.zeros(grid.shape)
    foot = cov > 0
    z_plan = float(cov.sum() * area)

    b = rule_bound(sc, prior)
    b0 = rule_bound(sc, prior, spill_m=0.0)
    share = z_plan / b0.effort_m2 if b0.effort_m2 > 0 else 0.0
    scaled = dataclasses.replace(sc, sensor=dataclasses.replace(sc.sensor, sweep_width_m=w * share))
    g = rule_bound(scaled, prior, spill_m=0.0).upper if share > 0 else 0.0
    f, sweeps = footprint_optimum(prior, area, per_uav, law)
    cell_pos = float(np.sum(prior * pod_from_coverage(cov, law)))
    pos_k, found_k = sampled_sweep(sc, grid, prior, [p if len(p) else [] for p in paths])
    found = np.sum(found_k, axis=0) if found_k else np.zeros(grid.shape)
    planned = float(sum(pos_k))
    inside = float(found[foot].sum())
    ideal, ideal_cells = ideal_found(sc, grid, prior, cov)
    values = {
        "bound": float(b.upper),
        "bound_nospill": float(b0.upper),
        "plan_effort": float(g),
        "footprint": float(f),
        "cell_model": cell_pos,
        "ideal_lines": ideal,
        "planned": planned,
        "flown": planned if flown is None else float(flown),
    }
    seq = [values[k] for k in VALUES]
    links = {name: seq[i] - seq[i + 1] for i, name in enumerate(LINKS)}

    # beside the chain
    crossed = np.sum([c > 0 for c in per_uav], axis=0) if per_uav else np.zeros(grid.shape)
    overlap = float(cov[crossed >= 2].sum() / cov.sum()) if cov.sum() > 0 else 0.0
    # the two sensor-model links split per cell (exactly additive): cells two or more UAVs'
    # tracks cross, cells one crosses, cells none crosses
    cell_pod = prior * pod_from_coverage(cov, law)
    split = {}
    for part, mask in (("shared", crossed >= 2), ("single", crossed == 1), ("none", crossed == 0)):
        split[f"sensor_law_{part}"] = float(cell_pod[mask].sum() - ideal_cells[mask].sum())
        split[f"line_geometry_{part}"] = float(ideal_cells[mask].sum() - found[mask].sum())
    graded = rule_bound(sc, prior * foot, spill_m=0.0) if foot.any() else None
    pattern_full = float(np.sum(prior * pod_from_coverage(cov / share, law))) if share > 0 else 0.0
    tb = time_budget(sc, plan)
    levels = {}
    for k in QUANTISED:
        qc = quantised(b0.coverage, k)
        levels[f"levels_{k}_cell"] = float(np.sum(prior * pod_from_coverage(qc, law)))
        levels[f"levels_{k}_lines"] = ideal_pos(sc, grid, prior, qc)
    side = {
        "ideal_tracks": ideal_pos(sc, grid, prior, b0.coverage),
        "bound_how": b.how,
        "effort_share": share,
        "bound_effort_m2": float(b0.effort_m2),
        "plan_effort_m2": z_plan,
        "footprint_cells": int(foot.sum()),
        "footprint_sweeps": sweeps,
        "overlap_share": overlap,
        "ceiling_pattern_full_effort": pattern_full,
        "ceiling_graded_footprint": float(graded.upper) if graded is not None else 0.0,
        "planned_inside_footprint": inside,
        "coincident_share": coincident_share(paths, grid),
        **split,
        "ideal_plan_full_effort": ideal_pos(sc, grid, prior, cov / share) if share > 0 else 0.0,
        "ideal_graded_footprint": (
            ideal_pos(sc, grid, prior, graded.coverage) if graded is not None else 0.0
        ),
        "plan_posc": float(plan["posc"]),
        "time_s": tb,
        **levels,
        "bound_sweep_share": float(
            b0.effort_m2 / (sc.uav.max_speed_mps * w * tb["total"]) if tb["total"] else 0.0
        ),
    }
    return {"values": values, "links": links, "side": side}


def fly_allocation(sc: Scenario, prior, seed: int) -> tuple[float, dict[str, Any]]:
    """``allocation_plan`` flown in the environment on ``prior`` (episode ``seed``): its POSC
    and the plan it flew."""
    from poc_env.agents.benchmarks.plan_scale import _flown

    return _flown(sc, "allocation_plan", seed, np.asarray(prior, dtype=float))
